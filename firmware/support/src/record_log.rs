//! An append-only log of fixed-size records in two erase sectors of NOR
//! flash, shared by the calibration's and the model's stores: a store
//! programs one record and erases nothing until a sector is full, and a
//! reset or power cut at any moment, an erase's included, leaves the last
//! complete record readable.
//!
//! A record is `R` bytes at a multiple of `R` from the region's start: a
//! four-byte magic (which store), a sequence number u32, the body, a
//! CRC-16 of those bytes, then zero bytes to `R`. NOR flash programs bits
//! from 1 to 0 only, so a slot is either erased (all 0xFF), a record whose
//! CRC checks, or damaged (a write cut short, a sector erase cut short):
//! the record in force is the valid one with the highest sequence number,
//! and the next store goes after the last slot of its sector that is not
//! erased. When that sector is full, the other one is erased and takes the
//! store: the newest record is never in the sector being erased.
//!
//! Only the boot reads the whole region ([`Log::open`], a CRC over every
//! used slot: tens of milliseconds for a full sector). It leaves a
//! [`Cursor`], the log's position in RAM, and a store after it touches one
//! slot: it programs the record and reads it back, with an erase first when
//! the sector is full ([`Log::append`]). Before it touches the flash, the
//! store says what it is about to do ([`Work`]), so that the board can
//! widen its watchdog to the datasheet's longest time for it
//! ([`crate::flash_timing`]).

use embedded_storage::nor_flash::{NorFlash, ReadNorFlash};
use finrs_frames::crc16;

/// The part of the flash that holds a log's records: two erase sectors of
/// the same length, one after the other, offsets from the flash's start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    /// Start of the first sector, bytes from the flash's start.
    pub offset: u32,
    /// Length of each sector, bytes (a multiple of the record length).
    pub sector_len: u32,
}

impl Region {
    /// Start of sector `k` (0 or 1).
    const fn sector(&self, k: usize) -> u32 {
        self.offset + k as u32 * self.sector_len
    }
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

/// A log's position, from the boot's scan ([`Log::open`]) and kept by each
/// store after it ([`Log::append`]), so that a store reads nothing but the
/// record it programmed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cursor {
    /// The sector holding the newest valid record, if any: never erased.
    newest: Option<u8>,
    /// The sector the next record goes to, and its slot there (the
    /// sector's slot count when it is full).
    sector: u8,
    slot: u32,
    /// The next record's sequence number: one past every number tried,
    /// so that a record whose read-back failed is never outnumbered by a
    /// stale one.
    seq: u32,
}

/// What a store is about to do to the flash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// Program `bytes` (one record) and read them back.
    Program {
        /// Bytes programmed.
        bytes: u32,
    },
    /// Erase a sector of `sector_bytes`, then program `bytes`.
    EraseAndProgram {
        /// The sector's length, bytes.
        sector_bytes: u32,
        /// Bytes programmed after it.
        bytes: u32,
    },
}

/// One store's records: `R` bytes each, a body of `body_len` bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Log<const R: usize> {
    magic: [u8; 4],
    body_len: usize,
}

/// What a scan of one sector found.
#[derive(Clone, Copy)]
struct Scan<const R: usize> {
    /// The valid record with the highest sequence number, and that number.
    newest: Option<([u8; R], u32)>,
    /// The slot after the last one that is not erased
    /// (`slots` if full).
    next_free: u32,
}

impl<const R: usize> Log<R> {
    /// A log of `body_len`-byte bodies behind `magic`.
    pub(crate) const fn new(magic: [u8; 4], body_len: usize) -> Self {
        // Magic, sequence number, body and CRC fit; a power of two never
        // straddles the flash's 16-byte rows.
        assert!(8 + body_len + 2 <= R && R.is_power_of_two());
        Self { magic, body_len }
    }

    const fn crc_at(&self) -> usize {
        8 + self.body_len
    }

    /// Records a sector of `region` holds.
    fn slots(&self, region: Region) -> u32 {
        region.sector_len / R as u32
    }

    /// The record of `body` (`body_len` bytes) with sequence number `seq`.
    pub(crate) fn encode(&self, body: &[u8], seq: u32) -> [u8; R] {
        let mut r = [0u8; R];
        r[..4].copy_from_slice(&self.magic);
        r[4..8].copy_from_slice(&seq.to_le_bytes());
        r[8..self.crc_at()].copy_from_slice(body);
        let crc = crc16(&r[..self.crc_at()]);
        r[self.crc_at()..self.crc_at() + 2].copy_from_slice(&crc.to_le_bytes());
        r
    }

