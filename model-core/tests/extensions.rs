//! The optional model terms: each off by default, each doing what its
//! physics says, checked against an exact equivalence or a closed form.

use model_core::{Extensions, Fixture, ParamError, Params, SegmentVariation, Strip};

type S3 = Strip<f64, 3, 1, 18>;

fn strip(ext: &Extensions, fixture: Fixture) -> S3 {
    S3::with_extensions(&Params::main_m_2006(), ext, fixture, 1e-3).unwrap()
}

/// Runs `steps` samples of `v` and returns the tip after each.
fn tips(s: &S3, v: [f64; 3], steps: usize) -> Vec<f64> {
    let mut x = s.rest();
    (0..steps)
        .map(|_| {
            s.step(&mut x, &v);
            s.tip_deflection_m(&x)
        })
        .collect()
}

#[test]
fn no_extension_is_the_baseline_bit_for_bit() {
    let p = Params::main_m_2006();
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let a = S3::new(&p, fixture, 1e-3).unwrap();
        let b = S3::with_extensions(&p, &Extensions::NONE, fixture, 1e-3).unwrap();
        let (mut xa, mut xb) = (a.rest(), b.rest());
        for k in 0..3000 {
            let v = [2.0, 1.0, -2.0].map(|x: f64| x * ((k / 1000) as f64 - 1.0));
            a.step(&mut xa, &v);
            b.step(&mut xb, &v);
            assert_eq!(xa, xb);
            assert_eq!(a.blocking_force_n(&xa), b.blocking_force_n(&xb));
            assert_eq!(a.currents_a(&xa, &v), b.currents_a(&xb, &v));
        }
    }
}

/// Mass-proportional damping `α` decays every mode's ringing as
/// `e^{−α t/2}`: after 1 s at `α = 4/s`, `e^{−2}` of it is left.
#[test]
fn rayleigh_mass_damping_decays_the_ringing_at_alpha_over_two() {
    let alpha = 4.0;
    // main.m's pure lag barely excites the ringing; z = p (a pure gain, the
    // moment follows the 16 ms charge) rings as a step.
    let lag = Params::main_m_2006();
    let p = Params {
        a_nm_per_c: lag.b_nm_per_c_s / lag.p_per_s,
        ..lag
    };
    let ringing = S3::with_extensions(
        &p,
        &Extensions {
            damping_mass_per_s: alpha,
            ..Extensions::NONE
        },
        Fixture::Free,
        1e-3,
    )
    .unwrap();
    // The quasi-static tip under the uniform moment, u L²/(2 EI): the
    // difference from it is the ringing alone.
    let mut x = ringing.rest();
    let ring: Vec<f64> = (0..1200)
        .map(|_| {
            ringing.step(&mut x, &[2.5; 3]);
            let u = ringing.moments_nm(&x)[0];
            ringing.tip_deflection_m(&x) - u * p.length_m * p.length_m / (2.0 * p.ei_nm2)
        })
        .collect();
    let amp = |from: usize| {
        (from..from + 100)
            .map(|k| ring[k].abs())
            .fold(0.0f64, f64::max)
    };
    let ratio = amp(1000) / amp(100);
    let want = (-alpha * 0.9 / 2.0f64).exp();
    assert!(
        (ratio / want - 1.0).abs() < 0.05,
        "decay over 0.9 s: {ratio} against e^(-α t/2) = {want}"
    );
}

/// Added mass lowers every frequency by `√(ρA/(ρA + m_a))`.
#[test]
fn added_mass_lowers_the_frequencies() {
    let p = Params::main_m_2006();
    let m_a = 10.0 * p.mass_per_length_kg_per_m;
    let dry = strip(&Extensions::NONE, Fixture::Free);
    let wet = strip(
        &Extensions {
            added_mass_kg_per_m: m_a,
            ..Extensions::NONE
        },
        Fixture::Free,
    );
    for (f_dry, f_wet) in dry
        .natural_frequencies_hz()
        .zip(wet.natural_frequencies_hz())
    {
        let want = f_dry * (1.0f64 / 11.0).sqrt();
        assert!((f_wet / want - 1.0).abs() < 1e-9, "{f_wet} Hz, want {want}");
    }
}

