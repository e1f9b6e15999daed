//! The stack's high-water mark, measured by painting.
//!
//! The stack runs from cortex-m-rt's `_stack_end` (lowest address) up to
//! `_stack_start` (the initial SP); with flip-link that is the bottom of RAM
//! up to just below `.data`/`.bss`, and flip-link defines both symbols.
//! Free stack is filled with [`PAINT`]; a later scan from the bottom for the
//! first word that differs finds the deepest point the stack ever reached
//! ([`watermark::used_bytes`]). Measured twice:
//! - init: painted at the top of `init` (below its SP), scanned at its end:
//!   what `init` and everything it calls used (on QEMU the plant's
//!   `Strip::new`), plus the frames above (reset handler, RTIC's `main`);
//! - tasks: the free part painted again from the first run of the
//!   low-priority housekeeping task, so the second scan sees the running
//!   tasks alone (with the idle frames below which they run).
//!
//! The stack's lowest
//! [`GUARD_BYTES`](finrs_firmware_support::stack_guard::GUARD_BYTES) are its guard
//! ([`finrs_firmware_support::stack_guard`]), set first thing in `init`
//! ([`guard`]): an MPU region nothing may access, so that an overflow is a
//! MemManage fault while there is still RAM to stack it on, and the
//! fault's handler zeroes the outputs (`board::stack_overflow_stop`)
//! instead of the core locking up. Painting and scans start above it.
//!
//! All unsafe code of the measurement and the guard is in this file.

use core::sync::atomic::{AtomicUsize, Ordering};

use finrs_firmware_support::stack_guard::{self, mpu_registers, MpuRegisters};

use crate::watermark::{self, PAINT};

finrs_firmware_support::stack_guard_handler!(crate::board::stack_overflow_stop);

extern "C" {
    /// Top of the stack (initial SP), from cortex-m-rt's link.x or flip-link.
    static _stack_start: u32;
    /// Bottom of the stack (lowest address), likewise.
    static _stack_end: u32;
}

/// Bytes just below the SP left unpainted: the painting function's own
/// frame sits above its SP, but keep clear of anything the compiler may
/// spill below it.
const SP_MARGIN_BYTES: usize = 128;

/// Words painted per critical section when painting from a task, so that
/// interrupts are not held off for long (256 words: about 1 k instructions).
const CHUNK_WORDS: usize = 256;

/// Stack use at the end of `init`, bytes (0 until measured).
static INIT_USED_B: AtomicUsize = AtomicUsize::new(0);

/// The guard's MPU registers, for the stack's lowest address.
fn guard_registers() -> Option<MpuRegisters> {
    // Only the symbol's address is taken (safe), never its contents.
    mpu_registers(core::ptr::addr_of!(_stack_end) as u32).ok()
}

/// The usable stack's bounds, `(bottom, top)` addresses, 4-aligned: from
/// the guard's top (the stack's bottom if it has none) to the initial SP.
fn bounds() -> (usize, usize) {
    // Only the symbols' addresses are taken (safe), never their contents.
    let bottom = match guard_registers() {
        Some(r) => r.guard_top as usize,
        None => core::ptr::addr_of!(_stack_end) as usize,
    };
    (bottom, core::ptr::addr_of!(_stack_start) as usize)
}

/// Makes the stack's lowest guard bytes the MPU's region 0, no access,
/// enables the MPU (the default map elsewhere, off in HardFault and NMI)
/// and the MemManage fault; call first thing in `init`, while the SP is
/// far above the guard. A stack too close to the address space's end for
/// a guard (not one the link makes) is left without.
pub fn guard() {
    let Some(r) = guard_registers() else {
        return;
    };
    // SAFETY: called once, in `init`, with interrupts disabled, before
    // anything else uses the MPU; the initial SP is at least 25 % of RAM
    // above the guard (`scripts/check-stack`).
    #[allow(unsafe_code)]
    unsafe {
        stack_guard::enable(&r)
    };
}

/// The stack's size, bytes.
pub fn size_bytes() -> usize {
    let (bottom, top) = bounds();
    top - bottom
}

/// Paints the words at addresses `from..to` (4-aligned; `to` clamped to
/// `SP − SP_MARGIN_BYTES` read here, so a live frame is never painted).
///
/// The caller makes sure nothing else runs on the stack below the current
/// SP meanwhile: interrupts disabled (RTIC's `init`) or a critical section.
#[inline(never)]
fn paint_below_sp(from: usize, to: usize) {
    let sp = cortex_m::register::msp::read() as usize;
    let to = to.min(sp.saturating_sub(SP_MARGIN_BYTES) & !3);
    let mut p = from;
    while p < to {
        // SAFETY: `p` is in the stack region (`bounds`) below the SP less a
        // margin: no live frame is there, and nothing else runs on this
        // stack meanwhile (the caller's contract).
        #[allow(unsafe_code)]
        unsafe {
            core::ptr::write_volatile(p as *mut u32, PAINT)
        };
        p += 4;
    }
}

/// Bytes of stack used since the last painting (high-water mark).
pub fn used_bytes() -> usize {
    let (bottom, top) = bounds();
    let len = (top - bottom) / 4;
    watermark::used_bytes(len, |i| {
        // SAFETY: word `i < len` of the stack region; a volatile read of
        // plain RAM, which a running frame may be writing (we only look for
        // "not the pattern", so a torn view is harmless).
        #[allow(unsafe_code)]
        unsafe {
            core::ptr::read_volatile((bottom + 4 * i) as *const u32)
        }
    })
}

/// Paints all free stack; call first thing in `init` (interrupts are
/// disabled there).
pub fn paint_init() {
    let (bottom, top) = bounds();
    paint_below_sp(bottom, top);
}

/// Records `init`'s use; call last thing in `init`.
pub fn record_init() {
    INIT_USED_B.store(used_bytes(), Ordering::Relaxed);
}

/// Paints all free stack again, from a task at the lowest priority, a chunk
/// per critical section: inside one, no other task runs, so everything
/// below this task's SP is free.
pub fn repaint_for_tasks() {
    let (bottom, top) = bounds();
    let mut from = bottom;
    while from < top {
        let to = (from + 4 * CHUNK_WORDS).min(top);
        cortex_m::interrupt::free(|_| paint_below_sp(from, to));
        if to > cortex_m::register::msp::read() as usize {
            break; // reached this task's own frame
        }
        from = to;
    }
}

/// Logs both measurements and the stack size.
pub fn report() {
    defmt::info!(
        "stack: init used {} B, tasks used {} B of {} B",
        INIT_USED_B.load(Ordering::Relaxed),
        used_bytes(),
        size_bytes()
    );
}
