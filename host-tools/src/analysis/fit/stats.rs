//! What a fit reports: confidence intervals from the Jacobian, fit per
//! channel (NRMSE, as MATLAB's `compare`), AIC and BIC.

use nalgebra::DMatrix;

use super::data::Target;
use super::space::{difference_step, Knob, Space};
use crate::recording::{Channel, Voltages};

/// A fitted parameter with its 95 % confidence interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The parameter.
    pub knob: Knob,
    /// Its value, in its unit.
    pub value: f64,
    /// Lower end of the 95 % interval.
    pub low: f64,
    /// Upper end of the 95 % interval.
    pub high: f64,
}

/// `1 − fit/100`: `‖y − ŷ‖ / ‖y − ȳ‖`; 0 is perfect, 1 is as good as the mean.
pub fn nrmse(y: &[f64], model: impl Iterator<Item = f64>) -> f64 {
    let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
    let (mut err, mut spread) = (0.0, 0.0);
    for (&v, m) in y.iter().zip(model) {
        err += (v - m) * (v - m);
        spread += (v - mean) * (v - mean);
    }
    if spread > 0.0 {
        (err / spread).sqrt()
    } else {
        f64::INFINITY
    }
}

/// How well a model fits one channel of one recording.
#[derive(Clone, Debug)]
pub struct ChannelFit {
    /// The recording's file name.
    pub recording: String,
    /// The channel.
    pub channel: Channel,
    /// `‖y − ŷ‖ / ‖y − ȳ‖`.
    pub nrmse: f64,
    /// `100 (1 − nrmse)`, MATLAB's fit percentage.
    pub fit_percent: f64,
    /// RMS of the residual in noise units (1 at the noise floor).
    pub rms_in_noise: f64,
    /// Whether the channel carries signal: its spread is over 3 noise levels.
    pub has_signal: bool,
    /// Weighted residuals, in sample order (for whiteness tests and plots).
    pub residuals: Vec<f64>,
    /// Whether the model predicts zero throughout (it cannot move this
    /// channel: motion along the strip, without arcs).
    pub model_is_zero: bool,
    /// Least-squares scale from model to data, `Σ y ŷ / Σ ŷ²` (1: the
    /// amplitude is right; NaN when the model is zero).
    pub gain: f64,
    /// The input at the residuals' rows, V: the channel's own segment
    /// voltage for a current, the mean over segments for the beam's
    /// channels (for the residual-input correlation test).
    pub input_v: Vec<f64>,
    /// Time between the residuals, s: the sample period, or the camera's
    /// frame period for its channels.
    pub sample_s: f64,
    /// For the beam's channels, each segment's voltage at the residuals'
    /// rows, V (`[segment][i]`: a travelling wave's mean is flat, its
    /// segments are not); empty for a current.
    pub segment_inputs_v: Vec<Vec<f64>>,
}

impl ChannelFit {
    /// A test channel of recording `recording` whose `n` residuals
    /// alternate `±level` (RSS per residual `level²`), all power at the
    /// top of the band, no input.
    #[cfg(test)]
    pub(crate) fn alternating(channel: Channel, recording: &str, level: f64, n: usize) -> Self {
        ChannelFit {
            recording: recording.to_string(),
            channel,
            nrmse: 0.0,
            fit_percent: 100.0,
            rms_in_noise: level,
            has_signal: true,
            residuals: (0..n)
                .map(|i| if i % 2 == 0 { level } else { -level })
                .collect(),
            model_is_zero: false,
            gain: 1.0,
            input_v: vec![0.0; n],
            sample_s: 1e-3,
            segment_inputs_v: Vec::new(),
        }
    }

