//! Bench imperfections: what a real bench adds that is not the strip.
//! None of them is a model effect (docs/FORMAT.md's catalogue notes): a
//! right diagnosis names no catalogue effect for them, reports them as
//! what they are where it can tell, and otherwise says `unexplained`.
//!
//! - `hum`: mains pickup at 50 Hz and its harmonics on the DAQ's analogue
//!   channels (currents, load cell), 1 to 3 times each channel's noise.
//! - `coloured-noise`: a third of every sensor's noise power is 1/f noise.
//! - `compliant-load-cell`: the load cell gives; the held strip's first
//!   mode falls to 0.45 to 0.7 of the rigid load cell's (about 50 to 80 Hz
//!   instead of ~117 Hz for the laminate's stiffness).
//! - `camera-exposure`: each camera frame is the mean position over an
//!   exposure of 8 to 25 ms before it.

use std::f64::consts::PI;

use rand::Rng;
use rand_distr::{Distribution, Normal};

/// The imperfections a bench can have; the default has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bench {
    /// Mains hum's rms, in units of each DAQ channel's noise.
    pub hum: Option<f64>,
    /// The 1/f part of each sensor's noise power, as a fraction of it.
    pub pink_fraction: Option<f64>,
    /// The held strip's first mode on the compliant load cell, as a
    /// fraction of its first mode on a rigid one.
    pub load_cell_mode_ratio: Option<f64>,
    /// Camera exposure, s.
    pub exposure_s: Option<f64>,
}

/// The names of the imperfections, as [`Bench::draw`] takes them.
pub const IMPERFECTIONS: [&str; 4] = [
    "hum",
    "coloured-noise",
    "compliant-load-cell",
    "camera-exposure",
];

/// Mains frequency, Hz.
pub const MAINS_HZ: f64 = 50.0;

/// Relative amplitudes of the hum's harmonics 1..=5 (a rectifier's
/// pickup: odd harmonics strong, even ones weaker).
const HARMONICS: [f64; 5] = [1.0, 0.3, 0.5, 0.1, 0.2];

impl Bench {
    /// A bench with `names` (from [`IMPERFECTIONS`]), each at a strength
    /// drawn from `rng`; an unknown name is refused.
    pub fn draw(names: &[&str], rng: &mut impl Rng) -> Result<Bench, String> {
        let mut b = Bench::default();
        for &name in names {
            match name {
                "hum" => b.hum = Some(rng.gen_range(1.0..3.0)),
                "coloured-noise" => b.pink_fraction = Some(rng.gen_range(0.25..0.4)),
                "compliant-load-cell" => b.load_cell_mode_ratio = Some(rng.gen_range(0.45..0.7)),
                "camera-exposure" => b.exposure_s = Some(rng.gen_range(0.008..0.025)),
                other => {
                    return Err(format!(
                        "unknown bench imperfection `{other}`: the rig has {IMPERFECTIONS:?}"
                    ))
                }
            }
        }
        Ok(b)
    }

    /// Whether the bench has any imperfection.
    pub fn is_perfect(&self) -> bool {
        *self == Bench::default()
    }
}

/// Mains hum at the instants `t_s`, rms `rms`: 50 Hz and harmonics with
/// random phases.
pub fn hum(t_s: &[f64], rms: f64, rng: &mut (impl Rng + ?Sized)) -> Vec<f64> {
    let phases: Vec<f64> = HARMONICS
        .iter()
        .map(|_| rng.gen_range(0.0..2.0 * PI))
        .collect();
    // A sum of sines of amplitudes a_h has power Σ a_h²/2.
    let power: f64 = HARMONICS.iter().map(|a| a * a / 2.0).sum();
    let scale = rms / power.sqrt();
    t_s.iter()
        .map(|t| {
            HARMONICS
                .iter()
                .zip(&phases)
                .enumerate()
                .map(|(h, (a, p))| a * (2.0 * PI * MAINS_HZ * (h + 1) as f64 * t + p).sin())
                .sum::<f64>()
                * scale
        })
        .collect()
}

