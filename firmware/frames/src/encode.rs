//! Encoding frames into a caller's buffer: no allocation, no panic.

use core::fmt;

use crate::{
    crc16, sample_payload_len, Dropped, Fault, Sample, CRC_LEN, DROPPED_PAYLOAD_LEN,
    FAULT_PAYLOAD_LEN, HEADER_LEN, KIND_DROPPED, KIND_FAULT, KIND_SAMPLE, MAX_SEGMENTS, NO_SEGMENT,
    SYNC,
};

/// Why a frame was not encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EncodeError {
    /// The output buffer is shorter than the frame.
    BufferTooSmall {
        /// The frame's length.
        needed: usize,
    },
    /// A Fault's segment index is not below [`MAX_SEGMENTS`].
    BadSegment(u8),
    /// An Info's segment count is not 1..=[`MAX_SEGMENTS`], or a DAC
    /// segment not below [`MAX_SEGMENTS`].
    BadInfo,
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall { needed } => {
                write!(f, "buffer too small, frame needs {needed} bytes")
            }
            Self::BadSegment(s) => write!(f, "segment index {s} not below {MAX_SEGMENTS}"),
            Self::BadInfo => write!(
                f,
                "Info: segments must be 1..={MAX_SEGMENTS}, DAC segments below {MAX_SEGMENTS}"
            ),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Writes `s` as a Sample frame at the start of `out`; returns the frame's
/// length, [`frame_len`](crate::frame_len)`(N)`.
pub fn encode_sample<const N: usize>(s: &Sample<N>, out: &mut [u8]) -> Result<usize, EncodeError> {
    const { assert!(N >= 1 && N <= MAX_SEGMENTS, "a Sample has 1..=8 segments") };
    let mut w = Writer::start(out, KIND_SAMPLE, sample_payload_len(N))?;
    w.put(&s.seq.to_le_bytes());
    w.put(&s.t_us.to_le_bytes());
    w.put(&s.force_n.to_le_bytes());
    w.put(&[s.flags.0]);
    for v in s.voltages_v.iter().chain(&s.currents_a) {
        w.put(&v.to_le_bytes());
    }
    Ok(w.finish())
}

/// Writes `d` as a Dropped frame at the start of `out`; returns the frame's
/// length, [`DROPPED_FRAME_LEN`](crate::DROPPED_FRAME_LEN).
pub fn encode_dropped(d: &Dropped, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut w = Writer::start(out, KIND_DROPPED, DROPPED_PAYLOAD_LEN)?;
    w.put(&d.first_seq.to_le_bytes());
    w.put(&d.count.to_le_bytes());
    Ok(w.finish())
}

/// Writes `f` as a Fault frame at the start of `out`; returns the frame's
/// length, [`FAULT_FRAME_LEN`](crate::FAULT_FRAME_LEN).
pub fn encode_fault(f: &Fault, out: &mut [u8]) -> Result<usize, EncodeError> {
    let segment = match f.segment {
        None => NO_SEGMENT,
        Some(s) if usize::from(s) < MAX_SEGMENTS => s,
        // 0xFF would read back as "none", and the decoder refuses the rest.
        Some(s) => return Err(EncodeError::BadSegment(s)),
    };
    let mut w = Writer::start(out, KIND_FAULT, FAULT_PAYLOAD_LEN)?;
    w.put(&f.seq.to_le_bytes());
    w.put(&f.t_us.to_le_bytes());
    w.put(&[f.code as u8, segment]);
    Ok(w.finish())
}

/// A frame being written. `start` checks the length once; the callers then
/// put exactly `payload_len` bytes, so the indexing below stays in bounds.
pub(crate) struct Writer<'a> {
    frame: &'a mut [u8],
    at: usize,
}

impl<'a> Writer<'a> {
    pub(crate) fn start(
        out: &'a mut [u8],
        kind: u8,
        payload_len: usize,
    ) -> Result<Self, EncodeError> {
        let needed = HEADER_LEN + payload_len + CRC_LEN;
        let frame = out
            .get_mut(..needed)
            .ok_or(EncodeError::BufferTooSmall { needed })?;
        frame[..2].copy_from_slice(&SYNC);
        frame[2] = kind;
        frame[3] = payload_len as u8;
        Ok(Self {
            frame,
            at: HEADER_LEN,
        })
    }

    pub(crate) fn put(&mut self, bytes: &[u8]) {
        self.frame[self.at..self.at + bytes.len()].copy_from_slice(bytes);
        self.at += bytes.len();
    }

    pub(crate) fn finish(self) -> usize {
        debug_assert_eq!(self.at + CRC_LEN, self.frame.len());
        let crc = crc16(&self.frame[2..self.at]);
        self.frame[self.at..].copy_from_slice(&crc.to_le_bytes());
        self.frame.len()
    }
}
