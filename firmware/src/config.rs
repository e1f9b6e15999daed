//! The fin driver's configuration: one place for the numbers both builds
//! run with (the QEMU build converts its plant with the same scales).

use finrs_controller::Config;
use finrs_drive::{LimitError, Limits};

// `N` (1..=8) and `DAC_SEGMENTS`, from the build-time variables
// `FINRS_SEGMENTS` and `FINRS_DAC_SEGMENTS` (see `build.rs`).
include!(concat!(env!("OUT_DIR"), "/segments.rs"));

/// DAC segments: the bipolar amplifier's output volts per DAC volt (3.0 V
/// reference, mid-scale = 0 V: ±4.2 V at the rails, above the 4 V limit).
#[allow(dead_code)] // the QEMU board drives the plant, not DACs
pub const DAC_GAIN: f32 = 2.8;

/// DAC reference (VDDA/VREF+ of the board), V.
#[allow(dead_code)] // the QEMU board drives the plant, not DACs
pub const DAC_VREF_V: f32 = 3.0;

/// DAC code of 0 V at the segment (the amplifier's mid-scale).
#[allow(dead_code)] // the QEMU board drives the plant, not DACs
pub const DAC_ZERO_CODE: u16 = 2048;

/// Sample rate of the load cell and of the control tick, Hz.
pub const SAMPLE_HZ: u32 = 1_000;

/// Supply voltage of the H-bridges, V: average segment voltage is duty ×
/// this.
#[allow(dead_code)] // the QEMU board drives the plant, not bridges
pub const BRIDGE_SUPPLY_V: f32 = 5.0;

/// Voltage limit at power-up, V (the Nafion strips' ±4 V; lower by command).
pub const MAX_ABS_V: f32 = 4.0;

/// Slew limit, V/s.
pub const SLEW_V_PER_S: f32 = 200.0;

/// Load-cell scale: the instrumentation amplifier maps about ±0.05 N (a
/// 10 g class cell) onto ±2048 counts of the 12-bit ADC.
pub const NEWTONS_PER_COUNT: f32 = 2.5e-5;

/// Shunt scale: ±0.512 A onto ±2048 counts around mid-scale.
pub const AMPS_PER_COUNT: f32 = 2.5e-4;

/// Shunt reading at zero current, counts (bipolar amplifier at mid-scale).
pub const CURRENT_ZERO_COUNTS: u16 = 2048;

/// A segment drawing more than this is a fault, A.
pub const OVERCURRENT_A: f32 = 0.4;

/// The controller's configuration.
pub fn controller_config() -> Result<Config, LimitError> {
    Ok(Config {
        sample_hz: SAMPLE_HZ,
        limits: Limits::new(MAX_ABS_V, SLEW_V_PER_S)?,
        newtons_per_count: NEWTONS_PER_COUNT,
        adc_full_scale: 4095,
        saturation_margin_counts: 8,
        amps_per_count: AMPS_PER_COUNT,
        current_zero_counts: CURRENT_ZERO_COUNTS,
        overcurrent_a: OVERCURRENT_A,
        tare_samples: 200,
    })
}
