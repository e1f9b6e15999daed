//! The limit as a physical promise: random commands through the controller
//! *and* the output stages, with the board's own constants (`config.rs`:
//! the controller's configuration, the bridge supply, the DAC reference,
//! zero code and amplifier gain; the timers' steps at 25 kHz), and the
//! voltage each stage puts on the strip checked against the limit in force
//! after every tick.
//!
//! - A bridge (slow decay) puts the forward fraction of its period times
//!   the supply on the strip on average: it must not exceed the limit, and
//!   must be within one PWM step of the command.
//! - The bridges' supply may move while the board runs: each tick's reading
//!   goes through the board's [`SupplyMonitor`] to the bridges, or raises
//!   a `Supply` fault that turns them off; the strip's voltage is worked
//!   out on the supply as it truly is.
//! - A DAC segment's amplifier gives the gain times (the DAC's volts − the
//!   0 V code's): the DAC's volts must lie within the output buffer's swing
//!   (a code beyond it would be clipped silently by the buffer), and the
//!   output must not exceed the limit.

use std::cell::Cell;
use std::convert::Infallible;
use std::rc::Rc;

use embedded_hal::pwm::{ErrorType, SetDutyCycle};
use finrs_controller::{
    Controller, DacOutput, DacWrite, FrameSink, HBridge, SegmentOutput, TickInput,
};
use finrs_drive::{Envelope, Limits, Program};
use finrs_firmware_support::config::{
    self, BRIDGE_SUPPLY_V, DAC_BUFFER_MARGIN_V, DAC_GAIN, DAC_VREF_V, DAC_ZERO_CODE, N,
};
use finrs_firmware_support::supply::{self, SupplyMonitor};
use finrs_frames::{Command, FaultCode};
use proptest::prelude::*;

/// TIM1/TIM8 at 168 MHz and TIM2/TIM4 at 84 MHz, counting 25 kHz periods.
const PWM_STEPS: [u16; 2] = [6720, 3360];

/// Held for ever from the start.
const ALWAYS: Envelope = Envelope {
    ramp_in_s: 0.0,
    hold_s: f32::INFINITY,
    ramp_out_s: 0.0,
};

/// A timer channel whose duty the test reads back.
#[derive(Clone)]
struct Leg {
    duty: Rc<Cell<u16>>,
    max: u16,
}

impl ErrorType for Leg {
    type Error = Infallible;
}

impl SetDutyCycle for Leg {
    fn max_duty_cycle(&self) -> u16 {
        self.max
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        assert!(duty <= self.max);
        self.duty.set(duty);
        Ok(())
    }
}

/// A DAC whose code the test reads back.
#[derive(Clone, Default)]
struct Dac(Rc<Cell<u16>>);

impl DacWrite for Dac {
    fn write_code(&mut self, code: u16) {
        self.0.set(code);
    }
}

/// An up channel that takes everything.
struct Sink;

impl FrameSink for Sink {
    fn try_write(&mut self, _: &[u8]) -> bool {
        true
    }
}

/// One bridge on a timer of `max` steps, with its legs' duties.
struct Bridge {
    bridge: HBridge<Leg, Leg>,
    a: Rc<Cell<u16>>,
    b: Rc<Cell<u16>>,
    max: u16,
}

impl Bridge {
    fn new(max: u16) -> Self {
        let (a, b) = (Rc::new(Cell::new(0)), Rc::new(Cell::new(0)));
        let leg = |duty: &Rc<Cell<u16>>| Leg {
            duty: duty.clone(),
            max,
        };
        let bridge = HBridge::new(leg(&a), leg(&b), BRIDGE_SUPPLY_V).unwrap();
        Bridge { bridge, a, b, max }
    }

    /// The average voltage on the strip on the supply `supply_v`: leg A
    /// held high and B high for all but the forward part drives forward,
    /// the other way round reverse, both high 0 V, both low open (no
    /// current: 0 V driven).
    fn on_strip_v(&self, supply_v: f32) -> f32 {
        let (a, b, max) = (self.a.get(), self.b.get(), self.max);
        let forward = |braking: u16| f32::from(max - braking) / f32::from(max) * supply_v;
        match (a == max, b == max) {
            (true, _) => forward(b),
            (false, true) => -forward(a),
            (false, false) => {
                assert_eq!((a, b), (0, 0), "a leg neither held nor off");
                0.0
            }
        }
    }
}

