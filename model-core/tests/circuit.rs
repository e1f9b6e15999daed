//! The circuit alone is the strip's electrics: the same currents, bit for
//! bit, with every electrical term on, in both fixtures; and it refuses
//! what the strip refuses.

use model_core::{Circuit, Extensions, Fixture, Params, SegmentVariation, Strip};

/// Every term that reaches the circuit on, and some that do not (the
/// beam's), which the circuit must ignore.
fn every_term() -> Extensions {
    let mut var = SegmentVariation::NONE;
    var.r1_deviation[1] = 0.12;
    var.c_deviation[2] = -0.08;
    var.k_deviation[1] = 0.3;
    Extensions {
        charge_cubic_per_v2: 0.01,
        leak_cubic_per_v2: -0.004,
        reaction_ratio: 0.8,
        reaction_ref_v: 2.0,
        reaction_tafel_v: 0.08,
        damping_mass_per_s: 2.0,
        crosstalk: 0.1,
        segment_variation: var,
        ..Extensions::NONE
    }
}

#[test]
fn the_circuits_currents_are_the_strips_bit_for_bit() {
    let p = Params::table_4_2_2006();
    let ext = every_term();
    let circuit = Circuit::<f64, 3>::new(&p, &ext, 1e-3).unwrap();
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let strip = Strip::<f64, 3, 2, 30>::with_extensions(&p, &ext, fixture, 1e-3).unwrap();
        let (mut xs, mut xc) = (strip.rest(), circuit.rest());
        for k in 0..4000 {
            // Steps of both signs, different on every segment.
            let v = [3.0, -1.5, 2.0].map(|a: f64| a * ((k / 700) % 3) as f64 - a);
            assert_eq!(
                strip.currents_a(&xs, &v),
                circuit.currents_a(&xc, &v),
                "row {k}"
            );
            strip.step(&mut xs, &v);
            circuit.step(&mut xc, &v);
        }
        // The relaxation states too: the strip's electrical tail.
        let tail: Vec<f64> = xc.iter().flatten().copied().collect();
        assert_eq!(&xs[xs.len() - 6..], &tail[..]);
    }
}

#[test]
fn the_circuit_refuses_what_the_strip_refuses() {
    let mut p = Params::main_m_2006();
    p.c_f = -1.0;
    assert!(Circuit::<f64, 3>::new(&p, &Extensions::NONE, 1e-3).is_err());
    let p = Params::main_m_2006();
    assert!(Circuit::<f64, 3>::new(&p, &Extensions::NONE, 0.0).is_err());
    // A deviation on a segment the strip does not have.
    let mut ext = Extensions::NONE;
    ext.segment_variation.r1_deviation[4] = 0.1;
    assert!(Circuit::<f64, 3>::new(&p, &ext, 1e-3).is_err());
}

#[test]
fn a_reaction_holds_the_layer_and_the_moment_down_at_a_high_drive_only() {
    // Held at 3 V and at 1 V until settled: the reaction, 2 V/R2 at 2 V on
    // the layer and e-fold every 60 mV, draws a steady current through R1
    // that a linear strip does not, and the moment (the layer's charge)
    // falls with the layer's voltage; at 1 V it is all but absent.
    let p = Params::table_4_2_2006();
    let ext = Extensions {
        reaction_ratio: 1.0,
        reaction_ref_v: 2.0,
        reaction_tafel_v: 0.06,
        ..Extensions::NONE
    };
    let settled = |ext: &Extensions, v: f64| {
        let strip =
            Strip::<f64, 3, 2, 30>::with_extensions(&p, ext, Fixture::Blocked, 1e-3).unwrap();
        let mut x = strip.rest();
        for _ in 0..20_000 {
            strip.step(&mut x, &[v; 3]);
        }
        (strip.currents_a(&x, &[v; 3])[0], strip.moments_nm(&x)[0])
    };
    let (i_lin, m_lin) = settled(&Extensions::NONE, 3.0);
    let (i, m) = settled(&ext, 3.0);
    assert!(i > 1.5 * i_lin, "{i} {i_lin}");
    assert!(m < 0.95 * m_lin && m > 0.0, "{m} {m_lin}");
    let (i_lin, m_lin) = settled(&Extensions::NONE, 1.0);
    let (i, m) = settled(&ext, 1.0);
    assert!(
        (i / i_lin - 1.0).abs() < 1e-3 && (m / m_lin - 1.0).abs() < 1e-3,
        "{i} {m}"
    );
}
