//! The beam's first blocked frequency, read off the load cell.
//!
//! The seed's beam is undamped: it rings for the whole recording, and a
//! model whose frequency is off by a fraction of a percent rings out of
//! phase within seconds. Least squares cannot find the frequency from far
//! away (the cost is rippled by the phase); the spectrum of the measured
//! ringing can. Candidates that move the frequency (the beam's stiffness,
//! the water's added mass) start where it matches.

use model_core::{state_len, Fixture as CoreFixture, Strip};

use crate::model::predict::ModelSpec;
use crate::recording::{Channel, Fixture};
use crate::session::Session;

/// Time after a step before the ringing is read: the moment has risen
/// (six charging time constants of the seed's 16 ms).
const SETTLE_S: f64 = 0.1;
/// Length of the ringing read, s.
const WINDOW_S: f64 = 2.0;

/// The first blocked natural frequency of `spec`'s beam, Hz.
pub fn model_blocked_hz(spec: &ModelSpec) -> Option<f64> {
    // Any segment count gives the beam; the fit's mesh is E = 4.
    let s = Strip::<f64, 3, 4, { state_len(3, 4) }>::with_extensions(
        &spec.params,
        &spec.ext,
        CoreFixture::Blocked,
        1e-3,
    )
    .ok()?;
    let first = s.natural_frequencies_hz().next();
    first
}

/// The ringing frequency of the load cell after the first step of each
/// blocked recording among `recordings`, median over those with a clear
/// peak (20 times the spectrum's median), searched between `lo_hz` and `hi_hz`.
pub fn measured_blocked_hz(
    session: &Session,
    recordings: &[usize],
    lo_hz: f64,
    hi_hz: f64,
) -> Option<f64> {
    let mut found = Vec::new();
    for &i in recordings {
        let r = &session.recordings[i];
        if r.rec.meta.fixture != Fixture::Blocked {
            continue;
        }
        let Some(force) = r.rec.channel(Channel::Force) else {
            continue;
        };
        let start = r.rest_rows + (SETTLE_S / r.dt_s).round() as usize;
        let len = (WINDOW_S / r.dt_s).round() as usize;
        if start + len > force.len() {
            continue;
        }
        // The drive must hold over the window, or its own steps dominate.
        let v0 = &r.rec.v_v[start];
        if (start..start + len).any(|row| &r.rec.v_v[row] != v0) {
            continue;
        }
        let y: Option<Vec<f64>> = force[start..start + len].iter().copied().collect();
        let Some(y) = y else { continue };
        if let Some(f) = ringing_hz(&y, r.dt_s, lo_hz, hi_hz) {
            found.push(f);
        }
    }
    found.sort_by(f64::total_cmp);
    found.get(found.len() / 2).copied()
}

/// The ringing's frequency in `y`, if it rings at all: what is left after
/// the trend must be more than rounding (a millionth of the signal).
fn ringing_hz(y: &[f64], dt_s: f64, lo_hz: f64, hi_hz: f64) -> Option<f64> {
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let left = detrend(y);
    let rings = rms(&left) > 1e-6 * rms(y);
    if !rings {
        return None;
    }
    peak_hz(&left, dt_s, lo_hz, hi_hz)
}

/// Removes the best quadratic: the slow relaxation under the ringing.
fn detrend(y: &[f64]) -> Vec<f64> {
    let n = y.len() as f64;
    let x = |i: usize| 2.0 * i as f64 / n - 1.0;
    // Normal equations for a + b x + c x², small and well scaled on [−1, 1].
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for (i, &v) in y.iter().enumerate() {
        let p = [1.0, x(i), x(i) * x(i)];
        for r in 0..3 {
            b[r] += p[r] * v;
            for c in 0..3 {
                a[r][c] += p[r] * p[c];
            }
        }
    }
    let coef = solve3(a, b);
    y.iter()
        .enumerate()
        .map(|(i, &v)| v - coef[0] - coef[1] * x(i) - coef[2] * x(i) * x(i))
        .collect()
}

// Gaussian elimination reads best with indices.
#[allow(clippy::needless_range_loop)]
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> [f64; 3] {
    for k in 0..3 {
        let p = (k..3)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap_or(k);
        a.swap(k, p);
        b.swap(k, p);
        if a[k][k] == 0.0 {
            return [0.0; 3];
        }
        for i in k + 1..3 {
            let f = a[i][k] / a[k][k];
            for j in k..3 {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; 3];
    for k in (0..3).rev() {
        x[k] = (b[k] - (k + 1..3).map(|j| a[k][j] * x[j]).sum::<f64>()) / a[k][k];
    }
    x
}

/// Power of `y` (Hann window) at `f_hz`.
fn power(y: &[f64], dt_s: f64, f_hz: f64) -> f64 {
    let n = y.len();
    let w = 2.0 * std::f64::consts::PI * f_hz * dt_s;
    let (mut re, mut im) = (0.0, 0.0);
    for (i, &v) in y.iter().enumerate() {
        let hann = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
        re += hann * v * (w * i as f64).cos();
        im += hann * v * (w * i as f64).sin();
    }
    re * re + im * im
}

/// The spectral peak of `y` in `lo..hi` Hz: a grid at a tenth of the
/// resolution `1/T`, then golden-section refinement, if it stands 20 times
/// above the median of the grid.
fn peak_hz(y: &[f64], dt_s: f64, lo_hz: f64, hi_hz: f64) -> Option<f64> {
    let t = y.len() as f64 * dt_s;
    let step = 0.1 / t;
    let count = ((hi_hz - lo_hz) / step).ceil() as usize;
    if count == 0 || count > 200_000 {
        return None;
    }
    let grid: Vec<(f64, f64)> = (0..=count)
        .map(|k| {
            let f = lo_hz + k as f64 * step;
            (f, power(y, dt_s, f))
        })
        .collect();
    let mut powers: Vec<f64> = grid.iter().map(|g| g.1).collect();
    powers.sort_by(f64::total_cmp);
    let median = powers[powers.len() / 2];
    let (f0, p0) = grid.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let clear = p0 > 20.0 * median;
    if !clear {
        return None;
    }
    // Golden section on [f0 − step, f0 + step].
    let (mut a, mut b) = (f0 - step, f0 + step);
    let g = 0.618_033_988_75;
    for _ in 0..40 {
        let c = b - g * (b - a);
        let d = a + g * (b - a);
        if power(y, dt_s, c) > power(y, dt_s, d) {
            b = d;
        } else {
            a = c;
        }
    }
    Some(0.5 * (a + b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_decaying_ringing_on_a_trend_is_found_to_a_millihertz() {
        let dt = 1e-3;
        let f = 117.2995;
        let y: Vec<f64> = (0..2000)
            .map(|i| {
                let t = i as f64 * dt;
                0.03 * (1.0 - 0.1 * t)
                    + 0.007 * (-1.5 * t).exp() * (2.0 * std::f64::consts::PI * f * t).sin()
            })
            .collect();
        let got = ringing_hz(&y, dt, 60.0, 240.0).unwrap();
        assert!((got - f).abs() < 1e-3, "{got}");
        // Pure trend: no peak.
        let flat: Vec<f64> = (0..2000).map(|i| 0.03 + 1e-6 * i as f64).collect();
        assert_eq!(ringing_hz(&flat, dt, 60.0, 240.0), None);
    }
}
