//! `finrs-drive`: the fin driver firmware's open-loop wave generation, and
//! the one place where its voltage and slew limits are enforced. `no_std`,
//! allocation-free, f32 throughout (the STM32F407's FPU is single
//! precision); the same code runs in the host's tests.
//!
//! - [`Generator`] evaluates a [`Program`] (travelling or standing sine,
//!   steps, pulses, logarithmic chirp) under an [`Envelope`] for N = 1..=8
//!   segments, at any time since the program started. It validates its
//!   configuration and never limits. It is the only wave generator of the
//!   project: the host's `finrs simulate --wave` evaluates waves with it
//!   as well, so simulations see the firmware's voltages.
//! - [`Limiter`] enforces [`Limits`]: every voltage the firmware writes
//!   passes through [`Limiter::apply`] (clamped to ±`max_abs_v` ≤
//!   [`HARD_LIMIT_V`], slew-limited, NaN turned into a 0 V request) or is a
//!   zero of [`Limiter::stop`].
//!
//! # Phase precision
//!
//! The generator keeps no state: it reduces the time's share of each phase
//! modulo one cycle exactly (see [`Generator`]), so after ten hours its
//! output still matches an f64 reference to within the sine's error.
//! [`Generator::voltages_at_tick_v`] takes the firmware's tick count, which
//! an f32 time could not resolve after hours.
//!
//! # Sine accuracy
//!
//! Sines are micromath's `F32Ext::sin` on every target, so the host's tests
//! run the firmware's code path. Against `libm::sin` in f64, over 10⁶ + 1
//! evenly spaced points, its largest error is 1.0905e-3 on [−π, π] and on
//! [0, 2π] (the generator's range, after wrapping): [`SINE_MAX_ERROR`]
//! bounds it, and `tests/sine_accuracy.rs` measures it again, also over
//! chirps. A wave of amplitude A is therefore within about A · 1.1e-3 V of
//! the exact sine (2.2 mV at 2 V); envelope ramps and standing-wave weights
//! use micromath's cosine, of the same error.
//!
//! # Example
//!
//! One second of the default program at 1 kHz, through a limiter:
//!
//! ```
//! use finrs_drive::{default_program, Generator, Limiter, Limits};
//!
//! let (program, envelope) = default_program();
//! let generator = Generator::<4>::new(program, envelope).unwrap();
//! let mut limiter = Limiter::<4>::new(Limits::new(1.5, 50.0).unwrap());
//! let dt_s = 1e-3;
//! let mut last = [0.0f32; 4];
//! for tick in 0..1000u64 {
//!     let out = limiter.apply(generator.voltages_at_tick_v(tick, 1000), dt_s);
//!     for (v, before) in out.iter().zip(last) {
//!         assert!(v.abs() <= 1.5);
//!         assert!((v - before).abs() <= 50.0 * dt_s + 1e-6);
//!     }
//!     last = out;
//! }
//! // Ramped in over the second, then clipped at the limit, not at 2 V.
//! assert!(last.iter().any(|v| v.abs() > 1.0));
//! ```

#![no_std]
#![deny(missing_docs, unsafe_code)]

mod limit;
mod math;
mod wave;

pub use limit::{Applied, LimitError, Limiter, Limits, HARD_LIMIT_V};
pub use wave::{
    default_program, Envelope, Generator, Program, WaveError, WaveRule, MAX_FREQUENCY_HZ,
    MAX_PROGRAM_V, MIN_FREQUENCY_HZ, MIN_HELD_STEP,
};

/// Most segments a fin can have (and the length of [`Program::Steps`]).
pub const MAX_SEGMENTS: usize = 8;

/// Bound on |micromath sin(x) − sin(x)| for x in [−π, π] and [0, 2π]:
/// measured 1.0905e-3 over 10⁶ + 1 points (see the crate's docs).
pub const SINE_MAX_ERROR: f32 = 1.1e-3;
