//! Open-loop wave programs and the [`Generator`] that evaluates them.
//!
//! A drive is a [`Program`] (what each segment does) times an [`Envelope`]
//! (a gain from 0 to 1 and back, with raised-cosine ramps) at the time since
//! the program started. Segments are numbered from 0 at the fin's root.
//!
//! The generator asks, it does not limit: its outputs go through a
//! [`Limiter`](crate::Limiter), the only place where the voltage and slew
//! limits are enforced.

use core::f32::consts::{PI, TAU};
use core::fmt;

use micromath::F32Ext;

use crate::math;

/// Lowest frequency of a program, Hz: a slower wave is a step.
pub const MIN_FREQUENCY_HZ: f32 = 1e-3;
/// Highest frequency of a program, Hz: far above the strip's response.
pub const MAX_FREQUENCY_HZ: f32 = 100.0;
/// Largest magnitude of a voltage in a program, V. Not a safety limit (that
/// is the limiter's): a bound that keeps every sum in the generator finite
/// and catches typing errors.
pub const MAX_PROGRAM_V: f32 = 1000.0;
/// Smallest rise (s) and smallest pole or zero (1/s) of a held step: a
/// strip's are milliseconds and hundredths of a second or more, and the
/// closed form stays finite in `f32` above this (`π/T` and `ω/z` bounded).
pub const MIN_HELD_STEP: f32 = 1e-6;

/// What each segment does. The host's one `--wave` parser (`finrs::wave`)
/// maps its texts onto these kinds one to one (`step:` → `Steps`, `sine:`
/// → `Travelling`, `standing:` → `Standing`, `chirp:` → `Chirp`,
/// `pulses:` → `Pulses`, `harmonic:` → `Harmonic`; `HeldStep` comes only
/// from a `motion-step:` through the strip's model), and the host
/// evaluates them with this generator too: `finrs simulate` and the
/// firmware drive the same voltages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Program {
    /// Travelling sine: segment k gets `offset_v + amplitude_v · sin(2π
    /// frequency_hz t − k · lag)`, so the wave runs from root to tip for a
    /// positive lag (as the host's `sine:`).
    Travelling {
        /// Amplitude, V (≥ 0).
        amplitude_v: f32,
        /// Frequency, Hz.
        frequency_hz: f32,
        /// Phase lag of each segment behind the one before it, degrees.
        lag_deg_per_segment: f32,
        /// Constant added to every segment, V.
        offset_v: f32,
    },
    /// Standing wave, every segment in phase or in antiphase: segment k of
    /// N gets `offset_v + amplitude_v · cos(π k/(N − 1)) · sin(2π
    /// frequency_hz t)`, half a wavelength along the fin with its node in
    /// the middle: root and tip segments in antiphase, the root at full
    /// amplitude (a single segment is the root).
    Standing {
        /// Amplitude at the root and tip, V (≥ 0).
        amplitude_v: f32,
        /// Frequency, Hz.
        frequency_hz: f32,
        /// Constant added to every segment, V.
        offset_v: f32,
    },
    /// Constant voltage per segment (the host's `step:`); levels beyond the
    /// generator's N segments are ignored.
    Steps {
        /// Voltage of each segment, V.
        levels_v: [f32; 8],
    },
    /// Pulse train on every segment: `on_s` at the amplitude, then `off_s`
    /// at 0 V, starting with on at t = 0 (the seed's 20 s pulses).
    Pulses {
        /// Voltage while on, V (≥ 0).
        amplitude_v: f32,
        /// Time on, s (≥ 0).
        on_s: f32,
        /// Time off, s (≥ 0; `on_s + off_s` above 0).
        off_s: f32,
    },
    /// Logarithmic chirp, every segment in phase: frequency
    /// `start_hz · (end_hz/start_hz)^(τ/duration_s)` and phase 0 at τ = 0,
    /// τ the time since the sweep began. The sweep starts again every
    /// `duration_s`; the jump at each restart is smoothed by the limiter's
    /// slew limit. Restarting also bounds the phase: in f32 it is off by
    /// up to about 1e-6 of a sweep's cycles (the exponent's rounding, which
    /// the exponential amplifies), 2.4e-4 cycle for 0.05 → 100 Hz in 30 s.
    Chirp {
        /// Amplitude, V (≥ 0).
        amplitude_v: f32,
        /// Frequency at the start of a sweep, Hz.
        start_hz: f32,
        /// Frequency at the end of a sweep, Hz (above `start_hz`).
        end_hz: f32,
        /// Length of one sweep, s (above 0).
        duration_s: f32,
    },
    /// Each segment its own sine at one frequency: segment k gets
    /// `offset_v + amplitudes_v[k] · sin(2π frequency_hz t + phases_deg[k])`.
    /// What a wave shaped by the strip's model asks: a travelling bending
    /// wave through segments that differ needs each its own amplitude and
    /// phase (`model_core::Strip::tip_wave`). Entries beyond the
    /// generator's N segments are ignored.
    Harmonic {
        /// Frequency, Hz.
        frequency_hz: f32,
        /// Constant added to every segment, V.
        offset_v: f32,
        /// Each segment's amplitude, V (≥ 0).
        amplitudes_v: [f32; 8],
        /// Each segment's phase, degrees (ahead for a positive one).
        phases_deg: [f32; 8],
    },
    /// A step held against the strip's relaxation (`motion-step:`,
    /// `model_core::Strip::tip_step`): segment k gets `levels_v[k] · y(t)`,
    /// `y` the inverse of a relaxation `(s + z)/(s + p)` (pole `p`, zero
    /// `z`) applied to a raised-cosine rise `ρ` from 0 to 1 over `rise_s`:
    /// `y = ρ + (z − p)/p · (e^{−z t} ∗ ρ′)`, in closed form. `y` ends at 1;
    /// it starts above it for a creep (`z > p`: more voltage while the
    /// moment has not yet grown) and below it for a partial relaxation.
    /// Entries beyond the generator's N segments are ignored.
    HeldStep {
        /// Each segment's voltage once settled, V.
        levels_v: [f32; 8],
        /// Length of the raised-cosine rise, s (0, or at least
        /// [`MIN_HELD_STEP`]; not 0 for `z = ∞`).
        rise_s: f32,
        /// The relaxation's pole `p`, 1/s (at least [`MIN_HELD_STEP`]).
        pole_per_s: f32,
        /// Its zero `z`, 1/s (at least [`MIN_HELD_STEP`]; `+∞` for a pure
        /// lag, whose inverse is `ρ + ρ′/p`).
        zero_per_s: f32,
    },
}

