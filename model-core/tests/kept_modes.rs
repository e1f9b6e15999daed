//! A strip built on kept modes ([`BeamModes`]) is the strip built afresh,
//! bit for bit, under any electrics, relaxation, damping, crosstalk or
//! sample time; and reading many points through one [`Strip::shape`] gives
//! each point's own reading.

use model_core::{BeamModes, Extensions, Fixture, Params, SegmentVariation, Strip};

type S = Strip<f64, 3, 2, 30>;

/// Steps both strips under the same varying drive and asserts every state
/// and output equal.
fn same(a: &S, b: &S) {
    let (mut xa, mut xb) = (a.rest(), b.rest());
    for k in 0..2000 {
        let v = [2.5, -1.0, 3.0].map(|x: f64| x * (k as f64 * 0.004).sin());
        a.step(&mut xa, &v);
        b.step(&mut xb, &v);
        assert_eq!(xa, xb, "step {k}");
        assert_eq!(a.blocking_force_n(&xa), b.blocking_force_n(&xb));
        assert_eq!(a.currents_a(&xa, &v), b.currents_a(&xb, &v));
    }
}

#[test]
fn kept_modes_build_the_fresh_strip_under_other_terms() {
    let p = Params::main_m_2006();
    let other = Params {
        r1_ohm: 1.7 * p.r1_ohm,
        c_f: 0.6 * p.c_f,
        p_per_s: 2.0 * p.p_per_s,
        ..p
    };
    let ext = Extensions {
        damping_ratio: 0.02,
        damping_stiffness_s: 1e-4,
        crosstalk: 0.03,
        large_deflection: true,
        segment_variation: SegmentVariation {
            r1_deviation: [0.0, 0.1, -0.05, 0.0, 0.0, 0.0, 0.0, 0.0],
            ..SegmentVariation::NONE
        },
        ..Extensions::NONE
    };
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let modes = BeamModes::new(&p, &Extensions::NONE, fixture).unwrap();
        assert_eq!(modes.fixture(), fixture);
        for (params, ext, dt_s) in [(p, Extensions::NONE, 1e-3), (other, ext, 2e-4)] {
            assert!(modes.is_for(&params, &ext));
            let kept = S::with_modes(&modes, &params, &ext, dt_s).unwrap();
            let fresh = S::with_extensions(&params, &ext, fixture, dt_s).unwrap();
            same(&kept, &fresh);
        }
    }
}

#[test]
fn modes_of_another_beam_are_solved_anew() {
    let p = Params::main_m_2006();
    let modes = BeamModes::new(&p, &Extensions::NONE, Fixture::Free).unwrap();
    let soft = Params {
        ei_nm2: 0.5 * p.ei_nm2,
        ..p
    };
    let wet = Extensions {
        added_mass_kg_per_m: 0.02,
        ..Extensions::NONE
    };
    for (params, ext) in [(soft, Extensions::NONE), (p, wet)] {
        assert!(!modes.is_for(&params, &ext));
        let kept = S::with_modes(&modes, &params, &ext, 1e-3).unwrap();
        let fresh = S::with_extensions(&params, &ext, Fixture::Free, 1e-3).unwrap();
        same(&kept, &fresh);
        // Not the kept beam's strip: the tip settles elsewhere.
        let mine = S::with_modes(&modes, &p, &Extensions::NONE, 1e-3).unwrap();
        let (mut xa, mut xb) = (kept.rest(), mine.rest());
        for _ in 0..200 {
            kept.step(&mut xa, &[2.5; 3]);
            mine.step(&mut xb, &[2.5; 3]);
        }
        assert_ne!(kept.tip_deflection_m(&xa), mine.tip_deflection_m(&xb));
    }
}

#[test]
fn a_shape_reads_each_point_as_alone() {
    for large_deflection in [false, true] {
        let ext = Extensions {
            large_deflection,
            ..Extensions::NONE
        };
        let s = S::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3).unwrap();
        let mut x = s.rest();
        for k in 0..1500 {
            s.step(
                &mut x,
                &[2.5, -1.0, 3.0].map(|v: f64| v * (k as f64 * 0.01).cos()),
            );
            if k % 100 != 0 {
                continue;
            }
            let shape = s.shape(&x);
            // Nodes (every 1/6 of L), between them, both ends, outside.
            for i in 0..=60 {
                let s_m = 0.05 * i as f64 / 60.0;
                let alone = s.position_at_m(&x, s_m).unwrap();
                assert_eq!(shape.position_at_m(s_m), Some(alone));
                assert_eq!(shape.deflection_at_m(s_m), s.deflection_at_m(&x, s_m));
                if !large_deflection {
                    assert_eq!(alone, (0.0, s.deflection_at_m(&x, s_m).unwrap()));
                }
            }
            for outside in [-1e-3, 0.0501, f64::NAN] {
                assert_eq!(shape.position_at_m(outside), None);
            }
        }
    }
}
