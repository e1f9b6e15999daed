//! Segment outputs: an H-bridge from two PWM outputs (slow decay) or a
//! DAC into a bipolar amplifier. They take voltages that the
//! [`Limiter`](finrs_drive::Limiter) has already limited, yet still clamp
//! to their own physical range and never panic.
//!
//! ```
//! use core::convert::Infallible;
//! use embedded_hal::pwm::{ErrorType, SetDutyCycle};
//! use finrs_controller::{HBridge, SegmentOutput};
//!
//! struct Pwm(u16);
//! impl ErrorType for Pwm {
//!     type Error = Infallible;
//! }
//! impl SetDutyCycle for Pwm {
//!     fn max_duty_cycle(&self) -> u16 {
//!         1000
//!     }
//!     fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
//!         self.0 = duty;
//!         Ok(())
//!     }
//! }
//!
//! let mut bridge = HBridge::new(Pwm(0), Pwm(0), 8.0).unwrap();
//! // A quarter of the supply, reversed: leg B held on, leg A braking for
//! // the other three quarters of each period.
//! bridge.set_v(-2.0);
//! let (a, b) = bridge.release();
//! assert_eq!((a.0, b.0), (750, 1000));
//! ```

use core::fmt;

use embedded_hal::pwm::SetDutyCycle;

/// A segment's driver.
pub trait SegmentOutput {
    /// Drives the segment at `v` volts (already limited). A value outside
    /// the driver's range is clamped to it; NaN turns the output off.
    fn set_v(&mut self, v: f32);
    /// Turns the segment off (0 V).
    fn off(&mut self);
}

/// A refused output configuration: which field, which rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutputError {
    /// The field, e.g. `"supply_v"`.
    pub field: &'static str,
    /// The rule it breaks, in words.
    pub rule: &'static str,
}

impl fmt::Display for OutputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.field, self.rule)
    }
}

impl core::error::Error for OutputError {}

fn abs(v: f32) -> f32 {
    if v < 0.0 {
        -v
    } else {
        v
    }
}

/// A supply a bridge can work duties out from: finite and above 0.
fn valid_supply(supply_v: f32) -> Result<(), OutputError> {
    if !supply_v.is_finite() {
        return Err(OutputError {
            field: "supply_v",
            rule: "must be finite",
        });
    }
    if supply_v <= 0.0 {
        return Err(OutputError {
            field: "supply_v",
            rule: "must be above 0",
        });
    }
    Ok(())
}

/// `x` (finite or infinite) clamped to `0..=max` and rounded down.
fn floor_clamped(x: f32, max: u16) -> u16 {
    let max_f = f32::from(max);
    if x >= max_f {
        max
    } else if x > 0.0 {
        // 0 < x < 65535: the cast truncates, which is the floor.
        x as u16
    } else {
        0
    }
}

/// An H-bridge of an IN1/IN2 driver (DRV8833 class: IN 1/0 drives OUT1
/// high and OUT2 low, 0/1 the reverse, 1/1 both low, 0/0 both open) driven
/// in slow decay: for positive volts leg A is held fully on and leg B
/// carries the PWM, low for the fraction |v| / `supply_v` of each period
/// (forward) and high for the rest (both outputs low: the strip's terminals
/// shorted); negative volts the other way round; 0 V both on (held at 0 V).
/// The terminals are driven at every instant, so their average over a
/// period is that fraction × `supply_v`, whatever the strip does. The
/// fraction is rounded down to a whole step, never above |v| / `supply_v`,
/// and a |v| above `supply_v` is clamped to full drive.
///
/// Slow decay, not the coast of one leg low and the other PWM'd: in the
/// off-time a coasting bridge leaves the strip open, and the strip, mostly
/// a capacitor, keeps its charge, so its terminal voltage averages well
/// above the duty × supply (a host simulation of the switching,
/// `firmware/support/tests/bridge_decay.rs`, measures both).
///
/// [`off`](SegmentOutput::off) opens both outputs (both inputs low: the
/// state the driver's pull-downs give an unprogrammed or reset MCU, and the
/// one the fault handlers force by register writes): no current flows, and
/// the strip's terminals float at most at the charge it holds.
///
/// PWM errors cannot be returned through [`SegmentOutput`]: on one, the
/// bridge tries to open both outputs and counts it
/// ([`errors`](Self::errors)), for the firmware to report.
#[derive(Debug)]
pub struct HBridge<A: SetDutyCycle, B: SetDutyCycle> {
    a: A,
    b: B,
    supply_v: f32,
    errors: u32,
}

impl<A: SetDutyCycle, B: SetDutyCycle> HBridge<A, B> {
    /// A bridge on the supply `supply_v` (finite, above 0), turned off.
    pub fn new(a: A, b: B, supply_v: f32) -> Result<Self, OutputError> {
        valid_supply(supply_v)?;
        let mut bridge = Self {
            a,
            b,
            supply_v,
            errors: 0,
        };
        bridge.off();
        Ok(bridge)
    }

    /// The bridge's supply, V.
    pub fn supply_v(&self) -> f32 {
        self.supply_v
    }

