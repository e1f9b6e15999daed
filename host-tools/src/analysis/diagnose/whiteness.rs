//! Residual tests, as MATLAB's `resid`: is what the model leaves white
//! noise, and is it independent of the input?

/// Normalised autocorrelation of `r` at lags `0..=max_lag`.
pub fn autocorrelation(r: &[f64], max_lag: usize) -> Vec<f64> {
    let n = r.len();
    let mean = r.iter().sum::<f64>() / n.max(1) as f64;
    let c0: f64 = r.iter().map(|x| (x - mean) * (x - mean)).sum();
    (0..=max_lag.min(n.saturating_sub(1)))
        .map(|k| {
            if c0 == 0.0 {
                return 0.0;
            }
            let ck: f64 = (k..n).map(|i| (r[i] - mean) * (r[i - k] - mean)).sum();
            ck / c0
        })
        .collect()
}

/// Ljung–Box statistic over lags `1..=h`: `Q = n(n+2) Σ ρₖ²/(n−k)`;
/// white noise gives `χ²(h)`, mean `h`, so `Q/h` near 1 is white.
pub fn ljung_box(r: &[f64], h: usize) -> f64 {
    let n = r.len() as f64;
    let rho = autocorrelation(r, h);
    rho.iter()
        .enumerate()
        .skip(1)
        .map(|(k, p)| p * p / (n - k as f64))
        .sum::<f64>()
        * n
        * (n + 2.0)
}

/// The 99 % quantile of `χ²(h)` (Wilson–Hilferty), the Ljung–Box threshold.
pub fn chi2_99(h: usize) -> f64 {
    crate::analysis::fit::wilson_hilferty(h, 2.326_347_874)
}

/// Lags of the residual–input correlation, as MATLAB's `resid` default.
pub const INPUT_LAGS: usize = 25;

/// Largest normalised cross-correlation between `r` and `u` over lags
/// `0..=max_lag` (`u` leading), and its 99 % band for white `r`: `2.58/√n`.
pub fn input_correlation(r: &[f64], u: &[f64], max_lag: usize) -> (f64, f64) {
    let (best, _, band) = input_correlation_lag(r, u, max_lag);
    (best, band)
}

/// As [`input_correlation`], with the lag (samples) of the largest.
pub fn input_correlation_lag(r: &[f64], u: &[f64], max_lag: usize) -> (f64, usize, f64) {
    let n = r.len().min(u.len());
    let mr = r[..n].iter().sum::<f64>() / n.max(1) as f64;
    let mu = u[..n].iter().sum::<f64>() / n.max(1) as f64;
    let sr = r[..n]
        .iter()
        .map(|x| (x - mr) * (x - mr))
        .sum::<f64>()
        .sqrt();
    let su = u[..n]
        .iter()
        .map(|x| (x - mu) * (x - mu))
        .sum::<f64>()
        .sqrt();
    let band = 2.58 / (n.max(1) as f64).sqrt();
    if sr == 0.0 || su == 0.0 {
        return (0.0, 0, band);
    }
    let (lag, best) = (0..=max_lag.min(n.saturating_sub(1)))
        .map(|k| {
            let c: f64 = (k..n).map(|i| (r[i] - mr) * (u[i - k] - mu)).sum();
            (k, (c / (sr * su)).abs())
        })
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    (best, lag, band)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_passes_and_a_sine_fails() {
        // A deterministic white-ish sequence: a linear congruential generator.
        let mut x = 12345u64;
        let white: Vec<f64> = (0..5000)
            .map(|_| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let q = ljung_box(&white, 20);
        assert!(q < chi2_99(20), "Q = {q}");
        let sine: Vec<f64> = (0..5000).map(|i| (i as f64 * 0.05).sin()).collect();
        assert!(ljung_box(&sine, 20) > 100.0 * chi2_99(20));
        let (c, band) = input_correlation(&white, &sine, 10);
        assert!(c < band, "{c} vs {band}");
        let (c, _) = input_correlation(&sine, &sine, 10);
        assert!(c > 0.99);
        // χ²(20) 99 % is 37.57.
        assert!((chi2_99(20) - 37.57).abs() < 0.1);
    }
}