/// The gain over the program: 0 → 1 over `ramp_in_s`, 1 for `hold_s`,
/// 1 → 0 over `ramp_out_s`, then 0. Ramps are raised cosines (½ − ½ cos),
/// whose slope is 0 at both ends so the strip is not jerked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Envelope {
    /// Time to full amplitude, s (≥ 0, finite).
    pub ramp_in_s: f32,
    /// Time at full amplitude, s (≥ 0; `f32::INFINITY` for ever).
    pub hold_s: f32,
    /// Time from full amplitude to zero, s (≥ 0, finite).
    pub ramp_out_s: f32,
}

impl Envelope {
    /// Full gain from the start, for ever: the program as it is.
    pub const STEADY: Envelope = Envelope {
        ramp_in_s: 0.0,
        hold_s: f32::INFINITY,
        ramp_out_s: 0.0,
    };
}

/// The rule a field of a program or envelope breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WaveRule {
    /// Must be finite (not NaN nor infinite).
    Finite,
    /// Must not be NaN (+∞ allowed).
    NotNan,
    /// Must be at least 0.
    NonNegative,
    /// Must be above 0.
    Positive,
    /// Magnitude must be at most [`MAX_PROGRAM_V`].
    ProgramRange,
    /// Must be within [`MIN_FREQUENCY_HZ`]..=[`MAX_FREQUENCY_HZ`].
    FrequencyRange,
    /// Must be above the chirp's `start_hz`.
    AboveStart,
    /// Must be at least [`MIN_HELD_STEP`] (a rate, 1/s).
    AtLeastMin,
    /// Must be 0 or at least [`MIN_HELD_STEP`] (a time, s).
    ZeroOrAtLeastMin,
}

/// A refused program or envelope: which field, which rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WaveError {
    /// The field, e.g. `"Travelling.frequency_hz"`.
    pub field: &'static str,
    /// The rule it breaks.
    pub rule: WaveRule,
}

