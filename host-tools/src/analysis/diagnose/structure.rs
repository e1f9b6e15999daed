//! What a channel's residuals hold when its sensor stays above the noise
//! floor: where in frequency their power lies, and how they follow the
//! input. `unexplained` says it of the sensor's worst channel, so that a
//! user can tell a slow drift (the relaxation, drying) from a ringing (the
//! mode's frequency or damping) or hum.

use std::fmt;

use rustfft::num_complex::Complex;
use serde::Serialize;

use super::whiteness::{input_correlation_lag, INPUT_LAGS};
use crate::analysis::fit::ChannelFit;
use crate::recording::Channel;

/// A channel's residual structure.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Structure {
    /// The octave band that holds the most residual power, Hz (the lowest
    /// band reaches down to 0).
    pub band_hz: (f64, f64),
    /// Its share of the residual power, percent (a white residual spreads
    /// half its power over the top octave, a quarter over the next).
    pub band_percent: f64,
    /// What the residual is correlated with: the segment's voltage for a
    /// current, the segment whose voltage it follows most for the beam's
    /// channels.
    pub input: String,
    /// The largest normalised cross-correlation with it over
    /// `0..=INPUT_LAGS` samples, the input leading.
    pub input_correlation: f64,
    /// At which lag, s.
    pub input_lag_s: f64,
    /// The 99 % band of that correlation for white residuals.
    pub input_band: f64,
    /// The residuals' sample rate, Hz: a camera's frame rate folds any
    /// faster motion (a first mode above half of it) into the bands below.
    pub sampled_hz: f64,
}

/// The structure of `c`'s residuals.
pub fn structure(c: &ChannelFit) -> Structure {
    let (band_hz, band_percent) = strongest_octave(&c.residuals, c.sample_s);
    // A current against its own segment's voltage; the beam's channels
    // against each segment's, the strongest kept.
    let inputs: Vec<(String, &[f64])> = match c.channel {
        Channel::Current(k) => vec![(format!("segment {}'s voltage", k + 1), &c.input_v)],
        _ => c
            .segment_inputs_v
            .iter()
            .enumerate()
            .map(|(k, u)| (format!("segment {}'s voltage", k + 1), u.as_slice()))
            .collect(),
    };
    let (input, (input_correlation, lag, input_band)) = inputs
        .into_iter()
        .map(|(name, u)| (name, input_correlation_lag(&c.residuals, u, INPUT_LAGS)))
        .fold(
            None,
            |best: Option<(String, (f64, usize, f64))>, x| match best {
                Some(b) if b.1 .0 >= x.1 .0 => Some(b),
                _ => Some(x),
            },
        )
        .unwrap_or_else(|| ("the drive".to_string(), (0.0, 0, 0.0)));
    // Below the band on every segment: none of them, not the best of none.
    let input = if input_correlation <= input_band && c.segment_inputs_v.len() > 1 {
        "any segment's voltage".to_string()
    } else {
        input
    };
    Structure {
        band_hz,
        band_percent,
        input,
        input_correlation,
        input_lag_s: lag as f64 * c.sample_s,
        input_band,
        sampled_hz: 1.0 / c.sample_s,
    }
}

/// The octave band (from the Nyquist frequency down) holding the largest
/// share of `r`'s power, sampled every `dt_s`, by a Hann-windowed
/// periodogram; the last band reaches down to 0 Hz (a drift or an offset).
fn strongest_octave(r: &[f64], dt_s: f64) -> ((f64, f64), f64) {
    let n = r.len();
    if n < 8 || dt_s.is_nan() || dt_s <= 0.0 {
        return ((0.0, 0.0), 0.0);
    }
    let len = n.next_power_of_two();
    let fft = rustfft::FftPlanner::new().plan_fft_forward(len);
    let mut buf: Vec<Complex<f64>> = (0..len)
        .map(|i| {
            let x = r.get(i).copied().unwrap_or(0.0);
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
            Complex::new(if i < n { x * w } else { 0.0 }, 0.0)
        })
        .collect();
    fft.process(&mut buf);
    let power: Vec<f64> = buf[..=len / 2].iter().map(|c| c.norm_sqr()).collect();
    let total: f64 = power.iter().sum();
    if total == 0.0 {
        return ((0.0, 0.0), 0.0);
    }
    let df_hz = 1.0 / (len as f64 * dt_s);
    let nyquist_hz = 0.5 / dt_s;
    // Octaves down from Nyquist while a band still spans a few bins.
    let mut best = ((0.0, nyquist_hz), 0.0);
    let mut hi_hz = nyquist_hz;
    loop {
        let lo_hz = if hi_hz / 2.0 < 4.0 * df_hz {
            0.0
        } else {
            hi_hz / 2.0
        };
        let share: f64 = power
            .iter()
            .enumerate()
            .filter(|(k, _)| {
                let f = *k as f64 * df_hz;
                f >= lo_hz && (f < hi_hz || *k == len / 2)
            })
            .map(|(_, p)| p)
            .sum::<f64>()
            / total;
        if share > best.1 {
            best = ((lo_hz, hi_hz), share);
        }
        if lo_hz == 0.0 {
            break;
        }
        hi_hz = lo_hz;
    }
    (best.0, 100.0 * best.1)
}

