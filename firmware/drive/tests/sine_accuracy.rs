//! micromath's sine, which the generator uses on every target, measured
//! against `libm::sin` in f64; the crate's docs state these numbers.

mod common;

use finrs_drive::{Generator, Program, SINE_MAX_ERROR};
use micromath::F32Ext;
use std::f64::consts::PI;

/// Largest |micromath sin(x) − sin(x)| over `points` + 1 evenly spaced x
/// in [lo, hi], x rounded to f32 first (the reference takes the same x).
fn max_error(lo: f64, hi: f64, points: usize) -> f64 {
    (0..=points)
        .map(|i| {
            let x = (lo + (hi - lo) * i as f64 / points as f64) as f32;
            (F32Ext::sin(x) as f64 - libm::sin(x as f64)).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn micromath_sine_error_is_as_documented() {
    // Measured: 1.0905e-3 on both ranges, over 10⁶ + 1 points.
    for (lo, hi) in [(-PI, PI), (0.0, 2.0 * PI)] {
        let e = max_error(lo, hi, 1_000_000);
        assert!(e <= SINE_MAX_ERROR as f64, "[{lo}, {hi}]: {e:e}");
        // The bound is tight: a much better sine would mean the docs lie.
        assert!(e > 1.0e-3, "[{lo}, {hi}]: {e:e}");
    }
}

/// Largest |generator − f64 reference| over two sweeps of `p` at 10 kHz.
fn chirp_error(p: Program) -> f64 {
    let Program::Chirp { duration_s, .. } = p else {
        unreachable!()
    };
    let g = Generator::<1>::new(p, common::ALWAYS).unwrap();
    let ticks = (2.0 * duration_s as f64 * 1e4) as u64;
    (0..ticks)
        .map(|tick| {
            let v = g.voltages_at_tick_v(tick, 10_000)[0] as f64;
            let t = tick as f64 * 1e-4;
            (v - common::reference_v(&p, &common::ALWAYS, 1, 0, t)).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn over_a_chirp_the_generator_is_within_the_sine_error() {
    // The f32 phase of a sweep of C cycles is off by up to about 1e-6 C
    // cycles (the exponent's rounding, amplified by it); the rest is the
    // sine's error. The host's `chirp:1,0.1,20` over 12 s, 45 cycles a
    // sweep, whose phases cover [0, 2π) densely (measured 1.21e-3 V):
    let host = Program::Chirp {
        amplitude_v: 1.0,
        start_hz: 0.1,
        end_hz: 20.0,
        duration_s: 12.0,
    };
    let e = chirp_error(host);
    assert!(e <= SINE_MAX_ERROR as f64 + 2.0 * PI * 45.0 * 1e-6, "{e:e}");
    // A wide sweep, 0.05 → 100 Hz in 30 s, 395 cycles (measured 2.63e-3 V):
    let wide = Program::Chirp {
        amplitude_v: 1.0,
        start_hz: 0.05,
        end_hz: 100.0,
        duration_s: 30.0,
    };
    let e = chirp_error(wide);
    assert!(
        e <= SINE_MAX_ERROR as f64 + 2.0 * PI * 395.0 * 1e-6,
        "{e:e}"
    );
}
