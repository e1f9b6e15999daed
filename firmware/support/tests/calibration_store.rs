//! The calibration log on a fake NOR flash (bits go from 1 to 0 only; an
//! erase sets a whole sector to 0xFF) that can lose power after any byte:
//! whatever the cut, an erase's included, a reboot reads the last complete
//! store; nothing outside the region is touched.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use finrs_firmware_support::calibration_store::{
    decode_record, encode_record, load, save, Cursor, Region, StoreError, Work, RECORD_LEN,
};
use finrs_frames::Calibration;
use proptest::prelude::*;

/// NOR flash in RAM with a power budget: once `budget` byte programs or
/// erases are spent, the operation stops where it is and fails.
struct Nor {
    mem: Vec<u8>,
    budget: Option<usize>,
    /// A byte that never programs (a worn cell).
    stuck: Option<usize>,
    /// Bytes read so far.
    read: usize,
}

impl Nor {
    fn new(len: usize) -> Self {
        Self {
            mem: vec![0xFF; len],
            budget: None,
            stuck: None,
            read: 0,
        }
    }

    /// Spends one unit; false once the power is gone.
    fn spend(&mut self) -> bool {
        match &mut self.budget {
            None => true,
            Some(0) => false,
            Some(b) => {
                *b -= 1;
                true
            }
        }
    }
}

impl ErrorType for Nor {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Nor {
    const READ_SIZE: usize = 1;
    fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
        let at = at as usize;
        let src = self
            .mem
            .get(at..at + out.len())
            .ok_or(NorFlashErrorKind::OutOfBounds)?;
        out.copy_from_slice(src);
        self.read += out.len();
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl NorFlash for Nor {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = 64;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        // A real sector erase leaves no order to rely on: cut, it leaves
        // the bytes erased so far at 0xFF and the rest as they were.
        for i in from as usize..to as usize {
            if !self.spend() {
                return Err(NorFlashErrorKind::Other);
            }
            self.mem[i] = 0xFF;
        }
        Ok(())
    }
    fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
        for (i, d) in data.iter().enumerate() {
            if !self.spend() {
                return Err(NorFlashErrorKind::Other);
            }
            if self.stuck != Some(at as usize + i) {
                self.mem[at as usize + i] &= d;
            }
        }
        Ok(())
    }
}

/// Two sectors of two records each, after 128 bytes that are not the
/// region's.
const REGION: Region = Region {
    offset: 128,
    sector_len: 2 * RECORD_LEN as u32,
};
const FLASH_LEN: usize = 128 + 4 * RECORD_LEN;

/// The record in sector `k`, slot `slot`.
fn slot(f: &Nor, k: usize, slot: usize) -> &[u8; RECORD_LEN] {
    let at = 128 + (2 * k + slot) * RECORD_LEN;
    f.mem[at..at + RECORD_LEN].try_into().unwrap()
}

/// The calibration in force after a reboot.
fn reboot(f: &mut Nor) -> Option<Calibration> {
    load(f, REGION).unwrap().0.map(|s| s.calibration)
}

/// The log's position after a reboot.
fn cursor(f: &mut Nor) -> Cursor {
    load(f, REGION).unwrap().1
}

fn cal(k: u32, zero: u16) -> Calibration {
    Calibration {
        newtons_per_count: (k + 1) as f32 * 1e-6,
        current_zero_counts: [zero; 8],
    }
}

/// The code's flash in `memory.x` ends where the model's records begin;
/// the calibration's follow them to the end of the 1 MiB flash.
#[test]
fn the_linker_leaves_the_board_regions_free() {
    use finrs_firmware_support::calibration_store::BOARD_REGION;
    use finrs_firmware_support::model_store::BOARD_REGION as MODEL_REGION;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../memory.x");
    let text = std::fs::read_to_string(path).unwrap();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("FLASH"))
        .expect("a FLASH line");
    let kib: u32 = line
        .split("LENGTH = ")
        .nth(1)
        .and_then(|v| v.trim().strip_suffix('K'))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no LENGTH = ...K in {line:?}"));
    assert!(line.contains("ORIGIN = 0x08000000"), "{line}");
    assert_eq!(kib * 1024, MODEL_REGION.offset);
    assert_eq!(
        MODEL_REGION.offset + 2 * MODEL_REGION.sector_len,
        BOARD_REGION.offset
    );
    assert_eq!(
        BOARD_REGION.offset + 2 * BOARD_REGION.sector_len,
        1024 * 1024
    );
}