fn program() -> impl Strategy<Value = Program> {
    let v = prop_oneof![4 => -4.5f32..4.5, 1 => -1000.0f32..1000.0];
    prop_oneof![
        (0.0f32..5.0, 0.1f32..20.0, -360.0f32..360.0, -2.0f32..2.0).prop_map(|(a, f, l, o)| {
            Program::Travelling {
                amplitude_v: a,
                frequency_hz: f,
                lag_deg_per_segment: l,
                offset_v: o,
            }
        }),
        prop::array::uniform8(v).prop_map(|levels_v| Program::Steps { levels_v }),
        (0.0f32..5.0, 0.001f32..0.05, 0.001f32..0.05).prop_map(|(a, on, off)| {
            Program::Pulses {
                amplitude_v: a,
                on_s: on,
                off_s: off,
            }
        }),
    ]
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        4 => program().prop_map(|program| Command::SetWave { program, envelope: ALWAYS }),
        1 => (0.05f32..4.5).prop_map(|max_abs_v| Command::SetLimit { max_abs_v }),
        1 => Just(Command::Stop),
    ]
}

/// Runs `ops` (a command, then that many ticks) on a controller with the
/// board's configuration (its starting limit `limit_v`) and checks each
/// stage's voltage on the strip after every tick, the bridges' supply
/// steady at the board's.
fn run(ops: &[(Command, u16)], limit_v: f32) -> Result<(), TestCaseError> {
    run_on(ops, limit_v, &|_| (BRIDGE_SUPPLY_V, 0))
}

/// The divider's reading of `v` at VDDA = the DAC's reference, rounded,
/// `noise` counts off.
fn counts_of(v: f32, noise: i16) -> u16 {
    let exact = supply::bridge_sense_counts(v, DAC_VREF_V);
    ((exact + 0.5) as i32 + i32::from(noise)).clamp(0, 4095) as u16
}

