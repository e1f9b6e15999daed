//! A stack overflow on the Cortex-M4F, with the board's stack guard
//! (`finrs_firmware_support::stack_guard`) and its MemManage handler set
//! up as the firmware sets them, or without them as the board was before
//! (#50): a function recurses until the stack runs out. Prints one line on
//! the host's stdout, `reached MSTKERR DACCVIOL MMFAR depth`, from the
//! handler the guard's fault enters (the firmware's stop zeroes the
//! outputs there), then exits with success. Without the guard nothing
//! stops the recursion before it leaves RAM, and the core locks up: no
//! line, and QEMU runs on until it is stopped. The host test
//! `a_stack_overflow_reaches_the_guards_handler`
//! (tests/scenarios/tests/qemu_vs_x86.rs) runs both.
//!
//! With interrupts masked (`masked`), as in `init` or a critical
//! section, the guard's fault cannot preempt and escalates to HardFault,
//! whose handler (the test library's: `HardFault` on stderr, a failure
//! code) runs with the MPU off, so the guard is RAM it can stack on.
//!
//! The run is chosen by the semihosting command line
//! (`-semihosting-config …,arg=stack_guard,arg=unguarded` or `arg=masked`).
#![no_std]
#![no_main]
#![deny(missing_docs)]

use core::fmt::Write;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use finrs_firmware_support::stack_guard::{self, mpu_registers};
use finrs_qemu_tests::exit;

finrs_firmware_support::stack_guard_handler!(overflowed);

extern "C" {
    /// The stack's lowest address, from cortex-m-rt's link.
    static _stack_end: u32;
}

/// How deep the recursion got.
static DEPTH: AtomicU32 = AtomicU32::new(0);

/// What the guard's handler calls, on the stack's top again: reports the
/// fault and ends the run.
extern "C" fn overflowed() -> ! {
    // SAFETY: read-only accesses to the SCB's fault status and address
    // registers, on the way out.
    #[allow(unsafe_code)]
    let (cfsr, mmfar) = unsafe {
        let scb = &*cortex_m::peripheral::SCB::PTR;
        (scb.cfsr.read(), scb.mmfar.read())
    };
    if let Ok(mut out) = hio::hstdout() {
        let _ = writeln!(
            out,
            "reached {} {} {:#010x} {}",
            cfsr >> 4 & 1,
            cfsr >> 1 & 1,
            mmfar,
            DEPTH.load(Ordering::Relaxed)
        );
    }
    exit(true)
}

/// Recurses as long as there is stack, each call a 1 KiB frame the optimiser cannot drop.
#[inline(never)]
fn recurse(level: u32) -> u32 {
    if level == u32::MAX {
        return 0;
    }
    let mut frame = [level; 256];
    DEPTH.store(level, Ordering::Relaxed);
    core::hint::black_box(&mut frame);
    recurse(level + 1).wrapping_add(frame[level as usize % 256])
}

/// Whether the semihosting command line holds `word`: `unguarded` for the
/// run without the guard, `masked` for the recursion with interrupts
/// masked (as in `init` or a critical section: the MemManage fault cannot
/// preempt, and escalates to HardFault).
fn mode(word: &[u8]) -> bool {
    let mut buf = [0u8; 64];
    let mut args = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most `buf.len()` bytes into `buf`
    // and its length into `args[1]`.
    #[allow(unsafe_code)]
    let status = unsafe { cortex_m_semihosting::syscall1!(GET_CMDLINE, args.as_mut_ptr()) };
    let len = args[1].min(buf.len());
    status == 0 && buf[..len].windows(word.len()).any(|w| w == word)
}

#[entry]
fn main() -> ! {
    if !mode(b"unguarded") {
        // Only the symbol's address is taken.
        let bottom = core::ptr::addr_of!(_stack_end) as u32;
        let Ok(regs) = mpu_registers(bottom) else {
            exit(false)
        };
        // SAFETY: as the board's init calls it, first and with the stack
        // far above the guard.
        #[allow(unsafe_code)]
        unsafe {
            stack_guard::enable(&regs)
        };
    }
    let r = if mode(b"masked") {
        cortex_m::interrupt::free(|_| recurse(0))
    } else {
        recurse(0)
    };
    // Never reached: the recursion does not end.
    exit(r == 0)
}
