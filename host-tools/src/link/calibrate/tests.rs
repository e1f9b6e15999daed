//! `finrs calibrate` against a fake board that runs the firmware's own
//! controller on simulated sensors with known true zeros and scale.

use std::cell::Cell;
use std::rc::Rc;

use finrs_frames::CalibrationOrigin;

use super::*;
use crate::link::capture::Link;
use crate::link::fake_board::{
    FakeBoard, AMPS_PER_COUNT, N, NOMINAL_SCALE, TRUE_SCALE, TRUE_ZEROS,
};

fn opts() -> CalibrateOptions {
    CalibrateOptions {
        timeout: Duration::from_secs(20),
        ..CalibrateOptions::default()
    }
}

#[test]
fn shunt_zeros_are_measured_within_a_count_and_stored() {
    let mut b = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let z = measure_shunt_zeros(&mut b, &opts()).unwrap();
    assert_eq!(z.before.calibration_origin, CalibrationOrigin::Defaults);
    for (k, &truth) in TRUE_ZEROS.iter().enumerate() {
        let got = i32::from(z.calibration.current_zero_counts[k]);
        assert!(
            (got - i32::from(truth)).abs() <= 1,
            "segment {k}: {got} against {truth}"
        );
        // The offset under the old zero (2048), in A, and a small error.
        let want_a = (f64::from(truth) - 2048.0) * f64::from(AMPS_PER_COUNT);
        assert!((z.offsets[k].0 - want_a).abs() < 1.5 * f64::from(AMPS_PER_COUNT));
        assert!(z.offsets[k].1 < 0.5, "se {} counts", z.offsets[k].1);
    }
    assert_eq!(
        z.calibration.newtons_per_count, NOMINAL_SCALE,
        "the scale is kept"
    );
    let info = apply(&mut b, &opts(), &z.calibration).unwrap();
    assert_eq!(info.calibration, z.calibration);
    assert_eq!(info.calibration_origin, CalibrationOrigin::Stored);
    assert_eq!(b.stores, 1);
    // The board now reads ~0 A at rest.
    let again = measure_shunt_zeros(&mut b, &opts()).unwrap();
    for (a, _) in &again.offsets {
        assert!(a.abs() < 1.5 * f64::from(AMPS_PER_COUNT), "{a} A");
    }
}

#[test]
fn a_discharging_strip_is_refused_not_averaged() {
    let mut b = FakeBoard::new(Rc::new(Cell::new(0.0)));
    // 400 counts decaying over 2 s: still tens of counts in the window.
    b.discharge_counts = 400.0;
    b.tau_ticks = 2000.0;
    let e = measure_shunt_zeros(&mut b, &opts()).unwrap_err();
    assert!(
        matches!(&e, CalibrateError::Drifting { what, .. } if what.contains("segment 1")),
        "{e}"
    );
    assert!(
        e.to_string().contains("wait, or disconnect the strip"),
        "{e}"
    );
}

#[test]
fn the_load_cell_scale_comes_out_of_a_reference_load() {
    let load = Rc::new(Cell::new(0.0));
    let mut b = FakeBoard::new(load.clone());
    // 2 g at standard gravity.
    let reference_n = 0.002 * STANDARD_GRAVITY_M_PER_S2;
    let mut prompts = Vec::new();
    // The operator takes 3 s to hang the mass: the board samples the
    // unloaded cell meanwhile and buffers what its channel holds.
    let pause = b.pause.clone();
    let s = measure_load_cell(&mut b, &opts(), reference_n, &mut |text: &str| {
        prompts.push(text.to_string());
        if text.contains("put the reference load") {
            pause.set((3000, Some(reference_n)));
        }
        Ok(())
    })
    .unwrap();
    assert_eq!(prompts.len(), 2);
    let got = f64::from(s.calibration.newtons_per_count);
    assert!(
        (got / TRUE_SCALE - 1.0).abs() < 0.005,
        "{got:e} against {TRUE_SCALE:e}"
    );
    assert_eq!(s.calibration.current_zero_counts, [2048; 8], "zeros kept");
    let info = apply(&mut b, &opts(), &s.calibration).unwrap();
    assert_eq!(
        info.calibration.newtons_per_count,
        s.calibration.newtons_per_count
    );
    // The same load now reads as itself.
    let mut l = Listener::new();
    let f = force_mean(&l.collect(&mut b, &opts(), 500, |_| true).unwrap());
    assert!((f.mean / reference_n - 1.0).abs() < 0.01, "{} N", f.mean);
}

