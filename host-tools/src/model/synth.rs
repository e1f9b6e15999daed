//! Recordings made from a wave: the drive only, ready to simulate.
//!
//! The voltages are the firmware's: the wave's [`finrs_drive::Generator`]
//! counts ticks of the sample rate from the first row of the wave, as the
//! firmware's controller counts its sample ticks, and, if asked, they pass
//! through the firmware's [`finrs_drive::Limiter`] on every row.

use crate::recording::{Fixture, Geometry, Medium, Metadata, Recording, Voltages};
use crate::wave::{Wave, WaveError, WaveOptions};

/// Why a drive was refused; each names the field of [`Drive`] or
/// [`WaveOptions`] (or the limit) and the rule it breaks.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DriveError {
    /// A time that must not be negative is.
    #[error("{field} must be zero or positive, got {value}")]
    Negative {
        /// The field, e.g. `rest_s`.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A duration or rate that must be above 0 is not.
    #[error("{field} must be positive, got {value}")]
    NotPositive {
        /// The field, e.g. `duration_s`.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The rate is not a whole number of Hz the generator can count.
    #[error("rate_hz must be a whole number of Hz up to {max} (the generator counts ticks), got {0}", max = u32::MAX)]
    RateNotWhole(f64),
    /// The ramps do not fit in the wave's duration.
    #[error("ramp_in_s + ramp_out_s must not exceed duration_s: {ramp_in_s} + {ramp_out_s} > {duration_s}")]
    RampsTooLong {
        /// Ramp in, s.
        ramp_in_s: f64,
        /// Ramp out, s.
        ramp_out_s: f64,
        /// The wave's duration, s.
        duration_s: f64,
    },
    /// A finite hold and the ramps do not fit in the wave's duration.
    #[error("ramp_in_s + hold_s + ramp_out_s must not exceed duration_s: {ramp_in_s} + {hold_s} + {ramp_out_s} > {duration_s}")]
    HoldTooLong {
        /// Ramp in, s.
        ramp_in_s: f64,
        /// Hold, s.
        hold_s: f64,
        /// Ramp out, s.
        ramp_out_s: f64,
        /// The wave's duration, s.
        duration_s: f64,
    },
    /// More rows than this tool writes (or too many to count).
    #[error("{0:.0} rows is more than this tool writes (50 million)")]
    TooManyRows(f64),
    /// Fewer rows than the cap, but too many to simulate in memory.
    #[error(
        "{rows} rows of {segments} segment(s) would take about {:.1} GiB to simulate \
         ({} bytes a row); this tool refuses above {:.0} GiB: shorten the drive or lower its rate",
        bytes_to_simulate(*rows, *segments) as f64 / GIB,
        bytes_to_simulate(1, *segments),
        MAX_BYTES as f64 / GIB
    )]
    TooMuchMemory {
        /// Rows of the drive.
        rows: usize,
        /// Segments driven.
        segments: usize,
    },
    /// The wave is refused for these segments and options.
    #[error(transparent)]
    Wave(#[from] WaveError),
    /// The firmware refuses a limit.
    #[error("{field} {value}: {rule}")]
    Limits {
        /// `limit_v` or `slew_v_per_s`.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The firmware's rule.
        rule: finrs_drive::LimitError,
    },
}

/// Rows a drive recording may have at most.
const MAX_ROWS: usize = 50_000_000;

/// Memory a drive may take to simulate at most, bytes (2 GiB).
const MAX_BYTES: usize = 2 << 30;

const GIB: f64 = (1u64 << 30) as f64;

/// Memory `finrs simulate --wave` takes for a drive of `rows` rows of
/// `segments` segments, bytes, from above: the drive and the predicted
/// channels are in memory at once (the prediction borrows the drive, and
/// the file's text is written in bounded chunks). Peak RSS of `finrs
/// simulate --wave step:1 --rest-s 0` grew by 55–56 bytes a row for 1
/// segment, 80–81 for 3 and 167–168 for 8 (free and blocked, 250 000 vs
/// 500 000 rows, `/usr/bin/time -f %M`); 48 + 16 per segment covers each.
fn bytes_to_simulate(rows: usize, segments: usize) -> usize {
    rows.saturating_mul(48 + 16 * segments)
}

