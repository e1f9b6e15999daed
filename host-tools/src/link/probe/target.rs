//! What the host does to the target through a debug probe, one call at a
//! time: the calls that talk to USB, behind a trait so that the time
//! bounds ([`super::Bounded`]) and the flash-and-run sequence
//! ([`super::flash_and_run`]) are tested with a fake target, without a
//! probe.

use std::path::Path;

use super::TargetError;

/// The target behind a debug probe. Every method is one USB exchange (or a
/// few) that may block for as long as the probe's USB connection stalls;
/// callers reach it only through [`super::Bounded`], which bounds each in
/// time.
pub trait Target: Send + 'static {
    /// Writes the ELF image at `elf` into flash.
    fn flash(&mut self, elf: &Path) -> Result<(), TargetError>;
    /// Resets core 0 and halts it before its first instruction.
    fn reset_and_halt(&mut self) -> Result<(), TargetError>;
    /// Writes `bytes` into target memory at `address`.
    fn write_memory(&mut self, address: u64, bytes: &[u8]) -> Result<(), TargetError>;
    /// Lets the halted core 0 run.
    fn run(&mut self) -> Result<(), TargetError>;
    /// One attempt to attach to the RTT control block at `address` (or
    /// found by scanning RAM when `None`): an error while the firmware has
    /// not set it up yet.
    fn attach_rtt(&mut self, address: Option<u64>) -> Result<(), TargetError>;
    /// Reads what RTT up channel `channel` holds now, without waiting.
    fn read_up(&mut self, channel: usize, buf: &mut [u8]) -> Result<usize, TargetError>;
    /// Writes what fits now of `bytes` into RTT down channel `channel`;
    /// returns how many bytes were written (0 while it is full).
    fn write_down(&mut self, channel: usize, bytes: &[u8]) -> Result<usize, TargetError>;
}
