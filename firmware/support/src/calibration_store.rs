//! The calibration's records in flash: an append-only log in two erase
//! sectors, so that a store programs 32 bytes and erases nothing until a
//! sector is full, and a reset or power cut at any moment, an erase's
//! included, leaves the last complete record readable.
//!
//! A record is [`RECORD_LEN`] bytes at a multiple of it from the region's
//! start: `FCAL`, a sequence number u32, the [`Calibration`] (20 bytes), a
//! CRC-16 of those 28 bytes, two zero bytes. NOR flash programs bits from 1
//! to 0 only, so a slot is either erased (all 0xFF), a record whose CRC
//! checks, or damaged (a write cut short, a sector erase cut short): the
//! calibration in force is the valid record with the highest sequence
//! number, and the next store goes after the last slot of its sector that
//! is not erased. When that sector is full, the other one is erased and
//! takes the store: the newest record is never in the sector being erased
//! (`before_erase` runs first: on the board an erase stalls the core for
//! seconds and the watchdog must be widened).
//!
//! Generic over embedded-storage's `NorFlash`, which the HAL implements for
//! the STM32F4's flash; the tests use a fake with NOR's rules.
//!
//! ```
//! use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
//! use finrs_firmware_support::calibration_store::{load, save, Region};
//! use finrs_frames::Calibration;
//!
//! struct Ram([u8; 256]);
//! impl ErrorType for Ram {
//!     type Error = NorFlashErrorKind;
//! }
//! impl ReadNorFlash for Ram {
//!     const READ_SIZE: usize = 1;
//!     fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
//!         out.copy_from_slice(&self.0[at as usize..at as usize + out.len()]);
//!         Ok(())
//!     }
//!     fn capacity(&self) -> usize {
//!         self.0.len()
//!     }
//! }
//! impl NorFlash for Ram {
//!     const WRITE_SIZE: usize = 1;
//!     const ERASE_SIZE: usize = 128;
//!     fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
//!         self.0[from as usize..to as usize].fill(0xFF);
//!         Ok(())
//!     }
//!     fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
//!         for (m, d) in self.0[at as usize..].iter_mut().zip(data) {
//!             *m &= d; // NOR: bits go from 1 to 0 only
//!         }
//!         Ok(())
//!     }
//! }
//!
//! let mut flash = Ram([0xFF; 256]);
//! let region = Region { offset: 0, sector_len: 128 };
//! assert_eq!(load(&mut flash, region).unwrap(), None);
//! let c = Calibration { newtons_per_count: 2.5e-5, current_zero_counts: [2048; 8] };
//! save(&mut flash, region, &c, || {}).unwrap();
//! assert_eq!(load(&mut flash, region).unwrap().map(|r| r.calibration), Some(c));
//! ```

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
use finrs_frames::{crc16, Calibration, CALIBRATION_LEN};

/// Bytes per record (a power of two: records never straddle a 16-byte
/// flash row).
pub const RECORD_LEN: usize = 32;

const MAGIC: [u8; 4] = *b"FCAL";
/// Bytes the CRC covers: magic, sequence number, calibration.
const BODY_LEN: usize = 8 + CALIBRATION_LEN;
const _: () = assert!(BODY_LEN + 4 == RECORD_LEN);

/// The part of the flash that holds the records: two erase sectors of the
/// same length, one after the other, offsets from the flash's start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    /// Start of the first sector, bytes from the flash's start.
    pub offset: u32,
    /// Length of each sector, bytes (a multiple of [`RECORD_LEN`]).
    pub sector_len: u32,
}

/// The board's region: the STM32F407VG's last two sectors, 10 and 11, of
/// 128 KiB each at 0x080C0000 and 0x080E0000 (RM0090 §3.3, table 5); the
/// workspace's `memory.x` ends the code's flash below them.
pub const BOARD_REGION: Region = Region {
    offset: 0xC_0000,
    sector_len: 0x2_0000,
};

impl Region {
    /// Records a sector holds.
    pub const fn slots_per_sector(&self) -> u32 {
        self.sector_len / RECORD_LEN as u32
    }

    /// Start of sector `k` (0 or 1).
    const fn sector(&self, k: usize) -> u32 {
        self.offset + k as u32 * self.sector_len
    }
}

/// The calibration in force, as read from flash.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stored {
    /// The calibration.
    pub calibration: Calibration,
    /// Its record's sequence number (1 for the first store).
    pub seq: u32,
}