/// Crosstalk is linear: segment 1 driven alone with `κ` moves the beam as
/// the baseline does with `κ` times the drive on segment 2 as well.
#[test]
fn crosstalk_equals_driving_the_neighbour() {
    let kappa = 0.3;
    let ext = strip(
        &Extensions {
            crosstalk: kappa,
            ..Extensions::NONE
        },
        Fixture::Free,
    );
    let base = strip(&Extensions::NONE, Fixture::Free);
    let a = tips(&ext, [2.0, 0.0, 0.0], 3000);
    let b = tips(&base, [2.0, 2.0 * kappa, 0.0], 3000);
    let peak = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!((x - y).abs() < 1e-12 * peak, "step {k}: {x} vs {y}");
    }
    let mut x = ext.rest();
    ext.step(&mut x, &[2.0, 0.0, 0.0]);
    let u = ext.moments_nm(&x);
    assert!((u[1] - kappa * u[0]).abs() < 1e-15 && u[2] == 0.0, "{u:?}");
}

/// The double layer sees `v (1 + a v²)`: the beam moves as the baseline's
/// under that voltage, and the current carries both cubic terms.
#[test]
fn electrochemical_terms_are_static_input_nonlinearities() {
    let (a, b) = (0.02, 0.05);
    let ext = Extensions {
        charge_cubic_per_v2: a,
        leak_cubic_per_v2: b,
        ..Extensions::NONE
    };
    let nl = strip(&ext, Fixture::Free);
    let base = strip(&Extensions::NONE, Fixture::Free);
    let v = 3.0;
    let v_eff = v * (1.0 + a * v * v);
    let x = tips(&nl, [v; 3], 2000);
    let y = tips(&base, [v_eff; 3], 2000);
    for (p, q) in x.iter().zip(&y) {
        assert!((p - q).abs() < 1e-15, "{p} vs {q}");
    }
    // DC current: leak only, v/R2 (1 + b v²), once the capacitor is full.
    let mut s = nl.rest();
    for _ in 0..2000 {
        nl.step(&mut s, &[v; 3]);
    }
    let p = Params::main_m_2006();
    let want = v / p.r2_ohm * (1.0 + b * v * v);
    let got = nl.currents_a(&s, &[v; 3])[0];
    assert!((got - want).abs() < 1e-9, "{got} A, want {want} A");
}

/// With `z < 0` (`b < 0`) the moment relaxes back past zero under a held
/// voltage; only the back-relaxation extension accepts such a network.
#[test]
fn back_relaxation_needs_the_extension_and_reverses_the_moment() {
    let lead = Params::table_4_2_2006();
    let p = Params {
        b_nm_per_c_s: lead.a_nm_per_c * -0.03,
        ..lead
    };
    assert!(matches!(
        S3::new(&p, Fixture::Free, 1e-3),
        Err(ParamError::BackRelaxation { .. })
    ));
    let ext = Extensions {
        back_relaxation: true,
        ..Extensions::NONE
    };
    let s = S3::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
    let mut x = s.rest();
    let mut first_peak = 0.0f64;
    for k in 0..60_000 {
        s.step(&mut x, &[2.0; 3]);
        if k < 1000 {
            first_peak = first_peak.max(s.moments_nm(&x)[0]);
        }
    }
    let late = s.moments_nm(&x)[0];
    assert!(first_peak > 0.0 && late < 0.0, "{first_peak} then {late}");
    // Without an instant part, b <= 0 is no relaxation at all: refused
    // even so.
    let bad = Params {
        a_nm_per_c: 0.0,
        ..p
    };
    assert!(matches!(
        S3::with_extensions(&bad, &ext, Fixture::Free, 1e-3),
        Err(ParamError::NotPositive {
            field: "a_nm_per_c",
            ..
        })
    ));
}

/// The moment gain scales the whole mechanical response, free and blocked.
#[test]
fn moment_gain_scales_deflection_and_force() {
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let base = strip(&Extensions::NONE, fixture);
        let mut half = base.clone();
        half.set_moment_gain(0.5);
        let (mut xa, mut xb) = (base.rest(), half.rest());
        for _ in 0..3000 {
            base.step(&mut xa, &[2.5; 3]);
            half.step(&mut xb, &[2.5; 3]);
            let (ya, yb) = match fixture {
                Fixture::Free => (base.tip_deflection_m(&xa), half.tip_deflection_m(&xb)),
                Fixture::Blocked => (base.blocking_force_n(&xa), half.blocking_force_n(&xb)),
            };
            assert!((yb - 0.5 * ya).abs() < 1e-15, "{fixture:?}: {yb} vs {ya}");
        }
    }
}

