//! The recorder against synthetic streams made by the firmware's encoder.

use finrs_frames::{
    encode_dropped, encode_fault, encode_sample, Dropped, Fault, FaultCode, Sample, MAX_FRAME_LEN,
};
use proptest::prelude::*;

use super::*;
use crate::recording::Geometry;
use crate::recording::{Channel, Fixture, Medium, Recording};

fn setup() -> Setup {
    Setup {
        geometry: Geometry::THESIS_2006,
        medium: Medium::Water,
        sample: Some("strip-7".to_string()),
        source: "a test stream".to_string(),
    }
}

/// A 3-segment Sample whose values are a function of `seq`, so that a row
/// tells which Sample it came from.
fn sample3(seq: u32, t_us: u32) -> Sample<3> {
    let x = (seq % 1000) as f32;
    Sample {
        seq,
        t_us,
        force_n: 0.001 * x,
        flags: finrs_frames::SampleFlags::default(),
        voltages_v: [0.001 * x, -0.002 * x, 3.5],
        currents_a: [1e-5 * x, -2e-5 * x, 0.03],
    }
}

fn sample_bytes<const N: usize>(s: &Sample<N>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_sample(s, &mut buf).unwrap();
    buf[..n].to_vec()
}

fn dropped_bytes(first_seq: u32, count: u32) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_dropped(&Dropped { first_seq, count }, &mut buf).unwrap();
    buf[..n].to_vec()
}

