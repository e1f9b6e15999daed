//! The calibration's records in flash, on the append-only log of
//! [`crate::record_log`] (a store programs 32 bytes and erases nothing
//! until a sector is full; a reset or power cut at any moment leaves the
//! last complete record readable).
//!
//! A record is [`RECORD_LEN`] bytes: `FCAL`, a sequence number u32, the
//! [`Calibration`] (20 bytes), a CRC-16 of those 28 bytes, two zero bytes.
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
//! let (none, mut cursor) = load(&mut flash, region).unwrap();
//! assert_eq!(none, None);
//! let c = Calibration { newtons_per_count: 2.5e-5, current_zero_counts: [2048; 8] };
//! save(&mut flash, region, &mut cursor, &c, |_| {}).unwrap();
//! assert_eq!(load(&mut flash, region).unwrap().0.map(|r| r.calibration), Some(c));
//! ```

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
use finrs_frames::{Calibration, CALIBRATION_LEN};

use crate::record_log::Log;
pub use crate::record_log::{Cursor, Region, StoreError, Work};

/// Bytes per record (a power of two: records never straddle a 16-byte
/// flash row).
pub const RECORD_LEN: usize = 32;

/// The calibration's log: `FCAL`, a sequence number, the calibration.
const LOG: Log<RECORD_LEN> = Log::new(*b"FCAL", CALIBRATION_LEN);

/// The board's region: the STM32F407VG's last two sectors, 10 and 11, of
/// 128 KiB each at 0x080C0000 and 0x080E0000 (RM0090 §3.3, table 5); the
/// workspace's `memory.x` ends the code's flash below them.
pub const BOARD_REGION: Region = Region {
    offset: 0xC_0000,
    sector_len: 0x2_0000,
};

/// The calibration in force, as read from flash.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stored {
    /// The calibration.
    pub calibration: Calibration,
    /// Its record's sequence number (1 for the first store).
    pub seq: u32,
}

/// The record for `calibration` with sequence number `seq`.
pub fn encode_record(calibration: &Calibration, seq: u32) -> [u8; RECORD_LEN] {
    LOG.encode(&calibration.to_bytes(), seq)
}

/// The slot's record, `None` if the slot is erased or damaged.
pub fn decode_record(r: &[u8; RECORD_LEN]) -> Option<Stored> {
    let (body, seq) = LOG.decode(r)?;
    Some(Stored {
        calibration: Calibration::from_bytes(body.try_into().ok()?),
        seq,
    })
}

/// The calibration in force, `None` if the region holds no valid record,
/// and the log's position for [`save`]. Reads the whole region: at boot.
pub fn load<F: ReadNorFlash>(
    flash: &mut F,
    region: Region,
) -> Result<(Option<Stored>, Cursor), F::Error> {
    let (newest, cursor) = LOG.open(flash, region)?;
    Ok((newest.and_then(|r| decode_record(&r)), cursor))
}

/// Appends `calibration` as the newest record at `cursor` (see
/// [`crate::record_log`]): one slot programmed and read back, a sector
/// erased first when the other is full; `before` is told which. Returns
/// the record's sequence number.
pub fn save<F: NorFlash>(
    flash: &mut F,
    region: Region,
    cursor: &mut Cursor,
    calibration: &Calibration,
    before: impl FnOnce(Work),
) -> Result<u32, StoreError<F::Error>> {
    LOG.append(flash, region, cursor, &calibration.to_bytes(), before)
}