    /// The record's body and sequence number, `None` if the slot is erased,
    /// damaged or another store's.
    pub(crate) fn decode<'r>(&self, r: &'r [u8; R]) -> Option<(&'r [u8], u32)> {
        let at = self.crc_at();
        let crc = u16::from_le_bytes([r[at], r[at + 1]]);
        if r[..4] != self.magic || crc != crc16(&r[..at]) || r[at + 2..].iter().any(|&b| b != 0) {
            return None;
        }
        Some((&r[8..at], u32::from_le_bytes([r[4], r[5], r[6], r[7]])))
    }

    fn scan<F: ReadNorFlash>(
        &self,
        flash: &mut F,
        region: Region,
        k: usize,
    ) -> Result<Scan<R>, F::Error> {
        let mut newest: Option<([u8; R], u32)> = None;
        let mut next_free = 0;
        let mut r = [0u8; R];
        for slot in 0..self.slots(region) {
            flash.read(region.sector(k) + slot * R as u32, &mut r)?;
            if r.iter().all(|&b| b == 0xFF) {
                continue;
            }
            next_free = slot + 1;
            if let Some((_, seq)) = self.decode(&r) {
                if newest.is_none_or(|(_, s)| seq > s) {
                    newest = Some((r, seq));
                }
            }
        }
        Ok(Scan { newest, next_free })
    }

    /// Reads the whole region once (at boot): the newest valid record,
    /// `None` if the region holds none, and the log's position.
    pub(crate) fn open<F: ReadNorFlash>(
        &self,
        flash: &mut F,
        region: Region,
    ) -> Result<(Option<[u8; R]>, Cursor), F::Error> {
        let scans = [self.scan(flash, region, 0)?, self.scan(flash, region, 1)?];
        let seq = |k: usize| scans[k].newest.map(|(_, s)| s);
        // The sector with the newest record (the first if neither has one).
        let active = usize::from(seq(1) > seq(0));
        let newest = scans[active].newest;
        let cursor = Cursor {
            newest: newest.map(|_| active as u8),
            sector: active as u8,
            slot: scans[active].next_free,
            seq: newest.map_or(1, |(_, s)| s.wrapping_add(1)),
        };
        Ok((newest.map(|(r, _)| r), cursor))
    }

    /// Appends `body` as the newest record at `cursor`: in the next slot of
    /// its sector or, when that sector is full, at the start of the other
    /// one (never the newest record's), erased first. Calls `before` with
    /// what it is about to do, then reads the record back. Returns the
    /// record's sequence number. Whatever fails, the cursor stays true to
    /// the flash: a slot programmed in part is passed over, an erase cut
    /// short is done again by the next store.
    pub(crate) fn append<F: NorFlash>(
        &self,
        flash: &mut F,
        region: Region,
        cursor: &mut Cursor,
        body: &[u8],
        before: impl FnOnce(Work),
    ) -> Result<u32, StoreError<F::Error>> {
        let full = cursor.slot >= self.slots(region);
        if full {
            before(Work::EraseAndProgram {
                sector_bytes: region.sector_len,
                bytes: R as u32,
            });
            // The other sector than the newest record's: after a record
            // that failed in a fresh sector, that is the same fresh one.
            let target = cursor.newest.map_or(1 - cursor.sector, |k| 1 - k);
            let from = region.sector(usize::from(target));
            flash
                .erase(from, from + region.sector_len)
                .map_err(StoreError::Flash)?;
            cursor.sector = target;
            cursor.slot = 0;
        } else {
            before(Work::Program { bytes: R as u32 });
        }
        let seq = cursor.seq;
        let at = region.sector(usize::from(cursor.sector)) + cursor.slot * R as u32;
        // From here the slot is no longer erased, whatever happens.
        cursor.slot += 1;
        cursor.seq = seq.wrapping_add(1);
        let record = self.encode(body, seq);
        flash.write(at, &record).map_err(StoreError::Flash)?;
        let mut back = [0u8; R];
        flash.read(at, &mut back).map_err(StoreError::Flash)?;
        if back != record {
            return Err(StoreError::Verify);
        }
        cursor.newest = Some(cursor.sector);
        Ok(seq)
    }
}
