//! The beam's first blocked mode, read off the load cell: its natural
//! frequency and its damping ratio.
//!
//! The seed's beam is undamped: it rings for the whole recording, and a
//! model whose frequency is off by a fraction of a percent rings out of
//! phase within seconds. Least squares cannot find the frequency from far
//! away (the cost is rippled by the phase); the spectrum of the measured
//! ringing can. A real strip is damped (ζ of a few percent): its ringing
//! is gone a tenth of a second after a step, so it is read from the
//! moment the drive's charge has risen, as a decaying sinusoid on a slow
//! trend. Candidates that move the frequency (the beam's stiffness, the
//! water's added mass) start where it matches; those that damp the beam
//! (damping, the water's drag) start where its decay matches.

use std::f64::consts::PI;

use model_core::{state_len, Fixture as CoreFixture, Strip};

use crate::analysis::median::median;
use crate::model::predict::ModelSpec;
use crate::recording::{Channel, Fixture};
use crate::session::Session;

/// Time after a step before the ringing is read, in charging time
/// constants `R1 C`: the moment has risen to within 2 % (e⁻⁴).
const SETTLE_TAUS: f64 = 4.0;
/// Length of the ringing read, s: long enough for an undamped ringing's
/// frequency to a millihertz.
const WINDOW_S: f64 = 2.0;
/// Length of the first look at the spectrum, s: a damped ringing is still
/// there, and the peak is four hertz wide.
const FIRST_LOOK_S: f64 = 0.25;

/// The fewest rows a ringing window may hold: the first look takes at
/// least 8, and a decay fitted on fewer than a few dozen is noise.
const MIN_WINDOW_ROWS: usize = 32;

/// A mode as it rings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ringing {
    /// Natural (undamped) frequency `f_n`, Hz.
    pub hz: f64,
    /// Damping ratio `ζ`.
    pub damping_ratio: f64,
}

/// The first blocked natural frequency of `spec`'s beam, Hz.
pub fn model_blocked_hz(spec: &ModelSpec) -> Option<f64> {
    model_first_hz(spec, Fixture::Blocked)
}

/// The first natural frequency of `spec`'s beam held as `fixture`, Hz
/// (none if the model is refused).
pub fn model_first_hz(spec: &ModelSpec, fixture: Fixture) -> Option<f64> {
    let fixture = match fixture {
        Fixture::Free => CoreFixture::Free,
        Fixture::Blocked => CoreFixture::Blocked,
    };
    // Any segment count gives the beam; the fit's mesh is E = 4.
    let s = Strip::<f64, 3, 4, { state_len(3, 4) }>::with_extensions(
        &spec.params,
        &spec.ext,
        fixture,
        1e-3,
    )
    .ok()?;
    let first = s.natural_frequencies_hz().next();
    first
}

/// The first blocked mode of `spec`'s beam: its frequency and the damping
/// ratio its damping terms give there.
pub fn model_blocked_ringing(spec: &ModelSpec) -> Option<Ringing> {
    let hz = model_blocked_hz(spec)?;
    let w = 2.0 * PI * hz;
    let two_zeta_omega = spec.ext.two_zeta_omega(
        model_core::Fixture::Blocked,
        0,
        w,
        spec.params.mass_per_length_kg_per_m,
    );
    Some(Ringing {
        hz,
        damping_ratio: two_zeta_omega / (2.0 * w),
    })
}

/// The first blocked mode as the load cell rings after the first step of
/// each blocked recording among `recordings`, read once `spec`'s charge
/// has risen ([`SETTLE_TAUS`]), searched between `lo_hz` and `hi_hz`: the
/// median frequency and damping ratio over the recordings with a clear
/// peak (20 times the spectrum's median).
pub fn measured_blocked_ringing(
    session: &Session,
    recordings: &[usize],
    spec: &ModelSpec,
    lo_hz: f64,
    hi_hz: f64,
) -> Option<Ringing> {
    let settle_s = SETTLE_TAUS * spec.params.r1_ohm * spec.params.c_f;
    let mut found = Vec::new();
    for &i in recordings {
        let r = &session.recordings[i];
        if r.rec.meta.fixture != Fixture::Blocked {
            continue;
        }
        let Some(force) = r.rec.channel(Channel::Force) else {
            continue;
        };
        // The casts saturate, and a charging time from a far-off model
        // can be any length: the sums are checked, not trusted.
        let settle = (settle_s / r.dt_s).round() as usize;
        let len = (WINDOW_S / r.dt_s).round() as usize;
        let Some(start) = r.rest_rows.checked_add(settle) else {
            continue;
        };
        // A window of a few rows (a sampling period of seconds) holds no
        // ringing to find; it is skipped, not read past its end.
        if len < MIN_WINDOW_ROWS || start.checked_add(len).is_none_or(|end| end > force.len()) {
            continue;
        }
        // The drive must hold over the window, or its own steps dominate.
        let Some(v0) = r.rec.v_v.row(start) else {
            continue;
        };
        let held = |row: usize| v0.iter().enumerate().all(|(k, &v)| r.reads_as(k, row, v));
        if !(start..start + len).all(held) {
            continue;
        }
        let y: Option<Vec<f64>> = force[start..start + len].iter().copied().collect();
        let Some(y) = y else { continue };
        if let Some(m) = ringing(&y, r.dt_s, lo_hz, hi_hz) {
            found.push(m);
        }
    }
    Some(Ringing {
        hz: median(found.iter().map(|m| m.hz).collect())?,
        damping_ratio: median(found.iter().map(|m| m.damping_ratio).collect())?,
    })
}