    /// The supply as measured now, V (finite, above 0): the next
    /// [`set_v`](SegmentOutput::set_v) works its duty out from it. Every
    /// volt on the strip is a fraction of the supply, so a supply that
    /// rose since the bridge was made would put more than the command on
    /// the strip. Refused, the supply kept, if it breaks a rule.
    pub fn set_supply_v(&mut self, supply_v: f32) -> Result<(), OutputError> {
        valid_supply(supply_v)?;
        self.supply_v = supply_v;
        Ok(())
    }

    /// PWM errors met so far.
    pub fn errors(&self) -> u32 {
        self.errors
    }

    /// The two PWM outputs back, A then B.
    pub fn release(self) -> (A, B) {
        (self.a, self.b)
    }

    /// The PWM'd leg's duty for `magnitude_v`: high (braking) for all but
    /// the forward steps, which are rounded down.
    fn braking_duty(pwm: &impl SetDutyCycle, magnitude_v: f32, supply_v: f32) -> u16 {
        let max = pwm.max_duty_cycle();
        max - floor_clamped(magnitude_v / supply_v * f32::from(max), max)
    }

    fn failed(&mut self) {
        self.errors = self.errors.saturating_add(1);
        // Best effort: nothing more can be done from here.
        let _ = self.a.set_duty_cycle_fully_off();
        let _ = self.b.set_duty_cycle_fully_off();
    }
}

impl<A: SetDutyCycle, B: SetDutyCycle> SegmentOutput for HBridge<A, B> {
    fn set_v(&mut self, v: f32) {
        if v.is_nan() {
            return self.off();
        }
        // The held leg first: between the two writes the bridge brakes (both
        // outputs low), never drives the other way.
        // Forward is IN1 (leg A) high with IN2 (leg B) low.
        let ok = if v >= 0.0 {
            let duty = Self::braking_duty(&self.b, v, self.supply_v);
            self.a.set_duty_cycle_fully_on().is_ok() && self.b.set_duty_cycle(duty).is_ok()
        } else {
            let duty = Self::braking_duty(&self.a, abs(v), self.supply_v);
            self.b.set_duty_cycle_fully_on().is_ok() && self.a.set_duty_cycle(duty).is_ok()
        };
        if !ok {
            self.failed();
        }
    }

    fn off(&mut self) {
        let a = self.a.set_duty_cycle_fully_off().is_ok();
        let b = self.b.set_duty_cycle_fully_off().is_ok();
        if !(a && b) {
            self.failed();
        }
    }
}

/// A 12-bit DAC's code register.
pub trait DacWrite {
    /// Writes `code` (0..=4095) to the DAC.
    fn write_code(&mut self, code: u16);
}

/// Largest 12-bit DAC code.
pub const DAC_MAX_CODE: u16 = 4095;

/// A 12-bit DAC into a bipolar amplifier (for up to 2 segments on the
/// STM32F407): code = `zero_code` + v / (`gain` · `vref_v` / 4095),
/// rounded toward `zero_code` (never more than |v|) and clamped to
/// 0..=4095. Off writes `zero_code`.
#[derive(Debug)]
pub struct DacOutput<D: DacWrite> {
    dac: D,
    /// Volts at the segment per DAC code step.
    volts_per_code: f32,
    zero_code: u16,
}

impl<D: DacWrite> DacOutput<D> {
    /// A DAC output: `gain` is the amplifier's output volts per DAC volt
    /// (finite, not zero; negative for an inverting amplifier), `vref_v` the
    /// DAC's reference (finite, above 0), `zero_code` the code of 0 V at the
    /// segment (0..=4095). Starts off.
    pub fn new(dac: D, gain: f32, vref_v: f32, zero_code: u16) -> Result<Self, OutputError> {
        if !gain.is_finite() || gain == 0.0 {
            return Err(OutputError {
                field: "gain",
                rule: "must be finite and not 0",
            });
        }
        if !vref_v.is_finite() || vref_v <= 0.0 {
            return Err(OutputError {
                field: "vref_v",
                rule: "must be finite and above 0",
            });
        }
        if zero_code > DAC_MAX_CODE {
            return Err(OutputError {
                field: "zero_code",
                rule: "must be at most 4095",
            });
        }
        let mut out = Self {
            dac,
            volts_per_code: gain * vref_v / f32::from(DAC_MAX_CODE),
            zero_code,
        };
        out.off();
        Ok(out)
    }

    /// The DAC back.
    pub fn release(self) -> D {
        self.dac
    }
}

impl<D: DacWrite> SegmentOutput for DacOutput<D> {
    fn set_v(&mut self, v: f32) {
        if v.is_nan() {
            return self.off();
        }
        // Toward the 0 V code, so that a code never asks more than |v|: the
        // cast truncates, and saturates ±inf onto a rail through the clamp.
        let offset = (v / self.volts_per_code) as i32;
        let code = i32::from(self.zero_code)
            .saturating_add(offset)
            .clamp(0, i32::from(DAC_MAX_CODE));
        // 0..=4095 after the clamp.
        self.dac.write_code(code as u16);
    }

    fn off(&mut self) {
        self.dac.write_code(self.zero_code);
    }
}
