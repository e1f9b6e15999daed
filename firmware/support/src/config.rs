//! The fin driver's configuration: one place for the numbers both builds
//! run with (the QEMU build converts its plant with the same scales).

use finrs_controller::{Calibration, Config};
use finrs_drive::{LimitError, Limits};

use crate::shunt_filter::ShuntFilter;

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

/// [`DAC_SEGMENTS`] as the Info frame carries them.
pub const DAC_SEGMENT_IDS: [Option<u8>; 2] = [
    match DAC_SEGMENTS[0] {
        Some(s) => Some(s as u8),
        None => None,
    },
    match DAC_SEGMENTS[1] {
        Some(s) => Some(s as u8),
        None => None,
    },
];

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
/// reference, mid-scale = 0 V: ±4.2 V at the codes' ends, ±3.64 V within
/// the buffer's swing, [`DAC_REACH_V`]).
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

/// The strips' voltage limit, V (the Nafion strips' ±4 V; lower by
/// command). What the board starts with is [`POWER_UP_LIMIT_V`].
pub const MAX_ABS_V: f32 = 4.0;

/// The DAC output buffer's swing from either rail, V: with the buffer on,
/// DAC_OUT reaches 0.2 V to VDDA − 0.2 V (STM32F407 datasheet, DS8626,
/// DAC characteristics), not the whole reference.
pub const DAC_BUFFER_MARGIN_V: f32 = 0.2;

/// The DAC's output at its 0 V code, V.
const DAC_ZERO_V: f32 = DAC_ZERO_CODE as f32 * DAC_VREF_V / 4095.0;

/// Largest |V| a DAC segment reaches on both sides: the amplifier's gain
/// times the buffer's swing either side of the 0 V code (±3.64 V for a
/// gain of 2.8 on a 3.0 V reference, where the codes alone would say
/// ±4.2 V).
pub const DAC_REACH_V: f32 = {
    let down = DAC_ZERO_V - DAC_BUFFER_MARGIN_V;
    let up = DAC_VREF_V - DAC_BUFFER_MARGIN_V - DAC_ZERO_V;
    let swing = if down < up { down } else { up };
    let gain = if DAC_GAIN < 0.0 { -DAC_GAIN } else { DAC_GAIN };
    gain * swing
};

/// The voltage limit the board starts with, V: [`MAX_ABS_V`], or less if a
/// DAC segment cannot reach it ([`DAC_REACH_V`]). A wave above it is
/// refused, not clipped by the output stage.
pub const POWER_UP_LIMIT_V: f32 =
    power_up_limit_v(DAC_SEGMENTS[0].is_some() || DAC_SEGMENTS[1].is_some());

/// [`POWER_UP_LIMIT_V`] for a build with DAC segments (`dac`) or without.
pub const fn power_up_limit_v(dac: bool) -> f32 {
    if dac && DAC_REACH_V < MAX_ABS_V {
        DAC_REACH_V
    } else {
        MAX_ABS_V
    }
}

const _: () = {
    assert!(POWER_UP_LIMIT_V > 0.0 && POWER_UP_LIMIT_V <= MAX_ABS_V);
    // A bridge reaches the limit at a duty of at most 1.
    assert!(
        BRIDGE_SUPPLY_V >= MAX_ABS_V,
        "the bridge supply must reach the limit"
    );
    assert!(DAC_ZERO_CODE <= 4095 && DAC_VREF_V > 2.0 * DAC_BUFFER_MARGIN_V);
};

/// Slew limit, V/s.
pub const SLEW_V_PER_S: f32 = 200.0;

/// Load-cell scale: the instrumentation amplifier maps about ±0.1 N (a
/// 10 g cell at full scale) onto ±2048 counts of the 12-bit ADC. The
/// example strip pushes up to 58 mN at a 4 V step (its blocked recording
/// 10): at half this scale (±0.05 N) the virtual bench's ADC saturated
/// there, a fault at the limit the firmware allows.
pub const NEWTONS_PER_COUNT: f32 = 5e-5;

/// Shunt scale: ±0.512 A onto ±2048 counts around mid-scale.
pub const AMPS_PER_COUNT: f32 = 2.5e-4;

/// Shunt reading at zero current, counts (bipolar amplifier at mid-scale).
pub const CURRENT_ZERO_COUNTS: u16 = 2048;

/// H-bridge PWM frequency, Hz: above the audible range and the 20 kHz the
/// issue asks; TIM1/TIM8 at 168 MHz still give 6720 steps (12.7 bits),
/// TIM2/TIM4 at 84 MHz 3360 (11.7 bits).
pub const PWM_HZ: u32 = 25_000;

/// The shunt amplifier's output filter, two buffered RC sections of 1.6 kΩ
/// and 100 nF (corner 995 Hz, 1 kHz here): the bridge's two-level current
/// reaches the ADC as its mean within 0.16 % of the jump between its
/// levels at any phase (0.06 mA on the seed's strip, a quarter of a
/// count), and a current that moves slowly reads `2τ` = 0.32 ms late.
/// See [`crate::shunt_filter`].
pub const SHUNT_FILTER: ShuntFilter = ShuntFilter {
    corner_hz: 1_000.0,
    pwm_hz: PWM_HZ as f32,
};

/// The calibration a board uses until one is stored in its flash
/// (`finrs calibrate`): the nominal scale, every shunt at its nominal zero.
pub const DEFAULT_CALIBRATION: Calibration = Calibration {
    newtons_per_count: NEWTONS_PER_COUNT,
    current_zero_counts: [CURRENT_ZERO_COUNTS; finrs_frames::MAX_SEGMENTS],
};

/// A segment drawing more than this is a fault, A.
pub const OVERCURRENT_A: f32 = 0.4;

/// The controller's configuration.
pub fn controller_config() -> Result<Config, LimitError> {
    Ok(Config {
        sample_hz: SAMPLE_HZ,
        limits: Limits::new(POWER_UP_LIMIT_V, SLEW_V_PER_S)?,
        calibration: DEFAULT_CALIBRATION,
        adc_full_scale: 4095,
        saturation_margin_counts: 8,
        amps_per_count: AMPS_PER_COUNT,
        overcurrent_a: OVERCURRENT_A,
        tare_samples: 200,
    })
}
