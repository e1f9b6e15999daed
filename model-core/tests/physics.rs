//! The seed's facts and textbook physics, as checks that can fail.

use model_core::{state_len, Fixture, Laminate, ParamError, Params, Strip};

const DT: f64 = 1e-3;

fn seed() -> Params {
    Params::main_m_2006()
}

/// Mean of the tip deflection (free) and force (blocked) over a window long
/// after the relaxation, which averages the undamped ringing out.
fn settled<const N: usize, const E: usize, const S: usize>(
    strip: &Strip<f64, N, E, S>,
    v: [f64; N],
) -> (f64, f64) {
    let mut x = strip.rest();
    // 200 s: the relaxation (1/p = 10 s) has decayed by e^-20.
    for _ in 0..200_000 {
        strip.step(&mut x, &v);
    }
    let (mut tip, mut force) = (0.0, 0.0);
    let window = 37_384; // 1000 periods of the 26.75 Hz mode
    for _ in 0..window {
        strip.step(&mut x, &v);
        tip += strip.tip_deflection_m(&x);
        force += strip.blocking_force_n(&x);
    }
    (tip / window as f64, force / window as f64)
}

#[test]
fn laminate_matches_seed_appendix_b() {
    let lam = Laminate::THESIS_2006;
    assert!(
        (lam.ei_nm2() / 1.1692e-4 - 1.0).abs() < 1e-4,
        "EI {}",
        lam.ei_nm2()
    );
    assert!((lam.mass_per_length_kg_per_m() / 8.1868e-3 - 1.0).abs() < 1e-6);
    assert!((lam.thickness_m() - 0.2858e-3).abs() < 1e-12);
}

#[test]
fn static_tip_at_2v5_is_13mm() {
    let s = Strip::<f64, 3, 1, 18>::new(&seed(), Fixture::Free, DT).unwrap();
    let (tip, _) = settled(&s, [2.5; 3]);
    assert!((tip / 13.0e-3 - 1.0).abs() < 0.01, "tip {tip}");
}

#[test]
fn uniform_moment_tip_is_u_l2_over_2ei() {
    let p = seed();
    let u = p.dc_moment_per_volt() * 2.5;
    let expected = u * p.length_m * p.length_m / (2.0 * p.ei_nm2);
    let s1 = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, DT).unwrap();
    let s2 = Strip::<f64, 3, 2, { state_len(3, 2) }>::new(&p, Fixture::Free, DT).unwrap();
    for tip in [settled(&s1, [2.5; 3]).0, settled(&s2, [2.5; 3]).0] {
        assert!(
            (tip / expected - 1.0).abs() < 1e-3,
            "tip {tip} vs {expected}"
        );
    }
}

#[test]
fn blocking_force_is_3u_over_2l() {
    let p = seed();
    let u = p.dc_moment_per_volt() * 2.0;
    let expected = 3.0 * u / (2.0 * p.length_m);
    let s = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Blocked, DT).unwrap();
    let (tip, force) = settled(&s, [2.0; 3]);
    assert_eq!(tip, 0.0);
    assert!(
        (force / expected - 1.0).abs() < 1e-3,
        "force {force} vs {expected}"
    );
}

fn euler_bernoulli_hz(p: &Params, beta_l: f64) -> f64 {
    beta_l * beta_l * (p.ei_nm2 / (p.mass_per_length_kg_per_m * p.length_m.powi(4))).sqrt()
        / (2.0 * std::f64::consts::PI)
}

/// Relative errors of the first two free modes against the analytic ones.
fn mode_errors(f: impl Iterator<Item = f64>, f1: f64, f2: f64) -> (f64, f64) {
    let f: Vec<f64> = f.collect();
    ((f[0] / f1 - 1.0).abs(), (f[1] / f2 - 1.0).abs())
}

#[test]
fn first_two_modes_converge_to_euler_bernoulli() {
    let p = seed();
    let f1 = euler_bernoulli_hz(&p, 1.875_104_068_7);
    let f2 = euler_bernoulli_hz(&p, 4.694_091_132_9);
    let free = Fixture::Free;
    let e1 = mode_errors(
        Strip::<f64, 3, 1, 18>::new(&p, free, DT)
            .unwrap()
            .natural_frequencies_hz(),
        f1,
        f2,
    );
    let e2 = mode_errors(
        Strip::<f64, 3, 2, { state_len(3, 2) }>::new(&p, free, DT)
            .unwrap()
            .natural_frequencies_hz(),
        f1,
        f2,
    );
    let e4 = mode_errors(
        Strip::<f64, 3, 4, { state_len(3, 4) }>::new(&p, free, DT)
            .unwrap()
            .natural_frequencies_hz(),
        f1,
        f2,
    );
    // The seed's mesh gives 26.75 Hz and 168.2 Hz (model notes).
    assert!(e1.0 < 2e-4 && e1.1 < 4e-3, "E=1 errors {e1:?}");
    // Hermite cubics converge as h^4 in frequency: each halving gains ~16x.
    assert!(
        e2.0 < e1.0 / 8.0 && e2.1 < e1.1 / 8.0,
        "E=2 {e2:?} vs E=1 {e1:?}"
    );
    assert!(
        e4.0 < e2.0 / 8.0 && e4.1 < e2.1 / 8.0,
        "E=4 {e4:?} vs E=2 {e2:?}"
    );
}

