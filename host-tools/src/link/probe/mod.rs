//! The probe-rs glue, kept thin: find and open a debug probe, attach to the
//! chip, flash an ELF, reset and run, attach to RTT at the ELF's
//! `_SEGGER_RTT`, read up channels and write the down channel.
//!
//! Anything that talks to USB or to the target is bounded in time: a call
//! that has not returned by then is an error, never a hang. The probe
//! search, open and attach run on a thread of their own (`bounded()`);
//! after that the session lives on the thread of a [`Bounded`] link, which
//! serves flash, reset, memory writes, RTT attach, reads and writes one at
//! a time, each within [`Timeouts`] (`--probe-timeout-s`, 5 s by default;
//! flashing `--flash-timeout-s`, 60 s). A stalled call fails naming what
//! stalled and for how long ("reading RTT up channel 1 did not finish
//! within 5.0 s: ..."), and the link refuses every later call, so the
//! command exits non-zero; `finrs log`/`run` still write the samples
//! recorded so far, with the stall in the file's notes.
//!
//! `finrs run` flashes, then resets and halts the core, zeroes the ID of
//! the RTT control block at the ELF's `_SEGGER_RTT` and only then runs it
//! ([`flash_and_run`]): RAM survives a reset, and without this the host
//! could attach to the previous run's block and read its stale bytes.
//! `finrs log` attaches to the running firmware and changes nothing.
//!
//! The sequences and the bounds are written against the [`Target`] trait;
//! [`ProbeTarget`] is its probe-rs implementation, and the tests use a fake
//! target that hangs or fails (no probe is attached where they run).

mod error;
#[cfg(feature = "probe")]
mod glue;
mod options;
#[cfg(feature = "probe")]
mod probe_rs_target;
mod steps;
mod target;
#[cfg(not(feature = "probe"))]
mod unbuilt;
mod worker;

pub use error::{ProbeError, TargetError};
#[cfg(feature = "probe")]
pub use glue::{attach, connect, open_probe, parse_selector, rtt_address};
pub use options::{
    read_elf, ProbeOptions, COMMAND_DOWN_CHANNEL, DEFAULT_CHIP, DEFAULT_FLASH_TIMEOUT,
    DEFMT_UP_CHANNEL, FORCE_UP_CHANNEL,
};
#[cfg(feature = "probe")]
pub use probe_rs_target::ProbeTarget;
pub use steps::{attach_rtt, flash_and_run, send, write_all, RTT_ID_LEN};
pub use target::Target;
#[cfg(not(feature = "probe"))]
pub use unbuilt::{attach, connect, parse_selector, rtt_address, ProbeTarget, Session};
pub use worker::{Bounded, Timeouts};

#[cfg(test)]
pub(crate) mod tests;
