//! The quadratic (Morison) drag `c₂ |v| v`: a swing that decays by more
//! of itself the larger it is, a step that tends to the continuous law as
//! the sample time falls, and one that never gives energy back.

use model_core::{Extensions, Fixture, HarmonicError, Params, Phasor, Strip, DRAGGED_MODES};

type S3 = Strip<f64, 3, 1, 18>;

/// main.m's strip as a pure gain (`z = p`: the moment follows the 16 ms
/// charge, so a step rings), in water's added mass (ten times its own).
fn wet(c2: f64, linear: f64, dt_s: f64) -> S3 {
    let lag = Params::main_m_2006();
    let p = Params {
        a_nm_per_c: lag.b_nm_per_c_s / lag.p_per_s,
        ..lag
    };
    let ext = Extensions {
        added_mass_kg_per_m: 10.0 * p.mass_per_length_kg_per_m,
        drag_quadratic_n_s2_per_m3: c2,
        drag_n_s_per_m2: linear,
        ..Extensions::NONE
    };
    S3::with_extensions(&p, &ext, Fixture::Free, dt_s).unwrap()
}

/// The ringing of a `volts` step about its static tip, `steps` samples.
fn ringing(s: &S3, volts: f64, steps: usize) -> Vec<f64> {
    let p = s.params();
    let mut x = s.rest();
    (0..steps)
        .map(|_| {
            s.step(&mut x, &[volts; 3]);
            let u = s.moments_nm(&x)[0];
            s.tip_deflection_m(&x) - u * p.length_m * p.length_m / (2.0 * p.ei_nm2)
        })
        .collect()
}

/// The largest `|ring|` over a window of `len` samples from `from`.
fn peak(ring: &[f64], from: usize, len: usize) -> f64 {
    ring[from..from + len]
        .iter()
        .fold(0.0f64, |m, r| m.max(r.abs()))
}

/// Quadratic drag takes a fixed fraction of the speed per unit of
/// amplitude, so a swing ten times larger loses a larger share of itself
/// per period; a linear drag takes the same share at any amplitude (the
/// control, which the same measure must see as equal).
#[test]
fn a_large_swing_loses_more_of_itself_than_a_small_one() {
    let kept = |s: &S3, volts: f64| {
        let ring = ringing(s, volts, 800);
        peak(&ring, 600, 200) / peak(&ring, 50, 200)
    };
    let quadratic = wet(50.0, 0.0, 1e-3);
    let (large, small) = (kept(&quadratic, 2.5), kept(&quadratic, 0.25));
    assert!(
        large < 0.8 * small,
        "quadratic: a 2.5 V swing keeps {large:.3} of itself, a 0.25 V one {small:.3}"
    );
    let linear = wet(0.0, 0.05, 1e-3);
    let (large, small) = (kept(&linear, 2.5), kept(&linear, 0.25));
    assert!(large < 0.95, "the linear control damps: {large:.3}");
    assert!(
        (large / small - 1.0).abs() < 1e-9,
        "linear: {large:.6} against {small:.6}"
    );
}

/// The lowest modes' node rows `ψₙₖ` (deflection of node `n + 1` per unit
/// of mode `k`), as the step reads them.
fn node_rows(s: &S3) -> [[f64; DRAGGED_MODES]; 3] {
    core::array::from_fn(|n| {
        core::array::from_fn(|k| {
            let mut x = s.rest();
            x[k] = 1.0;
            s.node_deflection_m(&x, n + 1).unwrap()
        })
    })
}