/// A uniform moment bends the strip into a circular arc of curvature
/// `κ = u/EI`: across `(1 − cos κs)/κ`, along `sin(κs)/κ − s`. At 2.5 V
/// that is the model notes' 12.73 mm across and −2.2 mm along.
#[test]
fn large_deflection_follows_the_circular_arc() {
    let ext = Extensions {
        large_deflection: true,
        damping_mass_per_s: 3000.0,
        ..Extensions::NONE
    };
    let s = strip(&ext, Fixture::Free);
    let mut x = s.rest();
    for _ in 0..120_000 {
        s.step(&mut x, &[2.5; 3]);
    }
    let u = s.moments_nm(&x)[0];
    let kappa = u / s.params().ei_nm2;
    for s_m in [0.01, 0.025, 0.05] {
        let (along, across) = s.position_at_m(&x, s_m).unwrap();
        let want_across = (1.0 - (kappa * s_m).cos()) / kappa;
        let want_along = (kappa * s_m).sin() / kappa - s_m;
        assert!(
            (across - want_across).abs() < 1e-4 * want_across,
            "s = {s_m}: across {across} vs {want_across}"
        );
        assert!(
            (along - want_along).abs() < 1e-3 * want_along.abs(),
            "s = {s_m}: along {along} vs {want_along}"
        );
    }
    let (along, across) = s.position_at_m(&x, 0.05).unwrap();
    assert!((across - 12.73e-3).abs() < 0.05e-3, "tip across {across}");
    assert!((along + 2.21e-3).abs() < 0.05e-3, "tip along {along}");
    // Without the extension, nothing moves along the strip.
    let small = strip(&Extensions::NONE, Fixture::Free);
    let (along, across) = small.position_at_m(&x, 0.05).unwrap();
    assert_eq!(along, 0.0);
    assert!((across - small.tip_deflection_m(&x)).abs() < 1e-15);
}

#[test]
fn out_of_range_terms_are_refused_by_name() {
    let p = Params::main_m_2006();
    let cases = [
        (
            Extensions {
                damping_mass_per_s: -1.0,
                ..Extensions::NONE
            },
            "damping_mass_per_s",
        ),
        (
            Extensions {
                added_mass_kg_per_m: f64::NAN,
                ..Extensions::NONE
            },
            "added_mass_kg_per_m",
        ),
        (
            Extensions {
                crosstalk: 1.0,
                ..Extensions::NONE
            },
            "crosstalk",
        ),
        (
            Extensions {
                charge_cubic_per_v2: -0.1,
                ..Extensions::NONE
            },
            "charge_cubic_per_v2",
        ),
    ];
    for (ext, field) in cases {
        let err = S3::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap_err();
        assert!(err.to_string().starts_with(field), "{err}");
    }
}

/// Extensions with only `segment-variation` set.
fn varied(var: SegmentVariation) -> Extensions {
    Extensions {
        segment_variation: var,
        ..Extensions::NONE
    }
}

/// Deviations of zero, given explicitly, are the baseline bit for bit:
/// the same `Φ`, `Γ`, states, currents and force.
#[test]
fn segment_variation_of_zero_is_the_baseline_bit_for_bit() {
    let p = Params::main_m_2006();
    let zero = SegmentVariation {
        r1_deviation: [0.0; 8],
        c_deviation: [0.0; 8],
        k_deviation: [0.0; 8],
    };
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let a = S3::new(&p, fixture, 1e-3).unwrap();
        let b = S3::with_extensions(&p, &varied(zero), fixture, 1e-3).unwrap();
        assert_eq!(a.phi(), b.phi());
        assert_eq!(a.gamma(), b.gamma());
        let (mut xa, mut xb) = (a.rest(), b.rest());
        for k in 0..2000 {
            let v = [2.0, -1.0, 1.5].map(|x: f64| x * ((k / 700) as f64 - 1.0));
            assert_eq!(a.currents_a(&xa, &v), b.currents_a(&xb, &v));
            a.step(&mut xa, &v);
            b.step(&mut xb, &v);
            assert_eq!(xa, xb);
            assert_eq!(a.blocking_force_n(&xa), b.blocking_force_n(&xb));
            assert_eq!(a.moments_nm(&xa), b.moments_nm(&xb));
        }
    }
}

