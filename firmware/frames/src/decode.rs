//! The streaming decoder: bytes in, in any chunks; events out.

use crate::info::parse_info;
use crate::{
    crc16, payload_len_ok, Dropped, Fault, FaultCode, Info, Sample, SampleFlags, CRC_LEN,
    HEADER_LEN, KIND_DROPPED, KIND_FAULT, KIND_INFO, KIND_SAMPLE, KIND_TRACKING, MAX_FRAME_LEN,
    MAX_SEGMENTS, NO_SEGMENT, SAMPLE_FIXED_LEN, SYNC,
};

/// A decoded Sample; its segment count is known only at run time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecodedSample {
    /// Sequence number.
    pub seq: u32,
    /// Time since start, µs.
    pub t_us: u32,
    /// Blocking force on the load cell, N.
    pub force_n: f32,
    /// What the firmware was doing.
    pub flags: SampleFlags,
    /// Segment count, 1..=8.
    pub n: usize,
    /// Segment voltages as commanded, V; entries from `n` on are zero.
    pub voltages_v: [f32; MAX_SEGMENTS],
    /// Segment currents, A; entries from `n` on are zero.
    pub currents_a: [f32; MAX_SEGMENTS],
}

impl DecodedSample {
    /// The `n` segment voltages, V.
    pub fn voltages(&self) -> &[f32] {
        &self.voltages_v[..self.n.min(MAX_SEGMENTS)]
    }

    /// The `n` segment currents, A.
    pub fn currents(&self) -> &[f32] {
        &self.currents_a[..self.n.min(MAX_SEGMENTS)]
    }
}

impl<const N: usize> From<&Sample<N>> for DecodedSample {
    /// The sample as the decoder would return it.
    fn from(s: &Sample<N>) -> Self {
        const { assert!(N >= 1 && N <= MAX_SEGMENTS, "a Sample has 1..=8 segments") };
        let mut d = Self {
            seq: s.seq,
            t_us: s.t_us,
            force_n: s.force_n,
            flags: s.flags,
            n: N,
            voltages_v: [0.0; MAX_SEGMENTS],
            currents_a: [0.0; MAX_SEGMENTS],
        };
        d.voltages_v[..N].copy_from_slice(&s.voltages_v);
        d.currents_a[..N].copy_from_slice(&s.currents_a);
        d
    }
}

/// What the decoder found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A Sample frame whose CRC checked.
    Sample(DecodedSample),
    /// The firmware reports Samples it could not send.
    Dropped(Dropped),
    /// The firmware reports a fault.
    Fault(Fault),
    /// The firmware says what it is and how it is set up.
    Info(Info),
    /// The gain tracker's correction of a shaped motion.
    Tracking(crate::Tracking),
    /// Sequence numbers jumped from `expected_seq` to `got_seq` without a
    /// Dropped report covering them; reported before the Sample or Dropped
    /// frame that carries `got_seq`. A `got_seq` behind `expected_seq` (in
    /// wrapping order) means the numbering restarted, e.g. after a reset.
    Gap {
        /// The sequence number that should have come next.
        expected_seq: u32,
        /// The one that came.
        got_seq: u32,
    },
    /// Bytes were discarded: no sync, bad kind, bad length, bad CRC or bad
    /// content, or a frame cut short by the end of the stream.
    Corrupt {
        /// How many bytes, since the previous event.
        skipped_bytes: usize,
    },
}

/// Running totals, updated as events are emitted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Sample events.
    pub samples: u64,
    /// Samples reported dropped by Dropped frames (sum of their counts).
    pub dropped_reported: u64,
    /// Sequence numbers skipped by forward Gaps (a restart adds none).
    pub gaps_unreported: u64,
    /// Bytes discarded (sum of Corrupt events).
    pub corrupt_bytes: u64,
    /// Fault events.
    pub faults: u64,
    /// Info events.
    pub infos: u64,
}