/// When and how a wave is applied.
#[derive(Clone, Copy, Debug)]
pub struct Drive {
    /// Segments driven.
    pub segments: usize,
    /// How the tip is held.
    pub fixture: Fixture,
    /// Rest at 0 V before the wave, s.
    pub rest_s: f64,
    /// Duration of the wave, s (ramps included).
    pub duration_s: f64,
    /// Rest at 0 V after the wave, s.
    pub off_s: f64,
    /// Sample rate, Hz: a whole number, the generator's tick rate.
    pub rate_hz: f64,
}

impl Drive {
    /// The row the wave starts on: the first at or after `rest_s` (the
    /// 1e-9 forgives rounding in the product, e.g. 0.1 s × 1000 Hz).
    pub fn start_row(&self) -> usize {
        (self.rest_s * self.rate_hz - 1e-9).ceil().max(0.0) as usize
    }
}

/// The firmware's limits, checked by [`finrs_drive::Limits::new`]; the
/// error names the value (`limit_v` or `slew_v_per_s`) and its rule.
pub fn limits(limit_v: f64, slew_v_per_s: f64) -> Result<finrs_drive::Limits, DriveError> {
    use finrs_drive::LimitError as E;
    finrs_drive::Limits::new(limit_v as f32, slew_v_per_s as f32).map_err(|rule| match rule {
        E::SlewNotFinite | E::SlewNotPositive => DriveError::Limits {
            field: "slew_v_per_s",
            value: slew_v_per_s,
            rule,
        },
        _ => DriveError::Limits {
            field: "limit_v",
            value: limit_v,
            rule,
        },
    })
}

/// A voltage-only recording of the seed's strip driven by `wave`, with no
/// ramps, offset nor limiter, and chirps sweeping over the whole duration.
pub fn drive_recording(wave: &Wave, d: &Drive) -> Result<Recording, DriveError> {
    drive_recording_shaped(wave, d, &WaveOptions::steady(d.duration_s), None)
}

/// A voltage-only recording of the seed's strip driven by `wave`, shaped by
/// `options` as `finrs wave` shapes it on the firmware, and through the
/// firmware's limiter if `limits` are given (else the generator's voltages
/// as they are, within the hard limit). The wave starts on the first row
/// at or after `rest_s` and its envelope lasts `duration_s`: ramp in, hold
/// (an infinite `hold_s`: until the ramp out ends at `duration_s`; a
/// finite one ends the wave early, at 0 V after), ramp out. Every row's
/// voltages are the firmware generator's at that row's tick.
pub fn drive_recording_shaped(
    wave: &Wave,
    d: &Drive,
    options: &WaveOptions,
    limits: Option<finrs_drive::Limits>,
) -> Result<Recording, DriveError> {
    for (field, value) in [
        ("rest_s", d.rest_s),
        ("off_s", d.off_s),
        ("ramp_in_s", options.ramp_in_s),
        ("ramp_out_s", options.ramp_out_s),
        ("hold_s", options.hold_s),
    ] {
        // An infinite hold is "until the ramp out".
        if value.is_nan() || value < 0.0 || (value.is_infinite() && field != "hold_s") {
            return Err(DriveError::Negative { field, value });
        }
    }
    for (field, value) in [("duration_s", d.duration_s), ("rate_hz", d.rate_hz)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(DriveError::NotPositive { field, value });
        }
    }
    // The firmware's generator counts whole ticks of a whole-hertz clock.
    if d.rate_hz.fract() != 0.0 || d.rate_hz > f64::from(u32::MAX) {
        return Err(DriveError::RateNotWhole(d.rate_hz));
    }
    let tick_hz = d.rate_hz as u32;
    let options = within_duration(options, d.duration_s)?;
    let generator = wave.generator(d.segments, &options)?;
    let total_s = d.rest_s + d.duration_s + d.off_s;
    // Counted in f64 first: a long drive overflows `usize`, or is infinite.
    let rows_f = (total_s * d.rate_hz).round() + 1.0;
    if rows_f.is_nan() || rows_f > MAX_ROWS as f64 {
        return Err(DriveError::TooManyRows(rows_f));
    }
    let rows = rows_f as usize;
    if bytes_to_simulate(rows, d.segments) > MAX_BYTES {
        return Err(DriveError::TooMuchMemory {
            rows,
            segments: d.segments,
        });
    }
    let start_row = d.start_row().min(rows);
    let mut v_v = Voltages::zeros(d.segments, start_row);
    let wave_rows = (rows - start_row) as u64;
    // A limiter through the rest would hold its outputs at 0 V: starting
    // it with the wave gives the same rows.
    for row in generator.run(wave_rows, tick_hz, limits) {
        v_v.push(&row);
    }
    let t_s: Vec<f64> = (0..rows).map(|k| k as f64 / d.rate_hz).collect();
    Ok(Recording {
        meta: Metadata {
            sample: Some("thesis_2006".to_string()),
            ..Metadata::new(d.segments, Geometry::THESIS_2006, d.fixture, Medium::Air)
        },
        t_s,
        v_v,
        channels: Vec::new(),
    })
}

