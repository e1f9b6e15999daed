//! Sequences of bounded calls: flash and run without a stale RTT control
//! block, attach to RTT once the firmware has set it up, write a whole
//! command to the down channel, and send one to a running firmware.

use std::path::Path;
use std::time::{Duration, Instant};

use super::options::{read_elf, ProbeOptions, COMMAND_DOWN_CHANNEL};
use super::{attach, connect, rtt_address, Bounded, ProbeError, Target};

/// Length of the RTT control block's ID (`"SEGGER RTT"` and NULs), bytes.
pub const RTT_ID_LEN: usize = 16;

/// Flashes the ELF at `elf`, then resets and halts the core, zeroes the
/// ID of the RTT control block at `rtt_at` (the ELF's `_SEGGER_RTT`) and
/// lets the core run.
///
/// Why the ID is zeroed: RAM survives the reset, so the previous run's
/// control block may still be at the same address, valid, with its old
/// bytes, and the host would attach to it and read them as if new. With
/// its ID zeroed, [`attach_rtt`] succeeds only once the new firmware has
/// set the block up again. That it does: rtt-target 0.6.2's `rtt_init!`
/// (run by the board's `init_rtt` in the firmware's `init`) zeroes the
/// whole block and writes the ID last, backwards. Before that, cortex-m-rt
/// zeroes `.bss`, where the block lives: `_SEGGER_RTT` is a `static mut
/// MaybeUninit` with no section of its own (in the release build,
/// `llvm-nm` shows it in `.bss` at 0x2001d970, 96 bytes). So the old block
/// is visible between the reset and that zeroing, and for ever when the
/// new image never gets that far (a fault in start-up, a wrong image):
/// with the ID zeroed the attach then fails with a clear error instead of
/// showing the old run's data.
pub fn flash_and_run<T: Target>(
    link: &mut Bounded<T>,
    elf: &Path,
    rtt_at: u64,
) -> Result<(), ProbeError> {
    link.flash(elf)?;
    link.reset_and_halt()?;
    link.write_memory(rtt_at, &[0; RTT_ID_LEN])?;
    link.run()
}

/// Attaches to the RTT control block at `address` (or found by scanning RAM
/// when `None`), retrying until the firmware has set it up or `timeout` has
/// passed. A stalled call is not retried.
pub fn attach_rtt<T: Target>(
    link: &mut Bounded<T>,
    address: Option<u64>,
    timeout: Duration,
) -> Result<(), ProbeError> {
    let started = Instant::now();
    loop {
        match link.attach_rtt_once(address) {
            Ok(()) => return Ok(()),
            Err(e) if link.stalled().is_some() => return Err(e),
            Err(e) if started.elapsed() >= timeout => {
                let at = address
                    .map(|a| format!("at {a:#010x}"))
                    .unwrap_or_else(|| "in RAM".to_string());
                return Err(ProbeError::NoRttBlock {
                    at,
                    timeout_s: timeout.as_secs_f64(),
                    last: Box::new(e),
                });
            }
            Err(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}

/// Writes all of `bytes` to down channel `channel`, waiting for room in its
/// buffer at most `timeout` in all (each call is bounded on its own too).
pub fn write_all<T: Target>(
    link: &mut Bounded<T>,
    channel: usize,
    mut bytes: &[u8],
    timeout: Duration,
) -> Result<(), ProbeError> {
    let started = Instant::now();
    while !bytes.is_empty() {
        let n = link.write_down(channel, bytes)?;
        bytes = &bytes[n..];
        if n == 0 {
            if started.elapsed() >= timeout {
                return Err(ProbeError::DownFull {
                    channel,
                    timeout_s: timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    Ok(())
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
