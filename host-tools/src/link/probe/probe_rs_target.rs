//! [`Target`] with probe-rs: a session attached to the chip and, once
//! found, its RTT control block.

use std::path::Path;
use std::time::Duration;

use probe_rs::flashing::{download_file, ElfLoader, ElfOptions};
use probe_rs::rtt::Rtt;
use probe_rs::{MemoryInterface, Session};

use super::{Target, TargetError};

/// Longest wait for the core to halt after a reset, inside probe-rs.
const HALT_TIMEOUT: Duration = Duration::from_millis(500);

/// A probe-rs session on core 0, and its RTT once attached.
pub struct ProbeTarget {
    session: Session,
    rtt: Option<Rtt>,
}

/// Core 0 of the session.
fn core0(session: &mut Session) -> Result<probe_rs::Core<'_>, TargetError> {
    session
        .core(0)
        .map_err(|e| TargetError::caused("core 0", e))
}

impl ProbeTarget {
    /// Wraps an attached session; RTT comes with [`Target::attach_rtt`].
    pub fn new(session: Session) -> Self {
        ProbeTarget { session, rtt: None }
    }

    fn rtt(&mut self) -> Result<(probe_rs::Core<'_>, &mut Rtt), TargetError> {
        let rtt = self
            .rtt
            .as_mut()
            .ok_or_else(|| TargetError::new("not attached to RTT yet"))?;
        let core = core0(&mut self.session)?;
        Ok((core, rtt))
    }
}

impl Target for ProbeTarget {
    fn flash(&mut self, elf: &Path) -> Result<(), TargetError> {
        // Another image means another RTT block.
        self.rtt = None;
        download_file(&mut self.session, elf, ElfLoader(ElfOptions::default()))
            .map_err(|e| TargetError::caused(format!("flashing {}", elf.display()), e))
    }

    fn reset_and_halt(&mut self) -> Result<(), TargetError> {
        self.rtt = None;
        let mut core = core0(&mut self.session)?;
        core.reset_and_halt(HALT_TIMEOUT)
            .map_err(|e| TargetError::caused("resetting and halting the core", e))?;
        Ok(())
    }

    fn write_memory(&mut self, address: u64, bytes: &[u8]) -> Result<(), TargetError> {
        let mut core = core0(&mut self.session)?;
        core.write_8(address, bytes).map_err(|e| {
            TargetError::caused(
                format!("writing {} bytes at {address:#010x}", bytes.len()),
                e,
            )
        })
    }

    fn run(&mut self) -> Result<(), TargetError> {
        let mut core = core0(&mut self.session)?;
        core.run()
            .map_err(|e| TargetError::caused("starting the core", e))
    }

    fn attach_rtt(&mut self, address: Option<u64>) -> Result<(), TargetError> {
        let mut core = core0(&mut self.session)?;
        let rtt = match address {
            Some(a) => Rtt::attach_at(&mut core, a),
            None => Rtt::attach(&mut core),
        }
        .map_err(|e| TargetError::caused("attaching to RTT", e))?;
        self.rtt = Some(rtt);
        Ok(())
    }

    fn read_up(&mut self, channel: usize, buf: &mut [u8]) -> Result<usize, TargetError> {
        let (mut core, rtt) = self.rtt()?;
        let up = rtt.up_channel(channel).ok_or_else(|| {
            TargetError::new(format!("the firmware has no RTT up channel {channel}"))
        })?;
        up.read(&mut core, buf)
            .map_err(|e| TargetError::caused(format!("reading RTT up channel {channel}"), e))
    }

    fn write_down(&mut self, channel: usize, bytes: &[u8]) -> Result<usize, TargetError> {
        let (mut core, rtt) = self.rtt()?;
        let down = rtt.down_channel(channel).ok_or_else(|| {
            TargetError::new(format!("the firmware has no RTT down channel {channel}"))
        })?;
        down.write(&mut core, bytes)
            .map_err(|e| TargetError::caused(format!("writing RTT down channel {channel}"), e))
    }
}
