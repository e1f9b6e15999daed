//! The fitted model's records in flash (`finrs tune`): the same
//! append-only log as the calibration's ([`crate::record_log`]), in two
//! sectors of its own, with 512-byte records: `FMOD`, a sequence number,
//! the [`ModelRecord`] (254 bytes), a CRC-16, zero bytes.
//!
//! ```
//! # use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
//! use finrs_firmware_support::model_store::{load, save, Region};
//! use finrs_frames::{ModelRecord, MODEL_RECORD_LEN};
//! # struct Ram([u8; 4096]);
//! # impl ErrorType for Ram {
//! #     type Error = NorFlashErrorKind;
//! # }
//! # impl ReadNorFlash for Ram {
//! #     const READ_SIZE: usize = 1;
//! #     fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
//! #         out.copy_from_slice(&self.0[at as usize..at as usize + out.len()]);
//! #         Ok(())
//! #     }
//! #     fn capacity(&self) -> usize {
//! #         self.0.len()
//! #     }
//! # }
//! # impl NorFlash for Ram {
//! #     const WRITE_SIZE: usize = 1;
//! #     const ERASE_SIZE: usize = 2048;
//! #     fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
//! #         self.0[from as usize..to as usize].fill(0xFF);
//! #         Ok(())
//! #     }
//! #     fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
//! #         for (m, d) in self.0[at as usize..].iter_mut().zip(data) {
//! #             *m &= d; // NOR: bits go from 1 to 0 only
//! #         }
//! #         Ok(())
//! #     }
//! # }
//!
//! let mut flash = Ram([0xFF; 4096]);
//! let region = Region { offset: 0, sector_len: 2048 };
//! let (none, mut cursor) = load(&mut flash, region).unwrap();
//! assert_eq!(none, None);
//! let record = ModelRecord([7; MODEL_RECORD_LEN]);
//! // Four records a sector: the fifth store moves to the other sector.
//! for k in 1..=5 {
//!     assert_eq!(save(&mut flash, region, &mut cursor, &record, |_| {}).unwrap(), k);
//! }
//! assert_eq!(load(&mut flash, region).unwrap().0, Some(record));
//! ```

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
use finrs_frames::{ModelRecord, MODEL_RECORD_LEN};

use crate::record_log::Log;
pub use crate::record_log::{Cursor, Region, StoreError, Work};

/// Bytes per record.
pub const RECORD_LEN: usize = 512;

const LOG: Log<RECORD_LEN> = Log::new(*b"FMOD", MODEL_RECORD_LEN);

/// The board's region: the STM32F407VG's sectors 8 and 9, of 128 KiB
/// each at 0x08080000 and 0x080A0000 (RM0090 §3.3, table 5), just below
/// the calibration's; the workspace's `memory.x` ends the code's flash
/// below them.
pub const BOARD_REGION: Region = Region {
    offset: 0x8_0000,
    sector_len: 0x2_0000,
};

/// The model stored last, `None` if the region holds no valid record,
/// and the log's position for [`save`]. Reads the whole region: at boot.
pub fn load<F: ReadNorFlash>(
    flash: &mut F,
    region: Region,
) -> Result<(Option<ModelRecord>, Cursor), F::Error> {
    let (newest, cursor) = LOG.open(flash, region)?;
    let record = newest.and_then(|r| {
        let (body, _) = LOG.decode(&r)?;
        Some(ModelRecord(body.try_into().ok()?))
    });
    Ok((record, cursor))
}

/// Appends `record` as the newest at `cursor` (see [`crate::record_log`]);
/// `before` is told what the store is about to do. Returns its sequence
/// number.
pub fn save<F: NorFlash>(
    flash: &mut F,
    region: Region,
    cursor: &mut Cursor,
    record: &ModelRecord,
    before: impl FnOnce(Work),
) -> Result<u32, StoreError<F::Error>> {
    LOG.append(flash, region, cursor, &record.0, before)
}
