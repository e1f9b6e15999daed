//! The controller's semantics, one scenario at a time: configuration
//! checks, power-up tare, Sample contents, drop accounting, faults and
//! their latch, and each command.

mod common;

use common::{config, input, Channel};
use finrs_controller::{CommandRefused, ConfigError, ConfigRule, Controller, FaultCode};
use finrs_drive::{Envelope, Generator, LimitError, Limiter, Program, WaveRule};
use finrs_frames::{Command, Dropped, Event, Fault};

const N: usize = 3;
const IDLE: [u16; N] = [2048; N];

/// A controller past its power-up tare (10 readings of 1000 counts), the
/// channel emptied.
fn tared() -> (Controller<N>, Channel, u64) {
    let mut c = Controller::<N>::new(config()).unwrap();
    let mut ch = Channel::default();
    for tick in 0..10 {
        c.tick(&input(tick, 1000, IDLE), &mut ch);
    }
    assert!(!c.taring());
    ch.bytes.clear();
    (c, ch, 10)
}

fn steps(level_v: f32) -> Command {
    Command::SetWave {
        program: Program::Steps {
            levels_v: [level_v; 8],
        },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    }
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

#[test]
fn config_errors_name_field_and_rule() {
    let check = |f: fn(&mut finrs_controller::Config), field, rule| {
        let mut cfg = config();
        f(&mut cfg);
        assert_eq!(
            Controller::<N>::new(cfg).err(),
            Some(ConfigError { field, rule }),
            "{field}"
        );
    };
    check(|c| c.sample_hz = 0, "sample_hz", ConfigRule::Positive);
    check(
        |c| c.calibration.newtons_per_count = f32::NAN,
        "calibration.newtons_per_count",
        ConfigRule::Finite,
    );
    check(
        |c| c.calibration.newtons_per_count = 0.0,
        "calibration.newtons_per_count",
        ConfigRule::NonZero,
    );
    check(
        |c| c.adc_full_scale = 0,
        "adc_full_scale",
        ConfigRule::Positive,
    );
    check(
        |c| c.saturation_margin_counts = 2048,
        "saturation_margin_counts",
        ConfigRule::MarginTooWide,
    );
    check(
        |c| c.amps_per_count = f32::INFINITY,
        "amps_per_count",
        ConfigRule::Finite,
    );
    check(
        |c| c.calibration.current_zero_counts[7] = 4096,
        "calibration.current_zero_counts",
        ConfigRule::AboveFullScale,
    );
    check(
        |c| c.overcurrent_a = 0.0,
        "overcurrent_a",
        ConfigRule::Positive,
    );
    check(
        |c| c.overcurrent_a = f32::NAN,
        "overcurrent_a",
        ConfigRule::Finite,
    );
    check(|c| c.tare_samples = 0, "tare_samples", ConfigRule::Positive);
    // A negative scale is a mounting direction, not an error.
    let mut cfg = config();
    cfg.calibration.newtons_per_count = -1e-3;
    cfg.amps_per_count = -1e-3;
    assert!(Controller::<N>::new(cfg).is_ok());
    // Every segment count builds its idle program.
    assert!(Controller::<1>::new(config()).is_ok());
    assert!(Controller::<8>::new(config()).is_ok());
}

#[test]
fn power_up_tares_then_stays_stopped_until_a_wave() {
    let mut c = Controller::<N>::new(config()).unwrap();
    let mut ch = Channel::default();
    assert!(c.taring() && !c.running());
    // Readings 1000, 1002, ..., 1018: average 1009.
    for tick in 0..10u64 {
        let out = c.tick(&input(tick, 1000 + 2 * tick as u16, IDLE), &mut ch);
        assert_eq!(out.voltages_v, [0.0; N], "held during the tare");
    }
    assert!(!c.taring());
    assert!(
        !c.running(),
        "after any reset nothing drives until the host asks"
    );
    assert_eq!(c.tare_offset_counts(), 1009.0);
    let s = samples(&ch.take_events());
    assert_eq!(s.len(), 10);
    // Force relative to the first reading until the tare is done; the
    // tick that completes it already uses the new offset.
    for (k, s) in s.iter().enumerate() {
        let want = if k < 9 { (2 * k) as f32 * 1e-3 } else { 0.009 };
        assert!((s.force_n - want).abs() < 1e-6, "{k}: {}", s.force_n);
    }
    for tick in 10..2000u64 {
        let out = c.tick(&input(tick, 1009, IDLE), &mut ch);
        assert_eq!(out.voltages_v, [0.0; N], "tick {tick}: stopped");
    }
    c.command(steps(0.5)).unwrap();
    assert!(c.running());
}

#[test]
fn a_wave_sent_during_the_power_up_tare_starts_at_its_time_0_when_the_tare_is_done() {
    let (program, envelope) = finrs_drive::default_program();
    let wave = Command::SetWave { program, envelope };
    let mut c = Controller::<N>::new(config()).unwrap();
    let mut ch = Channel::default();
    for tick in 0..10u64 {
        if tick == 3 {
            c.command(wave).unwrap();
            assert!(!c.running(), "held until the tare is done");
        }
        let out = c.tick(&input(tick, 1009, IDLE), &mut ch);
        assert_eq!(out.voltages_v, [0.0; N], "held during the tare");
    }
    assert!(!c.taring() && c.running());
    assert_eq!(c.tare_offset_counts(), 1009.0, "tared at rest");
    // The program started at its own time 0 on the tick that completed the
    // tare (tick 9, where it asks for 0 V), through the limiter.
    let generator = Generator::<N>::new(program, envelope).unwrap();
    let mut limiter = Limiter::<N>::new(config().limits);
    assert_eq!(
        limiter.apply(generator.voltages_at_tick_v(0, 1000), 1e-3),
        [0.0; N]
    );
    for k in 1..1500u64 {
        let out = c.tick(&input(9 + k, 1009, IDLE), &mut ch);
        let want = limiter.apply(generator.voltages_at_tick_v(k, 1000), 1e-3);
        assert_eq!(out.voltages_v, want, "tick {k}");
    }
    assert!(c.outputs_v().iter().any(|v| v.abs() > 1.0));

    // A Stop during the tare cancels the wave given before it.
    let mut c = Controller::<N>::new(config()).unwrap();
    c.command(wave).unwrap();
    c.command(Command::Stop).unwrap();
    for tick in 0..100u64 {
        let out = c.tick(&input(tick, 1009, IDLE), &mut ch);
        assert_eq!(out.voltages_v, [0.0; N], "tick {tick}");
    }
    assert!(!c.taring() && !c.running());
}

#[test]
fn sample_frames_carry_the_tick() {
    let (mut c, mut ch, t0) = tared();
    c.command(steps(0.05)).unwrap();
    let currents = [2048 + 100, 2048 - 50, 2048];
    let out = c.tick(&input(t0, 1250, currents), &mut ch);
    let s = samples(&ch.take_events());
    assert_eq!(s.len(), 1);
    let s = s[0];
    assert_eq!((s.seq, s.t_us, s.n), (10, 10_000, N));
    assert!((s.force_n - 0.25).abs() < 1e-6);
    assert_eq!(s.voltages(), &out.voltages_v[..]);
    assert_eq!(out.voltages_v, [0.05; N]);
    let want = [0.1, -0.05, 0.0];
    for (got, want) in s.currents().iter().zip(want) {
        assert!((got - want).abs() < 1e-6);
    }
}

#[test]
fn dropped_samples_are_reported_before_the_next_sample_sent() {
    let (mut c, mut ch, t0) = tared();
    let mut tick = t0;
    let mut run = |c: &mut Controller<N>, ch: &mut Channel, n: u64| {
        for _ in 0..n {
            c.tick(&input(tick, 1000, IDLE), ch);
            tick += 1;
        }
    };
    run(&mut c, &mut ch, 3); // seq 10..13 sent
    ch.full = true;
    run(&mut c, &mut ch, 5); // 13..18 dropped
    assert_eq!(
        c.pending_dropped(),
        Some(Dropped {
            first_seq: 13,
            count: 5
        })
    );
    // Room for a Sample but not... a Dropped frame is shorter, so let
    // only Dropped-sized frames through: the Dropped goes, Samples do not.
    ch.full = false;
    ch.max_len = Some(finrs_frames::DROPPED_FRAME_LEN);
    // Each tick: the pending Dropped goes, the Sample does not.
    run(&mut c, &mut ch, 2); // D{13,5}, 18 dropped; D{18,1}, 19 dropped
    assert_eq!(
        c.pending_dropped(),
        Some(Dropped {
            first_seq: 19,
            count: 1
        })
    );
    // Nothing at all goes: the pending report grows.
    ch.max_len = Some(1);
    run(&mut c, &mut ch, 2); // 20, 21 dropped
    assert_eq!(
        c.pending_dropped(),
        Some(Dropped {
            first_seq: 19,
            count: 3
        })
    );
    ch.max_len = None;
    run(&mut c, &mut ch, 2); // D{19,3}, then 22, 23
    assert_eq!(c.pending_dropped(), None);
    let (events, stats) = ch.events();
    let kinds: Vec<String> = events
        .iter()
        .map(|e| match e {
            Event::Sample(s) => format!("S{}", s.seq),
            Event::Dropped(d) => format!("D{}+{}", d.first_seq, d.count),
            other => format!("{other:?}"),
        })
        .collect();
    assert_eq!(
        kinds,
        ["S10", "S11", "S12", "D13+5", "D18+1", "D19+3", "S22", "S23"]
    );
    assert_eq!(stats.gaps_unreported, 0);
    assert_eq!(stats.samples + stats.dropped_reported, 14);
}

#[test]
fn an_overcurrent_latches_zeros_and_a_fault_report() {
    let (mut c, mut ch, t0) = tared();
    c.command(steps(1.0)).unwrap();
    for t in t0..t0 + 20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [1.0; N]);
    ch.bytes.clear();
    // Segment 1 draws 0.6 A > 0.5 A.
    let out = c.tick(&input(t0 + 20, 1000, [2048, 2648, 2048]), &mut ch);
    assert_eq!(out.voltages_v, [0.0; N]);
    assert_eq!(c.fault_state(), Some((FaultCode::Overcurrent, Some(1))));
    let events = ch.take_events();
    assert_eq!(
        events,
        vec![Event::Fault(Fault {
            seq: 30,
            t_us: 30_000,
            code: FaultCode::Overcurrent,
            segment: Some(1),
        })]
    );
    // Latched: exact zeros even with good readings; samples keep flowing
    // and take the number the fault carried.
    for t in t0 + 21..t0 + 30 {
        let out = c.tick(&input(t, 1000, IDLE), &mut ch);
        assert_eq!(out.voltages_v, [0.0; N]);
    }
    let s = samples(&ch.take_events());
    assert_eq!(s[0].seq, 30);
    assert!(s.iter().all(|s| s.voltages() == [0.0; N]));
    assert_eq!(c.command(steps(0.5)), Err(CommandRefused::Faulted));
    c.command(Command::ClearFault).unwrap();
    assert_eq!(c.fault_state(), None);
    // Cleared, but still at 0 until a SetWave.
    for t in t0 + 30..t0 + 40 {
        assert_eq!(c.tick(&input(t, 1000, IDLE), &mut ch).voltages_v, [0.0; N]);
    }
    c.command(steps(0.5)).unwrap();
    let out = c.tick(&input(t0 + 40, 1000, IDLE), &mut ch);
    assert_eq!(out.voltages_v, [0.1; N], "slewing up at 100 V/s");
}