/// Streaming decoder: [`push`](Self::push) bytes as they arrive, in chunks
/// of any size, and [`finish`](Self::finish) at the end of the stream.
///
/// It holds at most one frame's worth of bytes and never allocates or panics.
#[derive(Clone, Debug)]
pub struct Decoder {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    /// Bytes discarded and not yet reported.
    skipped: usize,
    /// The sequence number the next Sample should carry, once one is known.
    next_seq: Option<u32>,
    stats: Stats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

/// What the front of the buffer holds.
enum Step {
    /// Possibly the start of a frame; more bytes will tell.
    NeedMore,
    /// This many bytes are not the start of a valid frame.
    Skip(usize),
    /// A valid frame of this length.
    Frame(usize, Event),
}

impl Decoder {
    /// A decoder at the start of a stream.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            skipped: 0,
            next_seq: None,
            stats: Stats {
                samples: 0,
                dropped_reported: 0,
                gaps_unreported: 0,
                corrupt_bytes: 0,
                faults: 0,
                infos: 0,
            },
        }
    }

    /// The totals so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Decodes `bytes`, the next part of the stream, calling `out` for each
    /// event. A frame split across calls is decoded once its last byte comes.
    pub fn push(&mut self, mut bytes: &[u8], out: &mut impl FnMut(Event)) {
        while !bytes.is_empty() {
            let n = bytes.len().min(MAX_FRAME_LEN - self.len);
            self.buf[self.len..self.len + n].copy_from_slice(&bytes[..n]);
            self.len += n;
            bytes = &bytes[n..];
            // A full buffer always yields a frame or a skip, so this frees
            // room for the next round.
            self.process(out);
        }
    }

    /// Ends the stream: the bytes held back waiting for the rest of a frame
    /// are reported as Corrupt, except any good frames found in them. The
    /// decoder then accepts a new stream, keeping its sequence tracking and
    /// totals.
    pub fn finish(&mut self, out: &mut impl FnMut(Event)) {
        while self.len > 0 {
            // No more bytes will come, so the frame waited for cannot
            // complete: resynchronise past its sync as for a bad CRC.
            self.drop_front(1, true);
            self.process(out);
        }
        self.report_skipped(out);
    }

    fn process(&mut self, out: &mut impl FnMut(Event)) {
        loop {
            match self.step() {
                Step::NeedMore => return,
                Step::Skip(n) => self.drop_front(n, true),
                Step::Frame(n, event) => {
                    self.drop_front(n, false);
                    self.report_skipped(out);
                    self.emit(event, out);
                }
            }
        }
    }

    fn step(&self) -> Step {
        let b = &self.buf[..self.len];
        if b.is_empty() {
            return Step::NeedMore;
        }
        // A lone first sync byte at the end may be completed by the next push.
        let sync_at =
            (0..b.len()).find(|&i| b[i] == SYNC[0] && b.get(i + 1).is_none_or(|&x| x == SYNC[1]));
        match sync_at {
            None => return Step::Skip(b.len()),
            Some(0) => {}
            Some(i) => return Step::Skip(i),
        }
        if b.len() < HEADER_LEN {
            return Step::NeedMore;
        }
        let (kind, payload_len) = (b[2], usize::from(b[3]));
        // A bad header or CRC skips the first sync byte only: the next frame
        // may start anywhere after it.
        if !payload_len_ok(kind, payload_len) {
            return Step::Skip(1);
        }
        let crc_at = HEADER_LEN + payload_len;
        let frame_len = crc_at + CRC_LEN;
        if b.len() < frame_len {
            return Step::NeedMore;
        }
        if u16::from_le_bytes([b[crc_at], b[crc_at + 1]]) != crc16(&b[2..crc_at]) {
            return Step::Skip(1);
        }
        match parse(kind, &b[HEADER_LEN..crc_at]) {
            Some(event) => Step::Frame(frame_len, event),
            // The CRC vouches for the frame's bounds, so skip all of it.
            None => Step::Skip(frame_len),
        }
    }

    fn drop_front(&mut self, n: usize, skipped: bool) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
        if skipped {
            self.skipped = self.skipped.saturating_add(n);
        }
    }

    fn report_skipped(&mut self, out: &mut impl FnMut(Event)) {
        if self.skipped > 0 {
            let skipped_bytes = core::mem::take(&mut self.skipped);
            self.stats.corrupt_bytes = self
                .stats
                .corrupt_bytes
                .saturating_add(skipped_bytes as u64);
            out(Event::Corrupt { skipped_bytes });
        }
    }

    fn emit(&mut self, event: Event, out: &mut impl FnMut(Event)) {
        match event {
            Event::Sample(s) => {
                self.track(s.seq, 1, out);
                self.stats.samples = self.stats.samples.saturating_add(1);
            }
            Event::Dropped(d) => {
                self.track(d.first_seq, d.count, out);
                self.stats.dropped_reported = self
                    .stats
                    .dropped_reported
                    .saturating_add(u64::from(d.count));
            }
            Event::Fault(_) => self.stats.faults = self.stats.faults.saturating_add(1),
            Event::Info(_) => self.stats.infos = self.stats.infos.saturating_add(1),
            Event::Gap { .. } | Event::Corrupt { .. } | Event::Tracking(_) => {}
        }
        out(event);
    }

    /// A Sample (`taken` = 1) or a Dropped report (`taken` = its count)
    /// accounts for the sequence numbers `seq .. seq + taken`.
    fn track(&mut self, seq: u32, taken: u32, out: &mut impl FnMut(Event)) {
        if let Some(expected) = self.next_seq {
            if seq != expected {
                let skipped = seq.wrapping_sub(expected);
                // Half the number space ahead is a jump forward; further
                // means behind, a restart, which loses nothing we can count.
                if skipped < 1 << 31 {
                    self.stats.gaps_unreported = self
                        .stats
                        .gaps_unreported
                        .saturating_add(u64::from(skipped));
                }
                out(Event::Gap {
                    expected_seq: expected,
                    got_seq: seq,
                });
            }
        }
        self.next_seq = Some(seq.wrapping_add(taken));
    }
}

