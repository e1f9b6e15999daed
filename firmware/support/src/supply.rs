//! The supplies the limit rests on, measured at boot: VDDA (the ADCs' and
//! the DAC's reference) against the internal reference, and the bridges'
//! supply through a divider. Out of range, the board does not drive: the
//! duty that gives a voltage is that voltage over the supply, and every
//! scale assumes VDDA.
//!
//! The bridges' supply is then read again every tick ([`SupplyMonitor`]):
//! a bench supply turned from 5.0 to 5.5 V would otherwise turn a 4 V
//! command into 4.4 V on the strip. Each reading sets the supply the
//! duties are worked out from, and one that has drifted from the boot's
//! by more than [`BRIDGE_DRIFT_TOLERANCE`] is a fault.
//!
//! ```
//! use finrs_firmware_support::supply::{check, vdda_v};
//!
//! // VREFINT read 1500 counts where the factory read 1650 at 3.3 V: VDDA 3.63 V.
//! let vdda = vdda_v(1650, 1500).unwrap();
//! assert!((vdda - 3.63).abs() < 1e-3);
//! assert!(check(vdda, 5.0).is_err(), "VDDA off the DAC's 3.0 V reference");
//! assert!(check(3.0, 5.0).is_ok());
//! ```

use core::fmt;

use crate::config::{BRIDGE_SUPPLY_V, DAC_VREF_V, MAX_ABS_V};

/// VDDA at which the factory measured VREFINT_CAL (STM32F405/407 datasheet,
/// "Internal reference voltage calibration values": VDDA = 3.3 V, 30 °C).
pub const VREFINT_CAL_VDDA_V: f32 = 3.3;

/// The bridge supply's divider onto its ADC pin, (R_top + R_bottom) /
/// R_bottom: 10 kΩ over 4.7 kΩ, so 5 V reads 1.60 V, 5.5 V 1.76 V, well
/// inside VDDA.
pub const SUPPLY_DIVIDER: f32 = (10.0 + 4.7) / 4.7;

/// How far VDDA may be from [`DAC_VREF_V`], the reference every scale and
/// the DAC's codes assume (a fraction).
pub const VDDA_TOLERANCE: f32 = 0.05;

/// How far the bridge supply may be from [`BRIDGE_SUPPLY_V`] (a fraction).
pub const BRIDGE_TOLERANCE: f32 = 0.10;

/// How far the bridge supply may drift from its boot reading while the
/// board runs (a fraction) before it is a `Supply` fault: a supply that
/// moves by this much is being turned or is failing. Ten times the
/// reading's noise (a few counts in 2 180, 0.2 %).
pub const BRIDGE_DRIFT_TOLERANCE: f32 = 0.03;

/// Readings averaged into the supply the duties use besides the latest
/// (see [`SupplyMonitor::update`]).
pub const SUPPLY_MEAN_TICKS: usize = 8;

/// Counts added to a reading before it sets the duties: a reading low by
/// its rounding (half a count) and two counts of noise must not give a
/// duty that puts more than the command on the strip. At 2.0, a reading
/// two counts low and a few hundredths of a count low in its rounding
/// put 1.8·10⁻⁵ of the limit too much on the strip
/// (`tests/terminal_bound.rs`'s moving supply, its case kept in the
/// regressions file). The duties err low by 0.1 % at 5 V.
pub const SUPPLY_MARGIN_COUNTS: f32 = 2.5;

/// VDDA from the internal reference: `3.3 V × VREFINT_CAL / VREFINT`;
/// `None` for a reading of 0 (no conversion).
pub fn vdda_v(vrefint_cal_counts: u16, vrefint_counts: u16) -> Option<f32> {
    (vrefint_counts > 0)
        .then(|| VREFINT_CAL_VDDA_V * f32::from(vrefint_cal_counts) / f32::from(vrefint_counts))
}

/// The bridge supply from its divider's reading, with VDDA as measured.
pub fn bridge_supply_v(counts: u16, vdda_v: f32) -> f32 {
    supply_of_counts(f32::from(counts), vdda_v)
}

/// [`bridge_supply_v`] of a reading between counts (a mean, a margin).
fn supply_of_counts(counts: f32, vdda_v: f32) -> f32 {
    counts / 4095.0 * vdda_v * SUPPLY_DIVIDER
}

/// The divider's reading of the bridge supply `bridge_v` with VDDA at
/// `vdda_v`, in counts, unrounded: [`bridge_supply_v`]'s inverse.
pub fn bridge_sense_counts(bridge_v: f32, vdda_v: f32) -> f32 {
    bridge_v / SUPPLY_DIVIDER / vdda_v * 4095.0
}

/// The supplies, measured and within range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supplies {
    /// VDDA, V.
    pub vdda_v: f32,
    /// The bridges' supply, V: the duty that gives a voltage is that
    /// voltage over this.
    pub bridge_v: f32,
}

