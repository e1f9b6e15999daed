//! Streams: sequence tracking (Dropped reports, gaps), corruption and
//! resynchronisation, truncation.

mod common;

use common::*;
use finrs_frames::{Dropped, Fault, FaultCode, DROPPED_FRAME_LEN};

fn s3(seq: u32) -> Vec<u8> {
    sample_frame(&sample::<3>(seq))
}

fn k3(seq: u32) -> Key {
    sample_key(&sample::<3>(seq))
}

fn dropped(first_seq: u32, count: u32) -> Dropped {
    Dropped { first_seq, count }
}

#[test]
fn a_dropped_report_covers_its_numbers() {
    let stream = [s3(0), s3(1), dropped_frame(&dropped(2, 3)), s3(5), s3(6)].concat();
    let (keys, stats) = decode(&stream);
    assert_eq!(
        keys,
        [k3(0), k3(1), Key::Dropped(dropped(2, 3)), k3(5), k3(6)]
    );
    assert_eq!(stats.samples, 4);
    assert_eq!(stats.dropped_reported, 3);
    assert_eq!(stats.gaps_unreported, 0);
    assert_eq!(stats.corrupt_bytes, 0);
}

#[test]
fn silently_missing_frames_are_a_gap() {
    let stream = [s3(0), s3(1), s3(4), s3(5)].concat();
    let (keys, stats) = decode(&stream);
    let gap = Key::Gap {
        expected_seq: 2,
        got_seq: 4,
    };
    assert_eq!(keys, [k3(0), k3(1), gap, k3(4), k3(5)]);
    assert_eq!(stats.samples, 4);
    assert_eq!(stats.gaps_unreported, 2);
    assert_eq!(stats.dropped_reported, 0);
}

#[test]
fn a_hole_only_partly_reported_is_a_gap_for_the_rest() {
    // Reported 1, then 2 and 3 missing without a word.
    let stream = [s3(0), dropped_frame(&dropped(1, 1)), s3(4)].concat();
    let (keys, stats) = decode(&stream);
    let gap = Key::Gap {
        expected_seq: 2,
        got_seq: 4,
    };
    assert_eq!(keys, [k3(0), Key::Dropped(dropped(1, 1)), gap, k3(4)]);
    assert_eq!((stats.dropped_reported, stats.gaps_unreported), (1, 2));

    // 1 and 2 missing without a word, then 3 and 4 reported.
    let stream = [s3(0), dropped_frame(&dropped(3, 2)), s3(5)].concat();
    let (keys, stats) = decode(&stream);
    let gap = Key::Gap {
        expected_seq: 1,
        got_seq: 3,
    };
    assert_eq!(keys, [k3(0), gap, Key::Dropped(dropped(3, 2)), k3(5)]);
    assert_eq!((stats.dropped_reported, stats.gaps_unreported), (2, 2));
}

#[test]
fn numbers_wrap_and_a_restart_is_a_gap_that_loses_nothing() {
    let (keys, stats) = decode(&[s3(u32::MAX), s3(0)].concat());
    assert_eq!(keys, [k3(u32::MAX), k3(0)]);
    assert_eq!(stats.gaps_unreported, 0);

    let (keys, stats) = decode(&[s3(10), s3(0)].concat());
    let gap = Key::Gap {
        expected_seq: 11,
        got_seq: 0,
    };
    assert_eq!(keys, [k3(10), gap, k3(0)]);
    assert_eq!(stats.gaps_unreported, 0);
}

#[test]
fn faults_take_no_sequence_number() {
    let fault = Fault {
        seq: 1,
        t_us: 1_500,
        code: FaultCode::Overcurrent,
        segment: Some(2),
    };
    let (keys, stats) = decode(&[s3(0), fault_frame(&fault), s3(1)].concat());
    assert_eq!(keys, [k3(0), Key::Fault(fault), k3(1)]);
    assert_eq!((stats.faults, stats.gaps_unreported), (1, 0));
}

#[test]
fn a_flipped_bit_costs_its_frame_only() {
    let (a, b, c) = (s3(0), s3(1), s3(2));
    for i in 0..b.len() {
        for bit in 0..8 {
            let mut bad = b.clone();
            bad[i] ^= 1 << bit;
            let (keys, stats) = decode(&[a.clone(), bad, c.clone()].concat());
            let expected = [
                k3(0),
                Key::Corrupt {
                    skipped_bytes: b.len(),
                },
                Key::Gap {
                    expected_seq: 1,
                    got_seq: 2,
                },
                k3(2),
            ];
            assert_eq!(keys, expected, "byte {i} bit {bit}");
            assert_eq!(stats.corrupt_bytes, b.len() as u64);
            assert_eq!(stats.samples, 2);
        }
    }
}

