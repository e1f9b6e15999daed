//! The gain tracker in the controller's loop: a motion shaped by a model
//! drives a strip that dries while it runs (every admittance down alike:
//! the drift the tracker undoes exactly); tracked, the tip moves as asked,
//! untracked it misses by the drying. And on a strip whose `R1` and `C`
//! are off the model's in another proportion (which one sine cannot tell
//! from a scale) the tracker corrects part of the error only.

mod common;

use common::{config, error_against, input, set_motion, tared_with_model, Channel, LastTenSeconds};
use finrs_controller::shaper::{command, Shaped};
use finrs_controller::tracker::MAX_CORRECTION;
use finrs_controller::{Config, Controller};
use finrs_drive::Limits;
use finrs_frames::{Command, Event, Motion, StripModel, TrackingFlags};
use model_core::{state_len, Extensions, Fixture, Params, Phasor, Strip};
use rtic_core::Exclusive;

const N: usize = 3;
const HZ: u32 = 1000;
const TIP_M: f64 = 1e-4;

/// The seed's `main.m` strip, damped.
fn model() -> StripModel {
    StripModel {
        params: Params::main_m_2006(),
        extensions: Extensions {
            damping_ratio: 0.05,
            ..Extensions::NONE
        },
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    }
}

/// Shunts fine enough that their rounding is noise, not a bias; a 4 V
/// limit.
fn fine_config() -> Config {
    Config {
        amps_per_count: 2e-5,
        overcurrent_a: 0.04,
        limits: Limits::new(4.0, 100.0).unwrap(),
        ..config()
    }
}

/// `motion:TIP_M,1,60` (or `motion-ff:` if not `tracked`), steady, from
/// `t_session_s`.
fn motion_command(tip_m: f32, t_session_s: f32, tracked: bool) -> Command {
    let motion = Motion::Travelling {
        tip_amp_m: tip_m,
        frequency_hz: 1.0,
        lag_deg_per_segment: 60.0,
    };
    set_motion(motion, 0.0, t_session_s, tracked)
}

/// What a run measured: the tip's phasor over the last 10 s (asked: `TIP_M`
/// at phase 0) and the Tracking frames sent.
struct Run {
    tip: Phasor,
    tracking: Vec<finrs_frames::Tracking>,
}

/// 60 s of `motion:TIP_M,1,60` (tracked or not) from `model()` on a free
/// strip whose `R1` and `C` are the model's times `r1` and `c`, drying as
/// it runs if `drying`: every admittance down by 0.3 % a second (applied
/// as the voltage it sees, which scales `1/R1`, `1/R2` and `C` alike).
fn run(tracked: bool, (r1, c_factor): (f64, f64), drying: bool) -> Run {
    let (mut c, mut ch, tick, mut shaper) = tared_with_model(fine_config(), &model());
    let motion = motion_command(TIP_M as f32, f32::NAN, tracked);
    assert_eq!(
        command(motion, &mut shaper, 1e-3, &mut Exclusive(&mut c)),
        Ok(Shaped::WaveSet)
    );
    assert_eq!(c.tracking(), tracked);
    let m = model();
    let params = Params {
        r1_ohm: m.params.r1_ohm * r1,
        c_f: m.params.c_f * c_factor,
        ..m.params
    };
    let plant = Strip::<f64, N, 4, { state_len(N, 4) }>::with_extensions(
        &params,
        &m.extensions,
        Fixture::Free,
        1.0 / f64::from(HZ),
    )
    .unwrap();
    let mut x = plant.rest();
    let mut currents = [0.0f64; N];
    let steps = 60 * u64::from(HZ);
    let mut tip = LastTenSeconds::new(steps);
    let amps_per_count = f64::from(fine_config().amps_per_count);
    for k in 0..steps {
        let counts = currents.map(|i| (2048.0 + i / amps_per_count).round() as u16);
        let out = c.tick(&input(tick + k, 1000, counts), &mut ch);
        // The program's time 0 is this run's first tick.
        let dry = if drying {
            1.0 - 0.003 * k as f64 / f64::from(HZ)
        } else {
            1.0
        };
        let v = out.voltages_v.map(|v| dry * f64::from(v));
        plant.step(&mut x, &v);
        currents = plant.currents_a(&x, &v);
        // The tip after step k holds the sample at k + 1.
        tip.add(k + 1, plant.tip_deflection_m(&x));
    }
    let tracking = ch
        .take_events()
        .into_iter()
        .filter_map(|e| match e {
            Event::Tracking(t) => Some(t),
            _ => None,
        })
        .collect();
    Run {
        tip: tip.phasor(),
        tracking,
    }
}