impl fmt::Display for Structure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (lo, hi) = self.band_hz;
        write!(
            f,
            "{:.0} % of its residual power in {} to {} Hz",
            self.band_percent,
            hz(lo),
            hz(hi)
        )?;
        // Below the board's sample rate: a camera's frames.
        if self.sampled_hz < 200.0 {
            write!(
                f,
                " (at {} frames/s: motion above {} Hz shows folded into this range)",
                hz(self.sampled_hz),
                hz(self.sampled_hz / 2.0)
            )?;
        }
        if self.input_correlation > self.input_band {
            write!(
                f,
                "; it follows {} (correlation {:.2} at {:.0} ms, white residuals below {:.2})",
                self.input,
                self.input_correlation,
                1e3 * self.input_lag_s,
                self.input_band
            )
        } else {
            write!(f, "; not correlated with {}", self.input)
        }
    }
}

/// A frequency as written: three significant digits, no trailing zeros.
fn hz(f: f64) -> String {
    if f == 0.0 {
        "0".to_string()
    } else {
        let digits = (2 - f.abs().log10().floor() as i32).max(0) as usize;
        let s = format!("{f:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(
        channel: Channel,
        residuals: Vec<f64>,
        input_v: Vec<f64>,
        sample_s: f64,
    ) -> ChannelFit {
        ChannelFit {
            recording: "r.csv".into(),
            channel,
            nrmse: 0.0,
            fit_percent: 100.0,
            rms_in_noise: 1.0,
            has_signal: true,
            residuals,
            model_is_zero: false,
            gain: 1.0,
            segment_inputs_v: vec![input_v.clone()],
            input_v,
            sample_s,
        }
    }

    #[test]
    fn a_ringing_is_placed_in_its_octave_and_a_drift_at_the_bottom() {
        let dt = 1e-3;
        // 26 Hz ringing, 4 s at 1 kHz: the 15.6–31.2 Hz octave.
        let ring: Vec<f64> = (0..4000)
            .map(|i| (2.0 * std::f64::consts::PI * 26.0 * i as f64 * dt).sin())
            .collect();
        let s = structure(&channel(Channel::TipY, ring, vec![0.0; 4000], dt));
        assert!(s.band_hz.0 <= 26.0 && 26.0 < s.band_hz.1, "{s:?}");
        assert!(s.band_percent > 90.0, "{s:?}");
        assert!(s.to_string().contains("not correlated"), "{s}");
        assert!(!s.to_string().contains("frames/s"), "{s}");
        // A slow drift: the lowest band, from 0.
        let drift: Vec<f64> = (0..4000).map(|i| i as f64 * 1e-3).collect();
        let s = structure(&channel(Channel::Force, drift, vec![0.0; 4000], dt));
        assert_eq!(s.band_hz.0, 0.0, "{s:?}");
        assert!(s.band_percent > 90.0, "{s:?}");
    }

    #[test]
    fn a_residual_that_follows_the_drive_says_so_with_its_lag() {
        let dt = 1e-3;
        // A square drive; the residual is the drive 3 samples late.
        let u: Vec<f64> = (0..4000)
            .map(|i| if (i / 500) % 2 == 0 { 0.0 } else { 2.0 })
            .collect();
        let r: Vec<f64> = (0..4000)
            .map(|i| if i >= 3 { 0.1 * u[i - 3] } else { 0.0 })
            .collect();
        let s = structure(&channel(Channel::Current(1), r, u, dt));
        assert!(s.input_correlation > 0.99, "{s:?}");
        assert!((s.input_lag_s - 0.003).abs() < 1e-12, "{s:?}");
        let text = s.to_string();
        assert!(
            text.contains("segment 2's voltage") && text.contains("at 3 ms"),
            "{text}"
        );
    }

    #[test]
    fn a_beam_channel_is_read_against_each_segment_not_the_flat_mean_of_a_travelling_wave() {
        let dt = 1e-3;
        let sine = |k: usize| -> Vec<f64> {
            (0..4000)
                .map(|i| {
                    let phase = 2.0 * std::f64::consts::PI * (i as f64 * dt - k as f64 / 3.0);
                    2.5 * phase.sin()
                })
                .collect()
        };
        let segments: Vec<Vec<f64>> = (0..3).map(sine).collect();
        let mean: Vec<f64> = (0..4000)
            .map(|i| segments.iter().map(|u| u[i]).sum::<f64>() / 3.0)
            .collect();
        assert!(mean.iter().all(|m| m.abs() < 1e-9));
        // The residual follows segment 2's voltage, 2 samples late.
        let r: Vec<f64> = (0..4000)
            .map(|i| {
                if i >= 2 {
                    0.1 * segments[1][i - 2]
                } else {
                    0.0
                }
            })
            .collect();
        let mut c = channel(Channel::TipY, r, mean, dt);
        c.segment_inputs_v = segments;
        let s = structure(&c);
        assert_eq!(s.input, "segment 2's voltage", "{s:?}");
        assert!(s.input_correlation > 0.99, "{s:?}");
        assert!((s.input_lag_s - 0.002).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn white_noise_spreads_over_the_top_octaves() {
        let mut x = 1u32;
        let white: Vec<f64> = (0..8192)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                f64::from(x) / f64::from(u32::MAX) - 0.5
            })
            .collect();
        let s = structure(&channel(Channel::TipY, white, vec![0.0; 8192], 1.0 / 30.0));
        // The top octave (7.5–15 Hz at 30 frames/s), about half the power.
        assert_eq!(s.band_hz, (7.5, 15.0), "{s:?}");
        assert!((s.band_percent - 50.0).abs() < 5.0, "{s:?}");
        assert!(
            s.to_string().contains("at 30 frames/s: motion above 15 Hz"),
            "{s}"
        );
        assert_eq!(hz(7.5), "7.5");
        assert_eq!(hz(0.1171875), "0.117");
        assert_eq!(hz(125.0), "125");
    }
}
