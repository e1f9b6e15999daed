//! The fin driver's configuration: one place for the numbers both builds
//! run with (the QEMU build converts its plant with the same scales).

use finrs_controller::Config;
use finrs_drive::{LimitError, Limits};

/// Segments driven: `FINRS_SEGMENTS` at build time (1..=8), 3 if unset.
/// rustc records the variable, so cargo rebuilds when it changes; a bad
/// value stops the build naming the variable and the rule.
pub const N: usize = match option_env!("FINRS_SEGMENTS") {
    None => 3,
    Some(text) => segment_count(text.as_bytes()),
};

/// Segments driven by DAC1 and DAC2 instead of an H-bridge:
/// `FINRS_DAC_SEGMENTS` at build time, a comma list of at most two distinct
/// segment indices below [`N`] (`0`, `0,1`, `7,2`: the first on DAC1), none
/// if unset or empty.
#[allow(dead_code)] // the QEMU board drives the plant, not DACs
pub const DAC_SEGMENTS: [Option<usize>; 2] = match option_env!("FINRS_DAC_SEGMENTS") {
    None => [None, None],
    Some(text) => dac_segments(text.as_bytes()),
};

/// `FINRS_SEGMENTS`'s value (a build-time check: panics stop the build).
const fn segment_count(text: &[u8]) -> usize {
    match text {
        [d @ b'1'..=b'8'] => (*d - b'0') as usize,
        _ => panic!("FINRS_SEGMENTS must be one digit in 1..=8"),
    }
}

/// `FINRS_DAC_SEGMENTS`'s value (a build-time check: panics stop the build).
const fn dac_segments(text: &[u8]) -> [Option<usize>; 2] {
    let out = match text {
        [] => [None, None],
        [a] => [Some(dac_index(*a)), None],
        [a, b',', b] => [Some(dac_index(*a)), Some(dac_index(*b))],
        _ => panic!(
            "FINRS_DAC_SEGMENTS must be empty, `i` or `i,j` (at most 2 segments, DAC1 and DAC2)"
        ),
    };
    if let [Some(a), Some(b)] = out {
        if a == b {
            panic!("FINRS_DAC_SEGMENTS: the two segments must differ");
        }
    }
    out
}

/// One segment index of `FINRS_DAC_SEGMENTS`.
const fn dac_index(d: u8) -> usize {
    if !d.is_ascii_digit() || (d - b'0') as usize >= N {
        panic!("FINRS_DAC_SEGMENTS: each segment must be a digit below FINRS_SEGMENTS (default 3)");
    }
    (d - b'0') as usize
}

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
