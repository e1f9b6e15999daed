//! The safety invariant and the stream's accounting over random sequences
//! of ticks, readings, sink refusals, commands (valid or not) and faults
//! from outside:
//!
//! - every output |v| ≤ the `max_abs_v` in force ≤ HARD_LIMIT_V;
//! - each step from the previous output (clamped to the limit in force) is
//!   at most slew · dt;
//! - while a fault is latched every output is exactly 0;
//! - the Samples' voltages are the tick's outputs;
//! - every sequence number is a Sample sent, in a Dropped report sent, or
//!   in the pending report: the host's decoder sees no Gap; every latched
//!   fault is reported or pending.

mod common;

use common::Channel;
use finrs_controller::{Config, Controller, FaultCode, TickInput};
use finrs_drive::{Envelope, Limits, Program, HARD_LIMIT_V};
use finrs_frames::{Command, Event};
use proptest::prelude::*;

const N: usize = 4;

#[derive(Clone, Debug)]
enum Sink {
    Accept,
    Full,
    /// Only frames up to this many bytes (Dropped and Fault frames fit in
    /// 14, a Sample of 4 segments needs 50).
    Short(usize),
    /// Refuse the next few frames offered, then accept.
    RefuseFirst(usize),
}

// A Command carries a SetModel's 254-byte record by value.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Op {
    Tick {
        advance: u64,
        load_cell_counts: u16,
        current_counts: [u16; N],
        sink: Sink,
    },
    Command(Command),
    Fault(FaultCode, Option<u8>, Sink),
}

fn any_counts() -> impl Strategy<Value = u16> {
    prop_oneof![
        20 => 1000u16..3000,
        1 => Just(0u16),
        1 => Just(4095u16),
        1 => any::<u16>(),
    ]
}

fn any_current() -> impl Strategy<Value = u16> {
    // Zero at 2048, 1 mA per count, overcurrent above 0.5 A.
    prop_oneof![40 => 1900u16..2200, 1 => 1500u16..2600, 1 => any::<u16>()]
}

fn any_sink() -> impl Strategy<Value = Sink> {
    prop_oneof![
        8 => Just(Sink::Accept),
        2 => Just(Sink::Full),
        1 => (1usize..60).prop_map(Sink::Short),
        1 => (1usize..3).prop_map(Sink::RefuseFirst),
    ]
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -5.0f32..5.0,
        2 => -1000.0f32..1000.0,
        1 => any::<u32>().prop_map(f32::from_bits),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NAN),
    ]
}

fn any_program() -> BoxedStrategy<Program> {
    prop_oneof![
        (0.0f32..20.0, 0.01f32..100.0, any_f32(), -3.0f32..3.0).prop_map(|(a, f, l, o)| {
            Program::Travelling {
                amplitude_v: a,
                frequency_hz: f,
                lag_deg_per_segment: l,
                offset_v: o,
            }
        }),
        (0.0f32..20.0, 0.01f32..100.0, -3.0f32..3.0).prop_map(|(a, f, o)| Program::Standing {
            amplitude_v: a,
            frequency_hz: f,
            offset_v: o,
        }),
        prop::array::uniform8(any_f32()).prop_map(|levels_v| Program::Steps { levels_v }),
        (0.0f32..1000.0, 0.0f32..0.05, 0.0f32..0.05).prop_map(|(a, on, off)| {
            Program::Pulses {
                amplitude_v: a,
                on_s: on,
                off_s: off,
            }
        }),
        (0.0f32..10.0, 0.01f32..10.0, 0.01f32..100.0, 0.0f32..1.0).prop_map(|(a, s, e, d)| {
            Program::Chirp {
                amplitude_v: a,
                start_hz: s,
                end_hz: e,
                duration_s: d,
            }
        }),
        (any_f32(), any_f32(), any_f32(), any_f32()).prop_map(|(a, f, l, o)| {
            Program::Travelling {
                amplitude_v: a,
                frequency_hz: f,
                lag_deg_per_segment: l,
                offset_v: o,
            }
        }),
    ]
    .boxed()
}