fn fault_bytes(f: &Fault) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_fault(f, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// Samples `seqs`, 1 ms apart by sequence number.
fn stream(seqs: impl IntoIterator<Item = u32>) -> Vec<u8> {
    seqs.into_iter()
        .flat_map(|seq| sample_bytes(&sample3(seq, seq.wrapping_mul(1000))))
        .collect()
}

fn record(bytes: &[u8]) -> Recorder {
    let mut r = Recorder::new(setup());
    r.push_bytes(bytes);
    r.finish();
    r
}

fn force_column(rec: &Recording) -> Vec<f64> {
    rec.channel(Channel::Force)
        .unwrap()
        .iter()
        .map(|x| x.unwrap())
        .collect()
}

#[test]
fn a_clean_stream_becomes_a_blocked_recording_with_every_value() {
    let r = record(&stream(0..10));
    let rec = r.recording("clean.csv").unwrap();
    assert_eq!(rec.meta.segments, 3);
    assert_eq!(rec.meta.fixture, Fixture::Blocked);
    assert_eq!(rec.meta.medium, Medium::Water);
    assert_eq!(rec.meta.sample.as_deref(), Some("strip-7"));
    assert_eq!(rec.t_s.len(), 10);
    assert_eq!(rec.t_s[3], 0.003);
    let s = sample3(7, 7000);
    assert_eq!(
        rec.v_v[7],
        s.voltages_v
            .iter()
            .map(|&v| f64::from(v))
            .collect::<Vec<_>>()
    );
    assert_eq!(
        rec.channel(Channel::Current(1)).unwrap()[7],
        Some(f64::from(s.currents_a[1]))
    );
    assert_eq!(force_column(&rec)[7], f64::from(s.force_n));
    let names: Vec<String> = rec.channels.iter().map(|(c, _)| c.name()).collect();
    assert_eq!(names, ["i1_A", "i2_A", "i3_A", "force_N"]);
    assert!(r.gaps().is_empty());
    let notes = rec.meta.notes.unwrap();
    assert!(
        notes.contains(
            "10 samples; no Info frame from the firmware; no gaps; no faults; no corrupt bytes"
        ),
        "{notes}"
    );
}

#[test]
fn dropped_frames_are_gaps_reported_by_the_firmware() {
    let mut bytes = stream(0..5);
    bytes.extend(dropped_bytes(5, 3));
    bytes.extend(stream(8..10));
    let r = record(&bytes);
    assert_eq!(
        r.gaps(),
        [Gap {
            first_seq: 5,
            count: 3,
            source: GapSource::Reported
        }]
    );
    let s = r.summary();
    assert_eq!((s.rows, s.gaps, s.lost_samples), (7, 1, 3));
    // No row is invented for the dropped Samples.
    let rec = r.recording("d.csv").unwrap();
    assert_eq!(rec.t_s, [0.0, 0.001, 0.002, 0.003, 0.004, 0.008, 0.009]);
    assert!(rec
        .meta
        .notes
        .unwrap()
        .contains("3 samples lost in 1 gaps (first_seq+count): 5+3 reported"));
}

#[test]
fn unreported_holes_are_gaps_detected_on_the_host() {
    let bytes = stream((0..3).chain(5..8).chain(20..21));
    let r = record(&bytes);
    assert_eq!(
        r.gaps(),
        [
            Gap {
                first_seq: 3,
                count: 2,
                source: GapSource::Detected
            },
            Gap {
                first_seq: 8,
                count: 12,
                source: GapSource::Detected
            }
        ]
    );
    assert_eq!(r.summary().lost_samples, 14);
    let notes = r.notes();
    assert!(
        notes.contains("14 samples lost in 2 gaps (first_seq+count): 3+2 detected, 8+12 detected"),
        "{notes}"
    );
}

#[test]
fn a_corrupted_frame_is_counted_and_its_sample_is_a_gap() {
    let frame_len = sample_bytes(&sample3(0, 0)).len();
    let mut bytes = stream(0..6);
    // One bit flipped in Sample 2's force: its CRC fails.
    bytes[2 * frame_len + 12] ^= 0x10;
    let r = record(&bytes);
    let s = r.summary();
    assert_eq!(s.rows, 5);
    assert_eq!(s.corrupt_bytes, frame_len as u64);
    assert_eq!(s.corrupt_runs, 1);
    assert_eq!(
        r.gaps(),
        [Gap {
            first_seq: 2,
            count: 1,
            source: GapSource::Detected
        }]
    );
    assert_eq!(r.times_s(), [0.0, 0.001, 0.003, 0.004, 0.005]);
    assert!(r
        .notes()
        .contains(&format!("{frame_len} corrupt bytes in 1 runs")));
}

#[test]
fn a_stream_cut_short_counts_the_partial_frame_as_corrupt() {
    let mut bytes = stream(0..4);
    bytes.truncate(bytes.len() - 5);
    let frame_len = sample_bytes(&sample3(0, 0)).len();
    let r = record(&bytes);
    assert_eq!(r.summary().rows, 3);
    assert_eq!(r.summary().corrupt_bytes, (frame_len - 5) as u64);
    // Before finish, the partial frame is only held back, not reported.
    let mut open = Recorder::new(setup());
    open.push_bytes(&bytes);
    assert_eq!(open.summary().corrupt_bytes, 0);
}

#[test]
fn faults_are_listed_with_sequence_time_and_segment() {
    let mut bytes = stream(0..3);
    bytes.extend(fault_bytes(&Fault {
        seq: 3,
        t_us: 3000,
        code: FaultCode::Overcurrent,
        segment: Some(1),
    }));
    bytes.extend(fault_bytes(&Fault {
        seq: 3,
        t_us: 3000,
        code: FaultCode::MissedDeadline,
        segment: None,
    }));
    bytes.extend(stream(3..5));
    let r = record(&bytes);
    assert_eq!(r.faults().len(), 2);
    assert_eq!(r.summary().faults, 2);
    assert_eq!(r.summary().rows, 5);
    assert!(r.gaps().is_empty(), "a Fault consumes no sequence number");
    let notes = r.notes();
    assert!(
        notes.contains(
            "2 faults: seq 3 t_us 3000 overcurrent on segment 2, seq 3 t_us 3000 missed deadline"
        ),
        "{notes}"
    );
}

#[test]
fn sequence_numbers_wrap_at_2_pow_32_without_a_gap() {
    let seqs = [u32::MAX - 2, u32::MAX - 1, u32::MAX, 0, 1, 2];
    let bytes: Vec<u8> = seqs
        .iter()
        .enumerate()
        .flat_map(|(k, &seq)| sample_bytes(&sample3(seq, 1000 * k as u32)))
        .collect();
    let r = record(&bytes);
    assert_eq!(r.summary().rows, 6);
    assert!(r.gaps().is_empty());
    assert!(r.restart().is_none());

    // A hole across the wrap is a gap of the right size.
    let bytes: Vec<u8> = [u32::MAX - 1, 1]
        .iter()
        .enumerate()
        .flat_map(|(k, &seq)| sample_bytes(&sample3(seq, 1000 * k as u32)))
        .collect();
    let r = record(&bytes);
    assert_eq!(
        r.gaps(),
        [Gap {
            first_seq: u32::MAX,
            count: 2,
            source: GapSource::Detected
        }]
    );
}

#[test]
fn the_firmware_clock_wrap_at_71_minutes_keeps_time_increasing() {
    // Start 1.5 ms before the 32-bit µs counter wraps, 1 ms apart.
    let start = u32::MAX - 1499;
    let bytes: Vec<u8> = (0..5u32)
        .flat_map(|k| sample_bytes(&sample3(k, start.wrapping_add(1000 * k))))
        .collect();
    let r = record(&bytes);
    let t = r.recording("wrap.csv").unwrap().t_s;
    assert_eq!(t.len(), 5);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "{t:?}");
    let expected_last_us = u64::from(start) + 4000;
    assert!(expected_last_us > WRAP_US);
    assert_eq!(t[4], expected_last_us as f64 / 1e6);
    assert!((t[4] - t[3] - 0.001).abs() < 1e-9);
}

