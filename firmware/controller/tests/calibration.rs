//! SetCalibration and the stored calibration: refused while driving or
//! with a bad value, used from the next tick (force and each segment's
//! current), handed to the board once to store, and reported in Info with
//! its origin.

mod common;

use common::{config, input, tared};
use finrs_controller::{Calibration, CalibrationOrigin, CommandRefused, ConfigRule, Controller};
use finrs_drive::{Envelope, Program};
use finrs_frames::{Command, Event};

const N: usize = 3;
const IDLE: [u16; N] = [2048; N];

fn calibration(newtons_per_count: f32, zeros: [u16; N]) -> Calibration {
    let mut current_zero_counts = [2048; 8];
    current_zero_counts[..N].copy_from_slice(&zeros);
    Calibration {
        newtons_per_count,
        current_zero_counts,
    }
}

fn wave() -> Command {
    Command::SetWave {
        program: Program::Steps { levels_v: [1.0; 8] },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    }
}

fn infos(events: &[Event]) -> Vec<finrs_frames::Info> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Info(i) => Some(*i),
            _ => None,
        })
        .collect()
}

fn samples(events: &[Event]) -> Vec<finrs_frames::DecodedSample> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Sample(s) => Some(*s),
            _ => None,
        })
        .collect()
}

fn close(got: &[f32], want: &[f32]) {
    assert!(
        got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6),
        "{got:?} against {want:?}"
    );
}

#[test]
fn a_new_calibration_scales_force_and_currents_from_the_next_tick() {
    let (mut c, mut ch, t0) = tared();
    // Before: 1e-3 N/count, zeros at 2048, tare at 1000 counts.
    c.tick(&input(t0, 1100, [2058, 2048, 2038]), &mut ch);
    let before = samples(&ch.take_events())[0];
    assert!((before.force_n - 0.1).abs() < 1e-6);
    close(before.currents(), &[0.010, 0.0, -0.010]);

    let new = calibration(2e-3, [2058, 2040, 2038]);
    c.command(Command::SetCalibration(new)).unwrap();
    assert_eq!(c.calibration(), (new, CalibrationOrigin::Unsaved));
    c.tick(&input(t0 + 1, 1100, [2058, 2048, 2038]), &mut ch);
    let after = samples(&ch.take_events())[0];
    // The tare is in counts: kept; the scale is the new one.
    assert!((after.force_n - 0.2).abs() < 1e-6, "{}", after.force_n);
    // Each segment against its own zero.
    close(after.currents(), &[0.0, 0.008, 0.0]);
}

#[test]
fn the_board_stores_it_once_and_the_info_says_where_it_came_from() {
    let (mut c, mut ch, t0) = tared();
    assert_eq!(c.calibration().1, CalibrationOrigin::Defaults);
    assert_eq!(c.take_calibration_to_store(), None);
    let new = calibration(-3e-5, [2047, 2049, 2050]);
    c.command(Command::SetCalibration(new)).unwrap();
    assert_eq!(c.take_calibration_to_store(), Some(new));
    assert_eq!(c.take_calibration_to_store(), None, "taken once");

    // A failed store: Unsaved, and an Info tells the host so.
    c.calibration_stored(false);
    c.tick(&input(t0, 1000, IDLE), &mut ch);
    let got = infos(&ch.take_events());
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].calibration, new);
    assert_eq!(got[0].calibration_origin, CalibrationOrigin::Unsaved);

    c.calibration_stored(true);
    c.tick(&input(t0 + 1, 1000, IDLE), &mut ch);
    let got = infos(&ch.take_events());
    assert_eq!(got[0].calibration_origin, CalibrationOrigin::Stored);
    let defaults = config().calibration;
    assert_ne!(got[0].calibration, defaults);
}

