//! The link without the probe-rs library (`finrs` built without its
//! `probe` feature, as the README's quick start builds it to save half the
//! build): the same calls, each refusing with [`ProbeError::NotBuilt`],
//! which says how to build a `finrs` that talks to a board.

use std::convert::Infallible;
use std::path::Path;

use super::error::{ProbeError, TargetError};
use super::options::ProbeOptions;
use super::target::Target;
use super::worker::Bounded;

/// A probe session, of which this build has none.
pub enum Session {}

/// The probe's target, of which this build has none.
pub struct ProbeTarget(Session);

/// Refuses: this build opens no probe.
pub fn attach(_opts: &ProbeOptions) -> Result<Session, ProbeError> {
    Err(ProbeError::NotBuilt)
}

/// Never called: [`attach`] gives no session.
pub fn connect(session: Session, _opts: &ProbeOptions) -> Result<Bounded<ProbeTarget>, ProbeError> {
    match session {}
}

/// Refuses: a selector means a probe, which this build cannot open.
pub fn parse_selector(_text: &str) -> Result<Infallible, ProbeError> {
    Err(ProbeError::NotBuilt)
}

/// Refuses: the RTT block is only wanted for a probe.
pub fn rtt_address(_elf_name: &str, _elf: &[u8]) -> Result<u64, ProbeError> {
    Err(ProbeError::NotBuilt)
}

impl Target for ProbeTarget {
    fn flash(&mut self, _elf: &Path) -> Result<(), TargetError> {
        match self.0 {}
    }
    fn reset_and_halt(&mut self) -> Result<(), TargetError> {
        match self.0 {}
    }
    fn write_memory(&mut self, _address: u64, _bytes: &[u8]) -> Result<(), TargetError> {
        match self.0 {}
    }
    fn run(&mut self) -> Result<(), TargetError> {
        match self.0 {}
    }
    fn attach_rtt(&mut self, _address: Option<u64>) -> Result<(), TargetError> {
        match self.0 {}
    }
    fn read_up(&mut self, _channel: usize, _buf: &mut [u8]) -> Result<usize, TargetError> {
        match self.0 {}
    }
    fn write_down(&mut self, _channel: usize, _bytes: &[u8]) -> Result<usize, TargetError> {
        match self.0 {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_probe_call_says_how_to_build_a_finrs_that_has_one() {
        let opts = ProbeOptions {
            chip: crate::link::probe::DEFAULT_CHIP.to_string(),
            probe: None,
            timeout: std::time::Duration::from_secs(1),
            flash_timeout: crate::link::probe::DEFAULT_FLASH_TIMEOUT,
            speed_khz: None,
        };
        let said = [
            attach(&opts).err().map(|e| e.to_string()),
            parse_selector("0483:374b").err().map(|e| e.to_string()),
            rtt_address("fw.elf", b"").err().map(|e| e.to_string()),
            crate::link::probe::send(&opts, None, b"x")
                .err()
                .map(|e| e.to_string()),
        ];
        for e in said {
            let e = e.expect("refused");
            assert!(
                e.contains("`probe` feature") && e.contains("cargo build --release -p finrs`"),
                "{e}"
            );
        }
    }
}
