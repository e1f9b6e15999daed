//! The probe-rs glue, kept thin: find and open a debug probe, attach to the
//! chip, flash an ELF, reset and run, attach to RTT at the ELF's
//! `_SEGGER_RTT`, read up channels and write the down channel.
//!
//! Anything that talks to USB or to the target is bounded in time: a call
//! that has not returned by then is an error, never a hang.

use std::path::Path;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context};
use probe_rs::flashing::{download_file, ElfLoader, ElfOptions};
use probe_rs::probe::list::Lister;
use probe_rs::probe::{DebugProbeInfo, DebugProbeSelector, Probe};
use probe_rs::rtt::{find_rtt_control_block_in_raw_file, Rtt};
use probe_rs::{Permissions, Session};

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
    /// Longest wait for the probe search and the attach.
    pub timeout: Duration,
}

/// Runs `f` on its own thread and waits at most `timeout` for it: the USB
/// search can block (`probe-rs list` hung in this project's container).
fn bounded<T: Send + 'static>(
    what: &str,
    timeout: Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> anyhow::Result<T> {
    let (tx, rx) = mpsc::channel();
    std::thread::Builder::new()
        .name(what.to_string())
        .spawn(move || {
            let _ = tx.send(f());
        })
        .with_context(|| format!("cannot start a thread for {what}"))?;
    rx.recv_timeout(timeout).map_err(|_| {
        anyhow!(
            "{what} did not finish within {:.1} s (is the probe's USB connection stuck?)",
            timeout.as_secs_f64()
        )
    })
}

/// Parses `--probe VID:PID[:SERIAL]`.
pub fn parse_selector(text: &str) -> anyhow::Result<DebugProbeSelector> {
    text.parse::<DebugProbeSelector>()
        .map_err(|e| anyhow!("--probe {text:?}: expected VID:PID[:SERIAL] in hex: {e}"))
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

/// Finds and opens the probe: the one given by `--probe`, or the only one
/// attached. Fails fast, naming what was looked for, when there is none.
pub fn open_probe(opts: &ProbeOptions) -> anyhow::Result<Probe> {
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
            many => bail!(
                "{} debug probes found: {}; choose one with --probe VID:PID[:SERIAL]",
                many.len(),
                describe(many)
            ),
        },
    };
    let Some(chosen) = chosen else {
        let wanted = match &opts.probe {
            Some(p) => format!("matching --probe {p}"),
            None => "attached".to_string(),
        };
        let seen = if probes.is_empty() {
            "none is visible over USB".to_string()
        } else {
            format!("visible: {}", describe(&probes))
        };
        bail!(
            "no debug probe found {wanted} ({seen}); connect the board's ST-LINK or another probe and check its USB permissions"
        );
    };
    let shown = chosen.to_string();
    bounded("opening the debug probe", opts.timeout, move || {
        Lister::new().open(chosen).map_err(|e| e.to_string())
    })?
    .map_err(|e| anyhow!("cannot open debug probe {shown}: {e}"))
}

/// Opens the probe and attaches to the chip.
pub fn attach(opts: &ProbeOptions) -> anyhow::Result<Session> {
    let probe = open_probe(opts)?;
    let chip = opts.chip.clone();
    bounded("attaching to the chip", opts.timeout, move || {
        probe
            .attach(chip, Permissions::default())
            .map_err(|e| e.to_string())
    })?
    .map_err(|e| anyhow!("cannot attach to chip {}: {e}", opts.chip))
}

/// Flashes the ELF at `path`, then resets the core and lets it run.
pub fn flash_and_run(session: &mut Session, path: &Path) -> anyhow::Result<()> {
    download_file(session, path, ElfLoader(ElfOptions::default()))
        .with_context(|| format!("flashing {}", path.display()))?;
    let mut core = session.core(0).context("core 0")?;
    core.reset().context("resetting the core after flashing")?;
    Ok(())
}