#[test]
fn current_jumps_then_settles_to_v_over_r2() {
    let p = seed();
    let s = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, DT).unwrap();
    let mut x = s.rest();
    let v = [2.5; 3];
    let i0 = s.currents_a(&x, &v)[0];
    let jump = 2.5 / p.r1_ohm + 2.5 / p.r2_ohm;
    assert!((i0 / jump - 1.0).abs() < 1e-12, "initial {i0} vs {jump}");
    // τ1 = 16 ms later the transient part has fallen to 1/e.
    let tau_steps = (p.tau1_s() / DT).round() as usize;
    for _ in 0..tau_steps {
        s.step(&mut x, &v);
    }
    let i_tau = s.currents_a(&x, &v)[0];
    let expected = 2.5 / p.r2_ohm + 2.5 / p.r1_ohm * (-1.0f64).exp();
    assert!(
        (i_tau / expected - 1.0).abs() < 1e-9,
        "at tau1 {i_tau} vs {expected}"
    );
    for _ in 0..2000 {
        s.step(&mut x, &v);
    }
    let i_dc = s.currents_a(&x, &v)[0];
    assert!((i_dc / (2.5 / p.r2_ohm) - 1.0).abs() < 1e-9, "dc {i_dc}");
}

type SetField = fn(&mut Params);

#[test]
fn bad_parameters_are_refused_by_name() {
    let mut p = seed();
    p.r1_ohm = 0.0;
    assert_eq!(
        Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, DT).unwrap_err(),
        ParamError::NotPositive {
            field: "r1_ohm",
            value: 0.0
        }
    );
    let cases: [(&str, SetField); 6] = [
        ("r2_ohm", |p| p.r2_ohm = -1.0),
        ("c_f", |p| p.c_f = -1e-4),
        ("ei_nm2", |p| p.ei_nm2 = 0.0),
        ("mass_per_length_kg_per_m", |p| {
            p.mass_per_length_kg_per_m = -1.0
        }),
        ("length_m", |p| p.length_m = 0.0),
        ("p_per_s", |p| p.p_per_s = 0.0),
    ];
    for (field, set) in cases {
        let mut p = seed();
        set(&mut p);
        let err = p.validate().unwrap_err();
        assert!(
            matches!(err, ParamError::NotPositive { field: f, .. } if f == field),
            "{err}"
        );
    }
    let mut p = seed();
    p.c_f = f64::NAN;
    assert!(matches!(
        p.validate(),
        Err(ParamError::NotFinite { field: "c_f", .. })
    ));
    // A negative instant part, and b <= 0 (a zero z <= 0) without the
    // back-relaxation extension, are refused by name.
    let mut p = seed();
    p.a_nm_per_c = -1.0;
    assert!(matches!(
        p.validate(),
        Err(ParamError::OutOfRange {
            field: "a_nm_per_c",
            ..
        })
    ));
    let mut p = Params::table_4_2_2006();
    p.b_nm_per_c_s = -0.01;
    let err = p.validate().unwrap_err();
    assert!(matches!(err, ParamError::BackRelaxation { .. }), "{err}");
    assert!(err.to_string().contains("back-relaxation"), "{err}");
    // The seed's own sets are accepted: Table 4-2's creep (z > p) and
    // main.m's pure lag.
    assert_eq!(Params::table_4_2_2006().validate(), Ok(()));
    assert_eq!(seed().validate(), Ok(()));
    assert!(Strip::<f64, 3, 1, 18>::new(&seed(), Fixture::Free, 0.0).is_err());
    assert!(Strip::<f64, 3, 1, 18>::new(&seed(), Fixture::Free, f64::INFINITY).is_err());
}

/// Under a uniform moment the deflected shape is the parabola
/// `w(s) = u s²/(2 EI)`, which Hermite cubics hold exactly between nodes.
#[test]
fn shape_between_nodes_is_the_static_parabola() {
    let p = seed();
    let s = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, 1.0).unwrap();
    let mut x = s.rest();
    // One-second steps: the relaxation settles in the first 1000 s, and
    // the undamped ringing (26.75 Hz) is sampled at a phase that advances
    // 0.75 cycle a step, so the mean of 1000 samples averages it out.
    let mut mean = [0.0; 11];
    for k in 0..2000 {
        s.step(&mut x, &[1.0; 3]);
        if k >= 1000 {
            for (j, m) in mean.iter_mut().enumerate() {
                *m += s.deflection_at_m(&x, p.length_m * j as f64 / 10.0).unwrap() / 1000.0;
            }
        }
    }
    let u = p.dc_moment_per_volt();
    for (j, m) in mean.iter().enumerate() {
        let at = p.length_m * j as f64 / 10.0;
        let expected = u * at * at / (2.0 * p.ei_nm2);
        assert!(
            (m - expected).abs() < 2e-3 * (u * p.length_m * p.length_m / (2.0 * p.ei_nm2)),
            "s = {at}: {m} vs {expected}"
        );
    }
}