#[test]
fn a_refused_fault_report_goes_first_next_tick_and_blocks_clear_fault() {
    let (mut c, mut ch, t0) = tared();
    ch.full = true;
    c.tick(&input(t0, 4095, IDLE), &mut ch); // load cell saturated
    assert_eq!(c.fault_state(), Some((FaultCode::AdcSaturation, None)));
    assert!(c.fault_report_pending());
    assert_eq!(
        c.command(Command::ClearFault),
        Err(CommandRefused::FaultNotReported)
    );
    c.tick(&input(t0 + 1, 1000, IDLE), &mut ch); // still full: seq 10 dropped
    ch.full = false;
    c.tick(&input(t0 + 2, 1000, IDLE), &mut ch);
    let kinds: Vec<String> = ch
        .take_events()
        .iter()
        .map(|e| match e {
            Event::Sample(s) => format!("S{}", s.seq),
            Event::Dropped(d) => format!("D{}+{}", d.first_seq, d.count),
            Event::Fault(f) => format!("F{}", f.seq),
            other => format!("{other:?}"),
        })
        .collect();
    assert_eq!(kinds, ["F10", "D10+1", "S11"]);
    assert!(!c.fault_report_pending());
    c.command(Command::ClearFault).unwrap();
}

#[test]
fn saturation_of_each_channel() {
    for (counts, currents, want) in [
        (0u16, IDLE, (FaultCode::AdcSaturation, None)),
        (2, IDLE, (FaultCode::AdcSaturation, None)),
        (4093, IDLE, (FaultCode::AdcSaturation, None)),
        (1000, [2048, 2048, 4095], (FaultCode::Overcurrent, Some(2))),
        (1000, [2048, 1, 2048], (FaultCode::Overcurrent, Some(1))),
    ] {
        let (mut c, mut ch, t0) = tared();
        c.tick(&input(t0, counts, currents), &mut ch);
        assert_eq!(c.fault_state(), Some(want), "{counts} {currents:?}");
    }
    // A saturated current channel that is not (yet) an overcurrent: a
    // large overcurrent threshold.
    let mut cfg = config();
    cfg.overcurrent_a = 10.0;
    let mut c = Controller::<N>::new(cfg).unwrap();
    let mut ch = Channel::default();
    c.tick(&input(0, 1000, [2048, 4094, 2048]), &mut ch);
    assert_eq!(c.fault_state(), Some((FaultCode::AdcSaturation, Some(1))));
    // A unipolar shunt amplifier reads 0 at rest: no saturation there.
    let mut cfg = config();
    cfg.calibration.current_zero_counts = [0; 8];
    let mut c = Controller::<N>::new(cfg).unwrap();
    for t in 0..20 {
        c.tick(&input(t, 1000, [0; N]), &mut ch);
    }
    assert_eq!(c.fault_state(), None);
    c.tick(&input(20, 1000, [0, 0, 4095]), &mut ch);
    assert_eq!(c.fault_state(), Some((FaultCode::Overcurrent, Some(2))));
    // Just inside the margin is fine.
    let (mut c, mut ch, t0) = tared();
    c.tick(&input(t0, 3, IDLE), &mut ch);
    c.tick(&input(t0 + 1, 4092, IDLE), &mut ch);
    assert_eq!(c.fault_state(), None);
}

