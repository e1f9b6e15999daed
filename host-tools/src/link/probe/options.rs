//! What a probe session is opened with: the chip, the probe, the bounds
//! on waiting, the firmware's RTT channels, and the ELF image read from
//! disk.

use std::path::Path;
use std::time::Duration;

use super::error::ProbeError;

/// The chip on the fin's board.
pub const DEFAULT_CHIP: &str = "STM32F407VGTx";

/// The up channel of the firmware's force stream (channel 0 is defmt).
pub const FORCE_UP_CHANNEL: usize = 1;

/// The up channel of the firmware's defmt log.
pub const DEFMT_UP_CHANNEL: usize = 0;

/// The down channel the firmware reads commands from.
pub const COMMAND_DOWN_CHANNEL: usize = 0;

/// Which probe and chip, and how long to wait for them.
#[derive(Clone, Debug)]
pub struct ProbeOptions {
    /// probe-rs target name, e.g. `STM32F407VGTx`.
    pub chip: String,
    /// `VID:PID[:SERIAL]`, when more than one probe is attached.
    pub probe: Option<String>,
    /// Longest wait for the probe search, the attach, and each later call
    /// (reset, RTT attach attempt, read, write).
    pub timeout: Duration,
    /// Longest wait for flashing an ELF image.
    pub flash_timeout: Duration,
    /// The SWD clock to ask the probe for, kHz (`None`: the probe's
    /// default). RTT is read through it: a faster clock carries more
    /// frames per second, a slower one suits long wires.
    pub speed_khz: Option<u32>,
}

/// The default bound on flashing: generous, since it only has to catch a
/// stalled probe, not time a slow erase.
pub const DEFAULT_FLASH_TIMEOUT: Duration = Duration::from_secs(60);

/// Reads the ELF image at `path`.
pub fn read_elf(path: &Path) -> Result<Vec<u8>, ProbeError> {
    std::fs::read(path).map_err(|source| ProbeError::ReadElf {
        path: path.to_path_buf(),
        source,
    })
}