/// [`run`] with the bridges' true supply and its reading's noise in counts
/// at each tick from `supply`: the board's [`SupplyMonitor`] reads it
/// before the controller's tick, and either tells the bridges the supply
/// or raises the `Supply` fault, which holds them off.
fn run_on(
    ops: &[(Command, u16)],
    limit_v: f32,
    supply: &dyn Fn(u64) -> (f32, i16),
) -> Result<(), TestCaseError> {
    let boot = supply::check(DAC_VREF_V, BRIDGE_SUPPLY_V).unwrap();
    let mut monitor = SupplyMonitor::new(boot);
    let mut cfg = config::controller_config().unwrap();
    cfg.limits = Limits::new(limit_v, cfg.limits.slew_v_per_s()).unwrap();
    let mut c = Controller::<N>::new(cfg).unwrap();
    let mut bridges = PWM_STEPS.map(Bridge::new);
    let code = Dac::default();
    let mut dac = DacOutput::new(code.clone(), DAC_GAIN, DAC_VREF_V, DAC_ZERO_CODE).unwrap();
    let volts_per_code = DAC_VREF_V / 4095.0;
    let zero_v = f32::from(DAC_ZERO_CODE) * volts_per_code;
    let mut tick = 0u64;
    for (command, ticks) in ops {
        let _ = c.command(*command);
        for _ in 0..*ticks {
            let (supply_v, noise) = supply(tick);
            let told_v = match monitor.update(counts_of(supply_v, noise)) {
                Ok(duty_supply_v) => {
                    for b in bridges.iter_mut() {
                        b.bridge.set_supply_v(duty_supply_v).unwrap();
                    }
                    Some(duty_supply_v)
                }
                Err(_) => {
                    c.fault(FaultCode::Supply, None, &mut Sink);
                    None
                }
            };
            let input = TickInput {
                tick,
                t_us: (tick * 1000) as u32,
                load_cell_counts: 2048,
                current_counts: [2048; N],
            };
            tick += 1;
            let out = c.tick(&input, &mut Sink).voltages_v;
            let limit = c.limits().max_abs_v();
            let faulted = c.fault_state().is_some();
            prop_assert!(
                told_v.is_some() || faulted,
                "a bad supply reading latched no fault"
            );
            // What the monitor errs low by: its margin, and a supply that
            // fell within the last ticks.
            let low_by = told_v.map_or(0.0, |t| (t - supply_v).max(0.0) / t);
            for &v in &out {
                for b in bridges.iter_mut() {
                    // The board's `write_v`: off while a fault is latched.
                    if faulted {
                        b.bridge.off();
                    } else {
                        b.bridge.set_v(v);
                    }
                    let on_strip = b.on_strip_v(supply_v);
                    if faulted {
                        prop_assert_eq!(on_strip, 0.0);
                        continue;
                    }
                    let step = supply_v / f32::from(b.max) + low_by * v.abs();
                    prop_assert!(
                        on_strip.abs() <= limit * (1.0 + 1e-6),
                        "bridge: {v} V gives {on_strip} V, limit {limit} V"
                    );
                    prop_assert!(
                        (on_strip - v).abs() <= step * 1.0001,
                        "bridge: {v} V gives {on_strip} V"
                    );
                }
                dac.set_v(v);
                let dac_v = f32::from(code.0.get()) * volts_per_code;
                let swing = DAC_BUFFER_MARGIN_V - 1e-6..=DAC_VREF_V - DAC_BUFFER_MARGIN_V + 1e-6;
                prop_assert!(
                    swing.contains(&dac_v),
                    "DAC: {v} V asks for {dac_v} V out of the DAC, beyond its buffer's swing"
                );
                let on_strip = DAC_GAIN * (dac_v - zero_v);
                prop_assert!(
                    on_strip.abs() <= limit * (1.0 + 1e-6),
                    "DAC: {v} V gives {on_strip} V, limit {limit} V"
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The bridges' supply wanders, steps and jumps while the board runs
    /// (a bench supply turned, a battery sagging), its reading a count or
    /// two off: the strip never sees more than the limit.
    #[test]
    fn a_moving_supply_never_puts_more_than_the_limit_on_the_strip(
        ops in prop::collection::vec((command(), 1u16..400), 1..8),
        steps in prop::collection::vec((0u64..3000, 4.4f32..5.7), 0..6),
        noise_seed in any::<u64>(),
    ) {
        let supply = |tick: u64| {
            // The last step at or before `tick`, from the boot's 5 V.
            let v = steps
                .iter()
                .filter(|(at, _)| *at <= tick)
                .max_by_key(|(at, _)| *at)
                .map_or(BRIDGE_SUPPLY_V, |s| s.1);
            let noise = ((noise_seed ^ tick.wrapping_mul(0x9E37_79B9_7F4A_7C15)) % 5) as i16 - 2;
            (v, noise)
        };
        run_on(&ops, config::power_up_limit_v(true), &supply)?;
    }

    /// At the limit a build with DAC segments starts with, so that both
    /// stages run with the same controller.
    #[test]
    fn no_stage_puts_more_than_the_limit_on_the_strip(
        ops in prop::collection::vec((command(), 1u16..400), 1..12),
    ) {
        run(&ops, config::power_up_limit_v(true))?;
    }
}

/// At the bridges' 4 V a DAC segment would ask beyond its buffer's swing:
/// the check above can fail, and a build with a DAC segment must start
/// below it.
#[test]
fn a_dac_segment_at_4_v_would_be_clipped_by_its_buffer() {
    let (reach, max) = (config::DAC_REACH_V, config::MAX_ABS_V);
    assert!(reach < max && (reach - 3.64).abs() < 0.01, "{reach} V");
    assert_eq!(config::power_up_limit_v(false), config::MAX_ABS_V);
    assert_eq!(config::power_up_limit_v(true), config::DAC_REACH_V);
    let steps = Command::SetWave {
        program: Program::Steps { levels_v: [4.0; 8] },
        envelope: ALWAYS,
    };
    let failed = run(&[(steps, 300)], config::MAX_ABS_V).unwrap_err();
    assert!(
        failed.to_string().contains("beyond its buffer's swing"),
        "{failed}"
    );
}
