//! The calibration log on a fake NOR flash (bits go from 1 to 0 only; an
//! erase sets a whole sector to 0xFF) that can lose power after any byte:
//! whatever the cut, an erase's included, a reboot reads the last complete
//! store; nothing outside the region is touched.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use finrs_firmware_support::calibration_store::{
    decode_record, encode_record, load, save, Region, StoreError, RECORD_LEN,
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
}

impl Nor {
    fn new(len: usize) -> Self {
        Self {
            mem: vec![0xFF; len],
            budget: None,
            stuck: None,
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
    assert_eq!(load(&mut f, REGION).unwrap(), None);
    let mut erases = 0;
    for k in 0..6 {
        let seq = save(&mut f, REGION, &cal(k, 2048), || erases += 1).unwrap();
        assert_eq!(seq, k + 1);
        let got = load(&mut f, REGION).unwrap().unwrap();
        assert_eq!((got.calibration, got.seq), (cal(k, 2048), k + 1));
    }
    // Stores 1, 2 in sector 0; 3, 4 in sector 1 (erased first); 5, 6 in
    // sector 0 again (erased first).
    assert_eq!(erases, 2);
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

#[test]
fn a_torn_record_is_skipped_and_the_next_store_goes_after_it() {
    let mut f = Nor::new(FLASH_LEN);
    save(&mut f, REGION, &cal(0, 2048), || {}).unwrap();
    f.budget = Some(10);
    assert!(matches!(
        save(&mut f, REGION, &cal(1, 2048), || {}),
        Err(StoreError::Flash(_))
    ));
    f.budget = None;
    assert_eq!(
        load(&mut f, REGION).unwrap().map(|s| s.calibration),
        Some(cal(0, 2048)),
        "the complete one"
    );
    assert_eq!(decode_record(slot(&f, 0, 1)), None, "torn");
    // Sector 0 is used up: the next store opens sector 1.
    save(&mut f, REGION, &cal(2, 2048), || {}).unwrap();
    assert_eq!(decode_record(slot(&f, 1, 0)).unwrap().seq, 2);
    assert_eq!(decode_record(slot(&f, 0, 0)).unwrap().seq, 1, "kept");
}

#[test]
fn a_record_that_does_not_read_back_is_reported() {
    let mut f = Nor::new(FLASH_LEN);
    f.stuck = Some(128 + 5);
    assert_eq!(
        save(&mut f, REGION, &cal(0, 2048), || {}),
        Err(StoreError::Verify)
    );
    assert_eq!(load(&mut f, REGION).unwrap(), None);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Stores, some cut after a random number of byte operations (an
    /// erase's among them); after each, a reboot reads the last complete
    /// store.
    #[test]
    fn a_power_cut_never_loses_the_last_complete_store(
        ops in prop::collection::vec((any::<u16>(), prop::option::weighted(0.4, 0usize..200)), 1..30),
    ) {
        let mut f = Nor::new(FLASH_LEN);
        f.mem[..128].fill(0x3C);
        let mut last: Option<Calibration> = None;
        for (k, (zero, cut)) in ops.iter().enumerate() {
            let c = cal(k as u32, *zero);
            f.budget = *cut;
            let result = save(&mut f, REGION, &c, || {});
            f.budget = None;
            if result.is_ok() {
                last = Some(c);
            } else {
                prop_assert!(matches!(result, Err(StoreError::Flash(_))), "{:?}", result);
            }
            let got = load(&mut f, REGION).unwrap().map(|s| s.calibration);
            prop_assert_eq!(got, last);
            prop_assert!(f.mem[..128].iter().all(|&b| b == 0x3C));
        }
    }
}
