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

use std::path::Path;
use std::sync::mpsc;
use std::time::Duration;

use probe_rs::probe::list::Lister;
use probe_rs::probe::{DebugProbeInfo, DebugProbeSelector, Probe};
use probe_rs::rtt::find_rtt_control_block_in_raw_file;
use probe_rs::{Permissions, Session};

mod error;
mod probe_rs_target;
mod steps;
mod target;
mod worker;

pub use error::{ProbeError, TargetError};
pub use probe_rs_target::ProbeTarget;
pub use steps::{attach_rtt, flash_and_run, write_all, RTT_ID_LEN};
pub use target::Target;
pub use worker::{Bounded, Timeouts};

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

/// Runs `f` on its own thread and waits at most `timeout` for it: the USB
/// search can block (`probe-rs list` hung in this project's container).
fn bounded<T: Send + 'static>(
    what: &str,
    timeout: Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, ProbeError> {
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name(what.to_string())
        .spawn(move || {
            let _ = tx.send(f());
        })
        .map_err(|source| ProbeError::Thread {
            what: what.to_string(),
            source,
        })?;
    rx.recv_timeout(timeout)
        .map_err(|_| ProbeError::SetupTimeout {
            what: what.to_string(),
            timeout_s: timeout.as_secs_f64(),
        })
}

/// Parses a probe selector, `VID:PID[:SERIAL]` in hex.
pub fn parse_selector(text: &str) -> Result<DebugProbeSelector, ProbeError> {
    text.parse::<DebugProbeSelector>()
        .map_err(|e| ProbeError::Selector {
            text: text.to_string(),
            source: Box::new(e),
        })
}

fn describe(probes: &[DebugProbeInfo]) -> String {
    probes
        .iter()
        .map(|p| {
            format!(
                "{} ({:04x}:{:04x}{})",
                p.identifier,
                p.vendor_id,
                p.product_id,
                p.serial_number
                    .as_deref()
                    .map(|s| format!(":{s}"))
                    .unwrap_or_default()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Finds and opens the probe: the one given by [`ProbeOptions::probe`], or
/// the only one attached. Fails fast, naming what was looked for, when
/// there is none.
pub fn open_probe(opts: &ProbeOptions) -> Result<Probe, ProbeError> {
    let selector = opts.probe.as_deref().map(parse_selector).transpose()?;
    let probes = bounded("the debug probe search", opts.timeout, || {
        Lister::new().list_all()
    })?;
    let chosen = match &selector {
        Some(sel) => probes
            .iter()
            .find(|p| sel.matches_probe(p))
            .cloned()
            .map(DebugProbeSelector::from),
        None => match probes.as_slice() {
            [one] => Some(DebugProbeSelector::from(one)),
            [] => None,
            many => {
                return Err(ProbeError::ManyProbes {
                    count: many.len(),
                    found: describe(many),
                })
            }
        },
    };
    let Some(chosen) = chosen else {
        let seen = if probes.is_empty() {
            "none is visible over USB".to_string()
        } else {
            format!("visible: {}", describe(&probes))
        };
        return Err(ProbeError::NoProbe {
            selector: opts.probe.clone(),
            seen,
        });
    };
    let shown = chosen.to_string();
    bounded("opening the debug probe", opts.timeout, move || {
        Lister::new().open(chosen).map_err(|e| e.to_string())
    })?
    .map_err(|reason| ProbeError::Open {
        probe: shown,
        reason,
    })
}

/// Opens the probe and attaches to the chip.
pub fn attach(opts: &ProbeOptions) -> Result<Session, ProbeError> {
    let mut probe = open_probe(opts)?;
    if let Some(speed_khz) = opts.speed_khz {
        // The probe may round to a clock it has; what it took is logged.
        let took = probe.set_speed(speed_khz).map_err(|e| ProbeError::Speed {
            speed_khz,
            reason: e.to_string(),
        })?;
        eprintln!("SWD clock: {took} kHz (asked {speed_khz} kHz)");
    }
    let chip = opts.chip.clone();
    bounded("attaching to the chip", opts.timeout, move || {
        probe
            .attach(chip, Permissions::default())
            .map_err(|e| e.to_string())
    })?
    .map_err(|reason| ProbeError::Attach {
        chip: opts.chip.clone(),
        reason,
    })
}

/// Moves the attached session onto its own thread: from here on every call
/// to the target is bounded ([`Timeouts::call`] = `opts.timeout`, flashing
/// `opts.flash_timeout`).
pub fn connect(session: Session, opts: &ProbeOptions) -> Result<Bounded<ProbeTarget>, ProbeError> {
    Bounded::new(
        ProbeTarget::new(session),
        Timeouts {
            call: opts.timeout,
            flash: opts.flash_timeout,
        },
    )
}

/// The address of `_SEGGER_RTT` in an ELF image.
pub fn rtt_address(elf_name: &str, elf: &[u8]) -> Result<u64, ProbeError> {
    match find_rtt_control_block_in_raw_file(elf) {
        Ok(Some(address)) => Ok(address),
        Ok(None) => Err(ProbeError::NoRttSymbol {
            elf: elf_name.to_string(),
        }),
        Err(e) => Err(ProbeError::NotElf {
            elf: elf_name.to_string(),
            source: Box::new(e),
        }),
    }
}

/// Reads the ELF image at `path`.
pub fn read_elf(path: &Path) -> Result<Vec<u8>, ProbeError> {
    std::fs::read(path).map_err(|source| ProbeError::ReadElf {
        path: path.to_path_buf(),
        source,
    })
}

/// Sends `bytes` (encoded commands) to the running firmware's command down
/// channel: attach without reset, find RTT (at the ELF's `_SEGGER_RTT` if
/// `elf` is given, else by scanning RAM), write.
pub fn send(opts: &ProbeOptions, elf: Option<&Path>, bytes: &[u8]) -> Result<(), ProbeError> {
    // Read the file first so that a wrong path fails before any USB work.
    let image = elf.map(read_elf).transpose()?;
    let address = match (elf, &image) {
        (Some(p), Some(image)) => Some(rtt_address(&p.display().to_string(), image)?),
        _ => None,
    };
    let mut link = connect(attach(opts)?, opts)?;
    attach_rtt(&mut link, address, opts.timeout)?;
    write_all(&mut link, COMMAND_DOWN_CHANNEL, bytes, opts.timeout)
}

#[cfg(test)]
pub(crate) mod tests;

#[cfg(test)]
mod glue_tests {
    use super::*;

    #[test]
    fn probe_selectors_parse_or_are_refused_by_name() {
        let s = parse_selector("0483:374b:066DFF").unwrap();
        assert_eq!((s.vendor_id, s.product_id), (0x0483, 0x374b));
        assert_eq!(s.serial_number.as_deref(), Some("066DFF"));
        let e = parse_selector("stlink").unwrap_err().to_string();
        assert!(
            e.starts_with("\"stlink\": expected VID:PID[:SERIAL]"),
            "{e}"
        );
    }

    #[test]
    fn the_rtt_block_address_comes_from_the_elf_or_a_clear_refusal() {
        let e = rtt_address("junk.elf", b"not an elf at all").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("junk.elf: not a readable ELF file"),
            "{e}"
        );
        // This test program is an ELF without RTT.
        let me = std::env::current_exe().unwrap();
        let e = rtt_address("host.elf", &std::fs::read(me).unwrap()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "host.elf: no symbol `_SEGGER_RTT` (is the firmware built with RTT?)"
        );
    }
}