#[test]
fn an_outside_fault_latches_and_later_ones_only_count() {
    let (mut c, mut ch, t0) = tared();
    c.command(steps(1.0)).unwrap();
    for t in t0..t0 + 5 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    ch.bytes.clear();
    c.fault(FaultCode::MissedDeadline, None, &mut ch);
    assert_eq!(c.outputs_v(), [0.0; N]);
    c.fault(FaultCode::Other, Some(2), &mut ch);
    assert_eq!(c.fault_state(), Some((FaultCode::MissedDeadline, None)));
    assert_eq!(c.faults_while_latched(), 1);
    assert_eq!(
        ch.take_events(),
        vec![Event::Fault(Fault {
            seq: 15,
            t_us: 14_000,
            code: FaultCode::MissedDeadline,
            segment: None
        })]
    );
    c.command(Command::ClearFault).unwrap();
    // A segment beyond N is reported as none rather than refused.
    c.fault(FaultCode::Other, Some(7), &mut ch);
    assert_eq!(c.fault_state(), Some((FaultCode::Other, None)));
}

#[test]
fn set_wave_validates_and_starts_at_time_0() {
    let (mut c, mut ch, t0) = tared();
    let before = c.generator().program();
    let bad = Command::SetWave {
        program: Program::Travelling {
            amplitude_v: 1.0,
            frequency_hz: 500.0,
            lag_deg_per_segment: 0.0,
            offset_v: 0.0,
        },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: 1.0,
            ramp_out_s: 0.0,
        },
    };
    match c.command(bad) {
        Err(CommandRefused::Wave(e)) => {
            assert_eq!(e.field, "Travelling.frequency_hz");
            assert_eq!(e.rule, WaveRule::FrequencyRange);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(c.generator().program(), before, "refused: nothing changed");
    // Pulses of 5 ms on, 5 ms off, starting at its own time 0 whatever
    // the tick count.
    let pulses = Command::SetWave {
        program: Program::Pulses {
            amplitude_v: 0.2,
            on_s: 0.005,
            off_s: 0.005,
        },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    };
    for t in t0..t0 + 1003 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    c.command(pulses).unwrap();
    let start = t0 + 1003;
    let mut got = Vec::new();
    for t in start..start + 12 {
        got.push(c.tick(&input(t, 1000, IDLE), &mut ch).voltages_v[0]);
    }
    // 100 V/s: 0.1 V per tick; from wherever the old wave was, but the new
    // program's on/off pattern is aligned to the SetWave.
    let generator = Generator::<N>::new(
        Program::Pulses {
            amplitude_v: 0.2,
            on_s: 0.005,
            off_s: 0.005,
        },
        Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    )
    .unwrap();
    let wanted: Vec<f32> = (0..12)
        .map(|k| generator.voltages_at_tick_v(k, 1000)[0])
        .collect();
    assert_eq!(&wanted[..6], &[0.2, 0.2, 0.2, 0.2, 0.2, 0.0]);
    // Once caught up (from tick 3 on), the output follows the pattern.
    for k in 3..12 {
        assert!(
            (got[k] - wanted[k]).abs() <= 0.1 + 1e-6,
            "{k}: {got:?} {wanted:?}"
        );
    }
    assert!((got[4] - 0.2).abs() < 1e-6 && got[6].abs() < 0.1 + 1e-6);
}

#[test]
fn set_limit_only_lowers_and_applies_at_once() {
    let (mut c, mut ch, t0) = tared();
    c.command(steps(1.5)).unwrap();
    for t in t0..t0 + 20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [1.5; N]);
    assert_eq!(
        c.command(Command::SetLimit { max_abs_v: 3.0 }),
        Err(CommandRefused::Limit(LimitError::MaxAbsRaised))
    );
    assert_eq!(
        c.command(Command::SetLimit {
            max_abs_v: f32::NAN
        }),
        Err(CommandRefused::Limit(LimitError::MaxAbsNotFinite))
    );
    assert_eq!(c.limits().max_abs_v(), 2.0, "refused: unchanged");
    c.command(Command::SetLimit { max_abs_v: 0.5 }).unwrap();
    let out = c.tick(&input(t0 + 20, 1000, IDLE), &mut ch);
    assert_eq!(out.voltages_v, [0.5; N]);
    assert_eq!(c.limits().max_abs_v(), 0.5);
}

