//! Helpers shared by the tests: encoding to `Vec`s, decoding whole streams,
//! and comparing events bit for bit (NaN payloads and signed zeros included).
#![allow(dead_code)] // each test binary uses a different subset

use finrs_frames::{
    encode_dropped, encode_fault, encode_sample, frame_len, DecodedSample, Decoder, Dropped, Event,
    Fault, Sample, SampleFlags, Stats, DROPPED_FRAME_LEN, FAULT_FRAME_LEN, MAX_FRAME_LEN,
};

pub fn sample_frame<const N: usize>(s: &Sample<N>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let len = encode_sample(s, &mut buf).unwrap();
    buf[..len].to_vec()
}

pub fn dropped_frame(d: &Dropped) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let len = encode_dropped(d, &mut buf).unwrap();
    buf[..len].to_vec()
}

pub fn fault_frame(f: &Fault) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let len = encode_fault(f, &mut buf).unwrap();
    buf[..len].to_vec()
}

/// Encodes a sample whose segment count is known only at run time.
pub fn decoded_sample_frame(d: &DecodedSample) -> Vec<u8> {
    fn with_n<const N: usize>(d: &DecodedSample) -> Vec<u8> {
        sample_frame(&Sample::<N> {
            seq: d.seq,
            t_us: d.t_us,
            force_n: d.force_n,
            flags: d.flags,
            voltages_v: d.voltages_v[..N].try_into().unwrap(),
            currents_a: d.currents_a[..N].try_into().unwrap(),
        })
    }
    match d.n {
        1 => with_n::<1>(d),
        2 => with_n::<2>(d),
        3 => with_n::<3>(d),
        4 => with_n::<4>(d),
        5 => with_n::<5>(d),
        6 => with_n::<6>(d),
        7 => with_n::<7>(d),
        8 => with_n::<8>(d),
        n => panic!("{n} segments"),
    }
}

/// The frame that carries a Sample, Dropped or Fault event.
pub fn event_frame(e: &Event) -> Vec<u8> {
    match e {
        Event::Sample(s) => decoded_sample_frame(s),
        Event::Dropped(d) => dropped_frame(d),
        Event::Fault(f) => fault_frame(f),
        other => panic!("{other:?} has no frame"),
    }
}

/// Length of the frame an event was decoded from (0 for Gap and Corrupt).
pub fn frame_bytes(k: &Key) -> usize {
    match k {
        Key::Sample { n, .. } => frame_len(*n),
        Key::Dropped(_) => DROPPED_FRAME_LEN,
        Key::Fault(_) => FAULT_FRAME_LEN,
        Key::Info(_) => finrs_frames::INFO_FRAME_LEN,
        Key::Tracking { n, .. } => finrs_frames::tracking_frame_len(*n),
        Key::Gap { .. } | Key::Corrupt { .. } => 0,
    }
}

/// A sample with distinct, exactly representable values derived from `seq`.
pub fn sample<const N: usize>(seq: u32) -> Sample<N> {
    let x = seq as f32;
    Sample {
        seq,
        t_us: seq.wrapping_mul(1_000).wrapping_add(17),
        force_n: 0.001 * x + 0.5,
        flags: SampleFlags((seq % 32) as u8),
        voltages_v: core::array::from_fn(|k| k as f32 - 0.25 * x),
        currents_a: core::array::from_fn(|k| -0.001 * (k as f32 + 1.0) + x),
    }
}

/// An event compared bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    Sample {
        seq: u32,
        t_us: u32,
        force: u32,
        flags: u8,
        n: usize,
        voltages: [u32; 8],
        currents: [u32; 8],
    },
    Dropped(Dropped),
    Fault(Fault),
    /// The Info frame's bytes, as encoded.
    Info([u8; finrs_frames::INFO_FRAME_LEN]),
    /// The Tracking frame, its floats as bits.
    Tracking {
        t_us: u32,
        flags: u8,
        n: usize,
        gains: [u32; 8],
        phases: [u32; 8],
    },
    Gap {
        expected_seq: u32,
        got_seq: u32,
    },
    Corrupt {
        skipped_bytes: usize,
    },
}

pub fn key(e: &Event) -> Key {
    match *e {
        Event::Sample(s) => Key::Sample {
            seq: s.seq,
            t_us: s.t_us,
            force: s.force_n.to_bits(),
            flags: s.flags.0,
            n: s.n,
            voltages: s.voltages_v.map(f32::to_bits),
            currents: s.currents_a.map(f32::to_bits),
        },
        Event::Dropped(d) => Key::Dropped(d),
        Event::Fault(f) => Key::Fault(f),
        Event::Info(i) => {
            let mut frame = [0u8; finrs_frames::INFO_FRAME_LEN];
            finrs_frames::encode_info(&i, &mut frame).unwrap();
            Key::Info(frame)
        }
        Event::Tracking(t) => Key::Tracking {
            t_us: t.t_us,
            flags: t.flags.0,
            n: t.n,
            gains: t.gains.map(f32::to_bits),
            phases: t.phases_deg.map(f32::to_bits),
        },
        Event::Gap {
            expected_seq,
            got_seq,
        } => Key::Gap {
            expected_seq,
            got_seq,
        },
        Event::Corrupt { skipped_bytes } => Key::Corrupt { skipped_bytes },
    }
}

pub fn sample_key<const N: usize>(s: &Sample<N>) -> Key {
    key(&Event::Sample(DecodedSample::from(s)))
}

/// Decodes `stream` pushed in chunks of the given sizes (cycled; the whole
/// stream at once if empty), then finishes it.
pub fn decode_chunked(stream: &[u8], chunks: &[usize]) -> (Vec<Key>, Stats) {
    let mut decoder = Decoder::new();
    let mut keys = Vec::new();
    let mut out = |e: Event| keys.push(key(&e));
    let mut rest = stream;
    let mut sizes = chunks.iter().cycle();
    while !rest.is_empty() {
        let n = sizes.next().map_or(rest.len(), |&n| n.clamp(1, rest.len()));
        decoder.push(&rest[..n], &mut out);
        rest = &rest[n..];
    }
    decoder.finish(&mut out);
    (keys, decoder.stats())
}

pub fn decode(stream: &[u8]) -> (Vec<Key>, Stats) {
    decode_chunked(stream, &[])
}

/// The Sample, Dropped and Fault events only.
pub fn frames_only(keys: &[Key]) -> Vec<Key> {
    keys.iter()
        .copied()
        .filter(|k| !matches!(k, Key::Gap { .. } | Key::Corrupt { .. }))
        .collect()
}

/// The totals the decoder should report for these events.
pub fn stats_of(keys: &[Key]) -> Stats {
    let mut s = Stats::default();
    for k in keys {
        match k {
            Key::Sample { .. } => s.samples += 1,
            Key::Dropped(d) => s.dropped_reported += u64::from(d.count),
            Key::Fault(_) => s.faults += 1,
            Key::Info(_) => s.infos += 1,
            Key::Tracking { .. } => {}
            Key::Gap {
                expected_seq,
                got_seq,
            } => {
                let ahead = got_seq.wrapping_sub(*expected_seq);
                if ahead < 1 << 31 {
                    s.gaps_unreported += u64::from(ahead);
                }
            }
            Key::Corrupt { skipped_bytes } => s.corrupt_bytes += *skipped_bytes as u64,
        }
    }
    s
}