/// The mode ringing in `y`, if it rings at all: what is left after the
/// trend must be more than rounding (a millionth of the signal), and its
/// first [`FIRST_LOOK_S`] must show a clear spectral peak. The peak then
/// starts a fit of `e^{−σt}(c cos ω_d t + s sin ω_d t)` on a quadratic
/// trend over the whole of `y` (variable projection: the five linear
/// coefficients by least squares for each `ω_d`, `σ`).
fn ringing(y: &[f64], dt_s: f64, lo_hz: f64, hi_hz: f64) -> Option<Ringing> {
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let left = detrend(y);
    let rings = rms(&left) > 1e-6 * rms(y);
    if !rings || y.len() < MIN_WINDOW_ROWS {
        return None;
    }
    let first = ((FIRST_LOOK_S / dt_s).round() as usize).clamp(8, y.len());
    let f0 = peak_hz(&detrend(&y[..first]), dt_s, lo_hz, hi_hz)?;
    let t_s = y.len() as f64 * dt_s;
    let w0 = 2.0 * PI * f0;
    let cost = |f: f64, sigma: f64| decaying_fit_rss(y, dt_s, f, sigma);
    // The decay on a log grid at the first look's frequency, from a
    // hundredth of a cycle in the window to ζ = 0.5.
    let sigmas = (0..=40).map(|k| (0.01 / t_s) * (0.5 * w0 * t_s / 0.01).powf(k as f64 / 40.0));
    let mut sigma = sigmas
        .map(|s| (s, cost(f0, s)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    // Then the frequency over the first look's resolution, at a twentieth
    // of the window's (the cost ripples at 1/T for a long ringing), then
    // both refined.
    let half = 1.0 / FIRST_LOOK_S.min(t_s);
    let step = 0.05 / t_s;
    let steps = (2.0 * half / step).ceil() as usize;
    let mut f = (0..=steps)
        .map(|k| f0 - half + k as f64 * step)
        .filter(|&f| f > 0.0)
        .map(|f| (f, cost(f, sigma)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    f = golden(|x| cost(x, sigma), f - step, f + step);
    let ln_sigma = golden(|x| cost(f, x.exp()), (sigma / 1.5).ln(), (sigma * 1.5).ln());
    sigma = ln_sigma.exp();
    let wd = 2.0 * PI * f;
    let wn = wd.hypot(sigma);
    Some(Ringing {
        hz: wn / (2.0 * PI),
        damping_ratio: sigma / wn,
    })
}

/// The residual sum of squares of the best `a + b x + c x² +
/// e^{−σt}(d cos ωt + e sin ωt)` through `y`, `ω = 2π f_hz`.
fn decaying_fit_rss(y: &[f64], dt_s: f64, f_hz: f64, sigma: f64) -> f64 {
    let n = y.len() as f64;
    let w = 2.0 * PI * f_hz * dt_s;
    let decay = (-sigma * dt_s).exp();
    let mut a = [[0.0; 5]; 5];
    let mut b = [0.0; 5];
    let mut yy = 0.0;
    let mut env = 1.0;
    for (i, &v) in y.iter().enumerate() {
        let x = 2.0 * i as f64 / n - 1.0;
        let (s, c) = (w * i as f64).sin_cos();
        let p = [1.0, x, x * x, env * c, env * s];
        for r in 0..5 {
            b[r] += p[r] * v;
            for k in 0..5 {
                a[r][k] += p[r] * p[k];
            }
        }
        yy += v * v;
        env *= decay;
    }
    let Some(coef) = solve(a, b) else {
        return f64::INFINITY;
    };
    // RSS = yᵀy − cᵀ(Aᵀy) at the least-squares solution.
    yy - coef.iter().zip(&b).map(|(c, b)| c * b).sum::<f64>()
}

/// The minimum of a unimodal `g` on `[a, b]`.
fn golden(g: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let r = 0.618_033_988_75;
    for _ in 0..40 {
        let c = b - r * (b - a);
        let d = a + r * (b - a);
        if g(c) < g(d) {
            b = d;
        } else {
            a = c;
        }
    }
    0.5 * (a + b)
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
    let coef = solve(a, b).unwrap_or([0.0; 3]);
    y.iter()
        .enumerate()
        .map(|(i, &v)| v - coef[0] - coef[1] * x(i) - coef[2] * x(i) * x(i))
        .collect()
}

/// `A x = b` by Gaussian elimination with partial pivoting; `None` when
/// `A` is singular to working precision.
// Gaussian elimination reads best with indices.
#[allow(clippy::needless_range_loop)]
fn solve<const K: usize>(mut a: [[f64; K]; K], mut b: [f64; K]) -> Option<[f64; K]> {
    let scale = a.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    for k in 0..K {
        let p = (k..K)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap_or(k);
        a.swap(k, p);
        b.swap(k, p);
        if a[k][k].abs() <= 1e-14 * scale {
            return None;
        }
        for i in k + 1..K {
            let f = a[i][k] / a[k][k];
            for j in k..K {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; K];
    for k in (0..K).rev() {
        x[k] = (b[k] - (k + 1..K).map(|j| a[k][j] * x[j]).sum::<f64>()) / a[k][k];
    }
    Some(x)
}

/// Power of `y` (Hann window) at `f_hz`.
fn power(y: &[f64], dt_s: f64, f_hz: f64) -> f64 {
    let n = y.len();
    let w = 2.0 * PI * f_hz * dt_s;
    let (mut re, mut im) = (0.0, 0.0);
    for (i, &v) in y.iter().enumerate() {
        let hann = 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos();
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
    let floor = median(grid.iter().map(|g| g.1).collect())?;
    let (f0, p0) = grid.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let clear = p0 > 20.0 * floor;
    if !clear {
        return None;
    }
    Some(golden(|f| -power(y, dt_s, f), f0 - step, f0 + step))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ringing of natural frequency `f_n` and ratio `ζ` on a slow trend,
    /// `len` samples at 1 kHz, with a little deterministic "noise".
    fn ringing_on_trend(fn_hz: f64, zeta: f64, len: usize) -> Vec<f64> {
        let wn = 2.0 * PI * fn_hz;
        let (sigma, wd) = (zeta * wn, wn * (1.0 - zeta * zeta).sqrt());
        (0..len)
            .map(|i| {
                let t = i as f64 * 1e-3;
                0.03 * (1.0 - 0.1 * t)
                    + 0.007 * (-sigma * t).exp() * (wd * t).sin()
                    + 1e-6 * ((i * 7919 % 101) as f64 / 50.0 - 1.0)
            })
            .collect()
    }

    #[test]
    fn an_undamped_ringing_on_a_trend_is_found_to_a_millihertz() {
        let f = 117.2995;
        let got = ringing(&ringing_on_trend(f, 0.0005, 2000), 1e-3, 60.0, 240.0).unwrap();
        assert!((got.hz - f).abs() < 1e-3, "{got:?}");
        assert!((got.damping_ratio - 0.0005).abs() < 2e-4, "{got:?}");
        // Pure trend: no peak.
        let flat: Vec<f64> = (0..2000).map(|i| 0.03 + 1e-6 * i as f64).collect();
        assert_eq!(ringing(&flat, 1e-3, 60.0, 240.0), None);
    }

    #[test]
    fn a_damped_ringing_gone_in_a_tenth_of_a_second_is_read_with_its_ratio() {
        // A real strip's first blocked mode: ζ of a few percent, gone
        // (below a hundredth) within 0.2 s of a 2 s window.
        for (f, zeta) in [(67.0, 0.043), (45.0, 0.1), (80.0, 0.02)] {
            let got = ringing(&ringing_on_trend(f, zeta, 2000), 1e-3, 20.0, 300.0).unwrap();
            assert!((got.hz - f).abs() < 0.01 * f, "{f} {zeta}: {got:?}");
            assert!(
                (got.damping_ratio - zeta).abs() < 0.1 * zeta,
                "{f} {zeta}: {got:?}"
            );
        }
    }

    #[test]
    fn a_window_of_a_few_rows_is_no_ringing_and_no_panic() {
        // A sampling period of seconds leaves a 2 s window a row or two.
        for len in [0, 1, 2, 7, 8, MIN_WINDOW_ROWS - 1] {
            let y = ringing_on_trend(67.0, 0.04, len);
            assert_eq!(ringing(&y, 1e-3, 20.0, 300.0), None, "{len} rows");
        }
    }
}