    /// From a target, its weighted residuals `r = (ŷ − y)/σ` with the
    /// drift removed and `raw` without (the model alone: `ŷ` is rebuilt
    /// from them), the recording's voltages per row and segment and its
    /// sample time. The fit (`nrmse`) is the model's with the drift
    /// beside it; whether it is zero, and its gain, the model's alone.
    pub fn new(
        recording: &str,
        t: &Target,
        r: &[f64],
        raw: &[f64],
        v_v: &Voltages,
        dt_s: f64,
    ) -> ChannelFit {
        let with_drift = t.values.iter().zip(r).map(|(y, r)| y + r * t.sigma);
        let e = nrmse(&t.values, with_drift);
        let model = t.values.iter().zip(raw).map(|(y, r)| y + r * t.sigma);
        // ŷ is rebuilt from y and the residual, so "zero" is up to rounding.
        let scale = t.values.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        let model_is_zero = model.clone().fold(0.0f64, |m, y| m.max(y.abs())) <= 1e-9 * scale;
        let (yy, mm) = t
            .values
            .iter()
            .zip(model)
            .fold((0.0, 0.0), |(a, b), (y, m)| (a + y * m, b + m * m));
        let gain = if model_is_zero { f64::NAN } else { yy / mm };
        let n = t.values.len().max(1) as f64;
        let mean = t.values.iter().sum::<f64>() / n;
        let spread = (t
            .values
            .iter()
            .map(|v| (v - mean) * (v - mean))
            .sum::<f64>()
            / n)
            .sqrt();
        ChannelFit {
            recording: recording.to_string(),
            channel: t.channel,
            nrmse: e,
            fit_percent: 100.0 * (1.0 - e),
            rms_in_noise: (r.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            has_signal: spread > 3.0 * t.sigma,
            residuals: r.to_vec(),
            model_is_zero,
            gain,
            input_v: t
                .rows
                .iter()
                .map(|&row| {
                    let v = &v_v[row];
                    match t.channel {
                        Channel::Current(k) => v[k],
                        _ => v.iter().sum::<f64>() / v.len().max(1) as f64,
                    }
                })
                .collect(),
            segment_inputs_v: match t.channel {
                Channel::Current(_) => Vec::new(),
                _ => (0..v_v.segments())
                    .map(|k| t.rows.iter().map(|&row| v_v[row][k]).collect())
                    .collect(),
            },
            sample_s: dt_s
                * t.rows
                    .windows(2)
                    .map(|w| w[1] - w[0])
                    .min()
                    .unwrap_or(1)
                    .max(1) as f64,
        }
    }
}

/// A model's fit over a set of recordings.
#[derive(Clone, Debug)]
pub struct Score {
    /// Per channel and recording.
    pub channels: Vec<ChannelFit>,
    /// Mean NRMSE over the channels that carry signal.
    pub nrmse: f64,
    /// Sum of squared weighted residuals.
    pub rss: f64,
    /// Residual count.
    pub m: usize,
}

impl Score {
    /// Pools per-channel fits.
    pub fn new(channels: Vec<ChannelFit>) -> Score {
        let signal: Vec<f64> = channels
            .iter()
            .filter(|c| c.has_signal)
            .map(|c| c.nrmse)
            .collect();
        let nrmse = if signal.is_empty() {
            0.0
        } else {
            signal.iter().sum::<f64>() / signal.len() as f64
        };
        let rss = channels
            .iter()
            .flat_map(|c| c.residuals.iter())
            .map(|x| x * x)
            .sum();
        let m = channels.iter().map(|c| c.residuals.len()).sum();
        Score {
            channels,
            nrmse,
            rss,
            m,
        }
    }
}

/// `(AIC, BIC)` for least squares: `m ln(RSS/m) + 2k` and `m ln(RSS/m) + k ln m`.
pub fn information(rss: f64, m: usize, k: usize) -> (f64, f64) {
    let m_f = m as f64;
    let fit = m_f * (rss / m_f).ln();
    (fit + 2.0 * k as f64, fit + k as f64 * m_f.ln())
}

/// Each knob's value's gradient with respect to all of `θ`, by forward
/// differences: a row per knob of `space`, in its order, empty for a knob
/// not in `active` (nothing reads it).
pub fn value_gradients(space: &Space, theta: &[f64], active: &[usize]) -> Vec<Vec<f64>> {
    let here = space.spec(theta);
    space
        .knobs
        .iter()
        .enumerate()
        .map(|(j, &knob)| {
            if !active.contains(&j) {
                return Vec::new();
            }
            let value = Space::value(knob, &here);
            (0..theta.len())
                .map(|i| {
                    let h = difference_step(theta[i]);
                    let mut t = theta.to_vec();
                    t[i] += h;
                    (Space::value(knob, &space.spec(&t)) - value) / h
                })
                .collect()
        })
        .collect()
}

/// 95 % intervals by the delta method: each knob's variance is the
/// diagonal of `value_cov`, the covariance of the values (see
/// [`value_covariance`]; so `z`, which is fitted relative to `p`, carries
/// `p`'s uncertainty too). A parameter that must be positive gets its
/// interval on a log scale, so it stays positive. A knob not in `active`
/// gets an unbounded interval.
pub fn estimates(
    space: &Space,
    theta: &[f64],
    value_cov: &DMatrix<f64>,
    active: &[usize],
) -> Vec<Estimate> {
    let here = space.spec(theta);
    space
        .knobs
        .iter()
        .enumerate()
        .map(|(j, &knob)| {
            let value = Space::value(knob, &here);
            if !active.contains(&j) {
                return Estimate {
                    knob,
                    value,
                    low: f64::NEG_INFINITY,
                    high: f64::INFINITY,
                };
            }
            let se = value_cov[(j, j)].max(0.0).sqrt();
            let se = if se.is_finite() { se } else { f64::INFINITY };
            // A ramp knob at its floor has no slope there, so the delta
            // method gives it a zero-width interval: as if the data pinned
            // it at 0, where they only say it is not above what the rest
            // explains. The data do not bound it from here: 0 and up.
            let (low, high) = if knob.floored() && value == 0.0 && se == 0.0 {
                (0.0, f64::INFINITY)
            } else {
                interval(knob.positive(), value, se)
            };
            Estimate {
                knob,
                value,
                low,
                high,
            }
        })
        .collect()
}

/// The covariance of the knobs' values, `G C Gᵀ` with `G` the rows of
/// `grads`: what a joint test of several knobs needs, since knobs that do
/// the same work (two dampings of the first mode) can each be unsure
/// while together they are not. A knob not in `active` has an infinite
/// variance and no covariance.
pub fn value_covariance(cov: &DMatrix<f64>, active: &[usize], grads: &[Vec<f64>]) -> DMatrix<f64> {
    let n = grads.len();
    let mut out = DMatrix::zeros(n, n);
    for a in 0..n {
        for b in 0..n {
            out[(a, b)] = if !active.contains(&a) || !active.contains(&b) {
                if a == b {
                    f64::INFINITY
                } else {
                    0.0
                }
            } else {
                quadratic(&grads[a], cov, &grads[b])
            };
        }
    }
    out
}

/// The quantile `p` of `χ²(q)` (infinite for no degree of freedom).
pub fn chi2_quantile(q: usize, p: f64) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(q as f64).map_or(f64::INFINITY, |c| c.inverse_cdf(p))
}