/// `ẋ = A x + B v` plus the drag on the lowest modes, `ζ̇ₖ −= (1/ωₖ) Σₙ
/// ψₙₖ cₙ |vₙ| vₙ`, by classical Runge–Kutta at a tenth of a microsecond
/// per step: the continuous law the sampled step should approach. Returns
/// the tip every millisecond.
fn reference(c2: f64, volts: f64, ms: usize) -> Vec<f64> {
    let s = wet(c2, 0.0, 1e-3);
    let (a, b) = S3::continuous(s.params(), s.extensions(), Fixture::Free).unwrap();
    let psi = node_rows(&s);
    let omega: Vec<f64> = s
        .natural_frequencies_hz()
        .map(|f| 2.0 * core::f64::consts::PI * f)
        .collect();
    let element_m = s.params().length_m / 3.0;
    let share = [element_m, element_m, 0.5 * element_m];
    let f = |x: &[f64; 18]| -> [f64; 18] {
        let mut dx = [0.0; 18];
        for (i, d) in dx.iter_mut().enumerate() {
            *d = (0..18).map(|j| a[i][j] * x[j]).sum::<f64>()
                + (0..3).map(|j| b[i][j] * volts).sum::<f64>();
        }
        for n in 0..3 {
            let v_n: f64 = (0..DRAGGED_MODES)
                .map(|k| psi[n][k] * omega[k] * x[6 + k])
                .sum();
            let load = c2 * share[n] * v_n.abs() * v_n;
            for k in 0..DRAGGED_MODES {
                dx[6 + k] -= psi[n][k] * load / omega[k];
            }
        }
        dx
    };
    let h = 1e-5;
    let per_ms = 100;
    let mut x = [0.0; 18];
    let mut tips = Vec::with_capacity(ms);
    for _ in 0..ms {
        for _ in 0..per_ms {
            let k1 = f(&x);
            let at = |k: &[f64; 18], c: f64| core::array::from_fn(|i| x[i] + c * h * k[i]);
            let k2 = f(&at(&k1, 0.5));
            let k3 = f(&at(&k2, 0.5));
            let k4 = f(&at(&k3, 1.0));
            for i in 0..18 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        tips.push(s.tip_deflection_m(&x));
    }
    tips
}

/// The sampled strip's tip every millisecond at sample time `dt_s`.
fn sampled(c2: f64, volts: f64, ms: usize, dt_s: f64) -> Vec<f64> {
    let s = wet(c2, 0.0, dt_s);
    let per_ms = (1e-3 / dt_s).round() as usize;
    let mut x = s.rest();
    (0..ms)
        .map(|_| {
            for _ in 0..per_ms {
                s.step(&mut x, &[volts; 3]);
            }
            s.tip_deflection_m(&x)
        })
        .collect()
}

/// The step splits the drag from the exact linear step: its error is
/// small at the bench's millisecond and falls about as the sample time
/// does (first order), toward a Runge–Kutta solution of the continuous
/// law. Without the drag the two agree to the integrator's error, which
/// shows the reference is the same strip.
#[test]
fn the_step_tends_to_the_continuous_drag_as_the_sample_time_falls() {
    let (c2, volts, ms) = (50.0, 2.5, 300);
    let reference_tips = reference(c2, volts, ms);
    let swing = reference_tips.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let error = |tips: &[f64]| {
        tips.iter()
            .zip(&reference_tips)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / swing
    };
    let undragged = error(&sampled(0.0, volts, ms, 1e-3));
    let coarse = error(&sampled(c2, volts, ms, 1e-3));
    let fine = error(&sampled(c2, volts, ms, 1e-4));
    let clean = sampled(0.0, volts, ms, 1e-3);
    let free = reference(0.0, volts, ms);
    let linear_only = clean
        .iter()
        .zip(&free)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / swing;
    assert!(
        linear_only < 1e-6,
        "the linear parts differ by {linear_only:.2e}"
    );
    assert!(undragged > 0.05, "the drag does not show: {undragged:.3}");
    assert!(coarse < 0.02, "at 1 ms: {coarse:.4} of the swing");
    assert!(
        fine < coarse / 5.0,
        "at 0.1 ms: {fine:.5} against {coarse:.5} at 1 ms"
    );
}

/// The modes' energy `½ Σ ωₖ² (ηₖ² + ζₖ²)` of an unforced strip: the
/// exact linear step keeps it, the drag's implicit step only takes from
/// it, even at a drag so large that an explicit step would reverse the
/// nodes and blow up.
#[test]
fn the_drag_never_gives_energy_back() {
    for c2 in [1.0, 1e2, 1e6] {
        let s = wet(c2, 0.0, 1e-3);
        let omega: Vec<f64> = s
            .natural_frequencies_hz()
            .map(|f| 2.0 * core::f64::consts::PI * f)
            .collect();
        let energy = |x: &[f64; 18]| -> f64 {
            (0..6)
                .map(|k| 0.5 * omega[k] * omega[k] * (x[k] * x[k] + x[6 + k] * x[6 + k]))
                .sum()
        };
        let mut x = s.rest();
        x[0] = 1e-3;
        x[1] = -2e-4;
        let start = energy(&x);
        let mut last = start;
        for step in 0..2000 {
            s.step(&mut x, &[0.0; 3]);
            let e = energy(&x);
            assert!(
                e <= last * (1.0 + 1e-12),
                "c2 {c2}: energy rose at step {step}: {last} to {e}"
            );
            last = e;
        }
        assert!(last < 0.9 * start, "c2 {c2}: {last} of {start} left");
    }
}

/// A sine's response holds harmonics under the drag, so the harmonic
/// inverse refuses it by name; the held step's static inverse does not
/// see the drag and stands.
#[test]
fn the_harmonic_inverse_refuses_the_drag_and_the_held_step_stands() {
    let s = wet(10.0, 0.0, 1e-3);
    assert_eq!(
        s.harmonic(1.0, &[Phasor::real(1.0); 3]).map(|_| ()),
        Err(HarmonicError::Nonlinear {
            field: "drag_quadratic_n_s2_per_m3"
        })
    );
    let off = wet(0.0, 0.0, 1e-3);
    assert_eq!(s.tip_step(5e-3), off.tip_step(5e-3));
}

/// A negative or non-finite drag is refused by its field's name.
#[test]
fn a_negative_drag_is_refused_by_name() {
    for c2 in [-1.0, f64::NAN] {
        let ext = Extensions {
            drag_quadratic_n_s2_per_m3: c2,
            ..Extensions::NONE
        };
        let err =
            S3::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3).unwrap_err();
        assert!(
            err.to_string().starts_with("drag_quadratic_n_s2_per_m3"),
            "{err}"
        );
    }
}