#[test]
fn a_restart_stops_the_recording_and_is_reported() {
    let mut bytes = stream(100..105);
    bytes.extend(stream(0..3));
    let r = record(&bytes);
    assert_eq!(r.summary().rows, 5);
    assert_eq!(r.summary().after_restart, 3);
    assert_eq!(
        r.restart(),
        Some(Restart {
            expected_seq: 105,
            got_seq: 0
        })
    );
    assert!(r.gaps().is_empty(), "a restart loses nothing we can count");
    assert!(r
        .notes()
        .contains("firmware restarted (seq 0 after 104): 3 later samples not recorded"));
}

#[test]
fn samples_that_cannot_be_rows_are_refused_by_field_and_rule() {
    let mut bytes = stream(0..2);
    let mut hot = sample3(2, 2000);
    hot.voltages_v[1] = 4.5;
    bytes.extend(sample_bytes(&hot));
    let mut nan = sample3(3, 3000);
    nan.force_n = f32::NAN;
    bytes.extend(sample_bytes(&nan));
    let one = Sample::<1> {
        seq: 4,
        t_us: 4000,
        force_n: 0.0,
        flags: finrs_frames::SampleFlags::default(),
        voltages_v: [0.0],
        currents_a: [0.0],
    };
    bytes.extend(sample_bytes(&one));
    bytes.extend(sample_bytes(&sample3(5, 500)));
    bytes.extend(sample_bytes(&sample3(6, 1000)));
    bytes.extend(stream(7..8));
    let r = record(&bytes);
    let reasons: Vec<(u32, String)> = r
        .rejected()
        .iter()
        .map(|x| (x.seq, x.reason.to_string()))
        .collect();
    assert_eq!(
        reasons
            .iter()
            .map(|(seq, why)| (*seq, why.as_str()))
            .collect::<Vec<_>>(),
        [
            (2, "v2_V = 4.5 V is beyond the safe range of ±4 V"),
            (3, "force_N = NaN is not a finite number"),
            (4, "segment count 1 differs from the first Sample's 3"),
            (
                5,
                "t_us = 500 is before the previous Sample's 1000; time must increase"
            ),
            (
                6,
                "t_us = 1000 equals the previous Sample's; time must increase"
            ),
        ]
    );
    assert_eq!(r.summary().rejected, 5);
    assert_eq!(r.times_s(), [0.0, 0.001, 0.007]);
    assert!(r.gaps().is_empty(), "refused Samples are listed, not gaps");
    assert!(r.notes().contains("5 samples refused: seq 2 (v2_V = 4.5 V"));
    // The recording stays valid.
    r.recording("refused.csv").unwrap();
}

