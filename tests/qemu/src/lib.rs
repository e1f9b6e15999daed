//! What every QEMU test program shares: the end of a run (semihosting's
//! exit code), and a fault or panic that ends QEMU with a failure code (a
//! panic's message, or `HardFault`, on the host's stderr) instead of
//! hanging it.
#![no_std]
#![deny(missing_docs)]

use core::fmt::Write;

use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hio};

/// Ends the QEMU run with success or failure.
pub fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Only reached without a debugger or QEMU to end us.
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
#[allow(unsafe_code)] // cortex-m-rt requires the HardFault handler to be `unsafe fn`
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "HardFault");
    }
    exit(false)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "panic: {info}");
    }
    exit(false)
}
