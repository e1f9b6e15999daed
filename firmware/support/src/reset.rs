//! Why the core last reset, from the reset flags of RCC_CSR (RM0090, "RCC
//! clock control & status register": LPWRRSTF bit 31, WWDGRSTF 30,
//! IWDGRSTF 29, SFTRSTF 28, PORRSTF 27, PINRSTF 26, BORRSTF 25). The flags
//! stay set until software clears them (RMVF), so the firmware reads them
//! once at boot and clears them.
//!
//! ```
//! use finrs_firmware_support::reset::{from_rcc_csr, ResetCause};
//!
//! // A watchdog reset also pulls NRST low, so PINRSTF comes with it.
//! let csr = (1 << 29) | (1 << 26);
//! assert_eq!(from_rcc_csr(csr), ResetCause::Watchdog);
//! ```

pub use finrs_frames::ResetCause;

const LPWRRSTF: u32 = 1 << 31;
const WWDGRSTF: u32 = 1 << 30;
const IWDGRSTF: u32 = 1 << 29;
const SFTRSTF: u32 = 1 << 28;
const PORRSTF: u32 = 1 << 27;
const PINRSTF: u32 = 1 << 26;
const BORRSTF: u32 = 1 << 25;

/// The cause from RCC_CSR's value. Every internal reset also drives NRST
/// low, setting PINRSTF, and a power-on sets BORRSTF too: so the internal
/// causes are read first, then power-on, brown-out, and the pin only when
/// it is the one flag.
pub const fn from_rcc_csr(csr: u32) -> ResetCause {
    if csr & LPWRRSTF != 0 {
        ResetCause::LowPower
    } else if csr & WWDGRSTF != 0 {
        ResetCause::WindowWatchdog
    } else if csr & IWDGRSTF != 0 {
        ResetCause::Watchdog
    } else if csr & SFTRSTF != 0 {
        ResetCause::Software
    } else if csr & PORRSTF != 0 {
        ResetCause::PowerOn
    } else if csr & BORRSTF != 0 {
        ResetCause::BrownOut
    } else if csr & PINRSTF != 0 {
        ResetCause::Pin
    } else {
        ResetCause::Unknown
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_flag_set_is_read_with_what_comes_with_it() {
        let cases = [
            (PORRSTF | BORRSTF | PINRSTF, ResetCause::PowerOn),
            (BORRSTF | PINRSTF, ResetCause::BrownOut),
            (PINRSTF, ResetCause::Pin),
            (SFTRSTF | PINRSTF, ResetCause::Software),
            (IWDGRSTF | PINRSTF, ResetCause::Watchdog),
            (WWDGRSTF | PINRSTF, ResetCause::WindowWatchdog),
            (LPWRRSTF | PINRSTF, ResetCause::LowPower),
            (0, ResetCause::Unknown),
            // Flags not cleared since a power-on: the latest internal reset
            // still shows.
            (PORRSTF | BORRSTF | PINRSTF | IWDGRSTF, ResetCause::Watchdog),
            // Other bits of the register (LSION, LSIRDY, RMVF) are ignored.
            (PINRSTF | 0b11 | (1 << 24), ResetCause::Pin),
        ];
        for (csr, cause) in cases {
            assert_eq!(from_rcc_csr(csr), cause, "{csr:#010x}");
        }
        assert!(ResetCause::Watchdog.is_failure());
        assert!(!ResetCause::PowerOn.is_failure() && !ResetCause::Pin.is_failure());
    }
}