/// `options` with an infinite hold made the one that ends the ramp out at
/// `duration_s`; refused when the envelope does not fit in `duration_s`.
fn within_duration(options: &WaveOptions, duration_s: f64) -> Result<WaveOptions, DriveError> {
    let WaveOptions {
        ramp_in_s,
        hold_s,
        ramp_out_s,
        ..
    } = *options;
    let longest_hold_s = duration_s - ramp_in_s - ramp_out_s;
    if longest_hold_s < 0.0 {
        return Err(DriveError::RampsTooLong {
            ramp_in_s,
            ramp_out_s,
            duration_s,
        });
    }
    if hold_s.is_finite() && hold_s > longest_hold_s {
        return Err(DriveError::HoldTooLong {
            ramp_in_s,
            hold_s,
            ramp_out_s,
            duration_s,
        });
    }
    Ok(WaveOptions {
        hold_s: hold_s.min(longest_hold_s),
        ..*options
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    // Regression: 2^64 s of drive overflowed the row count (a panic).
    #[test]
    fn a_drive_too_long_to_count_is_refused() {
        let wave = Wave::parse("step:1").unwrap();
        for (duration_s, off_s) in [
            (18_446_744_073_709_551_616.0, 0.0),
            (1e300, 0.0),
            (f64::MAX, f64::MAX),
            (50_000.0, 0.001),
        ] {
            let d = Drive {
                segments: 1,
                fixture: Fixture::Free,
                rest_s: 0.0,
                duration_s,
                off_s,
                rate_hz: 1000.0,
            };
            let err = drive_recording(&wave, &d).unwrap_err().to_string();
            assert!(
                err.ends_with("rows is more than this tool writes (50 million)"),
                "{err}"
            );
        }
    }

    #[test]
    fn a_drive_under_the_row_cap_but_too_big_to_simulate_is_refused() {
        // 25 million rows of 3 segments: under 50 million, over 2 GiB.
        let d = Drive {
            segments: 3,
            fixture: Fixture::Free,
            rest_s: 0.0,
            duration_s: 25_000.0,
            off_s: 0.0,
            rate_hz: 1000.0,
        };
        let err = drive_recording(&Wave::parse("step:1").unwrap(), &d).unwrap_err();
        assert_eq!(
            err,
            DriveError::TooMuchMemory {
                rows: 25_000_001,
                segments: 3
            }
        );
        assert_eq!(
            err.to_string(),
            "25000001 rows of 3 segment(s) would take about 2.2 GiB to simulate (96 bytes a row); \
             this tool refuses above 2 GiB: shorten the drive or lower its rate"
        );
    }

    #[test]
    fn limits_name_the_value_and_rule() {
        assert_eq!(limits(1.5, 20.0).unwrap().max_abs_v(), 1.5);
        assert_eq!(
            limits(5.0, 20.0).unwrap_err().to_string(),
            "limit_v 5: max_abs_v must not exceed HARD_LIMIT_V (4 V)"
        );
        assert_eq!(
            limits(1.0, 0.0).unwrap_err().to_string(),
            "slew_v_per_s 0: slew_v_per_s must be above 0"
        );
        assert_eq!(
            limits(f64::NAN, 1.0).unwrap_err().to_string(),
            "limit_v NaN: max_abs_v must be finite"
        );
    }
}