#[test]
fn stop_slews_to_zero_and_stays_until_set_wave() {
    let (mut c, mut ch, t0) = tared();
    c.command(steps(1.0)).unwrap();
    for t in t0..t0 + 20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    c.command(Command::Stop).unwrap();
    assert!(!c.running());
    let mut last = 1.0f32;
    for t in t0 + 20..t0 + 40 {
        let v = c.tick(&input(t, 1000, IDLE), &mut ch).voltages_v[0];
        assert!(last - v <= 0.1 + 1e-6 && v <= last);
        last = v;
    }
    assert_eq!(c.outputs_v(), [0.0; N]);
    assert_eq!(c.fault_state(), None, "a stop is no fault");
    c.command(steps(0.3)).unwrap();
    for t in t0 + 40..t0 + 45 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [0.3; N]);
}

#[test]
fn tare_keeps_the_old_offset_until_done() {
    let (mut c, mut ch, t0) = tared();
    assert_eq!(c.tare_offset_counts(), 1000.0);
    c.command(Command::Tare).unwrap();
    for k in 0..10u64 {
        c.tick(&input(t0 + k, 1500 + k as u16 % 2, IDLE), &mut ch);
        if k < 9 {
            assert_eq!(c.tare_offset_counts(), 1000.0);
        }
    }
    assert_eq!(c.tare_offset_counts(), 1500.5);
    let s = samples(&ch.take_events());
    assert_eq!(s.len(), 10, "no frame lost while taring");
    assert!((s[0].force_n - 0.5).abs() < 1e-6);
    c.tick(&input(t0 + 10, 1500, IDLE), &mut ch);
    let s = samples(&ch.take_events());
    assert!((s[0].force_n + 0.5e-3).abs() < 1e-6);
}