#[test]
fn no_load_or_a_bad_reference_is_refused() {
    let mut b = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let e = measure_load_cell(&mut b, &opts(), 0.02, &mut |_: &str| Ok(())).unwrap_err();
    assert!(matches!(e, CalibrateError::NoLoad { .. }), "{e}");
    for bad in [0.0, f64::NAN] {
        let e = measure_load_cell(&mut b, &opts(), bad, &mut |_: &str| Ok(())).unwrap_err();
        assert!(e.to_string().starts_with("reference load: "), "{e}");
    }
}

#[test]
fn a_calibration_refused_while_driving_is_not_confirmed() {
    let mut b = FakeBoard::new(Rc::new(Cell::new(0.0)));
    // Past the power-up tare, then a wave.
    let mut buf = vec![0u8; 16 * 1024];
    for _ in 0..6 {
        b.read_force(&mut buf).unwrap();
    }
    b.send(
        &crate::link::command::wave_command("step:1", N, &crate::wave::WaveOptions::steady(10.0))
            .unwrap(),
    )
    .unwrap();
    let quick = CalibrateOptions {
        timeout: Duration::from_millis(300),
        ..opts()
    };
    let mut c = b.c.calibration().0;
    c.newtons_per_count = 3e-5;
    let e = apply(&mut b, &quick, &c).unwrap_err();
    assert!(matches!(e, CalibrateError::NotConfirmed { .. }), "{e}");
    assert_eq!(b.stores, 0);
}

#[test]
fn block_means_see_a_drift_and_not_white_noise() {
    let flat: Vec<f64> = (0..1000)
        .map(|i| f64::from((i * 7919) % 11) - 5.0)
        .collect();
    let m = block_mean(&flat);
    assert!(m.mean.abs() < 0.1 && m.drift.abs() < DRIFT_SIGMAS * m.drift_se);
    let ramp: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
    let m = block_mean(&ramp);
    assert!(m.drift > DRIFT_SIGMAS * m.drift_se, "{m:?}");
}

/// `finrs tune`: the board confirms the model by its CRC and is handed it
/// to store; a motion then drives the outputs; while they are driven,
/// another model is refused and the wait says so.
#[test]
fn a_model_is_confirmed_by_its_crc_and_then_shapes_motions() {
    use crate::model::motion::record;
    use crate::model::params::ModelFile;
    use crate::recording::Geometry;

    let mut b = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let spec = ModelFile::main_m_2006()
        .spec_for(&Geometry::THESIS_2006)
        .unwrap();
    let r = record(&spec);
    let info = apply_model(&mut b, &opts(), &r).unwrap();
    assert_eq!(info.model_crc, Some(r.crc()));
    assert_eq!(b.stored_model, Some(r));
    let options = crate::wave::WaveOptions {
        ramp_in_s: 0.1,
        ..crate::wave::WaveOptions::steady(10.0)
    };
    let motion = crate::link::command::wave_command("motion:0.0001,1,60", N, &options).unwrap();
    b.send(&motion).unwrap();
    // Past the power-up tare (200 ticks), 50 ticks a read.
    let mut buf = [0u8; 4096];
    for _ in 0..5 {
        b.read_force(&mut buf).unwrap();
    }
    assert!(b.c.running(), "the motion drives the outputs");
    let mut other = spec;
    other.params.r1_ohm *= 1.1;
    let short = CalibrateOptions {
        timeout: Duration::from_millis(300),
        ..opts()
    };
    assert!(matches!(
        apply_model(&mut b, &short, &record(&other)),
        Err(CalibrateError::NotTuned { .. })
    ));
}
