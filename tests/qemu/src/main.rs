//! Runs the shared scenarios of `finrs-tests` in `f32` on a Cortex-M4F and
//! prints them through semihosting; the host compares them with the same
//! scenarios run on x86 (`tests/scenarios/tests/qemu_vs_x86.rs`).
//!
//! Run it: `cargo run --release -p finrs-qemu-tests --target thumbv7em-none-eabihf`
//! (the runner in `.cargo/config.toml` starts QEMU's netduinoplus2, an
//! STM32F405 with the same Cortex-M4F and memory map as our STM32F407).
#![no_std]
#![no_main]
#![deny(missing_docs)]

use core::fmt::{self, Write};

use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use finrs_qemu_tests::exit;

/// Collects a line, then sends it in one semihosting call (one call per
/// fragment would be many times slower).
struct LineOut {
    host: hio::HostStream,
    buf: [u8; 512],
    len: usize,
}

impl LineOut {
    fn flush(&mut self) -> fmt::Result {
        let r = self
            .host
            .write_all(&self.buf[..self.len])
            .map_err(|_| fmt::Error);
        self.len = 0;
        r
    }
}

impl Write for LineOut {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for &b in s.as_bytes() {
            if self.len == self.buf.len() {
                self.flush()?;
            }
            self.buf[self.len] = b;
            self.len += 1;
            if b == b'\n' {
                self.flush()?;
            }
        }
        Ok(())
    }
}

#[entry]
fn main() -> ! {
    let ok = match hio::hstdout() {
        Ok(host) => {
            let mut out = LineOut {
                host,
                buf: [0; 512],
                len: 0,
            };
            finrs_tests::run_all::<f32, _>(&mut out).is_ok() && out.flush().is_ok()
        }
        Err(()) => false,
    };
    exit(ok)
}