#[test]
fn commands_from_the_down_channel_bytes() {
    use finrs_frames::{encode_command, CommandDecoder, CommandEvent, MAX_COMMAND_LEN};
    let (mut c, mut ch, t0) = tared();
    let mut stream = Vec::new();
    for cmd in [
        steps(0.7),
        Command::SetLimit { max_abs_v: 0.4 },
        Command::SetLimit { max_abs_v: 9.0 }, // refused by the controller
    ] {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let n = encode_command(&cmd, &mut buf).unwrap();
        stream.extend_from_slice(&buf[..n]);
    }
    stream.extend_from_slice(&[0xF1, 0x5E, 0x01, 0x00]); // not a command
    let mut results = Vec::new();
    let mut refused_frames = 0;
    CommandDecoder::new().push(&stream, &mut |e| match e {
        CommandEvent::Command(cmd) => results.push(c.command(cmd)),
        CommandEvent::Refused(_) => refused_frames += 1,
    });
    assert_eq!(
        results,
        [
            Ok(()),
            Ok(()),
            Err(CommandRefused::Limit(LimitError::MaxAbsAboveHardLimit))
        ]
    );
    assert_eq!(refused_frames, 1);
    for t in t0..t0 + 10 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [0.4; N]);
}

#[test]
fn a_wave_above_the_limit_is_refused_not_clipped() {
    let (mut c, mut ch, t0) = tared();
    assert_eq!(c.limits().max_abs_v(), 2.0);
    let before = c.generator().program();
    let refused = c.command(steps(2.5));
    assert_eq!(
        refused,
        Err(CommandRefused::AboveLimit {
            peak_v: 2.5,
            limit_v: 2.0
        })
    );
    assert_eq!(
        refused.unwrap_err().to_string(),
        "SetWave refused: the program peaks at 2.50 V, above the 2.00 V limit"
    );
    assert_eq!(c.generator().program(), before, "refused: nothing changed");
    // A sine's peak is its amplitude plus the offset's magnitude.
    let sine = |amplitude_v, offset_v| Command::SetWave {
        program: Program::Travelling {
            amplitude_v,
            frequency_hz: 1.0,
            lag_deg_per_segment: 90.0,
            offset_v,
        },
        envelope: Envelope {
            ramp_in_s: 1.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    };
    assert!(matches!(
        c.command(sine(1.5, -0.6)),
        Err(CommandRefused::AboveLimit { .. })
    ));
    c.command(sine(1.5, -0.5)).unwrap();
    // Levels beyond the N segments are not driven, so they do not count.
    let mut levels_v = [1.0; 8];
    levels_v[N..].fill(9.0);
    c.command(Command::SetWave {
        program: Program::Steps { levels_v },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    })
    .unwrap();
    c.command(steps(2.0)).unwrap();
    for t in t0..t0 + 20 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    assert_eq!(c.outputs_v(), [2.0; N]);
    // A lowered limit is never refused; the running wave is clipped, and a
    // new one above it is refused.
    c.command(Command::SetLimit { max_abs_v: 0.5 }).unwrap();
    assert_eq!(
        c.tick(&input(t0 + 20, 1000, IDLE), &mut ch).voltages_v,
        [0.5; N]
    );
    assert_eq!(
        c.command(steps(1.0)),
        Err(CommandRefused::AboveLimit {
            peak_v: 1.0,
            limit_v: 0.5
        })
    );
}

/// A sample task that ran too late to see a period: the hardware's period
/// count jumps, the periods it did not see take their sequence numbers and
/// are reported as dropped before the next Sample, whose time is the
/// hardware's.
#[test]
fn periods_no_tick_saw_are_reported_as_dropped_samples() {
    let (mut c, mut ch, t0) = tared();
    c.tick(&input(t0, 1000, IDLE), &mut ch);
    c.tick(&input(t0 + 3, 1000, IDLE), &mut ch); // t0 + 1 and t0 + 2 unseen
    c.tick(&input(t0 + 4, 1000, IDLE), &mut ch);
    assert_eq!(c.unseen_periods(), 2);
    let events = ch.take_events();
    let seqs: Vec<String> = events
        .iter()
        .map(|e| match e {
            Event::Sample(s) => format!("S{}@{}", s.seq, s.t_us),
            Event::Dropped(d) => format!("D{}+{}", d.first_seq, d.count),
            other => format!("{other:?}"),
        })
        .collect();
    assert_eq!(seqs, ["S10@10000", "D11+2", "S13@13000", "S14@14000"]);
    // A jump beyond what a Dropped frame counts saturates, never panics.
    let (mut c, mut ch, t0) = tared();
    c.tick(&input(t0 + (1 << 40), 1000, IDLE), &mut ch);
    assert_eq!(c.unseen_periods(), u64::from(u32::MAX));
    // A tick that does not advance (a caller's bug) skips nothing.
    c.tick(&input(t0 + (1 << 40), 1000, IDLE), &mut ch);
    assert_eq!(c.unseen_periods(), u64::from(u32::MAX));
}

/// The Info frame: once the board gives its identity, at the next tick
/// before the Sample, with the limit in force; a refused one waits without
/// holding back Samples; RequestInfo sends it again.
#[test]
fn the_info_frame_goes_first_and_again_on_request() {
    use finrs_controller::Identity;
    use finrs_frames::ResetCause;
    let (mut c, mut ch, t0) = tared();
    c.command(Command::RequestInfo).unwrap();
    c.tick(&input(t0, 1000, IDLE), &mut ch);
    let kinds = |events: &[Event]| -> Vec<&'static str> {
        events
            .iter()
            .map(|e| match e {
                Event::Info(_) => "I",
                Event::Sample(_) => "S",
                _ => "?",
            })
            .collect()
    };
    assert_eq!(kinds(&ch.take_events()), ["S"], "no identity: no Info");
    let id = Identity {
        version: [0, 1, 0],
        git_hash: 0xdead_beef,
        dac_segments: [None, Some(1)],
        bridge_supply_v: 5.0,
        reset_cause: ResetCause::Watchdog,
    };
    c.set_identity(id);
    // Refused once: the Sample still goes, the Info waits.
    ch.refuse_next = 1;
    c.tick(&input(t0 + 1, 1000, IDLE), &mut ch);
    assert_eq!(kinds(&ch.take_events()), ["S"]);
    c.tick(&input(t0 + 2, 1000, IDLE), &mut ch);
    let events = ch.take_events();
    assert_eq!(kinds(&events), ["I", "S"]);
    let Event::Info(info) = events[0] else {
        unreachable!()
    };
    assert_eq!(
        (info.segments, info.dac_segments, info.git_hash),
        (N as u8, [None, Some(1)], 0xdead_beef)
    );
    assert_eq!(
        (info.sample_hz, info.max_abs_v, info.reset_cause),
        (1000, 2.0, ResetCause::Watchdog)
    );
    c.tick(&input(t0 + 3, 1000, IDLE), &mut ch);
    assert_eq!(kinds(&ch.take_events()), ["S"], "once");
    c.command(Command::SetLimit { max_abs_v: 1.5 }).unwrap();
    c.command(Command::RequestInfo).unwrap();
    c.tick(&input(t0 + 4, 1000, IDLE), &mut ch);
    let events = ch.take_events();
    assert_eq!(kinds(&events), ["I", "S"]);
    let Event::Info(again) = events[0] else {
        unreachable!()
    };
    assert_eq!(again.max_abs_v, 1.5, "the limit in force");
    assert_ne!(again.config_crc(), info.config_crc());
}