/// The address of `_SEGGER_RTT` in an ELF image.
pub fn rtt_address(elf_name: &str, elf: &[u8]) -> anyhow::Result<u64> {
    match find_rtt_control_block_in_raw_file(elf) {
        Ok(Some(address)) => Ok(address),
        Ok(None) => bail!("{elf_name}: no symbol `_SEGGER_RTT` (is the firmware built with RTT?)"),
        Err(e) => bail!("{elf_name}: not a readable ELF file: {e}"),
    }
}

/// Attaches to the RTT control block at `address` (or found by scanning
/// RAM when `None`), retrying until the firmware has set it up or
/// `timeout` has passed.
pub fn attach_rtt(
    session: &mut Session,
    address: Option<u64>,
    timeout: Duration,
) -> anyhow::Result<Rtt> {
    let started = Instant::now();
    loop {
        let mut core = session.core(0).context("core 0")?;
        let attempt = match address {
            Some(a) => Rtt::attach_at(&mut core, a),
            None => Rtt::attach(&mut core),
        };
        match attempt {
            Ok(rtt) => return Ok(rtt),
            Err(e) if started.elapsed() >= timeout => {
                let at = address
                    .map(|a| format!("at {a:#010x}"))
                    .unwrap_or_else(|| "in RAM".to_string());
                bail!(
                    "no RTT control block {at} after {:.1} s: {e}",
                    timeout.as_secs_f64()
                );
            }
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

/// Reads what up channel `channel` holds now, without waiting.
pub fn read_up(
    session: &mut Session,
    rtt: &mut Rtt,
    channel: usize,
    buf: &mut [u8],
) -> anyhow::Result<usize> {
    let mut core = session.core(0).context("core 0")?;
    let up = rtt
        .up_channel(channel)
        .with_context(|| format!("the firmware has no RTT up channel {channel}"))?;
    up.read(&mut core, buf)
        .with_context(|| format!("reading RTT up channel {channel}"))
}

/// Writes all of `bytes` to down channel `channel`, waiting for room in its
/// buffer at most `timeout`.
pub fn write_down(
    session: &mut Session,
    rtt: &mut Rtt,
    channel: usize,
    mut bytes: &[u8],
    timeout: Duration,
) -> anyhow::Result<()> {
    let started = Instant::now();
    let mut core = session.core(0).context("core 0")?;
    let down = rtt
        .down_channel(channel)
        .with_context(|| format!("the firmware has no RTT down channel {channel}"))?;
    while !bytes.is_empty() {
        let n = down
            .write(&mut core, bytes)
            .with_context(|| format!("writing RTT down channel {channel}"))?;
        bytes = &bytes[n..];
        if n == 0 {
            if started.elapsed() >= timeout {
                bail!(
                    "RTT down channel {channel} stayed full for {:.1} s: is the firmware reading commands?",
                    timeout.as_secs_f64()
                );
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    Ok(())
}

/// Sends `bytes` (encoded commands) to the running firmware's command down
/// channel: attach without reset, find RTT (at the ELF's `_SEGGER_RTT` if
/// `elf` is given, else by scanning RAM), write.
pub fn send(opts: &ProbeOptions, elf: Option<&Path>, bytes: &[u8]) -> anyhow::Result<()> {
    // Read the file first so that a wrong path fails before any USB work.
    let image = elf
        .map(|p| std::fs::read(p).with_context(|| format!("reading {}", p.display())))
        .transpose()?;
    let mut session = attach(opts)?;
    let address = match (elf, &image) {
        (Some(p), Some(image)) => Some(rtt_address(&p.display().to_string(), image)?),
        _ => None,
    };
    let mut rtt = attach_rtt(&mut session, address, opts.timeout)?;
    write_down(
        &mut session,
        &mut rtt,
        COMMAND_DOWN_CHANNEL,
        bytes,
        opts.timeout,
    )
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
            e.starts_with("--probe \"stlink\": expected VID:PID[:SERIAL]"),
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
