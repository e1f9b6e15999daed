//! The QEMU build's simulated board, as numbers: how long it runs, how the
//! plant's force and currents become ADC counts, and the injected fault.
//! Plain constants, shared with the host's SIL test
//! (`tests/scenarios/tests/firmware_sil.rs`) so that it cannot drift from
//! the firmware.

/// Simulated seconds the QEMU build runs before it exits through
/// semihosting.
pub const RUN_S: u32 = 12;

/// Load-cell counts at zero force (the preload the tare removes).
pub const LOAD_CELL_ZERO_COUNTS: u16 = 2048;

/// Largest deterministic noise at the load cell's ADC input, counts
/// (uniform in ±this, before the ADC rounds: an input's noise, which also
/// dithers the rounding, so that a mean over many readings is not held
/// off by up to half a count as a noiseless input's would be).
pub const LOAD_CELL_NOISE_COUNTS: f32 = 2.0;

/// Largest deterministic noise at each shunt's ADC input, counts (as the
/// load cell's). Without it a shunt reads a held current as the same count
/// for seconds, off by up to half a count, differently at each voltage: a
/// fit of the currents saw that pattern as an electrochemical nonlinearity.
pub const SHUNT_NOISE_COUNTS: f32 = 1.0;

/// Where in its PWM period each segment's shunt is converted, a fraction
/// of the period after its timer's update: fixed, since 1 ms is 25
/// periods of the same clock, and on the board set by when each timer and
/// TIM5 started, so arbitrary; the QEMU board's plant spreads them. Read
/// through the shunt's filter ([`crate::config::SHUNT_FILTER`]).
pub const SHUNT_SAMPLE_PHASE: [f32; 8] = [0.05, 0.18, 0.31, 0.44, 0.57, 0.70, 0.83, 0.96];

/// The modal damping ratio of the plant built with `plant-damping`: the
/// virtual bench's hidden effect, within the 0.02 to 0.1 of real strips.
pub const PLANT_DAMPING_RATIO: f64 = 0.05;

/// Seed of the xorshift32 noise generator.
pub const NOISE_SEED: u32 = 0x2545_F491;

/// Tick (sample index) from which the shunt of [`INJECT_SEGMENT`] reads
/// full scale, in the `inject-overcurrent` build: 10.5 s at 1 kHz.
pub const INJECT_TICK: u64 = 10_500;

/// The segment whose shunt the injected overcurrent concerns.
pub const INJECT_SEGMENT: usize = 1;

/// The next number of a xorshift32 generator (Marsaglia 2003) whose state
/// is `state` (never 0): the simulated sensors' deterministic noise, the
/// same sequence on every run and target.
///
/// ```
/// let mut s = finrs_firmware_support::sim::NOISE_SEED;
/// let (a, b) = (finrs_firmware_support::sim::xorshift32(&mut s), finrs_firmware_support::sim::xorshift32(&mut s));
/// assert!(a != b && a != 0);
/// ```
pub fn xorshift32(state: &mut u32) -> u32 {
    let mut x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    x
}

/// The `plant-variant` strip's factors on the example session's `R1`, `C`
/// and moment per charge (`a` and `b` alike): a strip whose parameters
/// differ from its nominal ones by a spread real samples show.
pub const PLANT_VARIANT: (f64, f64, f64) = (1.15, 0.9, 0.8);

/// The `plant-drying` strip's drying time, s: from boot, every admittance
/// of every segment (`1/R1`, `1/R2`, `C`) is its own times `e^{−t/τ}`, as
/// if the wet part of the electrodes shrank; the moment per charge stays.
/// 300 s: 18 % less in the first minute, 24 % in the example protocol's
/// 80 s. Applied as the voltage the strip sees (the same currents and
/// moments, exactly).
pub const PLANT_DRYING_TIME_S: f32 = 300.0;