/// The event in a payload whose kind, length and CRC have checked; `None`
/// if its content is invalid.
fn parse(kind: u8, p: &[u8]) -> Option<Event> {
    let u32_at = |i: usize| u32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
    let f32_at = |i: usize| f32::from_bits(u32_at(i));
    match kind {
        KIND_SAMPLE => {
            let n = (p.len() - SAMPLE_FIXED_LEN) / 8;
            let mut s = DecodedSample {
                seq: u32_at(0),
                t_us: u32_at(4),
                force_n: f32_at(8),
                flags: SampleFlags(p[12]),
                n,
                voltages_v: [0.0; MAX_SEGMENTS],
                currents_a: [0.0; MAX_SEGMENTS],
            };
            for k in 0..n {
                s.voltages_v[k] = f32_at(SAMPLE_FIXED_LEN + 4 * k);
                s.currents_a[k] = f32_at(SAMPLE_FIXED_LEN + 4 * (n + k));
            }
            Some(Event::Sample(s))
        }
        KIND_DROPPED => Some(Event::Dropped(Dropped {
            first_seq: u32_at(0),
            count: u32_at(4),
        })),
        KIND_FAULT => Some(Event::Fault(Fault {
            seq: u32_at(0),
            t_us: u32_at(4),
            code: FaultCode::from_u8(p[8])?,
            segment: match p[9] {
                NO_SEGMENT => None,
                s if usize::from(s) < MAX_SEGMENTS => Some(s),
                _ => return None,
            },
        })),
        KIND_INFO => parse_info(p).map(Event::Info),
        KIND_TRACKING => Some(Event::Tracking(crate::tracking::parse_tracking(p))),
        _ => None,
    }
}