/// Why a store failed; the flash's own error where it gave one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreError<E> {
    /// The flash refused a read, write or erase.
    Flash(E),
    /// The record read back differs from the one written (a worn or
    /// protected sector).
    Verify,
}

/// The record for `calibration` with sequence number `seq`.
pub fn encode_record(calibration: &Calibration, seq: u32) -> [u8; RECORD_LEN] {
    let mut r = [0u8; RECORD_LEN];
    r[..4].copy_from_slice(&MAGIC);
    r[4..8].copy_from_slice(&seq.to_le_bytes());
    r[8..BODY_LEN].copy_from_slice(&calibration.to_bytes());
    let crc = crc16(&r[..BODY_LEN]);
    r[BODY_LEN..BODY_LEN + 2].copy_from_slice(&crc.to_le_bytes());
    r
}

/// The slot's record, `None` if the slot is erased or damaged.
pub fn decode_record(r: &[u8; RECORD_LEN]) -> Option<Stored> {
    let crc = u16::from_le_bytes([r[BODY_LEN], r[BODY_LEN + 1]]);
    if r[..4] != MAGIC || crc != crc16(&r[..BODY_LEN]) || r[BODY_LEN + 2..] != [0, 0] {
        return None;
    }
    let body: &[u8; CALIBRATION_LEN] = r[8..BODY_LEN].try_into().ok()?;
    Some(Stored {
        calibration: Calibration::from_bytes(body),
        seq: u32::from_le_bytes([r[4], r[5], r[6], r[7]]),
    })
}

/// What a scan of one sector found.
#[derive(Clone, Copy)]
struct Scan {
    /// The valid record with the highest sequence number.
    newest: Option<Stored>,
    /// The slot after the last one that is not erased
    /// (`slots_per_sector()` if full).
    next_free: u32,
}

fn scan<F: ReadNorFlash>(flash: &mut F, region: Region, k: usize) -> Result<Scan, F::Error> {
    let mut newest: Option<Stored> = None;
    let mut next_free = 0;
    let mut r = [0u8; RECORD_LEN];
    for slot in 0..region.slots_per_sector() {
        flash.read(region.sector(k) + slot * RECORD_LEN as u32, &mut r)?;
        if r.iter().all(|&b| b == 0xFF) {
            continue;
        }
        next_free = slot + 1;
        if let Some(s) = decode_record(&r) {
            if newest.is_none_or(|c| s.seq > c.seq) {
                newest = Some(s);
            }
        }
    }
    Ok(Scan { newest, next_free })
}

/// Both sectors' scans, and the sector holding the newest record (the
/// first if neither holds one).
fn scan_both<F: ReadNorFlash>(
    flash: &mut F,
    region: Region,
) -> Result<([Scan; 2], usize), F::Error> {
    let scans = [scan(flash, region, 0)?, scan(flash, region, 1)?];
    let seq = |k: usize| scans[k].newest.map(|s| s.seq);
    let active = usize::from(seq(1) > seq(0));
    Ok((scans, active))
}

/// The calibration in force, `None` if the region holds no valid record.
pub fn load<F: ReadNorFlash>(flash: &mut F, region: Region) -> Result<Option<Stored>, F::Error> {
    let (scans, active) = scan_both(flash, region)?;
    Ok(scans[active].newest)
}

/// Appends `calibration` as the newest record: after the last used slot of
/// the newest record's sector, or, if that sector is full, at the start of
/// the other one, erased first (after calling `before_erase`). Reads it
/// back. Returns the record's sequence number.
pub fn save<F: NorFlash>(
    flash: &mut F,
    region: Region,
    calibration: &Calibration,
    before_erase: impl FnOnce(),
) -> Result<u32, StoreError<F::Error>> {
    let (scans, mut active) = scan_both(flash, region).map_err(StoreError::Flash)?;
    let seq = scans[active].newest.map_or(1, |c| c.seq.wrapping_add(1));
    let mut slot = scans[active].next_free;
    if slot >= region.slots_per_sector() {
        // The newest record stays where it is until this one is complete.
        active = 1 - active;
        before_erase();
        let from = region.sector(active);
        flash
            .erase(from, from + region.sector_len)
            .map_err(StoreError::Flash)?;
        slot = 0;
    }
    let at = region.sector(active) + slot * RECORD_LEN as u32;
    let record = encode_record(calibration, seq);
    flash.write(at, &record).map_err(StoreError::Flash)?;
    let mut back = [0u8; RECORD_LEN];
    flash.read(at, &mut back).map_err(StoreError::Flash)?;
    if back != record {
        return Err(StoreError::Verify);
    }
    Ok(seq)
}
