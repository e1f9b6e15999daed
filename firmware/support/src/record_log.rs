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
//! store: the newest record is never in the sector being erased
//! (`before_erase` runs first: on the board an erase stalls the core for
//! seconds and the watchdog must be widened).

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

    /// Both sectors' scans, and the sector holding the newest record (the
    /// first if neither holds one).
    fn scan_both<F: ReadNorFlash>(
        &self,
        flash: &mut F,
        region: Region,
    ) -> Result<([Scan<R>; 2], usize), F::Error> {
        let scans = [self.scan(flash, region, 0)?, self.scan(flash, region, 1)?];
        let seq = |k: usize| scans[k].newest.map(|(_, s)| s);
        let active = usize::from(seq(1) > seq(0));
        Ok((scans, active))
    }

    /// The newest valid record, `None` if the region holds none.
    pub(crate) fn load<F: ReadNorFlash>(
        &self,
        flash: &mut F,
        region: Region,
    ) -> Result<Option<[u8; R]>, F::Error> {
        let (scans, active) = self.scan_both(flash, region)?;
        Ok(scans[active].newest.map(|(r, _)| r))
    }

    /// Appends `body` as the newest record: after the last used slot of
    /// the newest record's sector, or, if that sector is full, at the
    /// start of the other one, erased first (after calling
    /// `before_erase`). Reads it back. Returns the record's sequence
    /// number.
    pub(crate) fn save<F: NorFlash>(
        &self,
        flash: &mut F,
        region: Region,
        body: &[u8],
        before_erase: impl FnOnce(),
    ) -> Result<u32, StoreError<F::Error>> {
        let (scans, mut active) = self.scan_both(flash, region).map_err(StoreError::Flash)?;
        let seq = scans[active].newest.map_or(1, |(_, s)| s.wrapping_add(1));
        let mut slot = scans[active].next_free;
        if slot >= self.slots(region) {
            // The newest record stays where it is until this one is complete.
            active = 1 - active;
            before_erase();
            let from = region.sector(active);
            flash
                .erase(from, from + region.sector_len)
                .map_err(StoreError::Flash)?;
            slot = 0;
        }
        let at = region.sector(active) + slot * R as u32;
        let record = self.encode(body, seq);
        flash.write(at, &record).map_err(StoreError::Flash)?;
        let mut back = [0u8; R];
        flash.read(at, &mut back).map_err(StoreError::Flash)?;
        if back != record {
            return Err(StoreError::Verify);
        }
        Ok(seq)
    }
}
