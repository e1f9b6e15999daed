//! The controller's configuration and its validation.

use core::fmt;

use finrs_drive::Limits;
use finrs_frames::Calibration;

/// Everything the controller needs to know about the board, in SI units.
/// Checked by [`Controller::new`](crate::Controller::new); a refusal names
/// the field and the rule it breaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Load-cell sample rate, which is also the tick rate, Hz (above 0;
    /// 1000 by default on the board).
    pub sample_hz: u32,
    /// Voltage and slew limits at start (the host may lower the voltage
    /// limit, never raise it).
    pub limits: Limits,
    /// The load cell's scale (N per ADC count: finite, not zero, either
    /// sign) and each shunt's reading at 0 A (counts, at most
    /// `adc_full_scale`): the board's build defaults, its stored
    /// calibration, or the host's (`Command::SetCalibration`).
    pub calibration: Calibration,
    /// ADC full-scale reading, counts (4095 for 12 bits).
    pub adc_full_scale: u16,
    /// A reading within this many counts of 0 or of full scale is saturated
    /// (twice it must stay below `adc_full_scale`).
    pub saturation_margin_counts: u16,
    /// Shunt amplifier scale: i = (counts − the segment's zero in
    /// `calibration`) · `amps_per_count`, A per count (finite, not zero;
    /// either sign).
    pub amps_per_count: f32,
    /// A segment current whose magnitude is above this is an overcurrent,
    /// A (finite, above 0).
    pub overcurrent_a: f32,
    /// Load-cell readings averaged by a tare (at least 1).
    pub tare_samples: u16,
}

/// The rule a configuration field breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigRule {
    /// Must be above 0.
    Positive,
    /// Must be finite (not NaN nor infinite).
    Finite,
    /// Must not be zero.
    NonZero,
    /// Twice the margin must be below `adc_full_scale`, or every reading
    /// would be saturated.
    MarginTooWide,
    /// Must be at most `adc_full_scale`.
    AboveFullScale,
    /// The idle program (0 V) was refused by finrs-drive's generator (a
    /// bug there, not in the configuration).
    RefusedByGenerator,
}

/// A refused configuration: which field, which rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// The field, e.g. `"newtons_per_count"`.
    pub field: &'static str,
    /// The rule it breaks.
    pub rule: ConfigRule,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rule = match self.rule {
            ConfigRule::Positive => "must be above 0",
            ConfigRule::Finite => "must be finite",
            ConfigRule::NonZero => "must not be 0",
            ConfigRule::MarginTooWide => "must be less than half of adc_full_scale",
            ConfigRule::AboveFullScale => "must be at most adc_full_scale",
            ConfigRule::RefusedByGenerator => "was refused by the generator (a finrs-drive bug)",
        };
        write!(f, "config: {} {rule}", self.field)
    }
}

impl core::error::Error for ConfigError {}

fn err(field: &'static str, rule: ConfigRule) -> Result<(), ConfigError> {
    Err(ConfigError { field, rule })
}

fn finite_nonzero(field: &'static str, v: f32) -> Result<(), ConfigError> {
    if !v.is_finite() {
        err(field, ConfigRule::Finite)
    } else if v == 0.0 {
        err(field, ConfigRule::NonZero)
    } else {
        Ok(())
    }
}

impl Config {
    /// Checks every field; the error names the first that breaks a rule.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.sample_hz == 0 {
            return err("sample_hz", ConfigRule::Positive);
        }
        finite_nonzero(
            "calibration.newtons_per_count",
            self.calibration.newtons_per_count,
        )?;
        if self.adc_full_scale == 0 {
            return err("adc_full_scale", ConfigRule::Positive);
        }
        if u32::from(self.saturation_margin_counts) * 2 >= u32::from(self.adc_full_scale) {
            return err("saturation_margin_counts", ConfigRule::MarginTooWide);
        }
        finite_nonzero("amps_per_count", self.amps_per_count)?;
        // Every entry, the unused ones included: a stored calibration is
        // valid for any segment count.
        if self
            .calibration
            .current_zero_counts
            .iter()
            .any(|&z| z > self.adc_full_scale)
        {
            return err(
                "calibration.current_zero_counts",
                ConfigRule::AboveFullScale,
            );
        }
        if !self.overcurrent_a.is_finite() {
            return err("overcurrent_a", ConfigRule::Finite);
        }
        if self.overcurrent_a <= 0.0 {
            return err("overcurrent_a", ConfigRule::Positive);
        }
        if self.tare_samples == 0 {
            return err("tare_samples", ConfigRule::Positive);
        }
        Ok(())
    }

    /// Time between ticks, s.
    pub fn dt_s(&self) -> f32 {
        1.0 / self.sample_hz as f32
    }

    /// Whether a load-cell reading is saturated: within
    /// `saturation_margin_counts` of 0 or of full scale (or beyond it).
    pub fn load_cell_saturated(&self, counts: u16) -> bool {
        counts <= self.saturation_margin_counts
            || counts
                >= self
                    .adc_full_scale
                    .saturating_sub(self.saturation_margin_counts)
    }

    /// Whether segment `k`'s current reading is saturated. An end of the
    /// ADC's range counts only if 0 A is not itself within the margin of
    /// that end: a unipolar shunt amplifier reads 0 counts at rest, which
    /// is no saturation.
    pub fn current_saturated(&self, k: usize, counts: u16) -> bool {
        let zero = self.zero_counts(k);
        let low = self.saturation_margin_counts;
        let high = self
            .adc_full_scale
            .saturating_sub(self.saturation_margin_counts);
        (counts <= low && zero > low) || (counts >= high && zero < high)
    }

    /// The current segment `k`'s reading stands for, A.
    pub fn current_a(&self, k: usize, counts: u16) -> f32 {
        (f32::from(counts) - f32::from(self.zero_counts(k))) * self.amps_per_count
    }

    /// Segment `k`'s shunt zero; a `k` beyond the calibration's eight
    /// (never, for N ≤ 8) reads the last.
    fn zero_counts(&self, k: usize) -> u16 {
        let z = &self.calibration.current_zero_counts;
        z[k.min(z.len() - 1)]
    }
}