#[test]
fn a_record_round_trips_and_any_damage_is_refused() {
    let c = cal(3, 2047);
    let r = encode_record(&c, 9);
    let s = decode_record(&r).unwrap();
    assert_eq!((s.calibration, s.seq), (c, 9));
    for i in 0..RECORD_LEN {
        for bit in 0..8 {
            let mut bad = r;
            bad[i] ^= 1 << bit;
            assert_eq!(decode_record(&bad), None, "byte {i} bit {bit}");
        }
    }
    assert_eq!(decode_record(&[0xFF; RECORD_LEN]), None);
}

#[test]
fn stores_append_and_a_full_sector_moves_them_to_the_other() {
    let mut f = Nor::new(FLASH_LEN);
    f.mem[..128].fill(0x5A);
    assert_eq!(reboot(&mut f), None);
    let mut at = cursor(&mut f);
    let mut work = Vec::new();
    for k in 0..6 {
        let seq = save(&mut f, REGION, &mut at, &cal(k, 2048), |w| work.push(w)).unwrap();
        assert_eq!(seq, k + 1);
        let got = load(&mut f, REGION).unwrap().0.unwrap();
        assert_eq!((got.calibration, got.seq), (cal(k, 2048), k + 1));
        // The position kept in RAM is the one a reboot would find.
        assert_eq!(at, cursor(&mut f), "after store {}", k + 1);
    }
    // Stores 1, 2 in sector 0; 3, 4 in sector 1 (erased first); 5, 6 in
    // sector 0 again (erased first); each store said so before it began.
    let program = Work::Program {
        bytes: RECORD_LEN as u32,
    };
    let erase = Work::EraseAndProgram {
        sector_bytes: REGION.sector_len,
        bytes: RECORD_LEN as u32,
    };
    assert_eq!(work, [program, program, erase, program, erase, program]);
    let seqs: Vec<u32> = [(0, 0), (0, 1), (1, 0), (1, 1)]
        .iter()
        .map(|&(k, s)| decode_record(slot(&f, k, s)).unwrap().seq)
        .collect();
    assert_eq!(seqs, [5, 6, 3, 4]);
    assert!(
        f.mem[..128].iter().all(|&b| b == 0x5A),
        "outside the region"
    );
}

/// The board's sectors, 128 KiB each: 4096 calibration records apiece.
#[test]
fn a_store_reads_one_record_however_full_the_log() {
    const SECTOR: u32 = 0x2_0000;
    let region = Region {
        offset: 0,
        sector_len: SECTOR,
    };
    let slots = SECTOR as usize / RECORD_LEN;
    for stored in [0usize, 1_000, slots - 1] {
        let mut f = Nor::new(2 * SECTOR as usize);
        // A log of `stored` records, written directly (sequence 1..).
        for k in 0..stored {
            let r = encode_record(&cal(k as u32, 2048), k as u32 + 1);
            f.mem[k * RECORD_LEN..(k + 1) * RECORD_LEN].copy_from_slice(&r);
        }
        let (newest, mut at) = load(&mut f, region).unwrap();
        assert_eq!(newest.map(|s| s.seq), (stored > 0).then_some(stored as u32));
        // The boot read both sectors whole.
        assert_eq!(f.read, 2 * SECTOR as usize);
        for k in 0..3 {
            f.read = 0;
            let seq = save(&mut f, region, &mut at, &cal(7, 2048), |_| {}).unwrap();
            assert_eq!(seq as usize, stored + k + 1);
            // The read-back of the record it programmed, and nothing else.
            assert_eq!(f.read, RECORD_LEN, "{stored} records, store {k}");
        }
        let got = load(&mut f, region).unwrap().0.unwrap();
        assert_eq!(got.seq as usize, stored + 3);
    }
}