#[test]
fn a_flipped_byte_in_a_dropped_report_makes_its_numbers_a_gap() {
    let mut bad = dropped_frame(&dropped(1, 2));
    bad[6] ^= 0xFF;
    let (keys, stats) = decode(&[s3(0), bad, s3(3)].concat());
    let expected = [
        k3(0),
        Key::Corrupt {
            skipped_bytes: DROPPED_FRAME_LEN,
        },
        Key::Gap {
            expected_seq: 1,
            got_seq: 3,
        },
        k3(3),
    ];
    assert_eq!(keys, expected);
    assert_eq!((stats.dropped_reported, stats.gaps_unreported), (0, 2));
}

#[test]
fn a_false_header_does_not_swallow_the_frames_it_claims() {
    // A valid Sample header claiming 76 bytes of payload, then short frames
    // that lie inside that length: the CRC fails, and decoding resumes one
    // byte after the false sync.
    let junk = [0xF1, 0x5E, 0x01, 76];
    let d = dropped(7, 1);
    let body = [dropped_frame(&d), sample_frame(&sample::<1>(8))].concat();
    assert!(junk.len() + body.len() < finrs_frames::MAX_FRAME_LEN);
    let expected = [
        Key::Corrupt { skipped_bytes: 4 },
        Key::Dropped(d),
        sample_key(&sample::<1>(8)),
    ];

    // The stream ends inside the claimed length: finish resolves it.
    let (keys, _) = decode(&[&junk[..], &body].concat());
    assert_eq!(keys, expected);

    // More follows, enough to fill the claimed length: the CRC fails.
    let (keys, _) = decode(&[&junk[..], &body, &s3(9), &s3(10)].concat());
    assert_eq!(keys[..3], expected);
    assert_eq!(keys[3..], [k3(9), k3(10)]);

    // Sync bytes repeated or misplaced before a frame.
    for junk in [
        &[0xF1][..],
        &[0xF1, 0xF1],
        &[0x5E, 0xF1],
        &[0xF1, 0x5E],
        &[0xF1, 0x5E, 0xF1],
    ] {
        let (keys, _) = decode(&[junk, &s3(0)].concat());
        let skipped_bytes = junk.len();
        assert_eq!(keys, [Key::Corrupt { skipped_bytes }, k3(0)], "{junk:02X?}");
    }
}

/// Three frames of different lengths and where each starts.
fn three_frames() -> (Vec<u8>, [usize; 4], [Key; 3]) {
    let frames = [
        sample_frame(&sample::<1>(0)),
        sample_frame(&sample::<8>(1)),
        sample_frame(&sample::<3>(2)),
    ];
    let keys = [
        sample_key(&sample::<1>(0)),
        sample_key(&sample::<8>(1)),
        sample_key(&sample::<3>(2)),
    ];
    let mut starts = [0; 4];
    for i in 0..3 {
        starts[i + 1] = starts[i] + frames[i].len();
    }
    (frames.concat(), starts, keys)
}

#[test]
fn a_stream_cut_short_anywhere_loses_only_the_cut_frame() {
    let (stream, starts, all) = three_frames();
    for cut in 0..=stream.len() {
        let (keys, stats) = decode(&stream[..cut]);
        let complete = starts[1..].iter().filter(|&&end| end <= cut).count();
        let mut expected = all[..complete].to_vec();
        let partial = cut - starts[complete];
        if partial > 0 {
            expected.push(Key::Corrupt {
                skipped_bytes: partial,
            });
        }
        assert_eq!(keys, expected, "cut at {cut}");
        assert_eq!(stats.samples, complete as u64);
        assert_eq!(stats.corrupt_bytes, partial as u64);
    }
}

#[test]
fn a_stream_joined_anywhere_recovers_at_the_next_frame() {
    let (stream, starts, all) = three_frames();
    for cut in 0..=stream.len() {
        let (keys, stats) = decode(&stream[cut..]);
        let first = starts.iter().position(|&s| s >= cut).unwrap();
        let mut expected = Vec::new();
        if starts[first] > cut {
            expected.push(Key::Corrupt {
                skipped_bytes: starts[first] - cut,
            });
        }
        expected.extend_from_slice(&all[first.min(3)..]);
        assert_eq!(keys, expected, "joined at {cut}");
        assert_eq!(stats.samples, (3 - first.min(3)) as u64);
    }
}

#[test]
fn finish_leaves_the_decoder_ready_for_more() {
    let mut decoder = finrs_frames::Decoder::new();
    let mut n = 0;
    decoder.finish(&mut |_| n += 1);
    assert_eq!(n, 0, "nothing to report");
    let mut keys = Vec::new();
    decoder.push(&s3(0)[..10], &mut |e| keys.push(key(&e)));
    decoder.finish(&mut |e| keys.push(key(&e)));
    decoder.push(&[s3(1), s3(2)].concat(), &mut |e| keys.push(key(&e)));
    decoder.finish(&mut |e| keys.push(key(&e)));
    assert_eq!(keys, [Key::Corrupt { skipped_bytes: 10 }, k3(1), k3(2)]);
    assert_eq!(decoder.stats().samples, 2);
}
