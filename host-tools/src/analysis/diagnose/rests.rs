//! What the opening rests say about the bench.
//!
//! Every recording opens with at least a second at 0 V (docs/FORMAT.md),
//! so its DAQ channels (currents, load cell) show the bench alone there.
//! Bench imperfections are not model effects (docs/FORMAT.md, catalogue
//! notes): mains hum and coloured sensor noise show in those rests, and
//! are reported as what they are instead of as a catalogue name. Structure
//! in the rests that neither accounts for is what makes a verdict
//! `unexplained` before any model is fitted.
//!
//! Per channel, the rests of all recordings are pooled into one Welch
//! spectrum (segments of about half a second, linear trend removed, Hann
//! window), because hum and sensor noise belong to the sensor, not to a
//! recording:
//! - **mains hum**: a line at 50 Hz or 60 Hz or a harmonic (up to the
//!   5th) standing [`HUM_LINE_RATIO`] above the spectrum's median around it;
//! - **coloured noise**: the mean level at [`LOW_BAND_HZ`] over the level
//!   from a tenth of the sampling rate to 0.4 of it, mains lines left out,
//!   above [`COLOURED_RATIO`] and above four standard errors of a white
//!   spectrum's ratio.
//!
//! The whiteness test (Ljung–Box over 20 lags at 99 %) then runs on each
//! rest with the found hum's lines removed by least squares; a channel
//! with coloured noise fails it for that reason, so its failures are laid
//! to the bench.

use rustfft::num_complex::Complex;
use serde::Serialize;

use super::whiteness;
use crate::analysis::median::median;
use crate::session::Session;

/// Mains frequencies tried, Hz.
pub const MAINS_HZ: [f64; 2] = [50.0, 60.0];
/// Harmonics of the mains tried (a rectifier's pickup reaches the 5th).
pub const HARMONICS: usize = 5;
/// A mains line's spectral level over the median level around it above
/// which it is hum: averaged periodograms of white noise exceed 10 times
/// their median with odds below 1e-4 even from a single segment pair.
pub const HUM_LINE_RATIO: f64 = 10.0;
/// Band whose level is compared with the high band's for 1/f noise, Hz.
pub const LOW_BAND_HZ: (f64, f64) = (2.0, 20.0);
/// Least low-band to high-band level ratio called coloured noise.
pub const COLOURED_RATIO: f64 = 1.5;
/// Share of a channel kind's rests that may fail the whiteness test
/// before the rests are called structured: white noise fails one in a
/// hundred.
pub const REST_STRUCTURE_SHARE: f64 = 0.5;
/// Rest samples below which a rest is not tested.
const MIN_REST: usize = 200;
/// Half-width of the band around a mains line left out of the noise
/// levels, Hz.
const LINE_HALF_WIDTH_HZ: f64 = 3.0;
/// Half-width of the neighbourhood whose median is a line's floor, Hz.
const FLOOR_HALF_WIDTH_HZ: f64 = 12.0;

/// A bench imperfection seen in the opening rests.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct BenchFinding {
    /// `mains-hum`, `coloured-noise`, or `currents-read-before-update`
    /// (the bench samples its currents before each row's voltage: found in
    /// the currents by `fit::sampling`, and followed by the fit).
    pub what: String,
    /// The channel's column name.
    pub channel: String,
    /// The mains frequency, Hz (hum only).
    pub mains_hz: Option<f64>,
    /// For hum, its rms over the rest of the noise's rms; for coloured
    /// noise, the low band's level over the high band's.
    pub strength: f64,
    /// What was seen, in words.
    pub detail: String,
}