impl fmt::Display for WaveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rule = match self.rule {
            WaveRule::Finite => "must be finite",
            WaveRule::NotNan => "must not be NaN",
            WaveRule::NonNegative => "must be at least 0",
            WaveRule::Positive => "must be above 0",
            WaveRule::ProgramRange => "must be within ±1000 V",
            WaveRule::FrequencyRange => "must be within 0.001..=100 Hz",
            WaveRule::AboveStart => "must be above start_hz",
            WaveRule::AtLeastMin => "must be at least 1e-6",
            WaveRule::ZeroOrAtLeastMin => "must be 0 or at least 1e-6",
        };
        write!(f, "{} {rule}", self.field)
    }
}

/// The fin's everyday gait, and the wave the QEMU run asks for: a
/// travelling wave of 2.0 V at 1 Hz, 120° lag per segment, no offset,
/// ramped in over 1 s and run for ever. The firmware does not start it by
/// itself: it boots stopped.
pub fn default_program() -> (Program, Envelope) {
    (
        Program::Travelling {
            amplitude_v: 2.0,
            frequency_hz: 1.0,
            lag_deg_per_segment: 120.0,
            offset_v: 0.0,
        },
        Envelope {
            ramp_in_s: 1.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
    )
}

/// Evaluates a validated program for `N` segments (1..=8) at any time.
///
/// Time is split into whole seconds (u32) and a fraction, and each part's
/// share of a phase is reduced modulo one cycle (or one period) exactly
/// before the parts are added; so the phase error stays near 1e-7 cycle
/// after hours or days, where `2π f t` in f32 would be off by 0.01 rad
/// after ten hours. No state is kept: outputs depend on the time alone.
#[derive(Clone, Debug)]
pub struct Generator<const N: usize> {
    program: Program,
    envelope: Envelope,
    /// Travelling and Harmonic: each segment's lag in cycles, in [0, 1).
    /// Standing: each segment's weight.
    per_segment: [f32; N],
    /// Chirp: ln(end_hz / start_hz).
    chirp_ln_ratio: f32,
    /// HeldStep: the largest `y` (see [`Program::HeldStep`]).
    held_peak: f32,
}

impl<const N: usize> Generator<N> {
    /// Checks every field of `program` and `envelope` (the error names the
    /// first field that breaks a rule) and prepares the generator.
    pub fn new(program: Program, envelope: Envelope) -> Result<Self, WaveError> {
        const { assert!(N >= 1 && N <= crate::MAX_SEGMENTS) };
        check_program::<N>(&program)?;
        check_envelope(&envelope)?;
        let mut per_segment = [0.0; N];
        let mut chirp_ln_ratio = 0.0;
        let mut held_peak = 0.0;
        match program {
            Program::Travelling {
                lag_deg_per_segment,
                ..
            } => {
                let lag_cycles = math::frac(lag_deg_per_segment / 360.0);
                for (k, lag) in per_segment.iter_mut().enumerate() {
                    *lag = math::frac_of_product(lag_cycles, k as f32);
                }
            }
            Program::Standing { .. } => {
                for (k, weight) in per_segment.iter_mut().enumerate() {
                    *weight = if N == 1 {
                        1.0
                    } else {
                        F32Ext::cos(PI * k as f32 / (N - 1) as f32)
                    };
                }
            }
            Program::Harmonic { phases_deg, .. } => {
                for (lag, phase) in per_segment.iter_mut().zip(phases_deg) {
                    *lag = math::frac(-phase / 360.0);
                }
            }
            Program::Chirp {
                start_hz, end_hz, ..
            } => chirp_ln_ratio = math::ln(end_hz / start_hz),
            Program::HeldStep {
                levels_v,
                rise_s,
                pole_per_s,
                zero_per_s,
            } => {
                held_peak = held_step_peak(rise_s, pole_per_s, zero_per_s);
                let level = levels_v[..N]
                    .iter()
                    .fold(0.0, |m: f32, &v| m.max(math::abs(v)));
                let peak = held_peak * level;
                if peak.is_nan() || peak > MAX_PROGRAM_V {
                    return Err(err("HeldStep.levels_v", WaveRule::ProgramRange));
                }
            }
            Program::Steps { .. } | Program::Pulses { .. } => {}
        }
        Ok(Generator {
            program,
            envelope,
            per_segment,
            chirp_ln_ratio,
            held_peak,
        })
    }

    /// The largest magnitude the program asks of any of the N segments, V:
    /// the envelope's gain is at most 1, and each kind reaches its peak
    /// (a sine its amplitude plus the offset's magnitude, a standing wave
    /// at the root, a pulse train while on). The firmware refuses a program
    /// whose peak is above its limit rather than clip it into a square wave.
    pub fn peak_abs_v(&self) -> f32 {
        match self.program {
            Program::Travelling {
                amplitude_v,
                offset_v,
                ..
            }
            | Program::Standing {
                amplitude_v,
                offset_v,
                ..
            } => amplitude_v + math::abs(offset_v),
            Program::Steps { levels_v } => levels_v[..N]
                .iter()
                .fold(0.0, |peak: f32, &v| peak.max(math::abs(v))),
            Program::HeldStep { levels_v, .. } => {
                self.held_peak
                    * levels_v[..N]
                        .iter()
                        .fold(0.0, |peak: f32, &v| peak.max(math::abs(v)))
            }
            Program::Pulses {
                amplitude_v, on_s, ..
            } => {
                if on_s > 0.0 {
                    amplitude_v
                } else {
                    0.0
                }
            }
            Program::Chirp { amplitude_v, .. } => amplitude_v,
            Program::Harmonic {
                offset_v,
                amplitudes_v,
                ..
            } => {
                amplitudes_v[..N]
                    .iter()
                    .fold(0.0, |peak: f32, &a| peak.max(a))
                    + math::abs(offset_v)
            }
        }
    }

    /// The program.
    pub fn program(&self) -> Program {
        self.program
    }

    /// The envelope.
    pub fn envelope(&self) -> Envelope {
        self.envelope
    }

    /// The voltage each segment asks for at `t_s` seconds after the program
    /// started, V. Before the start, at a non-finite time, or from 2³² s
    /// on, every segment asks for 0 V. Exact for the f32 time given, but an
    /// f32 clock itself only resolves 4 ms after 10 h: a firmware should
    /// call [`Generator::voltages_at_tick_v`] with its tick count instead.
    pub fn voltages_v(&self, t_s: f32) -> [f32; N] {
        if !(0.0..4_294_967_296.0).contains(&t_s) {
            return [0.0; N];
        }
        let whole_s = t_s as u32;
        // Exact: whole_s is t_s itself from 2²⁴ on.
        self.at(whole_s, t_s - whole_s as f32)
    }

    /// The voltages at tick `tick` of a clock of `tick_hz` ticks per second
    /// counted from the program's start, V: exact for any tick count below
    /// 2³² s. A `tick_hz` of 0 or a time from 2³² s on asks for 0 V.
    pub fn voltages_at_tick_v(&self, tick: u64, tick_hz: u32) -> [f32; N] {
        if tick_hz == 0 {
            return [0.0; N];
        }
        let hz = u64::from(tick_hz);
        match u32::try_from(tick / hz) {
            Ok(whole_s) => self.at(whole_s, (tick % hz) as f32 / tick_hz as f32),
            Err(_) => [0.0; N],
        }
    }

    /// The voltages at `whole_s + frac_s` (0 ≤ `frac_s` ≤ 1).
    fn at(&self, whole_s: u32, frac_s: f32) -> [f32; N] {
        // The envelope's ramps take an f32 time: ms precision suffices there.
        let gain = self.gain(whole_s as f32 + frac_s);
        if gain == 0.0 {
            return [0.0; N];
        }
        let mut v = [0.0; N];
        match self.program {
            Program::Travelling {
                amplitude_v,
                frequency_hz,
                offset_v,
                ..
            } => {
                let cycles = cycles(frequency_hz, whole_s, frac_s);
                for (out, lag) in v.iter_mut().zip(self.per_segment) {
                    *out = offset_v + amplitude_v * sin_cycles(cycles - lag);
                }
            }
            Program::Standing {
                amplitude_v,
                frequency_hz,
                offset_v,
            } => {
                let s = amplitude_v * sin_cycles(cycles(frequency_hz, whole_s, frac_s));
                for (out, weight) in v.iter_mut().zip(self.per_segment) {
                    *out = offset_v + weight * s;
                }
            }
            Program::Harmonic {
                frequency_hz,
                offset_v,
                amplitudes_v,
                ..
            } => {
                let cycles = cycles(frequency_hz, whole_s, frac_s);
                for ((out, lag), a) in v.iter_mut().zip(self.per_segment).zip(amplitudes_v) {
                    *out = offset_v + a * sin_cycles(cycles - lag);
                }
            }
            Program::Steps { levels_v } => v.copy_from_slice(&levels_v[..N]),
            Program::HeldStep {
                levels_v,
                rise_s,
                pole_per_s,
                zero_per_s,
            } => {
                // Past the rise, the part of a second is enough: e^{−z t}
                // has decayed long before an f32 time loses its ms.
                let y = held_step(whole_s as f32 + frac_s, rise_s, pole_per_s, zero_per_s);
                for (out, level) in v.iter_mut().zip(levels_v) {
                    *out = level * y;
                }
            }
            Program::Pulses {
                amplitude_v,
                on_s,
                off_s,
            } => {
                if modulo(on_s + off_s, whole_s, frac_s) < on_s {
                    v = [amplitude_v; N];
                }
            }
            Program::Chirp {
                amplitude_v,
                start_hz,
                duration_s,
                ..
            } => {
                let tau = modulo(duration_s, whole_s, frac_s);
                // Phase f0 T (r^(τ/T) − 1)/ln r, written as f0 τ (eᵘ − 1)/u
                // with u = ln r · τ/T: no cancellation for r near 1.
                let u = self.chirp_ln_ratio * (tau / duration_s);
                let phase = start_hz * tau * math::expm1_over(u);
                v = [amplitude_v * sin_cycles(phase); N];
            }
        }
        v.map(|x| gain * x)
    }

    /// The envelope's gain at `t_s` (≥ 0).
    fn gain(&self, t_s: f32) -> f32 {
        let Envelope {
            ramp_in_s,
            hold_s,
            ramp_out_s,
        } = self.envelope;
        if t_s < ramp_in_s {
            return raised_cosine(t_s / ramp_in_s);
        }
        let t_s = t_s - ramp_in_s;
        if t_s < hold_s {
            return 1.0;
        }
        let t_s = t_s - hold_s;
        if t_s < ramp_out_s {
            return 1.0 - raised_cosine(t_s / ramp_out_s);
        }
        0.0
    }
}

/// `y(t)` of [`Program::HeldStep`] (checked values): with `ω = π/T`,
/// `u = ω/z` (0 for `z = ∞`), for `t ≤ T`
///
/// `z E = ½(1 − e^{−zt}) − ½(cos ωt + u sin ωt − e^{−zt})/(1 + u²)`,
/// `(z/p) D = ω/(2p) · (sin ωt − u cos ωt + u e^{−zt})/(1 + u²)`,
///
/// `E = e^{−z·} ∗ ρ` and `D = e^{−z·} ∗ ρ′`; `y = z E + (z/p) D`, written
/// in `u` so that a pure lag (`z = ∞`) is the same formula, without the
/// cancellation `ρ − z E` would have for a large `z`. After the rise both
/// parts relax to their ends with `e^{−z(t − T)}`: `z E` to 1, `D` to 0.
/// With no rise (`T = 0`, `z` finite): `y = 1 + (z/p − 1) e^{−zt}`.
fn held_step(t_s: f32, rise_s: f32, p: f32, z: f32) -> f32 {
    if rise_s == 0.0 {
        return 1.0 + (z / p - 1.0) * math::exp_neg(z * t_s);
    }
    let w = PI / rise_s;
    let u = w / z;
    let k = 1.0 / (1.0 + u * u);
    let tr = t_s.min(rise_s);
    // At t = 0 and z = ∞, z t is NaN: e^{−z·0} is 1.
    let e = if tr == 0.0 {
        1.0
    } else {
        math::exp_neg(z * tr)
    };
    // At the rise's end exactly: sin π = 0, cos π = −1 (micromath's are
    // off by 1e-3).
    let (s, c) = if t_s >= rise_s {
        (0.0, -1.0)
    } else {
        (F32Ext::sin(w * tr), F32Ext::cos(w * tr))
    };
    let ze = 0.5 * (1.0 - e) - 0.5 * (c + u * s - e) * k;
    let d = w / (2.0 * p) * (s - u * c + u * e) * k;
    if t_s <= rise_s {
        return ze + d;
    }
    let f = math::exp_neg(z * (t_s - rise_s));
    (ze + d - 1.0) * f + 1.0
}

/// The largest `y` of a [`Program::HeldStep`] (checked values): `y` ends
/// at 1 and, after the rise, moves monotonically from its value at the
/// rise's end to 1, so the peak is 1, the start (no rise), or in the rise:
/// the best of 64 points and the end, then refined between its
/// neighbours by ternary search (`y` is smooth there).
fn held_step_peak(rise_s: f32, p: f32, z: f32) -> f32 {
    let y = |t: f32| held_step(t, rise_s, p, z);
    if rise_s == 0.0 {
        return y(0.0).max(1.0);
    }
    let at = |i: u32| rise_s * i as f32 / 64.0;
    let best = (0..=64).fold(0, |b, i| if y(at(i)) > y(at(b)) { i } else { b });
    let (mut lo, mut hi) = (at(best.saturating_sub(1)), at((best + 1).min(64)));
    for _ in 0..24 {
        let (a, b) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if y(a) < y(b) {
            lo = a;
        } else {
            hi = b;
        }
    }
    y(at(best)).max(y(0.5 * (lo + hi))).max(1.0)
}

/// ½ − ½ cos(π x) for x in [0, 1): from 0 to 1 with zero slope at both
/// ends. micromath's cos is exact at 0 and π, so the ramp starts at 0.
fn raised_cosine(x: f32) -> f32 {
    0.5 - 0.5 * F32Ext::cos(PI * x)
}

/// sin(2π x), the argument first wrapped to [0, 2π) where micromath's sine
/// is accurate (see the crate's docs).
fn sin_cycles(x: f32) -> f32 {
    F32Ext::sin(TAU * math::frac(x))
}

/// `frequency_hz · (whole_s + frac_s)` modulo 1, in [0, 1). whole_s =
/// hi·2¹² + lo, each part exact in f32 and frequency_hz·2¹² exact too, so
/// each product's fraction comes out to about 1e-7.
fn cycles(frequency_hz: f32, whole_s: u32, frac_s: f32) -> f32 {
    let hi = (whole_s >> 12) as f32;
    let lo = (whole_s & 0xfff) as f32;
    math::frac(
        math::frac_of_product(frequency_hz * 4096.0, hi)
            + math::frac_of_product(frequency_hz, lo)
            + math::frac_of_product(frequency_hz, frac_s),
    )
}

/// `(whole_s + frac_s)` modulo `period_s` (> 0), in [0, period_s]. The
/// f32 `%` is exact, and each part is exact in f32 before it is reduced.
fn modulo(period_s: f32, whole_s: u32, frac_s: f32) -> f32 {
    let hi = ((whole_s >> 12) as f32 * 4096.0) % period_s;
    let lo = (whole_s & 0xfff) as f32 % period_s;
    (hi + lo + frac_s % period_s) % period_s
}

fn err(field: &'static str, rule: WaveRule) -> WaveError {
    WaveError { field, rule }
}

/// Finite.
fn finite(field: &'static str, v: f32) -> Result<(), WaveError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(err(field, WaveRule::Finite))
    }
}

