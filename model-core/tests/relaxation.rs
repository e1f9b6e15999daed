//! The relaxation network `u/Q = (a s + b)/(s + p)` over its whole range:
//! a partial relaxation (`z < p`), a pure gain (`z = p`), a creep
//! (`z > p`, Table 4-2) and the pure lag (`a = 0`, `main.m`).

use model_core::{Fixture, Params, Strip};

const DT: f64 = 1e-3;

type S1 = Strip<f64, 1, 1, 6>;

/// The moment of one segment under a held `v`, sampled every step.
fn moments(p: &Params, v: f64, steps: usize) -> Vec<f64> {
    let s = S1::new(p, Fixture::Free, DT).unwrap();
    let mut x = s.rest();
    (0..steps)
        .map(|_| {
            s.step(&mut x, &[v]);
            s.moments_nm(&x)[0]
        })
        .collect()
}

/// `p` with the seed's `K (s + z)/(s + p)` set to `K`, `z`.
fn lead(p: Params, k_nm_per_c: f64, z_per_s: f64) -> Params {
    Params {
        a_nm_per_c: k_nm_per_c,
        b_nm_per_c_s: k_nm_per_c * z_per_s,
        ..p
    }
}

#[test]
fn creep_rises_monotonically_to_its_dc_value() {
    let p = Params::table_4_2_2006();
    let z = p.zero_per_s().unwrap();
    assert!((z - 0.24).abs() < 1e-15 && z > p.p_per_s, "z {z}");
    let u = moments(&p, 1.0, 120_000);
    for (k, w) in u.windows(2).enumerate() {
        assert!(w[1] >= w[0], "step {k}: {} then {}", w[0], w[1]);
    }
    let dc = p.dc_moment_per_volt();
    // 120 s: τ1 = 1.6 s and 1/p = 10 s have decayed by e^-12.
    let last = u[u.len() - 1];
    assert!((last / dc - 1.0).abs() < 1e-4, "{last} vs {dc}");
}

#[test]
fn pure_lag_starts_at_zero_moment() {
    let p = Params::main_m_2006();
    assert_eq!(p.a_nm_per_c, 0.0);
    assert_eq!(p.zero_per_s(), None);
    let u = moments(&p, 1.0, 60_000);
    let dc = p.dc_moment_per_volt();
    // Two lags in series: after one step the moment is second order in the
    // step, (b C/τ1) h²/2.
    let second_order = p.b_nm_per_c_s * p.c_f / p.tau1_s() * DT * DT / 2.0;
    assert!(u[0] > 0.0 && u[0] < 1.01 * second_order, "{}", u[0]);
    // u(t) = dc (1 − (τ2 e^{−t/τ2} − τ1 e^{−t/τ1})/(τ2 − τ1)).
    let (t1, t2) = (p.tau1_s(), 1.0 / p.p_per_s);
    for k in [10, 100, 1000, 10_000, 59_999] {
        let t = (k + 1) as f64 * DT;
        let want = dc * (1.0 - (t2 * (-t / t2).exp() - t1 * (-t / t1).exp()) / (t2 - t1));
        assert!(
            (u[k] / want - 1.0).abs() < 1e-9,
            "t {t}: {} vs {want}",
            u[k]
        );
    }
}

#[test]
fn zero_on_the_pole_is_a_pure_gain() {
    let base = Params::main_m_2006();
    let p = lead(base, 3.0, base.p_per_s);
    let s = S1::new(&p, Fixture::Free, DT).unwrap();
    let mut x = s.rest();
    for k in 0..5000 {
        s.step(&mut x, &[1.0]);
        // The moment follows the charge with the gain K: u = K C v_C, and
        // v_C = 1 − e^{−t/τ1}.
        let t = (k + 1) as f64 * DT;
        let want = 3.0 * p.c_f * (1.0 - (-t / p.tau1_s()).exp());
        let u = s.moments_nm(&x)[0];
        assert!(
            (u - want).abs() < 1e-12 * want.max(1e-6),
            "t {t}: {u} vs {want}"
        );
    }
}

#[test]
fn the_response_is_continuous_across_z_equals_p() {
    let base = Params::table_4_2_2006();
    let k = base.a_nm_per_c;
    let at = moments(&lead(base, k, base.p_per_s), 1.0, 30_000);
    let scale = at.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    for eps in [1e-3, 1e-6] {
        let below = moments(&lead(base, k, base.p_per_s * (1.0 - eps)), 1.0, 30_000);
        let above = moments(&lead(base, k, base.p_per_s * (1.0 + eps)), 1.0, 30_000);
        for (side, u) in [("below", &below), ("above", &above)] {
            let gap = u
                .iter()
                .zip(&at)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            // The DC moment moves by eps of itself, the path by no more.
            assert!(
                gap <= 1.01 * eps * scale,
                "{side} by {eps}: gap {gap} of {scale}"
            );
            assert!(gap > 0.0, "{side} by {eps}: no change at all");
        }
    }
}

#[test]
fn lead_network_overshoots_by_p_over_z_and_relaxes() {
    let base = Params::main_m_2006();
    let p = lead(base, 6.0, 0.77 * base.p_per_s);
    let u = moments(&p, 1.0, 200_000);
    let peak = u[..200].iter().fold(0.0f64, |m, &x| m.max(x));
    let dc = p.dc_moment_per_volt();
    // Charging (16 ms) is fast against relaxation (10 s): the peak is nearly
    // K C = dc · p/z.
    assert!(
        (peak / dc - 1.0 / 0.77).abs() < 0.01,
        "peak/dc {}",
        peak / dc
    );
    assert!((u[u.len() - 1] / dc - 1.0).abs() < 1e-6);
}