fn any_command() -> BoxedStrategy<Command> {
    let envelope = (
        0.0f32..0.05,
        prop_oneof![Just(f32::INFINITY), 0.0f32..0.2],
        0.0f32..0.05,
    )
        .prop_map(|(i, h, o)| Envelope {
            ramp_in_s: i,
            hold_s: h,
            ramp_out_s: o,
        });
    let bad_envelope = (any_f32(), any_f32(), any_f32()).prop_map(|(i, h, o)| Envelope {
        ramp_in_s: i,
        hold_s: h,
        ramp_out_s: o,
    });
    prop_oneof![
        6 => (any_program(), prop_oneof![4 => envelope, 1 => bad_envelope])
            .prop_map(|(program, envelope)| Command::SetWave { program, envelope }),
        1 => Just(Command::Tare),
        2 => Just(Command::Stop),
        2 => prop_oneof![0.0f32..5.0, any_f32()].prop_map(|max_abs_v| Command::SetLimit { max_abs_v }),
        3 => Just(Command::ClearFault),
    ]
    .boxed()
}

fn any_op() -> BoxedStrategy<Op> {
    let code = prop_oneof![
        Just(FaultCode::Overcurrent),
        Just(FaultCode::AdcSaturation),
        Just(FaultCode::MissedDeadline),
        Just(FaultCode::Other),
        Just(FaultCode::Supply),
    ];
    prop_oneof![
        30 => (
            // Late sample tasks skip periods: each one a dropped sample.
            prop_oneof![20 => Just(1u64), 1 => 0u64..5, 1 => 5u64..300],
            any_counts(),
            prop::array::uniform4(any_current()),
            any_sink(),
        )
            .prop_map(|(advance, load_cell_counts, current_counts, sink)| Op::Tick {
                advance,
                load_cell_counts,
                current_counts,
                sink,
            }),
        4 => any_command().prop_map(Op::Command),
        1 => (code, prop::option::of(0u8..10), any_sink()).prop_map(|(c, s, k)| Op::Fault(c, s, k)),
    ]
    .boxed()
}

fn any_config() -> impl Strategy<Value = Config> {
    (
        0.1f32..=HARD_LIMIT_V,
        0.5f32..5000.0,
        prop_oneof![Just(100u32), Just(1000), Just(5000)],
        1u16..30,
    )
        // The sensor scales are the common test board's; what varies is
        // what the safety rules depend on.
        .prop_map(|(max_abs_v, slew, sample_hz, tare_samples)| Config {
            sample_hz,
            limits: Limits::new(max_abs_v, slew).unwrap(),
            tare_samples,
            ..common::config()
        })
}

fn set(ch: &mut Channel, sink: &Sink) {
    ch.full = matches!(sink, Sink::Full);
    ch.max_len = match sink {
        Sink::Short(n) => Some(*n),
        _ => None,
    };
    ch.refuse_next = match sink {
        Sink::RefuseFirst(n) => *n,
        _ => 0,
    };
}

