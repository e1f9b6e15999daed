//! What one calibration store costs the Cortex-M4F, with 0, 1 000, 4 095
//! and 4 096 records already in the log (#50): the log is opened once, as
//! at boot, then one record saved, its instructions counted by SysTick
//! around the call and its flash reads by the flash itself. Prints a line
//! per fill on the host's stdout: `records bytes_read systick_counts work`
//! (`work` 0 for a program, 1 for an erase first; the counts 4294967295
//! if the store outlasted the 24-bit counter). Under `-icount
//! shift=S` each instruction takes 2^S ns of the guest's clock and SysTick
//! counts at 168 MHz, so the counts are instructions × 0.168 · 2^S; the
//! host test `a_store_costs_the_same_however_full_the_log`
//! (tests/scenarios/tests/qemu_vs_x86.rs) checks them.
//!
//! The flash is the board's calibration region (sectors 10 and 11, 2 ×
//! 128 KiB), more than the 128 KiB of RAM: a filled slot's bytes are made
//! from its index when read (the record with sequence number slot + 1),
//! an erased one reads 0xFF, and what a store programs is kept in RAM
//! over them, with NOR's rule (bits go from 1 to 0 only).
#![no_std]
#![no_main]
#![deny(missing_docs)]

use core::fmt::Write;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use finrs_firmware_support::calibration_store::{
    encode_record, load, save, Region, Work, BOARD_REGION, RECORD_LEN,
};
use finrs_frames::Calibration;
use finrs_qemu_tests::exit;

const REGION: Region = BOARD_REGION;
/// Slots a sector holds.
const SLOTS: u32 = REGION.sector_len / RECORD_LEN as u32;
/// Records a store may program before the program ends: one per fill.
const WRITES: usize = 4;

/// The calibration of record `k`.
fn calibration(k: u32) -> Calibration {
    Calibration {
        newtons_per_count: (k + 1) as f32 * 1e-6,
        current_zero_counts: [2048; 8],
    }
}

/// The calibration region, its first sector's first `filled` slots holding
/// records 1..=filled, the rest erased; writes kept in RAM.
struct Filled {
    /// Slots of sector 0 holding a record (0 once it is erased).
    filled: u32,
    /// Slots programmed since, by their address.
    written: [(u32, [u8; RECORD_LEN]); WRITES],
    n_written: usize,
    /// Bytes read since the count was last cleared.
    bytes_read: u32,
}

impl Filled {
    fn new(filled: u32) -> Self {
        Self {
            filled,
            written: [(0, [0; RECORD_LEN]); WRITES],
            n_written: 0,
            bytes_read: 0,
        }
    }

    /// The bytes of the slot at `at` (a multiple of the record length
    /// inside the region).
    fn slot(&self, at: u32) -> [u8; RECORD_LEN] {
        if let Some((_, r)) = self.written[..self.n_written]
            .iter()
            .find(|(a, _)| *a == at)
        {
            return *r;
        }
        let rel = at - REGION.offset;
        let slot = rel / RECORD_LEN as u32;
        if rel < REGION.sector_len && slot < self.filled {
            encode_record(&calibration(slot), slot + 1)
        } else {
            [0xFF; RECORD_LEN]
        }
    }

    fn in_region(&self, at: u32, len: usize) -> bool {
        at >= REGION.offset && at as usize + len <= self.capacity()
    }
}

impl ErrorType for Filled {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Filled {
    const READ_SIZE: usize = 1;
    fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
        if !self.in_region(at, out.len()) {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        self.bytes_read += out.len() as u32;
        // The log reads whole slots; any other read goes slot by slot.
        for (i, b) in out.iter_mut().enumerate() {
            let a = at + i as u32;
            let base = a - (a - REGION.offset) % RECORD_LEN as u32;
            *b = self.slot(base)[(a - base) as usize];
        }
        Ok(())
    }
    fn capacity(&self) -> usize {
        (REGION.offset + 2 * REGION.sector_len) as usize
    }
}

impl NorFlash for Filled {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = REGION.sector_len as usize;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if !self.in_region(from, (to - from) as usize) {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        if from == REGION.offset {
            self.filled = 0;
        }
        // Forget what was written in the erased span.
        let mut kept = 0;
        for i in 0..self.n_written {
            if !(from..to).contains(&self.written[i].0) {
                self.written[kept] = self.written[i];
                kept += 1;
            }
        }
        self.n_written = kept;
        Ok(())
    }
    fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
        if data.len() != RECORD_LEN
            || (at - REGION.offset) % RECORD_LEN as u32 != 0
            || !self.in_region(at, data.len())
            || self.n_written == WRITES
        {
            return Err(NorFlashErrorKind::NotAligned);
        }
        let mut r = self.slot(at);
        for (m, d) in r.iter_mut().zip(data) {
            *m &= d;
        }
        self.written[self.n_written] = (at, r);
        self.n_written += 1;
        Ok(())
    }
}

/// SysTick counts since `start` (it counts down, 24 bits, from its
/// reload).
fn elapsed(start: u32) -> u32 {
    start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF
}

/// Opens a log of `filled` records and saves one more: (bytes read by the
/// save, SysTick counts of the save, whether it erased first).
fn one(syst: &mut SYST, filled: u32) -> Option<(u32, u32, bool)> {
    let mut flash = Filled::new(filled);
    let (stored, mut cursor) = load(&mut flash, REGION).ok()?;
    if stored.map(|s| s.seq) != Some(filled).filter(|&n| n > 0) {
        return None;
    }
    flash.bytes_read = 0;
    let mut erased = false;
    syst.clear_current();
    let start = SYST::get_current();
    let seq = save(&mut flash, REGION, &mut cursor, &calibration(filled), |w| {
        erased = matches!(w, Work::EraseAndProgram { .. })
    })
    .ok()?;
    // A store past 2^24 counts (100 ms) wrapped the counter: say so as
    // the largest count, never as a small one.
    let counts = if syst.has_wrapped() {
        u32::MAX
    } else {
        elapsed(start)
    };
    let bytes_read = flash.bytes_read;
    // The store is the newest, where the next boot finds it.
    let (back, _) = load(&mut flash, REGION).ok()?;
    (seq == filled + 1 && back.map(|s| s.calibration) == Some(calibration(filled)))
        .then_some((bytes_read, counts, erased))
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    let syst = &mut core.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();
    let Ok(mut out) = hio::hstdout() else {
        exit(false)
    };
    let mut ok = true;
    for filled in [0, 1000, SLOTS - 1, SLOTS] {
        match one(syst, filled) {
            Some((bytes, counts, erased)) => {
                ok &= writeln!(out, "{filled} {bytes} {counts} {}", u8::from(erased)).is_ok();
            }
            None => ok = false,
        }
    }
    exit(ok)
}