#[test]
fn refused_while_driving_or_slewing_and_with_a_bad_value() {
    let (mut c, mut ch, t0) = tared();
    let new = calibration(2e-3, [2050; N]);
    c.command(wave()).unwrap();
    // 1 V at 100 V/s: 10 ticks up.
    for k in 0..20 {
        c.tick(&input(t0 + k, 1000, IDLE), &mut ch);
    }
    assert_eq!(
        c.command(Command::SetCalibration(new)),
        Err(CommandRefused::CalibrationWhileDriving)
    );
    // Stop: refused until the outputs have slewed to 0 V (10 ticks down).
    c.command(Command::Stop).unwrap();
    c.tick(&input(t0 + 20, 1000, IDLE), &mut ch);
    assert_eq!(
        c.command(Command::SetCalibration(new)),
        Err(CommandRefused::CalibrationWhileDriving)
    );
    for k in 21..40 {
        c.tick(&input(t0 + k, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [0.0; N]);
    let before = c.calibration();
    for (bad, field, rule) in [
        (
            calibration(f32::NAN, [2048; N]),
            "calibration.newtons_per_count",
            ConfigRule::Finite,
        ),
        (
            calibration(0.0, [2048; N]),
            "calibration.newtons_per_count",
            ConfigRule::NonZero,
        ),
        (
            calibration(1e-3, [2048, 4096, 2048]),
            "calibration.current_zero_counts",
            ConfigRule::AboveFullScale,
        ),
    ] {
        let Err(CommandRefused::Calibration(e)) = c.command(Command::SetCalibration(bad)) else {
            panic!("{bad:?} accepted");
        };
        assert_eq!((e.field, e.rule), (field, rule));
        assert!(e.to_string().contains(field));
    }
    assert_eq!(c.calibration(), before, "a refusal changes nothing");
    assert_eq!(c.take_calibration_to_store(), None);
    c.command(Command::SetCalibration(new)).unwrap();
}

#[test]
fn a_wave_waiting_for_the_power_up_tare_counts_as_driving() {
    let mut c = Controller::<N>::new(config()).unwrap();
    c.command(wave()).unwrap();
    assert_eq!(
        c.command(Command::SetCalibration(calibration(2e-3, [2048; N]))),
        Err(CommandRefused::CalibrationWhileDriving)
    );
    // Without a wave, the power-up tare is no drive.
    let mut c = Controller::<N>::new(config()).unwrap();
    c.command(Command::SetCalibration(calibration(2e-3, [2048; N])))
        .unwrap();
}

#[test]
fn a_stored_calibration_is_checked_before_use() {
    let mut c = Controller::<N>::new(config()).unwrap();
    let bad = calibration(f32::INFINITY, [2048; N]);
    let e = c.use_stored_calibration(bad).unwrap_err();
    assert_eq!(e.field, "calibration.newtons_per_count");
    assert_eq!(
        c.calibration(),
        (config().calibration, CalibrationOrigin::Defaults)
    );
    let good = calibration(4e-5, [2000, 2100, 2048]);
    c.use_stored_calibration(good).unwrap();
    assert_eq!(c.calibration(), (good, CalibrationOrigin::Stored));
    assert_eq!(
        c.take_calibration_to_store(),
        None,
        "nothing to store again"
    );
}

#[test]
fn a_wave_right_after_a_calibration_defers_its_store_to_the_next_stop() {
    let (mut c, mut ch, t0) = tared();
    let new = calibration(2e-3, [2050; N]);
    c.command(Command::SetCalibration(new)).unwrap();
    c.command(wave()).unwrap();
    let mut t = t0;
    for _ in 0..20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
        t += 1;
        assert_eq!(c.take_calibration_to_store(), None, "driving");
    }
    assert_eq!(c.calibration(), (new, CalibrationOrigin::Unsaved), "in use");
    c.command(Command::Stop).unwrap();
    let mut stored = None;
    for _ in 0..20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
        t += 1;
        stored = stored.or(c.take_calibration_to_store());
        if stored.is_some() {
            assert_eq!(c.outputs_v(), [0.0; N], "stored only at 0 V");
        }
    }
    assert_eq!(stored, Some(new));
}
