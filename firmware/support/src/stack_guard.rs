//! The stack's guard: the lowest [`GUARD_BYTES`] of the stack made an MPU
//! region that nothing may access, so that an overflow faults while real
//! RAM is still below the stack pointer and the fault's handler can run.
//!
//! Without it a stack overflow on the board (flip-link puts the stack at
//! the bottom of RAM) first touches the reserved addresses below
//! 0x2000_0000: a BusFault, escalated to HardFault, whose own stacking
//! faults again, and a fault while running HardFault locks the core up
//! (PM0214, 2.4 "Fault handling", "Lockup"), the
//! outputs driving until the keep-alive lets the bridges sleep. With the
//! guard an overflow is a MemManage fault (a data access violation, or a
//! stacking error, MSTKERR, when the exception entry itself ran into the
//! guard). Its handler, [`stack_guard_handler!`], touches no stack before
//! it has moved the main stack pointer back to the top of the stack, and
//! then calls the firmware's stop, which zeroes the outputs.
//!
//! The guard must be wider than any one frame (and an exception's 108-byte
//! frame on top): a function whose `sub sp` stepped over it would write
//! below it unchecked. `scripts/check-stack` holds the board's largest
//! frame to that; the board's is 9.2 KB at N = 3.
//!
//! ```
//! use finrs_firmware_support::stack_guard::{mpu_registers, GUARD_BYTES};
//!
//! // flip-link's stack starts at the bottom of RAM.
//! let regs = mpu_registers(0x2000_0000).unwrap();
//! assert_eq!(regs.rbar, 0x2000_0000 | 1 << 4);
//! assert_eq!(regs.guard_bottom, 0x2000_0000);
//! assert_eq!(regs.guard_top, 0x2000_0000 + GUARD_BYTES);
//! // cortex-m-rt's own layout: the guard starts at the next 16 KiB boundary.
//! let regs = mpu_registers(0x2000_1234).unwrap();
//! assert_eq!(regs.guard_bottom, 0x2000_4000);
//! ```

/// The guard's size, bytes: a power of two (an MPU region's rule) above
/// the board's largest frame.
pub const GUARD_BYTES: u32 = 16 * 1024;

/// MPU_CTRL (PM0214, 4.2.2): ENABLE, and PRIVDEFENA so that every address
/// outside the regions keeps the default map for privileged code (the
/// firmware runs privileged); HFNMIENA clear, so that HardFault and NMI
/// run with the MPU off.
pub const MPU_CTRL: u32 = 0b101;

/// SCB_SHCSR's MEMFAULTENA (bit 16): a MemManage fault is taken by its
/// own handler instead of escalating to HardFault.
pub const SHCSR_MEMFAULTENA: u32 = 1 << 16;

/// The values region 0 takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MpuRegisters {
    /// MPU_RBAR: the guard's base, VALID and region 0.
    pub rbar: u32,
    /// MPU_RASR: no access at any privilege (AP = 000), never executed
    /// (XN), the size as `log2(size) − 1`, enabled.
    pub rasr: u32,
    /// The guard's lowest address.
    pub guard_bottom: u32,
    /// The first address above it: the stack's usable bottom.
    pub guard_top: u32,
}

/// Why no guard can be set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GuardError {
    /// The stack's bottom aligned up to the guard's size leaves no address
    /// space above it.
    NoRoom,
}

/// Region 0's registers for a guard at the bottom of a stack whose lowest
/// address is `stack_bottom`: at the first multiple of [`GUARD_BYTES`] at
/// or above it (an MPU region is aligned to its size).
pub const fn mpu_registers(stack_bottom: u32) -> Result<MpuRegisters, GuardError> {
    const _: () = assert!(GUARD_BYTES.is_power_of_two() && GUARD_BYTES >= 32);
    let Some(top) = stack_bottom.checked_add(GUARD_BYTES - 1) else {
        return Err(GuardError::NoRoom);
    };
    let bottom = top & !(GUARD_BYTES - 1);
    let Some(guard_top) = bottom.checked_add(GUARD_BYTES) else {
        return Err(GuardError::NoRoom);
    };
    let size_field = GUARD_BYTES.trailing_zeros() - 1;
    Ok(MpuRegisters {
        rbar: bottom | 1 << 4,
        rasr: 1 << 28 | size_field << 1 | 1,
        guard_bottom: bottom,
        guard_top,
    })
}

