//! Properties over random streams: no panic, chunking does not matter,
//! every byte is accounted for, corruption never invents a sample and never
//! costs an undamaged frame.

mod common;

use std::collections::HashSet;

use common::*;
use finrs_frames::{DecodedSample, Dropped, Event, Fault, FaultCode, MAX_SEGMENTS};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::RngSeed;

fn any_f32() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits)
}

fn any_sample() -> impl Strategy<Value = DecodedSample> {
    (
        1..=MAX_SEGMENTS,
        any::<u32>(),
        any::<u32>(),
        any_f32(),
        any::<u8>(),
        prop::array::uniform8(any_f32()),
        prop::array::uniform8(any_f32()),
    )
        .prop_map(
            |(n, seq, t_us, force_n, flags, mut voltages_v, mut currents_a)| {
                // The decoder zeroes the unused entries.
                voltages_v[n..].fill(0.0);
                currents_a[n..].fill(0.0);
                DecodedSample {
                    seq,
                    t_us,
                    force_n,
                    flags: finrs_frames::SampleFlags(flags),
                    n,
                    voltages_v,
                    currents_a,
                }
            },
        )
}

fn any_item() -> impl Strategy<Value = Event> {
    let dropped = (any::<u32>(), any::<u32>())
        .prop_map(|(first_seq, count)| Event::Dropped(Dropped { first_seq, count }));
    let segment = prop_oneof![Just(None), (0..MAX_SEGMENTS as u8).prop_map(Some)];
    let fault =
        (any::<u32>(), any::<u32>(), 1u8..=4, segment).prop_map(|(seq, t_us, c, segment)| {
            Event::Fault(Fault {
                seq,
                t_us,
                code: FaultCode::from_u8(c).unwrap(),
                segment,
            })
        });
    prop_oneof![3 => any_sample().prop_map(Event::Sample), 1 => dropped, 1 => fault]
}

/// Bytes that hit the sync pattern often enough to exercise false headers.
fn junk_byte() -> impl Strategy<Value = u8> {
    prop_oneof![4 => any::<u8>(), 1 => Just(0xF1), 1 => Just(0x5E), 1 => 1u8..=3]
}

#[derive(Clone, Debug)]
enum Damage {
    None,
    Flip { at: Index, xor: u8 },
    Cut { keep: Index },
    Insert { at: Index, bytes: Vec<u8> },
}

fn any_damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        6 => Just(Damage::None),
        2 => (any::<Index>(), 1u8..=255).prop_map(|(at, xor)| Damage::Flip { at, xor }),
        1 => any::<Index>().prop_map(|keep| Damage::Cut { keep }),
        1 => (any::<Index>(), prop::collection::vec(junk_byte(), 1..5))
            .prop_map(|(at, bytes)| Damage::Insert { at, bytes }),
    ]
}

fn any_junk() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![4 => Just(Vec::new()), 1 => prop::collection::vec(junk_byte(), 1..12)]
}

fn any_chunks() -> impl Strategy<Value = Vec<usize>> {
    prop::collection::vec(1usize..=100, 1..20)
}

/// What holds for the events of any stream, whatever it contains.
fn check_any_stream(stream: &[u8], chunks: &[usize]) -> Result<Vec<Key>, TestCaseError> {
    let (keys, stats) = decode(stream);
    prop_assert_eq!(&decode_chunked(stream, &[1]).0, &keys, "byte by byte");
    prop_assert_eq!(
        &decode_chunked(stream, chunks).0,
        &keys,
        "in chunks {:?}",
        chunks
    );
    prop_assert_eq!(stats, stats_of(&keys));
    // Every byte is part of a decoded frame or reported skipped.
    let frame_bytes: usize = keys.iter().map(frame_bytes).sum();
    prop_assert_eq!(frame_bytes + stats.corrupt_bytes as usize, stream.len());
    for pair in keys.windows(2) {
        let coalesced = !matches!(pair, [Key::Corrupt { .. }, Key::Corrupt { .. }]);
        prop_assert!(coalesced, "Corrupt events are coalesced: {:?}", pair);
        if let Key::Gap { got_seq, .. } = pair[0] {
            let seq = match pair[1] {
                Key::Sample { seq, .. } => Some(seq),
                Key::Dropped(d) => Some(d.first_seq),
                _ => None,
            };
            prop_assert_eq!(seq, Some(got_seq), "a Gap announces its frame");
        }
    }
    Ok(keys)
}

proptest! {
    #[test]
    fn arbitrary_bytes(
        stream in prop::collection::vec(junk_byte(), 0..600),
        chunks in any_chunks(),
    ) {
        check_any_stream(&stream, &chunks)?;
    }

    #[test]
    fn clean_streams_decode_exactly(
        items in prop::collection::vec(any_item(), 0..20),
        chunks in any_chunks(),
    ) {
        let stream: Vec<u8> = items.iter().flat_map(event_frame).collect();
        let keys = check_any_stream(&stream, &chunks)?;
        let corrupt = keys.iter().any(|k| matches!(k, Key::Corrupt { .. }));
        prop_assert!(!corrupt, "a clean stream has nothing to skip");
        prop_assert_eq!(frames_only(&keys), items.iter().map(key).collect::<Vec<_>>());
    }
}

proptest! {
    // A damaged frame passes CRC-16 with probability about 2^-16 (a cut or
    // an insertion moves the CRC; a flip is always caught). Over the many
    // damaged frames of a run that is a real chance, so this property runs
    // on a fixed seed: a failure is then a decoder bug, not bad luck. Nor
    // are failures saved, lest a collision met in a longer run
    // (PROPTEST_CASES) fail every later run.
    #![proptest_config(ProptestConfig {
        rng_seed: RngSeed::Fixed(0x5EF1_F15E),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn damaged_streams_lose_only_damaged_frames(
        frames in prop::collection::vec((any_item(), any_damage(), any_junk()), 0..20),
        chunks in any_chunks(),
    ) {
        let (mut stream, mut intact, mut encoded) = (Vec::new(), Vec::new(), HashSet::new());
        for (item, damage, junk) in &frames {
            stream.extend_from_slice(junk);
            let frame = event_frame(item);
            if let Event::Sample(_) = item {
                encoded.insert(key(item));
            }
            let mut f = frame.clone();
            match damage {
                Damage::None => {}
                Damage::Flip { at, xor } => {
                    let at = at.index(f.len());
                    f[at] ^= xor;
                }
                Damage::Cut { keep } => f.truncate(keep.index(f.len())),
                Damage::Insert { at, bytes } => {
                    let at = 1 + at.index(f.len() - 1);
                    f.splice(at..at, bytes.iter().copied());
                }
            }
            // An insertion can leave the whole frame after a bit of junk
            // (a sync byte inserted after the first one, say).
            if f.windows(frame.len()).any(|w| w == frame) {
                intact.push(key(item));
            }
            stream.extend(f);
        }
        let keys = check_any_stream(&stream, &chunks)?;
        for k in keys.iter().filter(|k| matches!(k, Key::Sample { .. })) {
            prop_assert!(encoded.contains(k), "invented sample {:?}", k);
        }
        prop_assert_eq!(frames_only(&keys), intact);
    }
}
