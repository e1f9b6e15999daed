//! The probe-rs library's side of the link (the `probe` feature): find
//! and open the probe, attach to the chip, find `_SEGGER_RTT` in an ELF.

use std::sync::mpsc;
use std::time::Duration;

use probe_rs::probe::list::Lister;
use probe_rs::probe::{DebugProbeInfo, DebugProbeSelector, Probe};
use probe_rs::rtt::find_rtt_control_block_in_raw_file;
use probe_rs::{Permissions, Session};

use super::error::ProbeError;
use super::options::ProbeOptions;
use super::probe_rs_target::ProbeTarget;
use super::worker::{Bounded, Timeouts};

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

#[cfg(test)]
mod tests {
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