/// Makes `r` the MPU's region 0, enables the MPU ([`MPU_CTRL`]) and the
/// MemManage fault ([`SHCSR_MEMFAULTENA`]), and waits until the new map
/// applies.
///
/// # Safety
///
/// Call once, with interrupts disabled, before anything else uses the MPU,
/// and with the stack pointer above `r.guard_top`: every access to the
/// guard faults from here on.
#[cfg(all(target_arch = "arm", target_os = "none"))]
#[allow(unsafe_code)]
pub unsafe fn enable(r: &MpuRegisters) {
    // SAFETY: the caller's contract; the registers are the core's own.
    unsafe {
        let mpu = &*cortex_m::peripheral::MPU::PTR;
        let scb = &*cortex_m::peripheral::SCB::PTR;
        mpu.rnr.write(0);
        mpu.rbar.write(r.rbar);
        mpu.rasr.write(r.rasr);
        mpu.ctrl.write(MPU_CTRL);
        scb.shcsr.modify(|v| v | SHCSR_MEMFAULTENA);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// Defines the MemManage handler (the `MemoryManagement` vector
/// cortex-m-rt provides for): it sets the main stack pointer to the
/// stack's top (`_stack_start`, cortex-m-rt's or flip-link's), abandoning
/// everything on it, then calls `$stop`, an `extern "C" fn() -> !` that
/// must not return. Nothing touches the stack before the move, so the
/// handler runs whatever the SP was.
#[macro_export]
macro_rules! stack_guard_handler {
    ($stop:path) => {
        #[allow(unsafe_code)] // the vector needs a handler that uses no stack
        mod __finrs_stack_guard {
            #[allow(unused_imports)]
            use super::*;
            core::arch::global_asm!(
                ".section .text.MemoryManagement,\"ax\",%progbits",
                ".global MemoryManagement",
                ".type MemoryManagement,%function",
                ".thumb_func",
                "MemoryManagement:",
                "    ldr r0, =_stack_start",
                "    msr msp, r0",
                "    isb",
                "    bl {stop}",
                "    udf #0",
                ".ltorg",
                ".size MemoryManagement, . - MemoryManagement",
                stop = sym $stop,
            );
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_guard_is_aligned_to_its_size_and_above_the_stack_bottom() {
        for bottom in [
            0x2000_0000u32,
            0x2000_0004,
            0x2000_3FFC,
            0x2000_4000,
            0x2001_0A10,
        ] {
            let r = mpu_registers(bottom).unwrap();
            assert!(r.guard_bottom >= bottom && r.guard_bottom - bottom < GUARD_BYTES);
            assert_eq!(r.guard_bottom % GUARD_BYTES, 0);
            assert_eq!(r.guard_top - r.guard_bottom, GUARD_BYTES);
            // SIZE encodes 2^(SIZE + 1) bytes.
            assert_eq!(1u32 << (((r.rasr >> 1) & 0x1F) + 1), GUARD_BYTES);
            // No access at any privilege: AP (bits 26:24) zero; XN set.
            assert_eq!(r.rasr >> 24 & 0b111, 0);
            assert_eq!(r.rasr >> 28 & 1, 1);
            assert_eq!(r.rbar & 0xF, 0, "region 0");
            assert_eq!(r.rbar & !0x1F, r.guard_bottom);
        }
    }

    #[test]
    fn no_guard_past_the_address_space() {
        assert_eq!(mpu_registers(u32::MAX - 16), Err(GuardError::NoRoom));
    }
}