/// Whether the measured channels carry structure before any drive.
#[derive(Clone, Debug, Serialize)]
pub struct RestStructure {
    /// Opening rests tested (recording × current or force channel).
    pub tested: usize,
    /// Those whose Ljung–Box `Q` over 20 lags exceeds the 99 % threshold
    /// once any found hum is removed.
    pub failing: usize,
    /// Of those, the ones on a channel without coloured noise: structure
    /// the bench findings do not account for.
    pub failing_unexplained: usize,
    /// Whether more than [`REST_STRUCTURE_SHARE`] of the tested rests
    /// carry structure the bench findings do not account for.
    pub structured: bool,
    /// Mains hum and coloured noise found, per channel.
    pub bench: Vec<BenchFinding>,
}

/// One channel's rests, pooled across the session.
struct ChannelRests {
    name: String,
    rate_hz: f64,
    rests: Vec<Vec<f64>>,
}

/// Tests the opening rest of every DAQ channel (currents, load cell) for
/// hum, coloured noise and whiteness; camera channels have too few frames
/// there to test.
pub fn rest_structure(session: &Session) -> RestStructure {
    let mut out = RestStructure {
        tested: 0,
        failing: 0,
        failing_unexplained: 0,
        structured: false,
        bench: Vec::new(),
    };
    for ch in channel_rests(session) {
        let spectrum = welch(&ch.rests, ch.rate_hz);
        let hum = spectrum.as_ref().and_then(|s| hum(s, &ch.name));
        let coloured = spectrum.as_ref().and_then(|s| coloured(s, &ch.name));
        let lines: Vec<f64> = hum
            .as_ref()
            .and_then(|h| h.mains_hz)
            .map(|f0| mains_lines(f0, ch.rate_hz))
            .unwrap_or_default();
        for rest in &ch.rests {
            let clean = remove_lines(rest, &lines, ch.rate_hz);
            out.tested += 1;
            if whiteness::ljung_box(&clean, 20) > whiteness::chi2_99(20) {
                out.failing += 1;
                out.failing_unexplained += usize::from(coloured.is_none());
            }
        }
        out.bench.extend(hum);
        out.bench.extend(coloured);
    }
    out.structured =
        out.tested > 0 && out.failing_unexplained as f64 > REST_STRUCTURE_SHARE * out.tested as f64;
    out
}

/// The rests of each DAQ channel, grouped by column name and sampling
/// rate (a session may mix rates; a spectrum pools one).
fn channel_rests(session: &Session) -> Vec<ChannelRests> {
    let mut out: Vec<ChannelRests> = Vec::new();
    for r in &session.recordings {
        let rate_hz = (1.0 / r.dt_s).round();
        for (ch, values) in &r.rec.channels {
            if ch.is_camera() {
                continue;
            }
            let rest: Option<Vec<f64>> = values[..r.rest_rows.min(values.len())]
                .iter()
                .copied()
                .collect();
            let Some(rest) = rest.filter(|v| v.len() >= MIN_REST) else {
                continue;
            };
            let name = ch.name();
            match out
                .iter_mut()
                .find(|c| c.name == name && c.rate_hz == rate_hz)
            {
                Some(c) => c.rests.push(rest),
                None => out.push(ChannelRests {
                    name,
                    rate_hz,
                    rests: vec![rest],
                }),
            }
        }
    }
    out
}

/// A one-sided power spectral density, averaged over segments.
struct Spectrum {
    /// Density per bin, unit²/Hz; bin `k` is at `k · df_hz`.
    psd: Vec<f64>,
    df_hz: f64,
    rate_hz: f64,
    /// Segments averaged.
    segments: usize,
}

impl Spectrum {
    fn bin(&self, f_hz: f64) -> usize {
        (f_hz / self.df_hz).round() as usize
    }

    /// Bins in `[lo, hi]` Hz that lie off every mains line.
    fn off_line_bins(&self, lo_hz: f64, hi_hz: f64) -> Vec<usize> {
        let lines: Vec<f64> = MAINS_HZ
            .iter()
            .flat_map(|&f0| mains_lines(f0, self.rate_hz))
            .collect();
        (self.bin(lo_hz).max(2)..=self.bin(hi_hz).min(self.psd.len() - 1))
            .filter(|&k| {
                let f = k as f64 * self.df_hz;
                lines.iter().all(|l| (f - l).abs() > LINE_HALF_WIDTH_HZ)
            })
            .collect()
    }
}