/// A voltage of a program: finite, within ±MAX_PROGRAM_V.
fn volts(field: &'static str, v: f32) -> Result<(), WaveError> {
    finite(field, v)?;
    if math::abs(v) <= MAX_PROGRAM_V {
        Ok(())
    } else {
        Err(err(field, WaveRule::ProgramRange))
    }
}

/// An amplitude: a voltage, not negative.
fn amplitude(field: &'static str, v: f32) -> Result<(), WaveError> {
    volts(field, v)?;
    at_least_zero(field, v)
}

fn at_least_zero(field: &'static str, v: f32) -> Result<(), WaveError> {
    if v >= 0.0 {
        Ok(())
    } else {
        Err(err(field, WaveRule::NonNegative))
    }
}

/// A finite duration, not negative.
fn duration(field: &'static str, v: f32) -> Result<(), WaveError> {
    finite(field, v)?;
    at_least_zero(field, v)
}

fn frequency(field: &'static str, v: f32) -> Result<(), WaveError> {
    finite(field, v)?;
    if (MIN_FREQUENCY_HZ..=MAX_FREQUENCY_HZ).contains(&v) {
        Ok(())
    } else {
        Err(err(field, WaveRule::FrequencyRange))
    }
}

fn check_program<const N: usize>(program: &Program) -> Result<(), WaveError> {
    match *program {
        Program::Travelling {
            amplitude_v,
            frequency_hz,
            lag_deg_per_segment,
            offset_v,
        } => {
            amplitude("Travelling.amplitude_v", amplitude_v)?;
            frequency("Travelling.frequency_hz", frequency_hz)?;
            finite("Travelling.lag_deg_per_segment", lag_deg_per_segment)?;
            volts("Travelling.offset_v", offset_v)
        }
        Program::Standing {
            amplitude_v,
            frequency_hz,
            offset_v,
        } => {
            amplitude("Standing.amplitude_v", amplitude_v)?;
            frequency("Standing.frequency_hz", frequency_hz)?;
            volts("Standing.offset_v", offset_v)
        }
        Program::Steps { levels_v } => levels_v[..N]
            .iter()
            .try_for_each(|&v| volts("Steps.levels_v", v)),
        Program::Harmonic {
            frequency_hz,
            offset_v,
            amplitudes_v,
            phases_deg,
        } => {
            frequency("Harmonic.frequency_hz", frequency_hz)?;
            volts("Harmonic.offset_v", offset_v)?;
            amplitudes_v[..N]
                .iter()
                .try_for_each(|&a| amplitude("Harmonic.amplitudes_v", a))?;
            phases_deg[..N]
                .iter()
                .try_for_each(|&p| finite("Harmonic.phases_deg", p))
        }
        Program::HeldStep {
            levels_v,
            rise_s,
            pole_per_s,
            zero_per_s,
        } => {
            levels_v[..N]
                .iter()
                .try_for_each(|&v| volts("HeldStep.levels_v", v))?;
            duration("HeldStep.rise_s", rise_s)?;
            if rise_s != 0.0 && rise_s < MIN_HELD_STEP {
                return Err(err("HeldStep.rise_s", WaveRule::ZeroOrAtLeastMin));
            }
            finite("HeldStep.pole_per_s", pole_per_s)?;
            if pole_per_s <= 0.0 {
                return Err(err("HeldStep.pole_per_s", WaveRule::Positive));
            }
            if pole_per_s < MIN_HELD_STEP {
                return Err(err("HeldStep.pole_per_s", WaveRule::AtLeastMin));
            }
            if zero_per_s.is_nan() {
                return Err(err("HeldStep.zero_per_s", WaveRule::NotNan));
            }
            if zero_per_s <= 0.0 {
                return Err(err("HeldStep.zero_per_s", WaveRule::Positive));
            }
            if zero_per_s < MIN_HELD_STEP {
                return Err(err("HeldStep.zero_per_s", WaveRule::AtLeastMin));
            }
            // The pure lag's inverse of an instant step is an impulse.
            if zero_per_s.is_infinite() && rise_s == 0.0 {
                return Err(err("HeldStep.rise_s", WaveRule::Positive));
            }
            Ok(())
        }
        Program::Pulses {
            amplitude_v,
            on_s,
            off_s,
        } => {
            amplitude("Pulses.amplitude_v", amplitude_v)?;
            duration("Pulses.on_s", on_s)?;
            duration("Pulses.off_s", off_s)?;
            if on_s + off_s > 0.0 {
                Ok(())
            } else {
                Err(err("Pulses.on_s + off_s", WaveRule::Positive))
            }
        }
        Program::Chirp {
            amplitude_v,
            start_hz,
            end_hz,
            duration_s,
        } => {
            amplitude("Chirp.amplitude_v", amplitude_v)?;
            frequency("Chirp.start_hz", start_hz)?;
            frequency("Chirp.end_hz", end_hz)?;
            if end_hz <= start_hz {
                return Err(err("Chirp.end_hz", WaveRule::AboveStart));
            }
            duration("Chirp.duration_s", duration_s)?;
            if duration_s > 0.0 {
                Ok(())
            } else {
                Err(err("Chirp.duration_s", WaveRule::Positive))
            }
        }
    }
}

fn check_envelope(envelope: &Envelope) -> Result<(), WaveError> {
    duration("Envelope.ramp_in_s", envelope.ramp_in_s)?;
    if envelope.hold_s.is_nan() {
        return Err(err("Envelope.hold_s", WaveRule::NotNan));
    }
    at_least_zero("Envelope.hold_s", envelope.hold_s)?;
    duration("Envelope.ramp_out_s", envelope.ramp_out_s)
}