/// The tip's amplitude error (fraction) and phase error, degrees.
fn err(r: &Run) -> (f64, f64) {
    error_against(r.tip, TIP_M)
}

#[test]
fn a_tracked_motion_holds_its_tip_on_a_drying_strip() {
    let tracked = run(true, (1.0, 1.0), true);
    let plain = run(false, (1.0, 1.0), true);
    let (a, p) = err(&tracked);
    let (a0, p0) = err(&plain);
    eprintln!(
        "drying, last 10 of 60 s: tracked {:+.2} % {p:+.2}°, untracked {:+.2} % {p0:+.2}°",
        100.0 * a,
        100.0 * a0
    );
    // The fit's memory lags the drying: about (4 + ½) periods of 0.3 %/s.
    assert!(a.abs() < 0.02 && p.abs() < 0.5, "tracked: {a} {p}°");
    // The drying's 0.835 over the last 10 s.
    assert!(a0 < -0.12, "untracked should miss: {a0} {p0}°");
    // One Tracking frame a period after the first (59 of 60 s), none
    // bounded or held at the limit; its gains undo the drying: at 60 s
    // the strip draws 0.82 of what it drew at the start (the last
    // estimate, a few periods' memory, a little less).
    assert!(plain.tracking.is_empty());
    assert!(
        (58..=60).contains(&tracked.tracking.len()),
        "{} frames",
        tracked.tracking.len()
    );
    let last = tracked.tracking.last().unwrap();
    assert_eq!(last.n, N);
    assert!(!last.flags.has(TrackingFlags::BOUNDED) && !last.flags.has(TrackingFlags::AT_LIMIT));
    for &g in &last.gains[..N] {
        assert!(
            (g * 0.82 - 1.0).abs() < 0.02 && g < MAX_CORRECTION,
            "{:?}",
            last.gains
        );
    }
}

/// `R1` 25 % up and `C` 15 % down, no drying: at 1 Hz most of this
/// strip's current is the leak through `R2`, which one sine cannot tell
/// from the double layer's, so holding the current holds the charge only
/// in part. Measured: −13.0 % tracked against −15.0 % untracked (see
/// docs/model.md); asserted: smaller, and of the same sign.
#[test]
fn off_the_scale_family_the_tracker_corrects_in_part() {
    let (a, p) = err(&run(true, (1.25, 0.85), false));
    let (a0, p0) = err(&run(false, (1.25, 0.85), false));
    eprintln!(
        "R1 +25 %, C -15 %: tracked {:+.2} % {p:+.2}°, untracked {:+.2} % {p0:+.2}°",
        100.0 * a,
        100.0 * a0
    );
    assert!(a0 < -0.1 && a < 0.0 && a > a0, "{a} against {a0}");
}

