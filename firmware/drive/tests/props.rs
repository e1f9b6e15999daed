//! Properties over arbitrary input, built from arbitrary f32 bits (NaN,
//! infinities, negative, huge and subnormal numbers included): the limiter
//! never lets a voltage past its bounds, and nothing panics.

use finrs_drive::{Envelope, Generator, Limiter, Limits, Program, HARD_LIMIT_V};
use proptest::prelude::*;

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => any::<u32>().prop_map(f32::from_bits),
        1 => prop::sample::select(vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            1e-45,
            4.0,
            100.0,
        ]),
        3 => -10.0f32..10.0,
        2 => 0.0f32..120.0,
    ]
}

fn program() -> impl Strategy<Value = Program> {
    (0..7u8, prop::array::uniform8(any_f32())).prop_map(|(kind, v)| match kind {
        0 => Program::Travelling {
            amplitude_v: v[0],
            frequency_hz: v[1],
            lag_deg_per_segment: v[2],
            offset_v: v[3],
        },
        1 => Program::Standing {
            amplitude_v: v[0],
            frequency_hz: v[1],
            offset_v: v[2],
        },
        2 => Program::Steps { levels_v: v },
        3 => Program::Pulses {
            amplitude_v: v[0],
            on_s: v[1],
            off_s: v[2],
        },
        4 => Program::Chirp {
            amplitude_v: v[0],
            start_hz: v[1],
            end_hz: v[2],
            duration_s: v[3],
        },
        5 => Program::Harmonic {
            frequency_hz: v[0],
            offset_v: v[1],
            amplitudes_v: v,
            phases_deg: [v[7], v[6], v[5], v[4], v[3], v[2], v[1], v[0]],
        },
        _ => Program::HeldStep {
            levels_v: v,
            rise_s: v[7],
            pole_per_s: v[6],
            zero_per_s: v[5],
        },
    })
}

fn envelope() -> impl Strategy<Value = Envelope> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(ramp_in_s, hold_s, ramp_out_s)| Envelope {
        ramp_in_s,
        hold_s,
        ramp_out_s,
    })
}

/// One call of the firmware's loop.
#[derive(Clone, Debug)]
struct Step {
    t_s: f32,
    tick: u64,
    tick_hz: u32,
    by_tick: bool,
    dt_s: f32,
    /// Asked directly instead of the generator's output.
    direct: Option<[f32; 8]>,
    stop: bool,
}

fn step() -> impl Strategy<Value = Step> {
    (
        any_f32(),
        (
            prop_oneof![any::<u64>(), 0..100_000_000_000u64],
            prop_oneof![any::<u32>(), 1..100_000u32],
            any::<bool>(),
        ),
        prop_oneof![3 => 1e-5f32..0.1, 1 => any_f32()],
        prop::option::weighted(0.3, prop::array::uniform8(any_f32())),
        prop::bool::weighted(0.05),
    )
        .prop_map(|(t_s, (tick, tick_hz, by_tick), dt_s, direct, stop)| Step {
            t_s,
            tick,
            tick_hz,
            by_tick,
            dt_s,
            direct,
            stop,
        })
}