/// A supply out of range: which, what it measured, the range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupplyError {
    /// `"VDDA"` or `"bridge supply"`.
    pub supply: &'static str,
    /// What it measured, V.
    pub measured_v: f32,
    /// The range it must be in, V.
    pub min_v: f32,
    /// The range it must be in, V.
    pub max_v: f32,
}

impl fmt::Display for SupplyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Millivolts in integers: no float formatting on the target.
        let mv = |v: f32| (v * 1000.0 + 0.5) as i32;
        write!(
            f,
            "{} at {} mV, outside {}..={} mV: not driving",
            self.supply,
            mv(self.measured_v),
            mv(self.min_v),
            mv(self.max_v)
        )
    }
}

/// Both supplies within range: VDDA within [`VDDA_TOLERANCE`] of
/// [`DAC_VREF_V`], the bridge supply within [`BRIDGE_TOLERANCE`] of
/// [`BRIDGE_SUPPLY_V`] and at least [`MAX_ABS_V`] (a duty of at most 1
/// must reach the limit). NaN fails both.
pub fn check(vdda_v: f32, bridge_v: f32) -> Result<Supplies, SupplyError> {
    let within = |supply, v: f32, min_v: f32, max_v: f32| {
        if (min_v..=max_v).contains(&v) {
            Ok(())
        } else {
            Err(SupplyError {
                supply,
                measured_v: v,
                min_v,
                max_v,
            })
        }
    };
    within(
        "VDDA",
        vdda_v,
        DAC_VREF_V * (1.0 - VDDA_TOLERANCE),
        DAC_VREF_V * (1.0 + VDDA_TOLERANCE),
    )?;
    let low = BRIDGE_SUPPLY_V * (1.0 - BRIDGE_TOLERANCE);
    within(
        "bridge supply",
        bridge_v,
        if low > MAX_ABS_V { low } else { MAX_ABS_V },
        BRIDGE_SUPPLY_V * (1.0 + BRIDGE_TOLERANCE),
    )?;
    Ok(Supplies { vdda_v, bridge_v })
}

/// The bridge supply, read every tick: the supply the duties are worked
/// out from, and the fault when it has drifted from the boot's reading.
///
/// ```
/// use finrs_firmware_support::supply::{check, SupplyMonitor};
///
/// let boot = check(3.0, 5.0).unwrap();
/// let mut monitor = SupplyMonitor::new(boot);
/// // 5 V through the divider at VDDA 3.0 V: 2183 counts.
/// let duty_supply_v = monitor.update(2183).unwrap();
/// assert!(duty_supply_v >= 5.0 && duty_supply_v < 5.01);
/// // 5.5 V: a fault, whatever the range at boot allowed.
/// assert!(monitor.update(2401).is_err());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SupplyMonitor {
    vdda_v: f32,
    boot_v: f32,
    recent: [u16; SUPPLY_MEAN_TICKS],
    next: usize,
    in_band: bool,
}

impl SupplyMonitor {
    /// A monitor of the supplies measured at boot (VDDA scales every
    /// reading; the bridge supply is the reference for the drift).
    pub fn new(boot: Supplies) -> Self {
        let counts = bridge_sense_counts(boot.bridge_v, boot.vdda_v);
        let counts = if counts > 0.0 && counts < 4095.0 {
            counts as u16
        } else {
            4095
        };
        SupplyMonitor {
            vdda_v: boot.vdda_v,
            boot_v: boot.bridge_v,
            recent: [counts; SUPPLY_MEAN_TICKS],
            next: 0,
            in_band: true,
        }
    }

    /// The supply at boot, V.
    pub fn boot_v(&self) -> f32 {
        self.boot_v
    }

    /// Whether the last reading was within the band (true before the
    /// first): nothing may be driven while it is not.
    pub fn in_band(&self) -> bool {
        self.in_band
    }

    /// One tick's reading of the divider, `counts`: the supply to work the
    /// duties out from, V, or the fault if the reading has drifted past
    /// [`BRIDGE_DRIFT_TOLERANCE`] of the boot's or left [`check`]'s range.
    ///
    /// The duties take the higher of this reading and the mean of the last
    /// [`SUPPLY_MEAN_TICKS`], plus [`SUPPLY_MARGIN_COUNTS`]: a supply that
    /// rises is followed at once, one that falls a few milliseconds late,
    /// so that a duty errs low, never high (the strip then sees a little
    /// less than the command, never more).
    pub fn update(&mut self, counts: u16) -> Result<f32, SupplyError> {
        self.recent[self.next] = counts;
        self.next = (self.next + 1) % SUPPLY_MEAN_TICKS;
        let duty_supply = self.duty_supply_v(counts);
        self.in_band = duty_supply.is_ok();
        duty_supply
    }