/// Unit test of the estimator alone: a known admittance ratio with a phase
/// is found within a period, whatever the reference phase of the lock-in.
#[test]
fn the_tracker_finds_a_complex_admittance_ratio() {
    use finrs_controller::tracker::{Shape, Sine, Target, Tracker};
    // The model: 20 mA/V in phase; the strip: 10 mA/V leading by 30°.
    let target = Target::<2> {
        shape: Shape::Sine(Sine {
            frequency_hz: 2.5,
            amplitudes_v: [1.0, 0.5],
            phases_deg: [0.0, -90.0],
            admittance_a_per_v: [[0.02, 0.0], [0.02, 0.0]],
            force_n_per_v: None,
        }),
        tracked: true,
        drying: None,
    };
    let mut t = Tracker::new(target, 1000);
    let lead = 30f32.to_radians();
    let mut last = None;
    for k in 0..2000 {
        let w = 2.0 * core::f32::consts::PI * 2.5 * k as f32 / 1000.0 + 0.7;
        let v = [w.sin(), 0.5 * (w - core::f32::consts::FRAC_PI_2).sin()];
        let i = [
            0.01 * (w + lead).sin(),
            0.005 * (w - core::f32::consts::FRAC_PI_2 + lead).sin(),
        ];
        if let Some(c) = t.feed(&v, &i, 0.0) {
            last = Some(c);
        }
    }
    let c = last.unwrap();
    for k in 0..2 {
        assert!((c.gains[k] - 2.0).abs() < 2e-3, "{c:?}");
        assert!((c.phases_deg[k] + 30.0).abs() < 0.1, "{c:?}");
    }
    // The corrected program: twice the amplitude, 30° later; at a 1.5 V
    // limit the first segment is held there and flagged.
    let (p, flags) = t.program(&c, 1.5);
    let finrs_drive::Program::Harmonic {
        amplitudes_v,
        phases_deg,
        ..
    } = p
    else {
        panic!("{p:?}")
    };
    assert_eq!(amplitudes_v[0], 1.5);
    assert!((amplitudes_v[1] - 1.0).abs() < 2e-3);
    assert!((phases_deg[1] + 120.0).abs() < 0.1, "{phases_deg:?}");
    assert!(TrackingFlags(flags).has(TrackingFlags::AT_LIMIT));
}

/// A controller past its tare with `model()` held and a tracked motion of
/// `tip_m` set under a limit of `limit_v`; its channel and next tick.
fn tracking_controller(tip_m: f32, limit_v: f32) -> (Controller<N>, Channel, u64) {
    let config = Config {
        limits: Limits::new(limit_v, 100.0).unwrap(),
        ..fine_config()
    };
    let (mut c, ch, tick, mut shaper) = tared_with_model(config, &model());
    let motion = motion_command(tip_m, f32::NAN, true);
    command(motion, &mut shaper, 1e-3, &mut Exclusive(&mut c)).unwrap();
    assert!(c.tracking());
    (c, ch, tick)
}

/// Stop, a plain wave and a fault each end the tracking; nothing is
/// tracked afterwards.
#[test]
fn stop_a_plain_wave_or_a_fault_ends_the_tracking() {
    let (mut c, _, _) = tracking_controller(1e-4, 4.0);
    c.command(Command::Stop).unwrap();
    assert!(!c.tracking());

    let (mut c, _, _) = tracking_controller(1e-4, 4.0);
    let (program, envelope) = finrs_drive::default_program();
    c.command(Command::SetWave { program, envelope }).unwrap();
    assert!(!c.tracking());

    let (mut c, mut ch, _) = tracking_controller(1e-4, 4.0);
    c.fault(finrs_frames::FaultCode::MissedDeadline, None, &mut ch);
    assert!(!c.tracking());
}