/// Every Sample says what the firmware was doing: taring, running, the
/// limiter clamping or slewing, a fault latched.
#[test]
fn sample_flags_tell_taring_running_limiting_slewing_and_faults() {
    use finrs_frames::SampleFlags as F;
    let flags = |ch: &mut Channel| -> Vec<u8> {
        samples(&ch.take_events())
            .iter()
            .map(|s| s.flags.0)
            .collect()
    };
    let mut c = Controller::<N>::new(config()).unwrap();
    let mut ch = Channel::default();
    for tick in 0..10 {
        c.tick(&input(tick, 1000, IDLE), &mut ch);
    }
    let power_up = flags(&mut ch);
    assert!(
        power_up[..9].iter().all(|&f| f == F::TARING),
        "{power_up:?}"
    );
    assert_eq!(power_up[9], 0, "tared, stopped");
    // A step to 1.5 V at 100 V/s (0.1 V a tick): slewed for 15 ticks, then
    // held; running throughout.
    c.command(steps(1.5)).unwrap();
    for t in 10..30 {
        c.tick(&input(t, 1000, IDLE), &mut ch);
    }
    let step = flags(&mut ch);
    let slewed = step
        .iter()
        .filter(|&&f| f == F::RUNNING | F::SLEWED)
        .count();
    assert!((14..=15).contains(&slewed), "{step:?}");
    assert_eq!(*step.last().unwrap(), F::RUNNING);
    // The limit lowered under the running wave: clamped from then on.
    c.command(Command::SetLimit { max_abs_v: 1.0 }).unwrap();
    c.tick(&input(30, 1000, IDLE), &mut ch);
    assert_eq!(flags(&mut ch), [F::RUNNING | F::LIMITED]);
    // A Tare while running.
    c.command(Command::Tare).unwrap();
    c.tick(&input(31, 1000, IDLE), &mut ch);
    assert_eq!(flags(&mut ch), [F::RUNNING | F::LIMITED | F::TARING]);
    // A fault latched: the faulting tick sends the Fault frame, the next
    // Samples say so.
    c.fault(FaultCode::Other, None, &mut ch);
    c.tick(&input(32, 1000, IDLE), &mut ch);
    let f = flags(&mut ch);
    assert!(
        f.iter().all(|&x| x & F::FAULT != 0 && x & F::RUNNING == 0),
        "{f:?}"
    );
}
