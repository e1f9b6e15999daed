//! Voltage and slew limits, and the [`Limiter`] that enforces them.
//!
//! The limiter is the one place where a voltage limit is enforced: every
//! voltage the firmware writes to a segment's driver is an output of
//! [`Limiter::apply`] (or the zeros of [`Limiter::stop`]). Programs, the
//! host and the generator may ask for anything; nothing else clips.

use core::fmt;

/// Absolute ceiling of any voltage limit, V: the safe range of the seed's
/// Nafion strips (electrolysis of the water in the strip starts above it).
pub const HARD_LIMIT_V: f32 = 4.0;

/// Why a limit was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitError {
    /// `max_abs_v` is NaN or infinite.
    MaxAbsNotFinite,
    /// `max_abs_v` is zero or negative.
    MaxAbsNotPositive,
    /// `max_abs_v` is above [`HARD_LIMIT_V`].
    MaxAbsAboveHardLimit,
    /// `max_abs_v` would rise: a limit can only be lowered in place.
    MaxAbsRaised,
    /// `slew_v_per_s` is NaN or infinite.
    SlewNotFinite,
    /// `slew_v_per_s` is zero or negative.
    SlewNotPositive,
}

impl fmt::Display for LimitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LimitError::MaxAbsNotFinite => "max_abs_v must be finite",
            LimitError::MaxAbsNotPositive => "max_abs_v must be above 0",
            LimitError::MaxAbsAboveHardLimit => "max_abs_v must not exceed HARD_LIMIT_V (4 V)",
            LimitError::MaxAbsRaised => "max_abs_v can only be lowered",
            LimitError::SlewNotFinite => "slew_v_per_s must be finite",
            LimitError::SlewNotPositive => "slew_v_per_s must be above 0",
        })
    }
}

/// Validated limits: |V| ≤ `max_abs_v` ≤ [`HARD_LIMIT_V`], |dV/dt| ≤
/// `slew_v_per_s`. The fields are private so that no invalid value can
/// reach the [`Limiter`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    max_abs_v: f32,
    slew_v_per_s: f32,
}

impl Limits {
    /// Checks both limits: finite, above zero, and `max_abs_v` at most
    /// [`HARD_LIMIT_V`].
    pub fn new(max_abs_v: f32, slew_v_per_s: f32) -> Result<Self, LimitError> {
        check_max_abs_v(max_abs_v)?;
        if !slew_v_per_s.is_finite() {
            return Err(LimitError::SlewNotFinite);
        }
        if slew_v_per_s <= 0.0 {
            return Err(LimitError::SlewNotPositive);
        }
        Ok(Limits {
            max_abs_v,
            slew_v_per_s,
        })
    }

    /// Largest magnitude of an output, V.
    pub fn max_abs_v(&self) -> f32 {
        self.max_abs_v
    }

    /// Largest rate of change of an output, V/s.
    pub fn slew_v_per_s(&self) -> f32 {
        self.slew_v_per_s
    }

    /// Lowers `max_abs_v` (or keeps it, if equal). Raising is refused: a
    /// running firmware may tighten its limit (say on a host's request) but
    /// only a new [`Limits`] can loosen it.
    pub fn set_max_abs_v_lower(&mut self, max_abs_v: f32) -> Result<(), LimitError> {
        check_max_abs_v(max_abs_v)?;
        if max_abs_v > self.max_abs_v {
            return Err(LimitError::MaxAbsRaised);
        }
        self.max_abs_v = max_abs_v;
        Ok(())
    }
}

fn check_max_abs_v(v: f32) -> Result<(), LimitError> {
    if !v.is_finite() {
        Err(LimitError::MaxAbsNotFinite)
    } else if v <= 0.0 {
        Err(LimitError::MaxAbsNotPositive)
    } else if v > HARD_LIMIT_V {
        Err(LimitError::MaxAbsAboveHardLimit)
    } else {
        Ok(())
    }
}

