//! How long a store may stall the core, from the datasheet's worst cases,
//! and the watchdog period that covers it on the slowest-looking LSI.
//!
//! - Programming, at the HAL's x8 parallelism: 100 µs a byte at most (16 µs
//!   typical; DS8626, "Flash memory programming" characteristics, `t_prog`).
//! - Erasing a 128 KiB sector at x8: 4 s at most (2 s typical; the same
//!   table, `t_ERASE128KB`); no sector of the STM32F407 is larger (RM0090
//!   §3.3, table 5), and a smaller one erases faster.
//! - The IWDG counts the LSI, 17 to 47 kHz (DS8626, "LSI oscillator
//!   characteristics"), while the
//!   HAL sets its period for 32 kHz (`stm32f4xx-hal` 0.23,
//!   `watchdog.rs`: `LSI_KHZ = 32`, a period rounded down to `RL + 1`
//!   counts of 4096 at most): a period set to `T` ms may last only
//!   `T · 32/47 · 4095/4096` ms.
//!
//! ```
//! use finrs_firmware_support::flash_timing::{store_watchdog_ms, worst_us};
//! use finrs_firmware_support::record_log::Work;
//! // A 256-byte model record: 25.6 ms at most, a 58 ms watchdog.
//! let work = Work::Program { bytes: 256 };
//! assert_eq!(worst_us(work), 25_600);
//! assert_eq!(store_watchdog_ms(work, 20), 58);
//! ```

use crate::record_log::Work;

/// The longest time to program one byte at x8, µs (DS8626, `t_prog`).
pub const PROGRAM_BYTE_MAX_US: u64 = 100;

/// The longest erase of a sector of up to 128 KiB at x8, µs (DS8626,
/// `t_ERASE128KB`).
pub const ERASE_SECTOR_MAX_US: u64 = 4_000_000;

/// The LSI's nominal frequency, which the HAL assumes, and its highest,
/// Hz (DS8626, `f_LSI`).
pub const LSI_NOMINAL_HZ: u64 = 32_000;
/// See [`LSI_NOMINAL_HZ`].
pub const LSI_MAX_HZ: u64 = 47_000;

/// The HAL's longest period, ms (`RL` 4095 at the /256 prescaler, less
/// one: it asserts below 32 768).
pub const WATCHDOG_MAX_MS: u32 = 32_767;

/// The longest `work` can stall the core, µs: the erase, if any, and the
/// programming (the read-back is a few hundred cycles).
pub const fn worst_us(work: Work) -> u64 {
    match work {
        Work::Program { bytes } => bytes as u64 * PROGRAM_BYTE_MAX_US,
        Work::EraseAndProgram { bytes, .. } => {
            ERASE_SECTOR_MAX_US + bytes as u64 * PROGRAM_BYTE_MAX_US
        }
    }
}

/// The watchdog period to set, ms, before `work`, when `base_ms` is the
/// period that covers a normal tick: `base_ms` plus the work's worst time
/// as it would read on the fastest LSI, rounded up.
pub const fn store_watchdog_ms(work: Work, base_ms: u32) -> u32 {
    // worst · (47/32) · (4096/4095), in µs, rounded up to whole ms.
    let num = worst_us(work) * LSI_MAX_HZ * 4096;
    let den = LSI_NOMINAL_HZ * 4095 * 1000;
    let ms = base_ms as u64 + num.div_ceil(den);
    if ms > WATCHDOG_MAX_MS as u64 {
        WATCHDOG_MAX_MS
    } else {
        ms as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The time a period set to `set_ms` lasts on an LSI at `hz`, µs, as
    /// the HAL sets it (its `setup` and `timeout_period`, written again).
    fn lasts_us(set_ms: u32, hz: u64) -> u64 {
        let div = [4u32, 8, 16, 32, 64, 128]
            .into_iter()
            .find(|d| set_ms <= 7 * d / 32 && *d > 4)
            .unwrap_or(256);
        let div = if set_ms == 0 { 4 } else { div };
        let max_period = 4096 * div / 32;
        let rl = (set_ms * 4095 / max_period).min(4095);
        (rl as u64 + 1) * div as u64 * 1_000_000 / hz
    }

    #[test]
    fn the_period_covers_the_worst_store_on_the_fastest_lsi() {
        for work in [
            Work::Program { bytes: 32 },
            Work::Program { bytes: 256 },
            Work::EraseAndProgram {
                sector_bytes: 0x2_0000,
                bytes: 32,
            },
            Work::EraseAndProgram {
                sector_bytes: 0x2_0000,
                bytes: 256,
            },
        ] {
            let set = store_watchdog_ms(work, 20);
            let lasts = lasts_us(set, LSI_MAX_HZ);
            assert!(
                lasts >= worst_us(work) + lasts_us(20, LSI_MAX_HZ) - 1_000,
                "{work:?}: set {set} ms lasts {lasts} µs"
            );
            assert!(set <= WATCHDOG_MAX_MS);
        }
        // The 20 ms tick period alone: 13.6 ms on the fastest LSI, as #50
        // says, and 640 counts.
        assert_eq!(lasts_us(20, LSI_MAX_HZ), 13_617);
        // An erase: under 6 s, well within the HAL's 32.8 s.
        let erase = Work::EraseAndProgram {
            sector_bytes: 0x2_0000,
            bytes: 256,
        };
        assert_eq!(store_watchdog_ms(erase, 20), 5_935);
    }
}
