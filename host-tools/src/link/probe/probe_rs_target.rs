//! [`Target`] with probe-rs: a session attached to the chip and, once
//! found, its RTT control block.

use std::path::Path;
use std::time::Duration;

use anyhow::{anyhow, Context};
use probe_rs::flashing::{download_file, ElfLoader, ElfOptions};
use probe_rs::rtt::Rtt;
use probe_rs::{MemoryInterface, Session};

use super::Target;

/// Longest wait for the core to halt after a reset, inside probe-rs.
const HALT_TIMEOUT: Duration = Duration::from_millis(500);

/// A probe-rs session on core 0, and its RTT once attached.
pub struct ProbeTarget {
    session: Session,
    rtt: Option<Rtt>,
}

impl ProbeTarget {
    /// Wraps an attached session; RTT comes with [`Target::attach_rtt`].
    pub fn new(session: Session) -> Self {
        ProbeTarget { session, rtt: None }
    }

    fn rtt(&mut self) -> anyhow::Result<(probe_rs::Core<'_>, &mut Rtt)> {
        let rtt = self
            .rtt
            .as_mut()
            .ok_or_else(|| anyhow!("not attached to RTT yet"))?;
        let core = self.session.core(0).context("core 0")?;
        Ok((core, rtt))
    }
}

impl Target for ProbeTarget {
    fn flash(&mut self, elf: &Path) -> anyhow::Result<()> {
        // Another image means another RTT block.
        self.rtt = None;
        download_file(&mut self.session, elf, ElfLoader(ElfOptions::default()))
            .with_context(|| format!("flashing {}", elf.display()))
    }

    fn reset_and_halt(&mut self) -> anyhow::Result<()> {
        self.rtt = None;
        let mut core = self.session.core(0).context("core 0")?;
        core.reset_and_halt(HALT_TIMEOUT)
            .context("resetting and halting the core")?;
        Ok(())
    }

    fn write_memory(&mut self, address: u64, bytes: &[u8]) -> anyhow::Result<()> {
        let mut core = self.session.core(0).context("core 0")?;
        core.write_8(address, bytes)
            .with_context(|| format!("writing {} bytes at {address:#010x}", bytes.len()))
    }

    fn run(&mut self) -> anyhow::Result<()> {
        let mut core = self.session.core(0).context("core 0")?;
        core.run().context("starting the core")
    }

    fn attach_rtt(&mut self, address: Option<u64>) -> anyhow::Result<()> {
        let mut core = self.session.core(0).context("core 0")?;
        let rtt = match address {
            Some(a) => Rtt::attach_at(&mut core, a),
            None => Rtt::attach(&mut core),
        }?;
        self.rtt = Some(rtt);
        Ok(())
    }

    fn read_up(&mut self, channel: usize, buf: &mut [u8]) -> anyhow::Result<usize> {
        let (mut core, rtt) = self.rtt()?;
        let up = rtt
            .up_channel(channel)
            .with_context(|| format!("the firmware has no RTT up channel {channel}"))?;
        up.read(&mut core, buf)
            .with_context(|| format!("reading RTT up channel {channel}"))
    }

    fn write_down(&mut self, channel: usize, bytes: &[u8]) -> anyhow::Result<usize> {
        let (mut core, rtt) = self.rtt()?;
        let down = rtt
            .down_channel(channel)
            .with_context(|| format!("the firmware has no RTT down channel {channel}"))?;
        down.write(&mut core, bytes)
            .with_context(|| format!("writing RTT down channel {channel}"))
    }
}
