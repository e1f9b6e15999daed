//! The supplies the limit rests on, measured at boot: VDDA (the ADCs' and
//! the DAC's reference) against the internal reference, and the bridges'
//! supply through a divider. Out of range, the board does not drive: the
//! duty that gives a voltage is that voltage over the supply, and every
//! scale assumes VDDA.
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

/// VDDA from the internal reference: `3.3 V × VREFINT_CAL / VREFINT`;
/// `None` for a reading of 0 (no conversion).
pub fn vdda_v(vrefint_cal_counts: u16, vrefint_counts: u16) -> Option<f32> {
    (vrefint_counts > 0)
        .then(|| VREFINT_CAL_VDDA_V * f32::from(vrefint_cal_counts) / f32::from(vrefint_counts))
}

/// The bridge supply from its divider's reading, with VDDA as measured.
pub fn bridge_supply_v(counts: u16, vdda_v: f32) -> f32 {
    f32::from(counts) / 4095.0 * vdda_v * SUPPLY_DIVIDER
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
}