#[test]
fn a_torn_record_is_skipped_and_the_next_store_goes_after_it() {
    let mut f = Nor::new(FLASH_LEN);
    let mut at = cursor(&mut f);
    save(&mut f, REGION, &mut at, &cal(0, 2048), |_| {}).unwrap();
    f.budget = Some(10);
    assert!(matches!(
        save(&mut f, REGION, &mut at, &cal(1, 2048), |_| {}),
        Err(StoreError::Flash(_))
    ));
    f.budget = None;
    assert_eq!(reboot(&mut f), Some(cal(0, 2048)), "the complete one");
    assert_eq!(decode_record(slot(&f, 0, 1)), None, "torn");
    // Sector 0 is used up: the next store opens sector 1, with or without
    // a reboot in between.
    let mut rebooted = f.mem.clone();
    save(&mut f, REGION, &mut at, &cal(2, 2048), |_| {}).unwrap();
    assert_eq!(
        decode_record(slot(&f, 1, 0)).unwrap().calibration,
        cal(2, 2048)
    );
    assert_eq!(decode_record(slot(&f, 0, 0)).unwrap().seq, 1, "kept");
    let mut g = Nor::new(FLASH_LEN);
    g.mem = std::mem::take(&mut rebooted);
    let mut at = cursor(&mut g);
    save(&mut g, REGION, &mut at, &cal(2, 2048), |_| {}).unwrap();
    assert_eq!(
        decode_record(slot(&g, 1, 0)).unwrap().calibration,
        cal(2, 2048)
    );
}

#[test]
fn a_record_that_does_not_read_back_is_reported() {
    let mut f = Nor::new(FLASH_LEN);
    f.stuck = Some(128 + 5);
    let mut at = cursor(&mut f);
    assert_eq!(
        save(&mut f, REGION, &mut at, &cal(0, 2048), |_| {}),
        Err(StoreError::Verify)
    );
    assert_eq!(reboot(&mut f), None);
    // The next store passes the bad slot by.
    f.stuck = None;
    save(&mut f, REGION, &mut at, &cal(1, 2048), |_| {}).unwrap();
    assert_eq!(reboot(&mut f), Some(cal(1, 2048)));
    assert_eq!(
        decode_record(slot(&f, 0, 1)).unwrap().calibration,
        cal(1, 2048)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Stores, some cut after a random number of byte operations (an
    /// erase's among them), some after a reboot (the position read again
    /// from flash), the others going on from the position kept in RAM;
    /// after each, a reboot reads the last complete store, and the newest
    /// record's sector is never the one erased.
    #[test]
    fn a_power_cut_never_loses_the_last_complete_store(
        ops in prop::collection::vec(
            (any::<u16>(), prop::option::weighted(0.4, 0usize..200), any::<bool>()),
            1..30,
        ),
    ) {
        let mut f = Nor::new(FLASH_LEN);
        f.mem[..128].fill(0x3C);
        let mut last: Option<Calibration> = None;
        let mut at = cursor(&mut f);
        for (k, (zero, cut, reboots)) in ops.iter().enumerate() {
            if *reboots {
                at = cursor(&mut f);
            }
            let c = cal(k as u32, *zero);
            f.budget = *cut;
            let result = save(&mut f, REGION, &mut at, &c, |_| {});
            f.budget = None;
            if result.is_ok() {
                last = Some(c);
            } else {
                prop_assert!(matches!(result, Err(StoreError::Flash(_))), "{:?}", result);
            }
            prop_assert_eq!(reboot(&mut f), last);
            prop_assert!(f.mem[..128].iter().all(|&b| b == 0x3C));
        }
    }
}