/// The mains' harmonics below 0.45 of the sampling rate, Hz.
fn mains_lines(f0_hz: f64, rate_hz: f64) -> Vec<f64> {
    (1..=HARMONICS)
        .map(|k| k as f64 * f0_hz)
        .filter(|&f| f < 0.45 * rate_hz)
        .collect()
}

/// Welch's averaged periodogram of the rests: segments of the power of two
/// nearest half a second (bins about 2 Hz wide, fine enough to part 50 Hz
/// from its neighbours), half overlapping, each detrended and Hann
/// windowed. `None` when no rest holds a segment.
fn welch(rests: &[Vec<f64>], rate_hz: f64) -> Option<Spectrum> {
    let len = ((rate_hz / 2.0).max(64.0) as usize).next_power_of_two();
    let window: Vec<f64> = (0..len)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / len as f64).cos())
        .collect();
    let power: f64 = window.iter().map(|w| w * w).sum();
    let fft = rustfft::FftPlanner::new().plan_fft_forward(len);
    let mut psd = vec![0.0; len / 2 + 1];
    let mut segments = 0;
    let mut buf = vec![Complex::new(0.0, 0.0); len];
    for rest in rests {
        let mut start = 0;
        while start + len <= rest.len() {
            let seg = &rest[start..start + len];
            let (a, b) = line_fit(seg);
            for (i, (x, w)) in seg.iter().zip(&window).enumerate() {
                buf[i] = Complex::new((x - a - b * i as f64) * w, 0.0);
            }
            fft.process(&mut buf);
            for (k, p) in psd.iter_mut().enumerate() {
                // One-sided: every bin but DC and Nyquist counts twice.
                let twice = if k == 0 || k == len / 2 { 1.0 } else { 2.0 };
                *p += twice * buf[k].norm_sqr() / (rate_hz * power);
            }
            segments += 1;
            start += len / 2;
        }
    }
    if segments == 0 {
        return None;
    }
    for p in &mut psd {
        *p /= segments as f64;
    }
    Some(Spectrum {
        psd,
        df_hz: rate_hz / len as f64,
        rate_hz,
        segments,
    })
}

/// Least-squares line `a + b i` through a segment.
fn line_fit(y: &[f64]) -> (f64, f64) {
    let n = y.len() as f64;
    let mean_i = (n - 1.0) / 2.0;
    let mean_y = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in y.iter().enumerate() {
        let di = i as f64 - mean_i;
        sxy += di * (v - mean_y);
        sxx += di * di;
    }
    let b = sxy / sxx;
    (mean_y - b * mean_i, b)
}

/// The strongest mains family's hum, if a line of it stands out.
fn hum(s: &Spectrum, channel: &str) -> Option<BenchFinding> {
    let mut best: Option<(f64, f64, f64)> = None; // (f0, strongest ratio, hum power)
    for &f0 in &MAINS_HZ {
        let (mut strongest, mut power) = (0.0f64, 0.0);
        for f in mains_lines(f0, s.rate_hz) {
            let around = s.off_line_bins(f - FLOOR_HALF_WIDTH_HZ, f + FLOOR_HALF_WIDTH_HZ);
            if around.len() < 4 {
                continue;
            }
            let Some(floor) = median(around.iter().map(|&k| s.psd[k]).collect()) else {
                continue;
            };
            let k = s.bin(f);
            // The Hann window spreads a line over about three bins.
            let near = k.saturating_sub(2)..=(k + 2).min(s.psd.len() - 1);
            let peak = near.clone().map(|k| s.psd[k]).fold(0.0, f64::max);
            let ratio = peak / floor.max(f64::MIN_POSITIVE);
            strongest = strongest.max(ratio);
            if ratio > HUM_LINE_RATIO {
                // Power of the line over the floor: a Hann window keeps a
                // line's power within two bins either side.
                power += near.map(|k| (s.psd[k] - floor).max(0.0)).sum::<f64>() * s.df_hz;
            }
        }
        if strongest > HUM_LINE_RATIO && best.is_none_or(|b| strongest > b.1) {
            best = Some((f0, strongest, power));
        }
    }
    let (f0, ratio, power) = best?;
    let total: f64 = s.psd.iter().skip(1).sum::<f64>() * s.df_hz;
    let noise = (total - power).max(f64::MIN_POSITIVE);
    let strength = (power / noise).sqrt();
    Some(BenchFinding {
        what: "mains-hum".to_string(),
        channel: channel.to_string(),
        mains_hz: Some(f0),
        strength,
        detail: format!(
            "{channel}: mains hum at {f0:.0} Hz and harmonics, rms {strength:.2} × the noise's (strongest line {ratio:.0} × the spectrum around it)"
        ),
    })
}

