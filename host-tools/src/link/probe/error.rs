//! Why talking to the target through the probe failed: each names what was
//! being done (the probe, the chip, the ELF, the RTT channel) and keeps
//! the underlying error as its source.

use std::error::Error;
use std::path::PathBuf;

/// One call to the [`super::Target`] failed: what it was doing, and the
/// error probe-rs (or a test's fake target) gave, if any.
#[derive(Debug, thiserror::Error)]
#[error("{what}")]
pub struct TargetError {
    what: String,
    #[source]
    source: Option<Box<dyn Error + Send + Sync>>,
}

impl TargetError {
    /// A failure told by `what` alone.
    pub fn new(what: impl Into<String>) -> Self {
        TargetError {
            what: what.into(),
            source: None,
        }
    }

    /// A failure while doing `what`, caused by `source`.
    pub fn caused(what: impl Into<String>, source: impl Error + Send + Sync + 'static) -> Self {
        TargetError {
            what: what.into(),
            source: Some(Box::new(source)),
        }
    }
}

/// Why finding the probe, attaching, or a bounded call failed.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// This `finrs` was built without the probe-rs library.
    #[error("this finrs was built without its `probe` feature (`--no-default-features`), so it cannot open a debug probe: build it with its default features, `cargo build --release -p finrs`")]
    NotBuilt,
    /// A probe selector that is not `VID:PID[:SERIAL]` in hex.
    #[error("{text:?}: expected VID:PID[:SERIAL] in hex")]
    Selector {
        /// The selector as given.
        text: String,
        /// probe-rs's reason.
        #[source]
        source: Box<dyn Error + Send + Sync>,
    },
    /// A thread for a bounded step could not be started.
    #[error("cannot start a thread for {what}")]
    Thread {
        /// The step.
        what: String,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The probe search, opening the probe or the attach ran over its bound.
    #[error(
        "{what} did not finish within {timeout_s:.1} s (is the probe's USB connection stuck?)"
    )]
    SetupTimeout {
        /// The step.
        what: String,
        /// The bound, s.
        timeout_s: f64,
    },
    /// Several probes are attached and none was chosen.
    #[error("{count} debug probes found: {found}; choose one by its VID:PID[:SERIAL]")]
    ManyProbes {
        /// How many.
        count: usize,
        /// Each, with its VID:PID[:SERIAL].
        found: String,
    },
    /// No probe (or none matching the selector) is attached.
    #[error(
        "no debug probe found {} ({seen}); connect the board's ST-LINK or another probe and check its USB permissions",
        match selector { Some(s) => format!("matching {s}"), None => "attached".to_string() }
    )]
    NoProbe {
        /// The selector asked for, if any.
        selector: Option<String>,
        /// What is visible over USB.
        seen: String,
    },
    /// probe-rs could not open the chosen probe.
    #[error("cannot open debug probe {probe}: {reason}")]
    Open {
        /// The probe's selector.
        probe: String,
        /// probe-rs's reason (said on the probe's thread, as text).
        reason: String,
    },
    /// probe-rs could not attach to the chip.
    #[error("cannot attach to chip {chip}: {reason}")]
    Attach {
        /// The probe-rs chip name.
        chip: String,
        /// probe-rs's reason (said on the probe's thread, as text).
        reason: String,
    },
    /// The probe refused the SWD clock asked for.
    #[error("the debug probe refused an SWD clock of {speed_khz} kHz: {reason}")]
    Speed {
        /// The clock asked for, kHz.
        speed_khz: u32,
        /// probe-rs's reason.
        reason: String,
    },
    /// The ELF file could not be read.
    #[error("reading {}", path.display())]
    ReadElf {
        /// The file.
        path: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The ELF has no RTT control block symbol.
    #[error("{elf}: no symbol `_SEGGER_RTT` (is the firmware built with RTT?)")]
    NoRttSymbol {
        /// The ELF's name.
        elf: String,
    },
    /// The file is not an ELF image probe-rs can read.
    #[error("{elf}: not a readable ELF file")]
    NotElf {
        /// The ELF's name.
        elf: String,
        /// The parser's reason.
        #[source]
        source: Box<dyn Error + Send + Sync>,
    },
    /// A call to the target failed (and returned).
    #[error(transparent)]
    Target(#[from] TargetError),
    /// A call was not tried: an earlier one stalled the link.
    #[error("{what}: not tried, the probe link is stuck ({earlier})")]
    Stuck {
        /// The call not tried.
        what: String,
        /// The call that stalled.
        earlier: String,
    },
    /// The link's thread is gone.
    #[error("{what}: the probe link's thread has ended")]
    Ended {
        /// The call not served.
        what: String,
    },
    /// A call ran over its bound and was abandoned.
    #[error("{stall}: the debug probe stopped answering (USB connection stalled?); the call was abandoned")]
    Stalled {
        /// The call and its bound (`… did not finish within 5.0 s`).
        stall: String,
    },
    /// A call panicked on the link's thread.
    #[error("{what} panicked in the probe link's thread")]
    Panicked {
        /// The call.
        what: String,
    },
    /// The target claimed to read more bytes than it was given room for.
    #[error("RTT up channel {channel}: read returned {got} bytes into a {room}-byte buffer")]
    ReadOverrun {
        /// The up channel.
        channel: usize,
        /// Bytes claimed.
        got: usize,
        /// The buffer's length.
        room: usize,
    },
    /// The target claimed to write more bytes than it was given.
    #[error("RTT down channel {channel}: write claimed {got} bytes of {given}")]
    WriteOverrun {
        /// The down channel.
        channel: usize,
        /// Bytes claimed.
        got: usize,
        /// Bytes given.
        given: usize,
    },
    /// No RTT control block appeared within the bound.
    #[error("no RTT control block {at} after {timeout_s:.1} s (is the firmware running and built with RTT?)")]
    NoRttBlock {
        /// `at 0x…` or `in RAM`.
        at: String,
        /// The bound, s.
        timeout_s: f64,
        /// The last attempt's error.
        #[source]
        last: Box<ProbeError>,
    },
    /// The down channel stayed full.
    #[error("RTT down channel {channel} stayed full for {timeout_s:.1} s: is the firmware reading commands?")]
    DownFull {
        /// The down channel.
        channel: usize,
        /// The bound, s.
        timeout_s: f64,
    },
}
