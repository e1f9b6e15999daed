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

/// Largest deterministic noise added to the load cell, counts (uniform in
/// `-LOAD_CELL_NOISE_COUNTS..=LOAD_CELL_NOISE_COUNTS`).
pub const LOAD_CELL_NOISE_COUNTS: i32 = 2;

/// Seed of the xorshift32 noise generator.
pub const NOISE_SEED: u32 = 0x2545_F491;

/// Tick (sample index) from which the shunt of [`INJECT_SEGMENT`] reads
/// full scale, in the `inject-overcurrent` build: 10.5 s at 1 kHz.
pub const INJECT_TICK: u64 = 10_500;

/// The segment whose shunt the injected overcurrent concerns.
pub const INJECT_SEGMENT: usize = 1;
