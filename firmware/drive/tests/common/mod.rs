//! The f64 reference of every program, written from the docs' formulas
//! with `libm`, independently of the generator's f32 phase reduction.

#![allow(dead_code)] // each test file uses a part

use finrs_drive::{Envelope, Program};
use std::f64::consts::PI;

/// `x` modulo 1, in [0, 1).
pub fn wrap(x: f64) -> f64 {
    x - libm::floor(x)
}

/// The envelope's gain at `t_s`.
pub fn gain(e: &Envelope, t_s: f64) -> f64 {
    let (ramp_in, hold, ramp_out) = (e.ramp_in_s as f64, e.hold_s as f64, e.ramp_out_s as f64);
    let raised = |x: f64| 0.5 - 0.5 * libm::cos(PI * x);
    if t_s < 0.0 {
        0.0
    } else if t_s < ramp_in {
        raised(t_s / ramp_in)
    } else if t_s - ramp_in < hold {
        1.0
    } else if t_s - ramp_in - hold < ramp_out {
        1.0 - raised((t_s - ramp_in - hold) / ramp_out)
    } else {
        0.0
    }
}

/// The program's phase in cycles, modulo 1, of segment `k` (for the
/// kinds that have one).
pub fn cycles(p: &Program, k: usize, t_s: f64) -> f64 {
    match *p {
        Program::Travelling {
            frequency_hz,
            lag_deg_per_segment,
            ..
        } => wrap(frequency_hz as f64 * t_s - k as f64 * lag_deg_per_segment as f64 / 360.0),
        Program::Standing { frequency_hz, .. } => wrap(frequency_hz as f64 * t_s),
        Program::Harmonic {
            frequency_hz,
            phases_deg,
            ..
        } => wrap(frequency_hz as f64 * t_s + phases_deg[k] as f64 / 360.0),
        Program::Chirp {
            start_hz,
            end_hz,
            duration_s,
            ..
        } => {
            let (f0, r, big_t) = (
                start_hz as f64,
                end_hz as f64 / start_hz as f64,
                duration_s as f64,
            );
            let tau = t_s % big_t;
            wrap(f0 * big_t * (libm::pow(r, tau / big_t) - 1.0) / libm::log(r))
        }
        _ => 0.0,
    }
}

/// The wave of segment `k` of `n` before the envelope, given sin(2π
/// cycles) as `sine`.
pub fn wave(p: &Program, n: usize, k: usize, t_s: f64, sine: impl Fn(f64) -> f64) -> f64 {
    let s = sine(cycles(p, k, t_s));
    match *p {
        Program::Travelling {
            amplitude_v,
            offset_v,
            ..
        } => offset_v as f64 + amplitude_v as f64 * s,
        Program::Standing {
            amplitude_v,
            offset_v,
            ..
        } => {
            let weight = if n == 1 {
                1.0
            } else {
                libm::cos(PI * k as f64 / (n - 1) as f64)
            };
            offset_v as f64 + amplitude_v as f64 * weight * s
        }
        Program::Steps { levels_v } => levels_v[k] as f64,
        Program::Pulses {
            amplitude_v,
            on_s,
            off_s,
        } => {
            // The period as the generator holds it, an f32 sum.
            let period_s = (on_s + off_s) as f64;
            if t_s % period_s < on_s as f64 {
                amplitude_v as f64
            } else {
                0.0
            }
        }
        Program::Chirp { amplitude_v, .. } => amplitude_v as f64 * s,
        Program::Harmonic {
            offset_v,
            amplitudes_v,
            ..
        } => offset_v as f64 + amplitudes_v[k] as f64 * s,
        Program::HeldStep {
            levels_v,
            rise_s,
            pole_per_s,
            zero_per_s,
        } => {
            levels_v[k] as f64 * held_step(t_s, rise_s as f64, pole_per_s as f64, zero_per_s as f64)
        }
    }
}

/// `y = ρ + (z − p)/p · ∫₀ᵗ e^{−z(t−τ)} ρ′(τ) dτ` of a held step, the
/// integral by Simpson's rule over the rise (where `ρ′` lives), not the
/// generator's closed form; `ρ + ρ′/p` for `z = ∞`.
pub fn held_step(t_s: f64, rise_s: f64, p: f64, z: f64) -> f64 {
    if t_s < 0.0 {
        return 0.0;
    }
    if rise_s == 0.0 {
        return 1.0 + (z - p) / p * libm::exp(-z * t_s);
    }
    let w = PI / rise_s;
    let rho = |t: f64| {
        if t < rise_s {
            0.5 - 0.5 * libm::cos(w * t)
        } else {
            1.0
        }
    };
    let d_rho = |t: f64| {
        if t < rise_s {
            0.5 * w * libm::sin(w * t)
        } else {
            0.0
        }
    };
    if z.is_infinite() {
        return rho(t_s) + d_rho(t_s) / p;
    }
    let end = t_s.min(rise_s);
    let n = 2000;
    let h = end / n as f64;
    let f = |tau: f64| libm::exp(-z * (t_s - tau)) * d_rho(tau);
    let mut sum = f(0.0) + f(end);
    for i in 1..n {
        sum += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    rho(t_s) + (z - p) / p * sum * h / 3.0
}

/// The exact voltage of segment `k` of `n`.
pub fn reference_v(p: &Program, e: &Envelope, n: usize, k: usize, t_s: f64) -> f64 {
    gain(e, t_s) * wave(p, n, k, t_s, |c| libm::sin(2.0 * PI * c))
}

/// An envelope of full gain from the start, for ever.
pub const ALWAYS: Envelope = Envelope {
    ramp_in_s: 0.0,
    hold_s: f32::INFINITY,
    ramp_out_s: 0.0,
};