/// A larger `C` on segment 2 slows its charging to `τ1 = R1 C (1 + δ)`
/// and leaves segments 1 and 3 as they were: each current after a step
/// from rest is `V/R2 + V/R1 e^{−t/τ1}` with its own segment's `τ1`.
#[test]
fn segment_two_capacitance_changes_segment_two_current_only() {
    let p = Params::main_m_2006();
    let delta = 0.3;
    let mut var = SegmentVariation::NONE;
    var.c_deviation[1] = delta;
    let base = strip(&Extensions::NONE, Fixture::Free);
    let s = strip(&varied(var), Fixture::Free);
    let v = [2.0; 3];
    let (mut xa, mut xb) = (base.rest(), s.rest());
    let mut differs = 0.0f64;
    for n in 0..200 {
        let t_s = n as f64 * 1e-3;
        let (ia, ib) = (base.currents_a(&xa, &v), s.currents_a(&xb, &v));
        assert_eq!(ib[0], ia[0], "segment 1 at step {n}");
        assert_eq!(ib[2], ia[2], "segment 3 at step {n}");
        for (i, tau1_s) in [(0, p.tau1_s()), (1, p.tau1_s() * (1.0 + delta))] {
            let want = 2.0 / p.r2_ohm + 2.0 / p.r1_ohm * (-t_s / tau1_s).exp();
            assert!(
                (ib[i] - want).abs() < 1e-12,
                "segment {} at {t_s} s: {} A, want {want} A",
                i + 1,
                ib[i]
            );
        }
        differs = differs.max((ib[1] - ia[1]).abs());
        base.step(&mut xa, &v);
        s.step(&mut xb, &v);
    }
    // A third more C: segment 2's current decays visibly slower.
    assert!(differs > 1e-4, "largest difference {differs} A");
}

/// A segment's `R1` sets its current's jump at a step, `V/R2 + V/(R1 (1 + δ))`.
#[test]
fn segment_resistance_sets_that_segments_jump() {
    let p = Params::main_m_2006();
    let mut var = SegmentVariation::NONE;
    var.r1_deviation[2] = -0.2;
    let s = strip(&varied(var), Fixture::Blocked);
    let i = s.currents_a(&s.rest(), &[1.0; 3]);
    let jump = |r1: f64| 1.0 / p.r2_ohm + 1.0 / r1;
    assert_eq!(i[0], jump(p.r1_ohm));
    assert_eq!(i[1], jump(p.r1_ohm));
    assert!((i[2] - jump(0.8 * p.r1_ohm)).abs() < 1e-15, "{i:?}");
}

/// The model is linear in the moments, so the static tip is the sum of each
/// segment's share, `(1 + δK)(1 + δC) u₀ ((L − a)² − (L − b)²)/(2 EI)` for
/// segment `[a, b]` under the DC moment `u₀ = K C z/p V` (the cubic
/// elements are exact for a piecewise-constant moment). Damped so that the
/// ringing dies; sampled at 10 ms (the discretisation is exact at any step).
#[test]
fn moment_gain_and_capacitance_scale_each_segments_share_of_the_static_tip() {
    let p = Params::main_m_2006();
    let mut var = SegmentVariation::NONE;
    var.k_deviation[1] = 0.15;
    var.k_deviation[2] = -0.1;
    var.c_deviation[2] = 0.05;
    var.r1_deviation[1] = 0.12;
    let ext = Extensions {
        damping_mass_per_s: 20.0,
        ..varied(var)
    };
    let s = S3::with_extensions(&p, &ext, Fixture::Free, 1e-2).unwrap();
    let volts = 2.0;
    let mut x = s.rest();
    for _ in 0..30_000 {
        s.step(&mut x, &[volts; 3]);
    }
    let u0 = p.dc_moment_per_volt() * volts;
    let seg_m = p.length_m / 3.0;
    let want: f64 = (0..3)
        .map(|i| {
            let (a, b) = (i as f64 * seg_m, (i + 1) as f64 * seg_m);
            let factor = (1.0 + var.k_deviation[i]) * (1.0 + var.c_deviation[i]);
            factor * u0 * ((p.length_m - a).powi(2) - (p.length_m - b).powi(2)) / (2.0 * p.ei_nm2)
        })
        .sum();
    let tip = s.tip_deflection_m(&x);
    assert!(
        (tip / want - 1.0).abs() < 1e-9,
        "tip {tip} m, want {want} m"
    );
    // And not the baseline's: the variation moved it by about 4 %.
    let uniform: f64 = u0 * p.length_m.powi(2) / (2.0 * p.ei_nm2);
    assert!((tip / uniform - 1.0).abs() > 0.01, "{tip} vs {uniform}");
}