fn clamp(v: f32, bound: f32) -> f32 {
    v.clamp(-bound, bound)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn no_sequence_breaks_the_limits_or_loses_a_report(
        config in any_config(),
        ops in prop::collection::vec(any_op(), 1..300),
    ) {
        let mut c = Controller::<N>::new(config).unwrap();
        let mut ch = Channel::default();
        let dt_s = 1.0 / config.sample_hz as f32;
        let mut tick = 0u64;
        let mut prev = [0.0f32; N];
        // Outputs by sequence number of the Sample that carried them (None:
        // a period no tick saw).
        let mut outputs: Vec<Option<[f32; N]>> = Vec::new();
        let mut ticked = false;
        let mut latches = 0usize;
        for op in &ops {
            let was_latched = c.fault_state().is_some();
            match op {
                Op::Tick { advance, load_cell_counts, current_counts, sink } => {
                    tick = tick.saturating_add(*advance);
                    set(&mut ch, sink);
                    let seq = c.next_seq();
                    let input = TickInput {
                        tick,
                        t_us: tick as u32,
                        load_cell_counts: *load_cell_counts,
                        current_counts: *current_counts,
                    };
                    let out = c.tick(&input, &mut ch).voltages_v;
                    let unseen = if ticked { advance.saturating_sub(1) } else { 0 };
                    ticked = true;
                    let seq = seq.wrapping_add(unseen as u32);
                    outputs.extend((0..unseen).map(|_| None));
                    let limits = c.limits();
                    prop_assert!(limits.max_abs_v() <= HARD_LIMIT_V);
                    let step = limits.slew_v_per_s() * dt_s;
                    let latched = c.fault_state().is_some();
                    for (k, (&v, &p)) in out.iter().zip(&prev).enumerate() {
                        prop_assert!(v.abs() <= limits.max_abs_v(), "segment {k}: {v}");
                        if latched {
                            prop_assert_eq!(v.to_bits(), 0, "latched: exactly 0");
                        } else {
                            let from = clamp(p, limits.max_abs_v());
                            prop_assert!(
                                (v - from).abs() <= step * (1.0 + 1e-5) + 1e-6,
                                "segment {}: {} -> {} (step {})", k, p, v, step
                            );
                        }
                    }
                    prop_assert_eq!(out, c.outputs_v());
                    if c.next_seq() != seq {
                        prop_assert_eq!(c.next_seq(), seq.wrapping_add(1));
                        outputs.push(Some(out));
                    } else {
                        prop_assert!(latched && !was_latched, "only the faulting tick takes no number");
                    }
                    prev = out;
                }
                Op::Command(command) => {
                    let limit_before = c.limits();
                    let program_before = c.generator().program();
                    let fault_before = c.fault_state();
                    let accepted = c.command(*command).is_ok();
                    if accepted && matches!(command, Command::SetWave { .. }) {
                        prop_assert!(
                            c.generator().peak_abs_v() <= c.limits().max_abs_v(),
                            "a wave above the limit was taken"
                        );
                    }
                    if !accepted {
                        prop_assert_eq!(c.limits(), limit_before, "refused: nothing changed");
                        prop_assert_eq!(format!("{:?}", c.generator().program()), format!("{:?}", program_before));
                        prop_assert_eq!(c.fault_state(), fault_before);
                    }
                    if matches!(command, Command::SetWave { .. }) && fault_before.is_some() {
                        prop_assert!(!c.running(), "no SetWave while faulted");
                    }
                }
                Op::Fault(code, segment, sink) => {
                    set(&mut ch, sink);
                    c.fault(*code, *segment, &mut ch);
                    prop_assert_eq!(c.outputs_v(), [0.0; N]);
                    prev = [0.0; N];
                }
            }
            if !was_latched && c.fault_state().is_some() {
                latches += 1;
            }
            if c.fault_state().is_some() {
                prop_assert_eq!(c.outputs_v(), [0.0; N]);
            }
        }
        // One clean tick with room in the channel sends whatever waits.
        let seq = c.next_seq();
        set(&mut ch, &Sink::Accept);
        let input = TickInput {
            tick: tick.saturating_add(1),
            t_us: 0,
            load_cell_counts: 2000,
            current_counts: [2048; N],
        };
        let out = c.tick(&input, &mut ch).voltages_v;
        prop_assert_eq!(c.next_seq(), seq.wrapping_add(1));
        outputs.push(Some(out));
        prop_assert!(!c.fault_report_pending());
        prop_assert_eq!(c.pending_dropped(), None);
        // What the host sees.
        let (events, stats) = ch.events();
        prop_assert_eq!(stats.gaps_unreported, 0);
        prop_assert!(!events.iter().any(|e| matches!(e, Event::Gap { .. } | Event::Corrupt { .. })), "{:?}", events);
        let pending = c.pending_dropped().map_or(0, |d| u64::from(d.count));
        prop_assert_eq!(stats.samples + stats.dropped_reported + pending, outputs.len() as u64);
        let pending_fault = usize::from(c.fault_report_pending());
        prop_assert_eq!(stats.faults as usize + pending_fault, latches);
        for e in &events {
            if let Event::Sample(s) = e {
                let out = outputs[s.seq as usize];
                prop_assert!(out.is_some(), "sample {} sent for a period no tick saw", s.seq);
                prop_assert_eq!(s.voltages(), &out.unwrap()[..]);
            }
        }
    }
}