/// A strip that draws a third of the model's current: the correction
/// reaches its ×2 bound, and, the limit low, each corrected amplitude is
/// held at the limit; both flagged, and no output ever beyond the limit.
#[test]
fn a_correction_is_bounded_and_never_drives_past_the_limit() {
    let limit_v = 2.5;
    let (mut c, mut ch, tick) = tracking_controller(1.2e-4, limit_v);
    // The model's voltages are within the limit, twice them are not.
    let finrs_drive::Program::Harmonic { amplitudes_v, .. } = c.generator().program() else {
        panic!("a harmonic program")
    };
    let needs_v = amplitudes_v[..N].iter().fold(0.0f32, |m, &a| m.max(a));
    assert!(needs_v <= limit_v && 2.0 * needs_v > limit_v, "{needs_v} V");
    let m = model();
    let plant = Strip::<f64, N, 1, { state_len(N, 1) }>::with_extensions(
        &m.params,
        &m.extensions,
        Fixture::Free,
        1e-3,
    )
    .unwrap();
    let mut x = plant.rest();
    let mut currents = [0.0f64; N];
    let amps_per_count = f64::from(fine_config().amps_per_count);
    let mut peak = 0.0f32;
    for k in 0..10_000 {
        let counts = currents.map(|i| (2048.0 + i / amps_per_count).round() as u16);
        let out = c.tick(&input(tick + k, 1000, counts), &mut ch);
        peak = out.voltages_v.iter().fold(peak, |p, v| p.max(v.abs()));
        // A third of the voltage: a third of every current and moment.
        let v = out.voltages_v.map(|v| f64::from(v) / 3.0);
        plant.step(&mut x, &v);
        currents = plant.currents_a(&x, &v);
    }
    assert!(peak <= limit_v, "peak {peak} V");
    let last = ch
        .take_events()
        .into_iter()
        .rev()
        .find_map(|e| match e {
            Event::Tracking(t) => Some(t),
            _ => None,
        })
        .expect("Tracking frames");
    assert!(
        last.flags.has(TrackingFlags::BOUNDED) && last.flags.has(TrackingFlags::AT_LIMIT),
        "{last:?}"
    );
    assert!(
        last.gains[..N].iter().all(|&g| g == MAX_CORRECTION),
        "{last:?}"
    );
    let finrs_drive::Program::Harmonic { amplitudes_v, .. } = c.generator().program() else {
        panic!("a harmonic program")
    };
    assert!(amplitudes_v[..N].contains(&limit_v), "{amplitudes_v:?}");
    assert!(
        amplitudes_v[..N].iter().all(|&a| a <= limit_v),
        "{amplitudes_v:?}"
    );
}

/// A model that dries (the law of `finrs fit --effects dehydration`) and a
/// strip that dries by it (its moment gain, which no current shows): a
/// motion fed forward only (`motion-ff:`) that starts 300 s into the
/// session follows the law once a period and holds the tip over 60 s; the
/// same motion on the model without its law misses by the drying.
#[test]
fn the_drying_law_holds_a_motion_fed_forward() {
    let (rate_per_s, curvature, t0_s) = (2e-3, 1.0, 300.0);
    let run = |law: bool| {
        let mut m = model();
        if law {
            m.dehydration_per_s = rate_per_s;
            m.dehydration_curvature = curvature;
        }
        let (mut c, mut ch, tick, mut shaper) = tared_with_model(fine_config(), &m);
        let mut lock = Exclusive(&mut c);
        let motion = |t_session_s: f32| motion_command(TIP_M as f32, t_session_s, false);
        if law {
            // Without its session time a drying model cannot shape it.
            assert_eq!(
                command(motion(f32::NAN), &mut shaper, 1e-3, &mut lock),
                Err(finrs_controller::shaper::ShapeRefused::NoSessionTime)
            );
        }
        command(motion(t0_s as f32), &mut shaper, 1e-3, &mut lock).unwrap();
        assert_eq!(c.tracking(), law, "held by the law only where it dries");
        let plant = Strip::<f64, N, 4, { state_len(N, 4) }>::with_extensions(
            &m.params,
            &m.extensions,
            Fixture::Free,
            1e-3,
        );
        let mut plant = plant.unwrap();
        let mut x = plant.rest();
        let steps = 60_000u64;
        let mut tip = LastTenSeconds::new(steps);
        for k in 0..steps {
            let out = c.tick(&input(tick + k, 1000, [2048; N]), &mut ch);
            // The strip dries by the law whichever model drives it.
            plant.set_moment_gain(model_core::drying_gain(
                rate_per_s,
                curvature,
                t0_s + k as f64 / 1000.0,
            ));
            plant.step(&mut x, &out.voltages_v.map(f64::from));
            tip.add(k + 1, plant.tip_deflection_m(&x));
        }
        error_against(tip.phasor(), TIP_M)
    };
    let (a, p) = run(true);
    let (a0, p0) = run(false);
    eprintln!(
        "drying law, last 10 of 60 s from 300 s: followed {:+.2} % {p:+.2}°, without {:+.2} % {p0:+.2}°",
        100.0 * a,
        100.0 * a0
    );
    // Once a period: the law moves 0.05 % a period here.
    assert!(a.abs() < 0.01 && p.abs() < 0.5, "followed: {a} {p}°");
    // 1/(1 + 2e-3 · 355 s) = 0.585.
    assert!(a0 < -0.35, "without the law: {a0}");
}

