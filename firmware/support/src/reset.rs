//! Why the core last reset, from the reset flags of RCC_CSR (RM0090, "RCC
//! clock control & status register": LPWRRSTF bit 31, WWDGRSTF 30,
//! IWDGRSTF 29, SFTRSTF 28, PORRSTF 27, PINRSTF 26, BORRSTF 25). The flags
//! stay set until software clears them (RMVF), so the firmware reads them
//! once at boot and clears them.
//!
//! ```
//! use finrs_firmware_support::reset::ResetCause;
//!
//! // A watchdog reset also pulls NRST low, so PINRSTF comes with it.
//! let csr = (1 << 29) | (1 << 26);
//! assert_eq!(ResetCause::from_rcc_csr(csr), ResetCause::IndependentWatchdog);
//! ```

/// The cause of the last reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResetCause {
    /// Power-on or power-down (PORRSTF; BORRSTF comes with it).
    PowerOn,
    /// Brown-out: the supply fell below the BOR threshold (BORRSTF alone).
    BrownOut,
    /// The NRST pin alone: the reset button or a debug probe's reset line.
    Pin,
    /// Software (SYSRESETREQ: a probe's or the firmware's own reset).
    Software,
    /// The independent watchdog: the firmware hung.
    IndependentWatchdog,
    /// The window watchdog (this firmware does not use it).
    WindowWatchdog,
    /// An illegal entry into Stop or Standby (low-power management reset).
    LowPower,
    /// No flag set (flags cleared and no reset since, or an emulator).
    Unknown,
}

const LPWRRSTF: u32 = 1 << 31;
const WWDGRSTF: u32 = 1 << 30;
const IWDGRSTF: u32 = 1 << 29;
const SFTRSTF: u32 = 1 << 28;
const PORRSTF: u32 = 1 << 27;
const PINRSTF: u32 = 1 << 26;
const BORRSTF: u32 = 1 << 25;

impl ResetCause {
    /// The cause from RCC_CSR's value. Every internal reset also drives
    /// NRST low, setting PINRSTF, and a power-on sets BORRSTF too: so the
    /// internal causes are read first, then power-on, brown-out, and the
    /// pin only when it is the one flag.
    pub const fn from_rcc_csr(csr: u32) -> Self {
        if csr & LPWRRSTF != 0 {
            Self::LowPower
        } else if csr & WWDGRSTF != 0 {
            Self::WindowWatchdog
        } else if csr & IWDGRSTF != 0 {
            Self::IndependentWatchdog
        } else if csr & SFTRSTF != 0 {
            Self::Software
        } else if csr & PORRSTF != 0 {
            Self::PowerOn
        } else if csr & BORRSTF != 0 {
            Self::BrownOut
        } else if csr & PINRSTF != 0 {
            Self::Pin
        } else {
            Self::Unknown
        }
    }

    /// The cause in words, for the log.
    pub const fn name(self) -> &'static str {
        match self {
            Self::PowerOn => "power-on",
            Self::BrownOut => "brown-out",
            Self::Pin => "reset pin",
            Self::Software => "software",
            Self::IndependentWatchdog => "watchdog",
            Self::WindowWatchdog => "window watchdog",
            Self::LowPower => "low-power management",
            Self::Unknown => "unknown",
        }
    }

    /// Whether the firmware itself failed (a watchdog or low-power reset):
    /// worth a warning, as the last run ended in a hang or a fault.
    pub const fn is_failure(self) -> bool {
        matches!(
            self,
            Self::IndependentWatchdog | Self::WindowWatchdog | Self::LowPower
        )
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
            (IWDGRSTF | PINRSTF, ResetCause::IndependentWatchdog),
            (WWDGRSTF | PINRSTF, ResetCause::WindowWatchdog),
            (LPWRRSTF | PINRSTF, ResetCause::LowPower),
            (0, ResetCause::Unknown),
            // Flags not cleared since a power-on: the latest internal reset
            // still shows.
            (
                PORRSTF | BORRSTF | PINRSTF | IWDGRSTF,
                ResetCause::IndependentWatchdog,
            ),
            // Other bits of the register (LSION, LSIRDY, RMVF) are ignored.
            (PINRSTF | 0b11 | (1 << 24), ResetCause::Pin),
        ];
        for (csr, cause) in cases {
            assert_eq!(ResetCause::from_rcc_csr(csr), cause, "{csr:#010x}");
        }
        assert!(ResetCause::IndependentWatchdog.is_failure());
        assert!(!ResetCause::PowerOn.is_failure() && !ResetCause::Pin.is_failure());
    }
}
