//! `finrs calibrate` against a fake board that runs the firmware's own
//! controller on simulated sensors with known true zeros and scale.

use std::cell::Cell;
use std::rc::Rc;

use finrs_controller::{Config, Controller, FrameSink, Identity, TickInput};
use finrs_drive::Limits;
use finrs_frames::{
    Calibration, CalibrationOrigin, Command, CommandDecoder, CommandEvent, ResetCause,
};

use super::*;
use crate::link::capture::Link;

const N: usize = 3;
const NOMINAL_SCALE: f32 = 2.5e-5;
const TRUE_SCALE: f64 = 3.1e-5;
const TRUE_ZEROS: [u16; N] = [2056, 2041, 2048];
const AMPS_PER_COUNT: f32 = 2.5e-4;

struct Bytes(Vec<u8>);

impl FrameSink for Bytes {
    fn try_write(&mut self, frame: &[u8]) -> bool {
        self.0.extend_from_slice(frame);
        true
    }
}

/// The firmware's controller on simulated sensors: a load (N, set by the
/// test), the shunts at their true zeros plus a decaying discharge, and
/// ±`noise` counts of noise; 50 ticks per read.
struct FakeBoard {
    c: Controller<N>,
    tick: u64,
    decoder: CommandDecoder,
    load_n: Rc<Cell<f64>>,
    noise: u32,
    rng: u32,
    /// Counts added to every shunt at tick 0, decaying with `tau_ticks`.
    discharge_counts: f64,
    tau_ticks: f64,
    stores: usize,
}

impl FakeBoard {
    fn new(load_n: Rc<Cell<f64>>) -> Self {
        let config = Config {
            sample_hz: 1000,
            limits: Limits::new(3.64, 200.0).unwrap(),
            calibration: Calibration {
                newtons_per_count: NOMINAL_SCALE,
                current_zero_counts: [2048; 8],
            },
            adc_full_scale: 4095,
            saturation_margin_counts: 8,
            amps_per_count: AMPS_PER_COUNT,
            overcurrent_a: 0.4,
            tare_samples: 200,
        };
        let mut c = Controller::new(config).unwrap();
        c.set_identity(Identity {
            version: [0, 1, 0],
            git_hash: 0,
            dac_segments: [None, None],
            bridge_supply_v: 5.0,
            reset_cause: ResetCause::PowerOn,
        });
        Self {
            c,
            tick: 0,
            decoder: CommandDecoder::new(),
            load_n,
            noise: 3,
            rng: 0x1234_5678,
            discharge_counts: 0.0,
            tau_ticks: 1.0,
            stores: 0,
        }
    }

    fn noise(&mut self) -> f64 {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        f64::from(x % (2 * self.noise + 1)) - f64::from(self.noise)
    }
}

impl Link for FakeBoard {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        let mut out = Bytes(Vec::new());
        for _ in 0..50 {
            let load_counts = 2000.0 + self.load_n.get() / TRUE_SCALE + self.noise();
            let discharge = self.discharge_counts * (-(self.tick as f64) / self.tau_ticks).exp();
            let current_counts = std::array::from_fn(|k| {
                (f64::from(TRUE_ZEROS[k]) + discharge + self.noise()) as u16
            });
            self.c.tick(
                &TickInput {
                    tick: self.tick,
                    t_us: (self.tick * 1000) as u32,
                    load_cell_counts: load_counts.round() as u16,
                    current_counts,
                },
                &mut out,
            );
            if self.c.take_calibration_to_store().is_some() {
                self.stores += 1;
                self.c.calibration_stored(true);
            }
            self.tick += 1;
        }
        assert!(out.0.len() <= buf.len());
        buf[..out.0.len()].copy_from_slice(&out.0);
        Ok(out.0.len())
    }

    fn read_log(&mut self, _: &mut [u8]) -> Result<usize, ProbeError> {
        Ok(0)
    }
}

impl Board for FakeBoard {
    fn send(&mut self, command: &Command) -> Result<(), ProbeError> {
        let bytes = crate::link::command::encode(command);
        let c = &mut self.c;
        self.decoder.push(&bytes, &mut |e| {
            if let CommandEvent::Command(cmd) = e {
                // A refusal changes nothing, as on the board.
                let _ = c.command(cmd);
            }
        });
        Ok(())
    }
}

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
    let l = load.clone();
    let s = measure_load_cell(&mut b, &opts(), reference_n, &mut |text: &str| {
        prompts.push(text.to_string());
        if text.contains("put the reference load") {
            l.set(reference_n);
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