/// A force motion on the strip held by the load cell (#16: the load cell
/// in blocked runs): the example session's strip (an instant moment, so
/// that 1 mN at 1 Hz is within 4 V), its moment per charge weakening by
/// 0.3 % a second (the dehydration extension's moment gain, which no
/// current shows). Tracked, the tracker reads the force against the
/// model's and the force stays as asked; fed forward, it falls with the
/// moment. Over the last 10 of 60 s, by lock-in.
#[test]
fn a_force_motion_is_held_by_the_load_cell() {
    const FORCE_N: f64 = 1e-3;
    let m = StripModel {
        params: Params::baseline_air_example(),
        ..model()
    };
    let config = Config {
        calibration: finrs_frames::Calibration {
            newtons_per_count: 1e-5,
            current_zero_counts: [2048; 8],
        },
        ..fine_config()
    };
    let run = |tracked: bool| {
        let (mut c, mut ch, tick, mut shaper) = tared_with_model(config, &m);
        let force = Motion::Force {
            force_amp_n: FORCE_N as f32,
            frequency_hz: 1.0,
            lag_deg_per_segment: 60.0,
        };
        let motion = set_motion(force, 0.0, f32::NAN, tracked);
        command(motion, &mut shaper, 1e-3, &mut Exclusive(&mut c)).unwrap();
        assert_eq!(c.tracking(), tracked);
        let mut plant = Strip::<f64, N, 4, { state_len(N, 4) }>::with_extensions(
            &m.params,
            &m.extensions,
            Fixture::Blocked,
            1e-3,
        )
        .unwrap();
        let mut x = plant.rest();
        let (mut force, mut currents) = (0.0f64, [0.0f64; N]);
        let steps = 60_000u64;
        let mut y = LastTenSeconds::new(steps);
        for k in 0..steps {
            // The tare's 1000 counts are the load cell's zero.
            let counts = (1000.0 + force / 1e-5).round() as u16;
            let shunts = currents.map(|i| (2048.0 + i / 2e-5).round() as u16);
            let out = c.tick(&input(tick + k, counts, shunts), &mut ch);
            plant.set_moment_gain(1.0 - 0.003 * k as f64 / 1000.0);
            let v = out.voltages_v.map(f64::from);
            plant.step(&mut x, &v);
            force = plant.blocking_force_n(&x);
            currents = plant.currents_a(&x, &v);
            y.add(k + 1, force);
        }
        error_against(y.phasor(), FORCE_N)
    };
    let (a, p) = run(true);
    let (a0, p0) = run(false);
    eprintln!(
        "force motion, moment per charge -0.3 %/s, last 10 of 60 s: tracked {:+.2} % {p:+.2}°, fed forward {:+.2} % {p0:+.2}°",
        100.0 * a,
        100.0 * a0
    );
    assert!(a.abs() < 0.03 && p.abs() < 1.0, "tracked: {a} {p}°");
    assert!(a0 < -0.12, "fed forward: {a0}");
}