#[test]
fn segment_deviations_are_refused_by_segment_and_rule() {
    let p = Params::main_m_2006();
    let mut reference = SegmentVariation::NONE;
    reference.c_deviation[0] = 0.1;
    let mut past_the_tip = SegmentVariation::NONE;
    past_the_tip.k_deviation[3] = 0.1;
    let mut negative = SegmentVariation::NONE;
    negative.r1_deviation[1] = -1.0;
    let mut nan = SegmentVariation::NONE;
    nan.k_deviation[2] = f64::NAN;
    let cases = [
        (reference, "c_deviation of segment 1", "reference"),
        (past_the_tip, "k_deviation of segment 4", "fewer segments"),
        (negative, "r1_deviation of segment 2", "above -1"),
        (nan, "k_deviation of segment 3", "finite"),
    ];
    for (var, head, rule) in cases {
        let err = S3::with_extensions(&p, &varied(var), Fixture::Free, 1e-3).unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with(head) && text.contains(rule), "{text}");
        assert!(
            matches!(err, ParamError::SegmentDeviation { .. }),
            "{err:?}"
        );
    }
    // The fourth segment is fine on a strip that has one.
    assert!(Strip::<f64, 4, 1, 24>::with_extensions(
        &p,
        &varied(past_the_tip),
        Fixture::Free,
        1e-3
    )
    .is_ok());
}

/// Every mode's own ratio the same is the constant ratio; a fixture's
/// ratios are that fixture's alone; a mode's own ratio damps that mode.
#[test]
fn each_modes_own_ratio_damps_that_mode_in_its_fixture() {
    use model_core::{ModalDamping, DAMPED_MODES};
    let mut own = Extensions::NONE;
    own.modal_damping.free = [0.02; DAMPED_MODES];
    let law = Extensions {
        damping_ratio: 0.02,
        ..Extensions::NONE
    };
    assert_eq!(
        tips(&strip(&own, Fixture::Free), [2.5; 3], 3000),
        tips(&strip(&law, Fixture::Free), [2.5; 3], 3000)
    );
    // The held strip's ratios leave the free strip alone, bit for bit.
    let mut held_only = law;
    held_only.modal_damping.blocked = [0.05; DAMPED_MODES];
    assert_eq!(
        tips(&strip(&held_only, Fixture::Free), [2.5; 3], 3000),
        tips(&strip(&law, Fixture::Free), [2.5; 3], 3000)
    );
    // Only a higher mode damped more: the first mode's slow ringing is the
    // law's, so the tip after its higher modes have died out is nearly
    // the law's; damping the first mode instead changes it.
    let mut second = law;
    second.modal_damping.free[1] = 0.06;
    let mut first = law;
    first.modal_damping.free[0] = 0.06;
    let base = tips(&strip(&law, Fixture::Free), [2.5; 3], 400);
    let off = |e: &Extensions| {
        let t = tips(&strip(e, Fixture::Free), [2.5; 3], 400);
        (t[399] - base[399]).abs() / base[399].abs()
    };
    assert!(
        off(&second) < 0.2 * off(&first),
        "{} {}",
        off(&second),
        off(&first)
    );
    // A ratio outside [0, 1) is refused, by field.
    let mut bad = law;
    bad.modal_damping = ModalDamping {
        blocked: [1.0; DAMPED_MODES],
        ..ModalDamping::NONE
    };
    let err = S3::with_extensions(&Params::main_m_2006(), &bad, Fixture::Free, 1e-3).unwrap_err();
    assert!(
        matches!(
            err,
            ParamError::OutOfRange {
                field: "modal_damping.blocked",
                ..
            }
        ),
        "{err:?}"
    );
}