/// Octaves of 1/f noise: one unit-variance first-order process per
/// octave below the Nyquist frequency, so that their sum's spectrum falls
/// as 1/f over these octaves (equal power per octave) and is flat below.
const PINK_OCTAVES: usize = 10;

/// `rows` samples of 1/f noise of standard deviation `sigma`, for a
/// channel sampled at `rate_hz`.
pub fn pink(rows: usize, sigma: f64, rate_hz: f64, rng: &mut (impl Rng + ?Sized)) -> Vec<f64> {
    let white = Normal::new(0.0, 1.0).expect("unit normal");
    let poles: Vec<f64> = (1..=PINK_OCTAVES)
        .map(|k| {
            let corner_hz = rate_hz / 2.0 / 2f64.powi(k as i32);
            (-2.0 * PI * corner_hz / rate_hz).exp()
        })
        .collect();
    // Each process starts from its stationary distribution.
    let mut state: Vec<f64> = poles.iter().map(|_| white.sample(rng)).collect();
    let norm = sigma / (PINK_OCTAVES as f64).sqrt();
    (0..rows)
        .map(|_| {
            let mut sum = 0.0;
            for (x, a) in state.iter_mut().zip(&poles) {
                *x = a * *x + (1.0 - a * a).sqrt() * white.sample(rng);
                sum += *x;
            }
            sum * norm
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn rng() -> rand::rngs::StdRng {
        rand::rngs::StdRng::seed_from_u64(3)
    }

    fn rms(x: &[f64]) -> f64 {
        (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
    }

    /// Power of `x` at `f_hz` by correlation with a sine and a cosine.
    fn amplitude_at(x: &[f64], rate_hz: f64, f_hz: f64) -> f64 {
        let (mut c, mut s) = (0.0, 0.0);
        for (i, v) in x.iter().enumerate() {
            let w = 2.0 * PI * f_hz * i as f64 / rate_hz;
            c += v * w.cos();
            s += v * w.sin();
        }
        2.0 * (c * c + s * s).sqrt() / x.len() as f64
    }

    #[test]
    fn hum_has_its_rms_and_sits_on_the_mains_lines() {
        let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 1e-3).collect();
        let h = hum(&t, 2.0, &mut rng());
        assert!((rms(&h) - 2.0).abs() < 0.01, "{}", rms(&h));
        let at_50 = amplitude_at(&h, 1000.0, 50.0);
        let at_150 = amplitude_at(&h, 1000.0, 150.0);
        let off_line = amplitude_at(&h, 1000.0, 73.0);
        assert!(at_50 > 2.0 && at_150 > 0.4 * at_50, "{at_50} {at_150}");
        assert!(off_line < 0.01 * at_50, "{off_line}");
    }

    #[test]
    fn pink_noise_has_its_level_and_falls_as_one_over_f() {
        let rows = 1 << 17;
        let x = pink(rows, 3.0, 1000.0, &mut rng());
        assert!((rms(&x) / 3.0 - 1.0).abs() < 0.1, "{}", rms(&x));
        // Power in two octaves a factor 8 apart in frequency: 1/f gives the
        // same power per octave, white noise eight times more in the higher.
        let band = |lo: f64| -> f64 {
            let mut p = 0.0;
            let mut f = lo;
            while f < 2.0 * lo {
                p += amplitude_at(&x[..1 << 14], 1000.0, f).powi(2);
                f += 1000.0 / (1 << 14) as f64;
            }
            p
        };
        let (low, high) = (band(4.0), band(32.0));
        let ratio = high / low;
        assert!(ratio > 0.4 && ratio < 2.5, "octave power ratio {ratio}");
    }

    #[test]
    fn unknown_imperfections_are_refused_by_name() {
        let e = Bench::draw(&["hum", "wobble"], &mut rng()).unwrap_err();
        assert!(e.contains("`wobble`"), "{e}");
        let b = Bench::draw(&IMPERFECTIONS, &mut rng()).unwrap();
        assert!(b.hum.is_some() && b.pink_fraction.is_some());
        assert!(b.load_cell_mode_ratio.is_some() && b.exposure_s.is_some());
        assert!(Bench::default().is_perfect() && !b.is_perfect());
    }
}