/// What [`Limiter::apply_reporting`] did to a step's requests, over all
/// segments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Applied {
    /// A request beyond the voltage limit was clamped to it.
    pub clamped: bool,
    /// An output was held short of its target by the slew limit.
    pub slewed: bool,
}

/// Enforces [`Limits`] on the voltages of `N` segments, step by step.
///
/// Every voltage sent to the hardware must come out of [`Limiter::apply`]
/// or [`Limiter::stop`]: this is the only place a limit is enforced.
#[derive(Clone, Debug)]
pub struct Limiter<const N: usize> {
    limits: Limits,
    last_v: [f32; N],
}

impl<const N: usize> Limiter<N> {
    /// A limiter whose outputs start at 0 V (the driver's power-up state).
    pub fn new(limits: Limits) -> Self {
        const { assert!(N >= 1 && N <= crate::MAX_SEGMENTS) };
        Limiter {
            limits,
            last_v: [0.0; N],
        }
    }

    /// The limits in force.
    pub fn limits(&self) -> Limits {
        self.limits
    }

    /// The limits, to lower with [`Limits::set_max_abs_v_lower`]. A lower
    /// bound takes effect at the next [`Limiter::apply`], at once: the
    /// voltage bound wins over the slew bound.
    pub fn limits_mut(&mut self) -> &mut Limits {
        &mut self.limits
    }

    /// The last outputs, V.
    pub fn last_v(&self) -> [f32; N] {
        self.last_v
    }

    /// Moves each output toward `wanted_v`, clamped to ±`max_abs_v`, by at
    /// most `slew_v_per_s · dt_s`, and returns the outputs.
    ///
    /// A wanted value that is NaN or infinite is a request for 0 V (still
    /// slew-limited): a broken program never reaches the driver. A `dt_s`
    /// that is not finite and above zero is a caller's timing fault: every
    /// request becomes 0 V, and since no known time has passed the outputs
    /// do not move (call [`Limiter::stop`] to drop them at once).
    pub fn apply(&mut self, wanted_v: [f32; N], dt_s: f32) -> [f32; N] {
        self.apply_reporting(wanted_v, dt_s).0
    }

    /// [`Limiter::apply`], saying also what the limits did to the step: a
    /// finite request beyond ±`max_abs_v` was clamped, or an output stopped
    /// short of its (clamped) target at the slew limit.
    pub fn apply_reporting(&mut self, wanted_v: [f32; N], dt_s: f32) -> ([f32; N], Applied) {
        let mut applied = Applied::default();
        let max = self.limits.max_abs_v;
        let timing_ok = dt_s.is_finite() && dt_s > 0.0;
        // Overflow to +inf for huge dt is fine: the step is then unbounded.
        let step = if timing_ok {
            self.limits.slew_v_per_s * dt_s
        } else {
            0.0
        };
        for (last, wanted) in self.last_v.iter_mut().zip(wanted_v) {
            let target = if timing_ok && wanted.is_finite() {
                clamp(wanted, max)
            } else {
                0.0
            };
            applied.clamped |= timing_ok && wanted.is_finite() && target != wanted;
            let moved = *last + clamp(target - *last, step);
            // Clamp again: a lowered limit applies at once, and the sum
            // above may round an ulp past the target.
            *last = clamp(moved, max);
            applied.slewed |= *last != target;
        }
        (self.last_v, applied)
    }

    /// Fault stop: every output to 0 V at once, bypassing the slew limit.
    pub fn stop(&mut self) -> [f32; N] {
        self.last_v = [0.0; N];
        self.last_v
    }
}

/// `v` clamped to ±`bound` (`bound` ≥ 0, not NaN; `v` not NaN).
fn clamp(v: f32, bound: f32) -> f32 {
    if v > bound {
        bound
    } else if v < -bound {
        -bound
    } else {
        v
    }
}