/// Coloured noise: the low band well above the high band.
fn coloured(s: &Spectrum, channel: &str) -> Option<BenchFinding> {
    let high = (s.rate_hz / 10.0, 0.4 * s.rate_hz);
    if high.0 < 2.0 * LOW_BAND_HZ.1 {
        return None;
    }
    let low_bins = s.off_line_bins(LOW_BAND_HZ.0, LOW_BAND_HZ.1);
    let high_bins = s.off_line_bins(high.0, high.1);
    if low_bins.len() < 3 || high_bins.is_empty() {
        return None;
    }
    let level = |bins: &[usize]| bins.iter().map(|&k| s.psd[k]).sum::<f64>() / bins.len() as f64;
    let ratio = level(&low_bins) / level(&high_bins).max(f64::MIN_POSITIVE);
    // A white spectrum's low-band mean has a relative standard error of
    // about 1/sqrt(segments · bins / 1.5): Hann's neighbouring bins share
    // half their information.
    let se = (1.5 / (s.segments * low_bins.len()) as f64).sqrt();
    if ratio <= COLOURED_RATIO.max(1.0 + 4.0 * se) {
        return None;
    }
    Some(BenchFinding {
        what: "coloured-noise".to_string(),
        channel: channel.to_string(),
        mains_hz: None,
        strength: ratio,
        detail: format!(
            "{channel}: coloured noise, {:.0}–{:.0} Hz at {ratio:.1} × the level at {:.0}–{:.0} Hz",
            LOW_BAND_HZ.0, LOW_BAND_HZ.1, high.0, high.1
        ),
    })
}

