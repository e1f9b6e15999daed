//! The one interface between the app and a board. Each board module
//! provides the same items:
//!
//! - `init(core, device) -> Parts`: clocks, pins, peripherals, the SysTick
//!   monotonic and the log channel;
//! - `Io`: `read() -> Option<TickInput<N>>` (the sample period's ADC
//!   counts, numbered by the board's count of periods; `None` when the run
//!   is over), `write_v(Option<&[f32; N]>)`
//!   through the `SegmentOutput`s (`None`: every output off, where 0 V
//!   would hold the strip), `off()`, `feed_watchdog()`, `deadline_missed()`,
//!   `store_calibration(&Calibration) -> bool` and
//!   `store_model(&ModelRecord) -> bool` (false where it could not be
//!   stored);
//! - `FrameOut`: the controller's non-blocking `FrameSink`;
//! - `CommandIn`: `read(&mut [u8]) -> usize`, never blocking;
//! - `pace()` and `housekeeping(&mut Housekeeping)`: the board's async
//!   chores (pacing the sample interrupt where no hardware does, flushing);
//! - outputs at zero on panic and HardFault.

#[cfg(feature = "qemu")]
mod qemu;
#[cfg(feature = "qemu")]
pub use qemu::*;

#[cfg(not(feature = "qemu"))]
mod stm32f407;
#[cfg(not(feature = "qemu"))]
pub use stm32f407::*;

/// What `init` hands to the app.
pub struct Parts {
    /// Sampling and outputs.
    pub io: Io,
    /// The binary frame channel.
    pub frames: FrameOut,
    /// The command channel.
    pub commands: CommandIn,
    /// State of the low-priority chores.
    pub housekeeping: Housekeeping,
    /// Why the core last reset (the board's flags; unknown in QEMU).
    pub reset_cause: finrs_frames::ResetCause,
    /// The supplies as measured at boot, or which was out of range (the
    /// board then never drives). QEMU has none to measure: nominal.
    pub supply: Result<
        finrs_firmware_support::supply::Supplies,
        finrs_firmware_support::supply::SupplyError,
    >,
    /// The calibration stored in flash, if any (QEMU: none, it has no
    /// flash to keep one).
    pub stored_calibration: Option<finrs_frames::Calibration>,
    /// The fitted model stored in flash, if any (QEMU: none).
    pub stored_model: Option<finrs_frames::ModelRecord>,
}
