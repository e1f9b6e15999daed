//! The lab-like bench (`finrs_rig::lab`): each artefact present in the
//! written session as docs/rig.md states it, and the sessions without it
//! unchanged byte for byte. Short sessions of the rig's own strip, no
//! diagnosis.

use std::path::{Path, PathBuf};

use finrs_rig::{Bench, Hidden, Sample, Sensors};
use rand::SeedableRng;

fn rng(seed: u64) -> rand::rngs::StdRng {
    rand::rngs::StdRng::seed_from_u64(seed)
}

/// A fresh directory under the system's temporary one.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("finrs-lab-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// FNV-1a over every file of `dir` (names and bytes, in name order): a
/// hash that no Rust release changes, unlike `DefaultHasher`'s.
fn hash_dir(dir: &Path) -> u64 {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in names {
        eat(p.file_name().unwrap().to_string_lossy().as_bytes());
        eat(&std::fs::read(&p).unwrap());
    }
    h
}

/// The existing rigs' sessions, written by this build: an off-class strip
/// with two departures, mains pickup and every bench imperfection, and an
/// ideal strip with two effects on a perfect bench; a few short runs each.
fn existing_sessions(dir: &Path) -> (u64, u64) {
    let runs = finrs_rig::short_protocol(0.2);
    let pick =
        |idx: &[usize]| -> Vec<finrs_rig::Run> { idx.iter().map(|&i| runs[i].clone()).collect() };
    let mut r = rng(4242);
    let sample = Sample::draw_off_class(&mut r);
    let hidden = Hidden::draw_off_class(
        &["dehydration", "segment-crosstalk", "mains-pickup"],
        &mut r,
    )
    .unwrap();
    let sensors = Sensors::draw(&mut r);
    let bench = Bench::draw(&finrs_rig::IMPERFECTIONS, &mut r).unwrap();
    let off = dir.join("off-class");
    finrs_rig::write_session(
        &off,
        &sample,
        &hidden,
        &sensors,
        &bench,
        &pick(&[0, 3, 8, 9]),
        "HASH-1",
        &mut r,
    )
    .unwrap();
    let mut r = rng(4243);
    let sample = Sample::draw(&mut r);
    let hidden = Hidden::draw(&["large-deflection", "damping"], &mut r).unwrap();
    let sensors = Sensors::draw(&mut r);
    let ideal = dir.join("ideal");
    finrs_rig::write_session(
        &ideal,
        &sample,
        &hidden,
        &sensors,
        &Bench::default(),
        &pick(&[2, 4, 9]),
        "HASH-2",
        &mut r,
    )
    .unwrap();
    (hash_dir(&off), hash_dir(&ideal))
}

#[test]
fn the_existing_sessions_are_unchanged_byte_for_byte() {
    let dir = scratch("existing");
    let (off, ideal) = existing_sessions(&dir);
    std::fs::remove_dir_all(&dir).ok();
    // Written by main's rig (31b57b3) before the lab bench joined.
    assert_eq!(
        (off, ideal),
        (0x506b_16c4_e167_45d7, 0x4561_99bd_82aa_0a72),
        "{off:#x} {ideal:#x}"
    );
}