    /// [`update`](Self::update)'s answer once `counts` is in `recent`.
    fn duty_supply_v(&self, counts: u16) -> Result<f32, SupplyError> {
        let v = bridge_supply_v(counts, self.vdda_v);
        let (low, high) = (
            self.boot_v * (1.0 - BRIDGE_DRIFT_TOLERANCE),
            self.boot_v * (1.0 + BRIDGE_DRIFT_TOLERANCE),
        );
        if !(low..=high).contains(&v) {
            return Err(SupplyError {
                supply: "bridge supply",
                measured_v: v,
                min_v: low,
                max_v: high,
            });
        }
        check(self.vdda_v, v)?;
        let sum: u32 = self.recent.iter().map(|&c| u32::from(c)).sum();
        let mean = sum as f32 / SUPPLY_MEAN_TICKS as f32;
        let highest = if mean > f32::from(counts) {
            mean
        } else {
            f32::from(counts)
        };
        Ok(supply_of_counts(
            highest + SUPPLY_MARGIN_COUNTS,
            self.vdda_v,
        ))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn the_supplies_are_read_and_checked() {
        assert_eq!(vdda_v(1650, 0), None);
        assert!((vdda_v(1650, 1815).unwrap() - 3.0).abs() < 1e-6);
        // 5 V through 10k/4.7k at VDDA 3.0 V: 1.599 V, 2183 counts.
        assert!((bridge_supply_v(2183, 3.0) - 5.0).abs() < 0.005);
        assert!(check(3.0, 5.0).is_ok());
        assert!(check(2.86, 4.51).is_ok());
        let e = check(2.8, 5.0).unwrap_err();
        assert_eq!(e.supply, "VDDA");
        assert_eq!(
            e.to_string(),
            "VDDA at 2800 mV, outside 2850..=3150 mV: not driving"
        );
        let e = check(3.0, 4.4).unwrap_err();
        assert_eq!(e.supply, "bridge supply");
        assert_eq!(
            e.to_string(),
            "bridge supply at 4400 mV, outside 4500..=5500 mV: not driving"
        );
        assert!(check(3.0, 5.6).is_err());
        assert!(check(f32::NAN, 5.0).is_err() && check(3.0, f32::NAN).is_err());
    }

    /// The counts the divider gives for `v` at VDDA 3.0 V, rounded.
    fn counts(v: f32) -> u16 {
        (bridge_sense_counts(v, 3.0) + 0.5) as u16
    }

    #[test]
    fn the_monitor_follows_a_rise_at_once_and_a_fall_late() {
        let mut m = SupplyMonitor::new(check(3.0, 5.0).unwrap());
        let at = |m: &mut SupplyMonitor, v: f32| m.update(counts(v)).unwrap();
        // Steady: the reading plus its margin, a few millivolts above.
        let steady = at(&mut m, 5.0);
        assert!((5.0..5.015).contains(&steady), "{steady}");
        // A rise within the tolerance counts on the tick it is read.
        assert!(at(&mut m, 5.1) >= 5.1);
        // A fall is followed as the mean forgets the higher readings: the
        // duties stay those of a higher supply meanwhile (the strip gets
        // less, not more).
        let after_fall = at(&mut m, 4.9);
        assert!(after_fall > 4.95, "{after_fall}");
        for _ in 0..SUPPLY_MEAN_TICKS {
            at(&mut m, 4.9);
        }
        let settled = at(&mut m, 4.9);
        assert!((4.9..4.915).contains(&settled), "{settled}");
    }

    #[test]
    fn a_drift_past_the_tolerance_is_a_fault_in_range_or_not() {
        let mut m = SupplyMonitor::new(check(3.0, 5.0).unwrap());
        // 5.5 V (read to the count: 5 499 mV) is within the boot check's
        // ±10 %, yet past the drift's 3 %.
        let e = m.update(counts(5.5)).unwrap_err();
        assert_eq!(e.supply, "bridge supply");
        assert_eq!(
            e.to_string(),
            "bridge supply at 5499 mV, outside 4850..=5150 mV: not driving"
        );
        assert!(m.update(counts(4.8)).is_err());
        assert!(!m.in_band());
        // Back within: no fault (the controller's latch keeps the one seen).
        assert!(m.update(counts(5.1)).is_ok());
        assert!(m.in_band());
        // A board that booted at 4.55 V may not drift below the 4.5 V its
        // duties need at full drive, however small the drift.
        let mut low = SupplyMonitor::new(check(3.0, 4.55).unwrap());
        assert!(low.update(counts(4.48)).is_err());
        // No conversion (0 counts) or a full-scale one is never a supply.
        assert!(m.update(0).is_err() && m.update(4095).is_err());
    }
}
