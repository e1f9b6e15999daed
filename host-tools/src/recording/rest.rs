//! What a DAQ reads of a voltage channel when nothing is applied: never
//! exactly 0 V, but an offset of a few millivolts, noise, and the ADC's
//! step (docs/FORMAT.md, "What a DAQ measures"). A rest, and a reading of
//! the safe limit, are judged against the channel's own reading of a rest.
//!
//! ```
//! use finrs::recording::{RestReading, Voltages};
//! // 1 s at rest read as 0.6 or 0.9 mV (a 0.3 mV step), then 2.5 V.
//! let t_s: Vec<f64> = (0..1500).map(|i| i as f64 * 1e-3).collect();
//! let v = Voltages::from_rows(1, t_s.iter().enumerate().map(|(i, _)| {
//!     [if i >= 1000 { 2.5 } else if i % 3 == 0 { 0.0009 } else { 0.0006 }]
//! }));
//! let rest = RestReading::measure(&t_s, &v, 0);
//! assert!(rest.is_rest());
//! assert!(rest.at_rest(0.0009) && !rest.at_rest(0.01));
//! ```

use super::error::RecordingError;
use super::{Voltages, SAFE_VOLTAGE_LIMIT_V};

/// The opening stretch a channel's rest reading is measured on, s: half
/// of the second of rest every session's recording opens with.
pub const REST_OPENING_S: f64 = 0.5;

/// How many standard deviations of its rest noise a reading may stray
/// from the rest's offset and still be a rest: over the thousands of
/// samples of a rest, Gaussian noise passes 5σ about once in 1.7 million.
pub const REST_SIGMAS: f64 = 5.0;

/// The most a rest may read, offset and noise band together, V: 0.6 % of
/// the ±4 V range. A 16-bit DAQ's rest reads a few millivolts; the
/// weakest drive a strip shows is some 0.1 V. An opening that reads more
/// is a drive, not a rest, and no reading past the safe limit is allowed
/// by it.
pub const REST_BAND_LIMIT_V: f64 = 0.025;

/// A voltage channel's reading of a rest, measured on a recording's first
/// [`REST_OPENING_S`]: its offset, noise and step. All zero for a channel
/// that reads a rest as exactly 0 V (a synthetic drive, the board's
/// commanded voltages).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RestReading {
    /// The rest's level (median), V.
    pub offset_v: f64,
    /// The rest's rms spread about that level, V.
    pub noise_v: f64,
    /// The channel's resolution: the smallest step between two of its
    /// values no further apart than [`REST_BAND_LIMIT_V`] (0 where none
    /// is), V.
    pub step_v: f64,
}

impl RestReading {
    /// The reading of segment `k`'s (0-based) channel of `v_v`, timed by
    /// `t_s`, on its first [`REST_OPENING_S`] (every row if shorter), or
    /// up to its first reading beyond [`REST_BAND_LIMIT_V`] (at least one
    /// row).
    pub fn measure(t_s: &[f64], v_v: &Voltages, k: usize) -> RestReading {
        let n = v_v.segments();
        let column = v_v.as_flat().iter().skip(k).step_by(n);
        let t0 = t_s.first().copied().unwrap_or(0.0);
        // Up to a clear drive, if one comes first: a drive after 0.3 s
        // leaves a rest of 0.3 s, which the session's rule then refuses
        // as too short, at the drive's row.
        let opening = t_s
            .iter()
            .zip(column.clone())
            .position(|(&t, v)| t >= t0 + REST_OPENING_S || v.abs() > REST_BAND_LIMIT_V)
            .unwrap_or(t_s.len())
            .max(1);
        let mut window: Vec<f64> = column.clone().take(opening).copied().collect();
        let Some(offset_v) = middle(&mut window) else {
            return RestReading::default();
        };
        // rms about the median, not a robust spread: a quantised rest that
        // mostly reads one count has no median deviation, yet strays a
        // count or two now and then.
        let noise_v = (window.iter().map(|v| (v - offset_v).powi(2)).sum::<f64>()
            / window.len() as f64)
            .sqrt();
        let mut all: Vec<f64> = column.copied().collect();
        all.sort_unstable_by(f64::total_cmp);
        let step_v = all
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|&d| d > 0.0 && d <= REST_BAND_LIMIT_V)
            .min_by(f64::total_cmp)
            .unwrap_or(0.0);
        RestReading {
            offset_v,
            noise_v,
            step_v,
        }
    }

    /// How far from its offset a rest may read, V: [`REST_SIGMAS`] times
    /// the noise with the step's rounding (`Δ²/12`) added.
    pub fn band_v(&self) -> f64 {
        REST_SIGMAS * (self.noise_v.powi(2) + self.step_v.powi(2) / 12.0).sqrt()
    }

    /// Whether the opening read a rest: offset and band within
    /// [`REST_BAND_LIMIT_V`].
    pub fn is_rest(&self) -> bool {
        self.offset_v.abs() + self.band_v() <= REST_BAND_LIMIT_V
    }

    /// Whether `v_v` reads as this rest.
    pub fn at_rest(&self, v_v: f64) -> bool {
        (v_v - self.offset_v).abs() <= self.band_v()
    }

    /// How far past the safe limit a reading of it may lie, V: the rest's
    /// offset and band, which a reading of any voltage carries; none if
    /// the opening is not a rest.
    pub fn allowance_v(&self) -> f64 {
        if self.is_rest() {
            self.offset_v.abs() + self.band_v()
        } else {
            0.0
        }
    }
}