/// `y` with least-squares sinusoids at `lines_hz` removed (mean too).
fn remove_lines(y: &[f64], lines_hz: &[f64], rate_hz: f64) -> Vec<f64> {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let mut out: Vec<f64> = y.iter().map(|v| v - mean).collect();
    // Mains harmonics are nearly orthogonal over a second or more, so one
    // pass per line is least squares to within the rest's length.
    for &f in lines_hz {
        let w = 2.0 * std::f64::consts::PI * f / rate_hz;
        let (mut sc, mut ss, mut cc, mut css, mut ccs) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (i, v) in out.iter().enumerate() {
            let (s, c) = (w * i as f64).sin_cos();
            sc += v * c;
            ss += v * s;
            cc += c * c;
            css += s * s;
            ccs += c * s;
        }
        let det = cc * css - ccs * ccs;
        if det <= 0.0 {
            continue;
        }
        let a = (sc * css - ss * ccs) / det;
        let b = (ss * cc - sc * ccs) / det;
        for (i, v) in out.iter_mut().enumerate() {
            let (s, c) = (w * i as f64).sin_cos();
            *v -= a * c + b * s;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use std::f64::consts::PI;

    const RATE_HZ: f64 = 1000.0;

    fn white(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let d = Normal::new(0.0, sigma).unwrap();
        (0..n).map(|_| d.sample(&mut rng)).collect()
    }

    /// 1/f noise as the sum of first-order processes an octave apart.
    fn pink(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let d = Normal::new(0.0, 1.0).unwrap();
        let poles: Vec<f64> = (1..=10)
            .map(|k| (-2.0 * PI * (RATE_HZ / 2.0 / 2f64.powi(k)) / RATE_HZ).exp())
            .collect();
        let mut x: Vec<f64> = poles.iter().map(|_| d.sample(&mut rng)).collect();
        (0..n)
            .map(|_| {
                let mut sum = 0.0;
                for (x, a) in x.iter_mut().zip(&poles) {
                    *x = a * *x + (1.0 - a * a).sqrt() * d.sample(&mut rng);
                    sum += *x;
                }
                sum * sigma / 10f64.sqrt()
            })
            .collect()
    }

    fn with_hum(mut y: Vec<f64>, f0: f64, rms: f64) -> Vec<f64> {
        for (i, v) in y.iter_mut().enumerate() {
            let t = i as f64 / RATE_HZ;
            *v += rms * (2f64.sqrt() * (2.0 * PI * f0 * t + 0.3).sin());
        }
        y
    }

    fn findings(rests: Vec<Vec<f64>>) -> (Option<BenchFinding>, Option<BenchFinding>) {
        let s = welch(&rests, RATE_HZ).unwrap();
        (hum(&s, "i1_A"), coloured(&s, "i1_A"))
    }

    #[test]
    fn white_rests_show_neither_hum_nor_colour() {
        // Many sessions' worth of seeds: a false finding on white noise
        // would make every verdict carry a bench imperfection.
        for seed in 0..40 {
            let rests = (0..10).map(|r| white(1000, 1e-4, seed * 100 + r)).collect();
            let (h, c) = findings(rests);
            assert!(h.is_none(), "seed {seed}: {h:?}");
            assert!(c.is_none(), "seed {seed}: {c:?}");
        }
    }

    #[test]
    fn hum_is_found_at_its_mains_frequency_with_its_strength() {
        for (f0, seed) in [(50.0, 1), (60.0, 2)] {
            let rests = (0..5)
                .map(|r| with_hum(white(1000, 1.0, seed * 10 + r), f0, 1.0))
                .collect();
            let (h, c) = findings(rests);
            let h = h.expect("hum");
            assert_eq!(h.mains_hz, Some(f0));
            assert!((h.strength - 1.0).abs() < 0.2, "{h:?}");
            assert!(c.is_none(), "{c:?}");
        }
        // A tenth of the noise is still a line above the spectrum.
        let rests = (0..10)
            .map(|r| with_hum(white(1000, 1.0, 70 + r), 50.0, 0.3))
            .collect();
        assert!(findings(rests).0.is_some());
    }

    #[test]
    fn a_third_of_the_noise_as_1_over_f_is_coloured() {
        let rests = (0..10)
            .map(|r| {
                let w = white(1000, (2.0f64 / 3.0).sqrt(), 200 + r);
                let p = pink(1000, (1.0f64 / 3.0).sqrt(), 300 + r);
                w.iter().zip(&p).map(|(a, b)| a + b).collect()
            })
            .collect();
        let (h, c) = findings(rests);
        assert!(h.is_none(), "{h:?}");
        let c = c.expect("coloured");
        assert!(c.strength > 3.0, "{c:?}");
    }

    #[test]
    fn removing_the_found_lines_whitens_a_hummed_rest() {
        let rest = with_hum(white(2000, 1.0, 9), 50.0, 2.0);
        assert!(whiteness::ljung_box(&rest, 20) > whiteness::chi2_99(20));
        let clean = remove_lines(&rest, &mains_lines(50.0, RATE_HZ), RATE_HZ);
        assert!(whiteness::ljung_box(&clean, 20) < whiteness::chi2_99(20));
    }
}