#[test]
fn the_written_file_reads_back_with_its_notes() {
    let mut bytes = stream(0..3);
    bytes.extend(dropped_bytes(3, 1));
    bytes.extend(stream(4..6));
    let r = record(&bytes);
    let rec = r.recording("x.csv").unwrap();
    let dir = std::env::temp_dir().join(format!("finrs-stream-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("log.csv");
    rec.write(&path).unwrap();
    let back = Recording::read(&path).unwrap();
    // Time and drive exactly; measured channels to the written resolution.
    assert_eq!(
        (&back.meta, &back.t_s, &back.v_v),
        (&rec.meta, &rec.t_s, &rec.v_v)
    );
    for ((bc, bv), (rc, rv)) in back.channels.iter().zip(&rec.channels) {
        assert_eq!(bc, rc);
        for (b, r) in bv.iter().zip(rv) {
            let (b, r) = (b.unwrap(), r.unwrap());
            assert!(
                (b - r).abs() <= crate::recording::max_written_error(r),
                "{r} read back as {b}"
            );
        }
    }
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("# fixture = \"blocked\""));
    assert!(text.contains("t_s,v1_V,v2_V,v3_V,i1_A,i2_A,i3_A,force_N\n"));
    assert!(text.contains("3+1 reported"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_stream_without_samples_is_refused_clearly() {
    let r = record(b"no frames here");
    assert_eq!(r.summary().corrupt_bytes, 14);
    let e = r.recording("empty.csv").unwrap_err().to_string();
    assert!(e.contains("no valid Sample frame"), "{e}");
}

/// One piece of a test stream.
#[derive(Clone, Debug)]
enum Piece {
    Sample,
    Skip(u32),
    Dropped(u32),
    Garbage(Vec<u8>),
    FlipBit(usize),
    Fault,
}

fn piece() -> impl Strategy<Value = Piece> {
    prop_oneof![
        6 => Just(Piece::Sample),
        1 => (1u32..5).prop_map(Piece::Skip),
        1 => (1u32..5).prop_map(Piece::Dropped),
        1 => prop::collection::vec(any::<u8>(), 1..40).prop_map(Piece::Garbage),
        1 => (0usize..40).prop_map(Piece::FlipBit),
        1 => Just(Piece::Fault),
    ]
}

/// The stream the pieces make, and the intact Samples encoded in it, as
/// (time s, force N) on the host's unwrapped clock.
fn build(pieces: &[Piece], start_seq: u32, start_us: u32) -> (Vec<u8>, Vec<(f64, f64)>) {
    let (mut seq, mut bytes, mut encoded) = (start_seq, Vec::new(), Vec::new());
    let mut clock = Clock::new();
    for p in pieces {
        match p {
            Piece::Sample | Piece::FlipBit(_) => {
                let t_us = start_us.wrapping_add(seq.wrapping_sub(start_seq).wrapping_mul(250));
                let s = sample3(seq, t_us);
                let mut b = sample_bytes(&s);
                if let Piece::FlipBit(i) = p {
                    let i = i % b.len();
                    b[i] ^= 0x01;
                } else {
                    // The host's clock sees only intact Samples (CRC-16
                    // catches every single-bit flip): a wrap the damaged
                    // ones crossed before the first intact one is unseen.
                    encoded.push((
                        clock.unwrap(t_us).unwrap() as f64 / 1e6,
                        f64::from(s.force_n),
                    ));
                }
                bytes.extend(b);
                seq = seq.wrapping_add(1);
            }
            Piece::Skip(n) => seq = seq.wrapping_add(*n),
            Piece::Dropped(n) => {
                bytes.extend(dropped_bytes(seq, *n));
                seq = seq.wrapping_add(*n);
            }
            Piece::Garbage(g) => bytes.extend(g),
            Piece::Fault => bytes.extend(fault_bytes(&Fault {
                seq,
                t_us: 0,
                code: FaultCode::Other,
                segment: None,
            })),
        }
    }
    (bytes, encoded)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_never_panic_and_rows_stay_increasing(
        bytes in prop::collection::vec(any::<u8>(), 0..2000),
    ) {
        let r = record(&bytes);
        prop_assert!(r.times_s().windows(2).all(|w| w[1] > w[0]));
        let s = r.summary();
        prop_assert!(s.corrupt_bytes <= bytes.len() as u64);
        let _ = r.notes();
        let _ = r.recording("arbitrary.csv");
    }

    #[test]
    fn every_row_is_an_encoded_sample_and_every_loss_is_counted(
        pieces in prop::collection::vec(piece(), 1..80),
        start_seq in prop_oneof![Just(u32::MAX - 20), any::<u32>()],
        start_us in prop_oneof![Just(u32::MAX - 5000), any::<u32>()],
        cut in 1usize..64,
    ) {
        let (bytes, encoded) = build(&pieces, start_seq, start_us);
        // Split into chunks of `cut` bytes: the result must not depend on it.
        let mut chunked = Recorder::new(setup());
        for c in bytes.chunks(cut) {
            chunked.push_bytes(c);
        }
        chunked.finish();
        let whole = record(&bytes);
        prop_assert_eq!(chunked.times_s(), whole.times_s());
        prop_assert_eq!(chunked.gaps(), whole.gaps());
        prop_assert_eq!(chunked.summary(), whole.summary());

        let t = whole.times_s();
        prop_assert!(t.windows(2).all(|w| w[1] > w[0]));
        if let Ok(rec) = whole.recording("p.csv") {
            for (t, f) in rec.t_s.iter().zip(force_column(&rec)) {
                prop_assert!(
                    encoded.iter().any(|&(et, ef)| et == *t && ef == f),
                    "row at {} s with {} N was never encoded", t, f
                );
            }
        }
        // Every encoded Sample is a row, or inside a gap (reported or
        // detected), or refused: none vanishes unaccounted.
        let s = whole.summary();
        let intact = pieces.iter().filter(|p| matches!(p, Piece::Sample)).count() as u64;
        let damaged = pieces.iter().filter(|p| matches!(p, Piece::FlipBit(_))).count() as u64;
        let skipped: u64 = pieces.iter().map(|p| match p {
            Piece::Skip(n) | Piece::Dropped(n) => u64::from(*n),
            _ => 0,
        }).sum();
        // Damage or garbage never hides an intact Sample.
        prop_assert_eq!(s.rows, intact);
        prop_assert_eq!(s.rejected, 0);
        // Losses come only from skipped numbers and damaged frames.
        prop_assert!(s.lost_samples <= skipped + damaged);
        let faults = pieces.iter().filter(|p| matches!(p, Piece::Fault)).count() as u64;
        prop_assert!(s.faults >= faults);
        if damaged == 0 && !pieces.iter().any(|p| matches!(p, Piece::Garbage(_))) {
            prop_assert_eq!(s.faults, faults);
            prop_assert_eq!(s.corrupt_bytes, 0);
        }
    }
}

fn info_bytes(max_abs_v: f32) -> Vec<u8> {
    let info = finrs_frames::Info {
        version: [0, 1, 0],
        git_hash: 0xdead_beef,
        segments: 3,
        dac_segments: [None, Some(2)],
        sample_hz: 1000,
        calibration: finrs_frames::Calibration {
            newtons_per_count: 2.5e-5,
            current_zero_counts: [2048, 2050, 2046, 2048, 2048, 2048, 2048, 2048],
        },
        amps_per_count: 2.5e-4,
        max_abs_v,
        slew_v_per_s: 200.0,
        bridge_supply_v: 5.0,
        overcurrent_a: 0.4,
        calibration_origin: finrs_frames::CalibrationOrigin::Stored,
        reset_cause: finrs_frames::ResetCause::Watchdog,
        model_crc: None,
    };
    let mut buf = [0u8; finrs_frames::INFO_FRAME_LEN];
    let n = finrs_frames::encode_info(&info, &mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn the_firmwares_info_goes_into_the_notes_once_per_configuration() {
    let mut bytes = info_bytes(4.0);
    bytes.extend(stream(0..5));
    // Sent again on request: the same set-up is not repeated.
    bytes.extend(info_bytes(4.0));
    bytes.extend(stream(5..8));
    // The limit lowered mid-recording: a new configuration, noted.
    bytes.extend(info_bytes(1.5));
    bytes.extend(stream(8..10));
    let r = record(&bytes);
    assert_eq!(r.infos().len(), 2);
    let rec = r.recording("info.csv").unwrap();
    assert_eq!(rec.t_s.len(), 10, "an Info takes no row");
    assert!(r.gaps().is_empty(), "nor a sequence number");
    let notes = rec.meta.notes.unwrap();
    assert!(
        notes.contains(
            "10 samples; firmware 0.1.0 (git deadbeef), 3 segments (DAC on segment 3), 1000 Hz, limit 4 V, slew 200 V/s, bridge supply 5 V, overcurrent 0.4 A, load cell 2.5e-5 N/count, shunts 2.5e-4 A/count from zeros of 2048/2050/2046 counts (calibration: stored in flash), reset cause watchdog, configuration CRC "
        ),
        "{notes}"
    );
    assert!(notes.contains("; then firmware 0.1.0 (git deadbeef), 3 segments (DAC on segment 3), 1000 Hz, limit 1.5 V"), "{notes}");
}

#[test]
fn the_samples_flags_are_counted_in_the_notes() {
    use finrs_frames::SampleFlags as F;
    let bytes: Vec<u8> = (0..6u32)
        .flat_map(|seq| {
            let mut s = sample3(seq, seq * 1000);
            s.flags = F(match seq {
                0 | 1 => F::TARING,
                2 => F::RUNNING | F::SLEWED,
                3 | 4 => F::RUNNING | F::LIMITED,
                _ => F::FAULT,
            });
            sample_bytes(&s)
        })
        .collect();
    let r = record(&bytes);
    let s = r.summary();
    assert_eq!((s.taring, s.slewed, s.limited, s.faulted), (2, 1, 2, 1));
    let notes = r.recording("flags.csv").unwrap().meta.notes.unwrap();
    assert!(
        notes.contains("; the firmware's limiter clamped 2 samples to the voltage limit and slew-limited 1; 2 samples during a tare; 1 samples with a fault latched"),
        "{notes}"
    );
}