/// Wilson and Hilferty's approximation to the quantile of `χ²(h)` whose
/// normal deviate is `z`: `h (1 − a + z √a)³`, `a = 2/(9h)`.
pub fn wilson_hilferty(h: usize, z: f64) -> f64 {
    let h = h as f64;
    let a = 2.0 / (9.0 * h);
    h * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Whether the values `d` (each knob's value less its "off") differ from
/// zero jointly at the level `1 − tail`, by Wald's test `dᵀ Σ⁺ d` above
/// the quantile `1 − tail` of `χ²(r)`: `Σ⁺` the
/// pseudo-inverse of their covariance `sigma` and `r` its rank, so two
/// knobs that are one direction in the data count as one. False when a
/// variance is not finite.
pub fn wald_excludes(d: &[f64], sigma: &DMatrix<f64>, tail: f64) -> bool {
    let n = d.len();
    if n == 0 || (0..n).any(|i| !sigma[(i, i)].is_finite() || !d[i].is_finite()) {
        return false;
    }
    // A knob with no spread at all (held at a bound) differs exactly when
    // it differs, and at "off" leaves the test to the others.
    let s: Vec<f64> = (0..n).map(|i| sigma[(i, i)].max(0.0).sqrt()).collect();
    if (0..n).any(|i| s[i] == 0.0 && d[i] != 0.0) {
        return true;
    }
    let keep: Vec<usize> = (0..n).filter(|&i| s[i] > 0.0).collect();
    let n = keep.len();
    if n == 0 {
        return false;
    }
    // Scaled to unit variances first, so the rank's tolerance is relative.
    let r = DMatrix::from_fn(n, n, |a, b| {
        let (i, j) = (keep[a], keep[b]);
        sigma[(i, j)] / (s[i] * s[j])
    });
    let z = nalgebra::DVector::from_fn(n, |a, _| d[keep[a]] / s[keep[a]]);
    let svd = r.svd(true, true);
    let tol = 1e-9 * svd.singular_values.max();
    let rank = svd.singular_values.iter().filter(|&&x| x > tol).count();
    let Ok(inv) = svd.pseudo_inverse(tol) else {
        return false;
    };
    rank > 0 && (z.transpose() * inv * &z)[(0, 0)] > chi2_quantile(rank, 1.0 - tail)
}

/// `gᵀ C h`.
fn quadratic(g: &[f64], cov: &DMatrix<f64>, h: &[f64]) -> f64 {
    let k = g.len();
    let mut v = 0.0;
    for a in 0..k {
        for b in 0..k {
            // 0 · ∞ from an inactive knob the value does not depend on.
            if g[a] != 0.0 && h[b] != 0.0 {
                v += g[a] * cov[(a, b)] * h[b];
            }
        }
    }
    v
}

/// The normal deviate of the fit's two-sided 95 % intervals.
pub(super) const Z95: f64 = 1.96;

/// Whether `est`'s interval, widened from 95 % to `z` standard errors (in
/// the space it is symmetric in), excludes `off`.
pub fn excludes_at(est: &Estimate, off: f64, z: f64) -> bool {
    if !(est.low.is_finite() && est.high.is_finite()) {
        return false;
    }
    let widen = z / Z95;
    if est.knob.positive() && est.value > 0.0 {
        // Log-symmetric: a positive interval never reaches 0 or below.
        off <= 0.0 || (est.value / off).ln().abs() > widen * (est.high / est.value).ln()
    } else {
        (est.value - off).abs() > widen * 0.5 * (est.high - est.low)
    }
}

/// Whether `est`'s interval, widened as [`excludes_at`] does, lies
/// wholly beyond `±margin`: the value departs from 0 by more than
/// `margin`, not merely from 0. On the symmetric scale (a deviation).
pub fn beyond_at(est: &Estimate, margin: f64, z: f64) -> bool {
    est.low.is_finite()
        && est.high.is_finite()
        && est.value.abs() - margin > z / Z95 * 0.5 * (est.high - est.low)
}

/// Whether `est`'s upper end, widened as [`excludes_at`] does, is below
/// `off`.
pub fn below_at(est: &Estimate, off: f64, z: f64) -> bool {
    est.high.is_finite() && est.value + z / Z95 * (est.high - est.value) < off
}

/// Whether `est`'s lower end, widened as [`excludes_at`] does, is above
/// `off`.
pub fn above_at(est: &Estimate, off: f64, z: f64) -> bool {
    est.low.is_finite() && est.value - z / Z95 * (est.value - est.low) > off
}

/// The 95 % interval of `value` with standard error `se`: unbounded for an
/// infinite `se`, log-symmetric for a positive knob, else symmetric.
fn interval(positive: bool, value: f64, se: f64) -> (f64, f64) {
    if !se.is_finite() {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else if positive && value > 0.0 {
        let f = (Z95 * se / value).exp();
        (value / f, value * f)
    } else {
        (value - Z95 * se, value + Z95 * se)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wald's test at 95 %.
    fn wald(d: &[f64], sigma: &DMatrix<f64>) -> bool {
        wald_excludes(d, sigma, 0.05)
    }

    /// Unit variances with correlation `rho`.
    fn corr(rho: f64) -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[1.0, rho, rho, 1.0])
    }

    #[test]
    fn two_unsure_knobs_that_trade_off_can_differ_from_off_together() {
        // Each 1 σ from zero alone (inside its 95 % interval); along the
        // direction they share, far out.
        assert!(wald(&[1.0, 1.0], &corr(-0.95)));
        // The same values along the direction they trade: no evidence.
        assert!(!wald(&[1.0, 1.0], &corr(0.95)));
        assert!(!wald(&[1.0, -1.0], &corr(-0.95)));
    }

    #[test]
    fn knobs_that_are_one_direction_count_as_one_degree_of_freedom() {
        // Rank one: the statistic is (z₁ + z₂)²/4 against χ²₉₅(1).
        assert!(wald(&[2.0, 2.0], &corr(1.0)));
        assert!(!wald(&[1.9, 1.9], &corr(1.0)));
    }

    #[test]
    fn a_lone_knob_is_its_interval() {
        let one = |d: f64, var: f64| wald(&[d], &DMatrix::from_element(1, 1, var));
        assert!(one(2.0, 1.0));
        assert!(!one(1.9, 1.0));
        assert!(one(-2.0 * 3.0, 9.0));
        assert!(!one(5.0, f64::INFINITY));
        assert!(!one(f64::NAN, 1.0));
        assert!(!wald(&[], &DMatrix::zeros(0, 0)));
    }

    #[test]
    fn a_knob_held_at_off_leaves_the_test_to_the_others() {
        // ζ₀ at its bound 0 with no spread, β 3 σ from zero.
        let sigma = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]);
        assert!(wald(&[0.0, 3.0], &sigma));
        assert!(!wald(&[0.0, 1.0], &sigma));
        // Held away from off: it differs.
        assert!(wald(&[0.5, 0.0], &sigma));
        assert!(!wald(&[0.0, 0.0], &DMatrix::zeros(2, 2)));
    }

    #[test]
    fn the_chi_square_quantiles_are_the_tables() {
        for (q, p, table) in [
            (1, 0.95, 3.8415),
            (2, 0.95, 5.9915),
            (9, 0.95, 16.9190),
            (2, 0.9983, 12.7553),
        ] {
            assert!((chi2_quantile(q, p) / table - 1.0).abs() < 1e-4, "{q} {p}");
        }
        // Wilson–Hilferty's (the whiteness tests') within 0.2 % of it.
        assert!((wilson_hilferty(9, 1.644_853_6) / chi2_quantile(9, 0.95) - 1.0).abs() < 2e-3);
    }

    #[test]
    fn a_ramp_knob_at_its_floor_is_bounded_below_only() {
        use super::super::effect::Effect;
        let fixed = crate::model::predict::ModelSpec::baseline(model_core::Params::main_m_2006());
        let space = Space::new(&[Effect::Damping], 3, fixed);
        let mut theta = space.start_theta(&fixed);
        let zeta = space.knobs.iter().position(|k| *k == Knob::Zeta).unwrap();
        let r1 = space.knobs.iter().position(|k| *k == Knob::R1).unwrap();
        // θ below the ramp's bend: ζ₀ = 0 and no slope, so no spread.
        theta[zeta] = -0.5;
        let n = space.knobs.len();
        let active: Vec<usize> = (0..n).collect();
        let est = estimates(&space, &theta, &DMatrix::zeros(n, n), &active);
        assert_eq!(est[zeta].value, 0.0);
        assert_eq!((est[zeta].low, est[zeta].high), (0.0, f64::INFINITY));
        // It never counts as excluding 0 or as above it.
        assert!(!excludes_at(&est[zeta], 0.0, 1.96) && !above_at(&est[zeta], 0.0, 1.96));
        // A knob off any floor keeps its delta-method interval.
        assert_eq!(est[r1].low, est[r1].value);
        assert_eq!(est[r1].high, est[r1].value);
    }

    #[test]
    fn beyond_a_margin_asks_the_whole_interval_past_it() {
        let est = |value: f64, half: f64| Estimate {
            knob: Knob::SegmentK(1),
            value,
            low: value - half,
            high: value + half,
        };
        // A 2 % deviation known to ±0.2 %: not 0, but within a 5 % margin.
        assert!(excludes_at(&est(0.02, 0.002), 0.0, 3.0));
        assert!(!beyond_at(&est(0.02, 0.002), 0.05, 3.0));
        // 10 % ± 2 % (95 %): 3 σ reach 6.9 %, beyond 5 %; either sign.
        assert!(beyond_at(&est(0.10, 0.02), 0.05, 3.0));
        assert!(beyond_at(&est(-0.10, 0.02), 0.05, 3.0));
        // ± 4 % at 95 %: 3 σ reach 3.9 %, inside.
        assert!(!beyond_at(&est(0.10, 0.04), 0.05, 3.0));
        // No interval, no claim.
        assert!(!beyond_at(&est(0.5, f64::INFINITY), 0.05, 3.0));
    }

    #[test]
    fn a_wider_interval_asks_more_of_a_knob() {
        let est = |value: f64, low: f64, high: f64| Estimate {
            knob: Knob::Crosstalk,
            value,
            low,
            high,
        };
        // 0.04 ± 0.03 (at 1.96 σ, so 2.6 σ from 0): excludes 0 at 95 %,
        // not at 3 σ.
        let e = est(0.04, 0.01, 0.07);
        assert!(excludes_at(&e, 0.0, 1.96) && !excludes_at(&e, 0.0, 3.0));
        assert!(!excludes_at(
            &est(0.05, f64::NEG_INFINITY, f64::INFINITY),
            0.0,
            1.0
        ));
        // A positive knob's interval is log-symmetric: EI 0.8 of the
        // laminate's with a factor 1.1 at 95 %.
        let ei = Estimate {
            knob: Knob::Ei,
            value: 0.8,
            low: 0.8 / 1.1,
            high: 0.88,
        };
        assert!(excludes_at(&ei, 1.0, 1.96));
        let f = (1.0f64 / 0.8).ln() / 1.1f64.ln() * 1.96;
        assert!(excludes_at(&ei, 1.0, 0.99 * f) && !excludes_at(&ei, 1.0, 1.01 * f));
        // Below zero: b's upper end.
        let b = est(-1.0, -1.5, -0.5);
        assert!(below_at(&b, 0.0, 1.96) && below_at(&b, 0.0, 3.9) && !below_at(&b, 0.0, 4.0));
    }
}