fn run<const N: usize>(
    program: Program,
    envelope: Envelope,
    (max_abs_v, slew_v_per_s): (f32, f32),
    steps: &[Step],
) -> Result<(), TestCaseError> {
    // A refused configuration falls back to 0 V, as the firmware does.
    let generator = Generator::<N>::new(program, envelope).ok();
    let limits = match Limits::new(max_abs_v, slew_v_per_s) {
        Ok(l) => {
            prop_assert!(l.max_abs_v() > 0.0 && l.max_abs_v() <= HARD_LIMIT_V);
            prop_assert!(l.slew_v_per_s() > 0.0 && l.slew_v_per_s().is_finite());
            l
        }
        Err(_) => Limits::new(HARD_LIMIT_V, 1.0).unwrap(),
    };
    let (max, slew) = (limits.max_abs_v() as f64, limits.slew_v_per_s() as f64);
    let mut limiter = Limiter::<N>::new(limits);
    let mut before = [0.0f32; N];
    for s in steps {
        let wanted = match (s.direct, &generator) {
            (Some(direct), _) => core::array::from_fn(|k| direct[k]),
            (None, Some(g)) => {
                let v = if s.by_tick {
                    g.voltages_at_tick_v(s.tick, s.tick_hz)
                } else {
                    g.voltages_v(s.t_s)
                };
                // A valid program asks for finite voltages at any time.
                prop_assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
                v
            }
            (None, None) => [0.0; N],
        };
        if s.stop {
            before = limiter.stop();
            prop_assert_eq!(before, [0.0; N]);
            continue;
        }
        let out = limiter.apply(wanted, s.dt_s);
        let dt_ok = s.dt_s.is_finite() && s.dt_s > 0.0;
        for (&v, &b) in out.iter().zip(&before) {
            prop_assert!(!v.is_nan());
            prop_assert!((v as f64).abs() <= max, "{v} beyond ±{max}");
            let change = (v as f64 - b as f64).abs();
            if dt_ok {
                let allowed = slew * s.dt_s as f64;
                prop_assert!(
                    change <= allowed * (1.0 + 1e-6) + 1e-6,
                    "moved {change} V in {} s at {slew} V/s",
                    s.dt_s
                );
            } else {
                prop_assert_eq!(change, 0.0);
            }
        }
        prop_assert_eq!(limiter.last_v(), out);
        before = out;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn limiter_output_stays_within_bounds_whatever_is_asked(
        program in program(),
        envelope in envelope(),
        limits in prop_oneof![
            (any_f32(), any_f32()),
            (1e-3f32..=4.0, 1e-3f32..1e5),
        ],
        steps in prop::collection::vec(step(), 1..64),
    ) {
        run::<1>(program, envelope, limits, &steps)?;
        run::<3>(program, envelope, limits, &steps)?;
        run::<8>(program, envelope, limits, &steps)?;
    }

    /// Valid programs, so that the generator's outputs (not only the direct
    /// requests) are what the limiter sees.
    #[test]
    fn limiter_bounds_valid_programs_too(
        kind in 0..7u8,
        amplitude_v in 0.0f32..20.0,
        frequency_hz in 0.001f32..100.0,
        offset_v in -5.0f32..5.0,
        ramp_in_s in 0.0f32..2.0,
        limits in (1e-3f32..=4.0, 1e-3f32..1e3),
        steps in prop::collection::vec(step(), 1..64),
    ) {
        let program = match kind {
            0 => Program::Travelling { amplitude_v, frequency_hz, lag_deg_per_segment: 120.0, offset_v },
            1 => Program::Standing { amplitude_v, frequency_hz, offset_v },
            2 => Program::Steps { levels_v: [offset_v, -amplitude_v, amplitude_v, 0.0, 1.0, -1.0, 3.5, -3.5] },
            3 => Program::Pulses { amplitude_v, on_s: 1.0 / frequency_hz, off_s: 0.5 },
            4 => Program::Chirp { amplitude_v, start_hz: frequency_hz.max(0.002) * 0.5, end_hz: frequency_hz, duration_s: 10.0 },
            5 => Program::Harmonic {
                frequency_hz,
                offset_v,
                amplitudes_v: [amplitude_v, 0.5 * amplitude_v, 0.0, 3.5, 1.0, 2.0, amplitude_v, 0.1],
                phases_deg: [0.0, -60.0, 721.0, 90.0, -1e4, 33.0, 180.0, -180.0],
            },
            // A creep's start (z/p up to 41), its rise the ramp's.
            _ => Program::HeldStep {
                levels_v: [offset_v, -amplitude_v, amplitude_v, 0.0, 1.0, -1.0, 3.5, -3.5],
                rise_s: ramp_in_s,
                pole_per_s: 0.1,
                zero_per_s: 0.1 + 0.04 * frequency_hz,
            },
        };
        let envelope = Envelope { ramp_in_s, hold_s: f32::INFINITY, ramp_out_s: 0.0 };
        prop_assert!(Generator::<8>::new(program, envelope).is_ok());
        run::<8>(program, envelope, limits, &steps)?;
    }
}

proptest! {
    /// A held step accepted with any rise, pole and zero over wide ranges
    /// (a zero at infinity too) asks finite voltages at any time, within
    /// its peak.
    #[test]
    fn a_held_step_asks_finite_voltages_within_its_peak(
        rise_s in prop_oneof![Just(0.0f32), 1e-6f32..1e4],
        pole_per_s in 1e-6f32..1e6,
        zero_per_s in prop_oneof![1e-6f32..1e6, Just(f32::INFINITY)],
        level_v in -10.0f32..10.0,
        t_s in prop_oneof![0.0f32..1e-3, 0.0f32..1e4, any::<f32>()],
    ) {
        let program = Program::HeldStep {
            levels_v: [level_v, -level_v, 0.5 * level_v, 0.0, 0.0, 0.0, 0.0, 0.0],
            rise_s,
            pole_per_s,
            zero_per_s,
        };
        let envelope = Envelope { ramp_in_s: 0.0, hold_s: f32::INFINITY, ramp_out_s: 0.0 };
        if let Ok(g) = Generator::<3>::new(program, envelope) {
            let v = g.voltages_v(t_s);
            prop_assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
            let peak = g.peak_abs_v();
            prop_assert!(v.iter().all(|x| x.abs() <= peak * 1.001 + 1e-6), "{v:?} above {peak}");
        }
    }
}