/// The most any reading may lie past the safe limit, V: a rest's offset
/// and band at their widest. A row beyond it is refused as it is read;
/// one short of it, by [`check_range`] once the channel's rest is known.
pub const READING_LIMIT_V: f64 = SAFE_VOLTAGE_LIMIT_V + REST_BAND_LIMIT_V;

/// The range rule on a drive of rows numbered from `header_line + 1`:
/// no voltage beyond the safe range by more than its channel's reading of
/// a rest allows ([`RestReading::allowance_v`]): a 4 V drive read back as
/// 4.0007 V by a DAQ whose rest reads 0.7 mV is a 4 V drive.
pub(super) fn check_range(
    file: &str,
    header_line: usize,
    t_s: &[f64],
    v_v: &Voltages,
) -> Result<(), RecordingError> {
    // The common case in one tight pass; a rest is measured only for a
    // channel that reads past the limit.
    if v_v
        .as_flat()
        .iter()
        .all(|v| v.abs() <= SAFE_VOLTAGE_LIMIT_V)
    {
        return Ok(());
    }
    let n = v_v.segments();
    let rests: Vec<RestReading> = (0..n).map(|k| RestReading::measure(t_s, v_v, k)).collect();
    for (row, v) in v_v.rows().enumerate() {
        for (k, (&x, rest)) in v.iter().zip(&rests).enumerate() {
            if x.abs() > SAFE_VOLTAGE_LIMIT_V + rest.allowance_v() {
                let why = if rest.is_rest() {
                    format!(
                        "by more than its channel's reading of a rest allows (offset {:.4} V, band {:.4} V on its first {REST_OPENING_S} s)",
                        rest.offset_v,
                        rest.band_v()
                    )
                } else {
                    format!("and its first {REST_OPENING_S} s is no rest, which alone would allow a reading past it")
                };
                return Err(RecordingError::at(
                    file,
                    header_line + 1 + row,
                    format!(
                        "v{}_V = {x} V is beyond the safe range of ±{SAFE_VOLTAGE_LIMIT_V} V {why} (docs/FORMAT.md)",
                        k + 1
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The median of `v` (the upper middle value for an even count), `None`
/// when empty; `v` is reordered.
fn middle(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(values: &[f64], dt_s: f64) -> (Vec<f64>, Voltages) {
        let t: Vec<f64> = (0..values.len()).map(|i| i as f64 * dt_s).collect();
        (t, Voltages::from_rows(1, values.iter().map(|&v| [v])))
    }

    #[test]
    fn an_exact_rest_has_no_band() {
        let (t, v) = channel(&[0.0; 1000], 1e-3);
        let r = RestReading::measure(&t, &v, 0);
        assert_eq!(r, RestReading::default());
        assert!(r.is_rest() && r.at_rest(0.0) && !r.at_rest(1e-12));
        assert_eq!(r.allowance_v(), 0.0);
    }

    #[test]
    fn a_quantised_noisy_rest_allows_its_offset_and_noise() {
        // 0.3 mV counts around 0.7 mV, a 4 V step read as 4.0007 V.
        let mut values: Vec<f64> = (0..200)
            .map(|i| 0.0003 * (2 + [0, 1, 0, 2, 1][i % 5]) as f64)
            .collect();
        values.extend([4.0007; 100]);
        let (t, v) = channel(&values, 0.01);
        let r = RestReading::measure(&t, &v, 0);
        assert!((r.offset_v - 0.0009).abs() < 1e-12, "{r:?}");
        assert!((r.step_v - 0.0003).abs() < 1e-12, "{r:?}");
        assert!(r.is_rest());
        assert!(r.at_rest(0.0006) && r.at_rest(0.0015));
        assert!(!r.at_rest(0.01));
        assert!(4.0007 <= 4.0 + r.allowance_v(), "{r:?}");
        assert!(4.01 > 4.0 + r.allowance_v(), "{r:?}");
    }

    #[test]
    fn steps_of_a_drive_are_not_a_resolution() {
        let mut values = vec![0.0; 600];
        values.extend([1.0; 100]);
        values.extend([2.5; 100]);
        let (t, v) = channel(&values, 1e-3);
        let r = RestReading::measure(&t, &v, 0);
        assert_eq!(r.step_v, 0.0);
        assert_eq!(r.band_v(), 0.0);
    }

    #[test]
    fn a_driven_opening_is_no_rest_and_allows_nothing() {
        let (t, v) = channel(&[1.0; 1000], 1e-3);
        let r = RestReading::measure(&t, &v, 0);
        assert!(!r.is_rest());
        assert_eq!(r.allowance_v(), 0.0);
        let (t, v) = channel(&[0.03; 1000], 1e-3);
        assert!(!RestReading::measure(&t, &v, 0).is_rest());
    }

    #[test]
    fn segments_are_read_apart() {
        let t: Vec<f64> = (0..800).map(|i| i as f64 * 1e-3).collect();
        let v = Voltages::from_rows(2, (0..800).map(|i| [0.0, 0.001 * (i % 2) as f64]));
        assert_eq!(RestReading::measure(&t, &v, 0), RestReading::default());
        let r = RestReading::measure(&t, &v, 1);
        assert!((r.step_v - 0.001).abs() < 1e-15 && r.noise_v > 0.0, "{r:?}");
    }

    #[test]
    fn no_rows_read_as_an_exact_rest() {
        let r = RestReading::measure(&[], &Voltages::zeros(1, 0), 0);
        assert_eq!(r, RestReading::default());
    }
}
