//! The virtual bench's world channel: what surrounds a real board on a
//! bench (the clamp, the strip free or against the load cell, the camera)
//! as messages on the QEMU board's second serial port, beside the
//! firmware's own link. The host's `finrs bench run --qemu` sends the
//! operator's acts ([`Request`]) and reads what the camera sees
//! ([`Event`]); the firmware's controller knows nothing of it, as on a
//! board.
//!
//! Messages are little-endian, each a tag byte and a fixed or counted body;
//! the channel is a local socket, so no checksum. A byte that starts no
//! message is refused and skipped.
//!
//! | message | bytes |
//! |---|---|
//! | request: strip free (the camera watches) | `b'F'` |
//! | request: strip blocked (against the load cell) | `b'B'` |
//! | request: the dots the camera tracks | `b'D'`, n (1..=[`MAX_DOTS`]), n × f32 arc length from the clamp, m |
//! | event: a camera frame | [`CAMERA_TAG`], u32 tick, n, n × f32 deflection, m (the dots', then the tip's) |
//! | event: the drive's onset (the sync LED) | [`ONSET_TAG`], u32 tick |
//! | event: a fixture request done, the strip at rest in it | [`CLAMPED_TAG`], u32 tick, 1 if free else 0 |
//!
//! ```
//! use finrs_firmware_support::world::{encode_event, Event, EventDecoder, MAX_MARKS};
//!
//! let mut y_m = [0.0; MAX_MARKS];
//! y_m[..2].copy_from_slice(&[1e-3, 2e-3]);
//! let frame = Event::Camera { tick: 1234, marks: 2, y_m };
//! let mut buf = [0u8; 64];
//! let n = encode_event(&frame, &mut buf);
//! let mut d = EventDecoder::new();
//! let got: Vec<_> = buf[..n].iter().filter_map(|&b| d.push(b)).collect();
//! assert_eq!(got, [Ok(frame)]);
//! ```

/// Dots a camera tracks at most (the tip comes beside them).
pub const MAX_DOTS: usize = 8;
/// Marks in a camera frame at most: the dots and the tip.
pub const MAX_MARKS: usize = MAX_DOTS + 1;

/// Sample periods between camera frames: 33 ms, a 30 frames/s camera.
pub const CAMERA_PERIOD_TICKS: u32 = 33;
/// Largest tracking error added to each mark's deflection, m (uniform in
/// ±this): about a fifth of a pixel at 0.1 mm per pixel.
pub const CAMERA_NOISE_M: f32 = 20e-6;

/// A camera frame's tag.
pub const CAMERA_TAG: u8 = 0xCA;
/// The onset event's tag.
pub const ONSET_TAG: u8 = 0x05;
/// The clamped event's tag.
pub const CLAMPED_TAG: u8 = 0xC1;

/// The operator's act.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Request {
    /// The strip free in the clamp, the camera watching.
    Free,
    /// The strip's tip against the load cell.
    Blocked,
    /// The dots the camera tracks, m from the clamp (the first `dots`).
    Dots {
        /// How many.
        dots: u8,
        /// Their arc lengths, m.
        s_m: [f32; MAX_DOTS],
    },
}

/// What the world shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A camera frame: the strip's state at `tick` (the board's sample
    /// period count), the deflection at each dot and then the tip.
    Camera {
        /// The state's period.
        tick: u32,
        /// How many marks (dots, then the tip).
        marks: u8,
        /// Their deflections, m.
        y_m: [f32; MAX_MARKS],
    },
    /// The sync mark's onset ([`crate::sync`]): the drive rose above
    /// [`crate::sync::ONSET_V`] at `tick`, after a rest.
    Onset {
        /// The period.
        tick: u32,
    },
    /// A [`Request::Free`] or [`Request::Blocked`] is done: from period
    /// `tick` on the strip is in that fixture, at rest (the operator
    /// re-clamped a rested strip). The host waits for it, so that a
    /// recording never starts before its fixture.
    Clamped {
        /// The first period in the new fixture.
        tick: u32,
        /// Free (else blocked).
        free: bool,
    },
}

/// A byte or count that breaks the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorldError {
    /// A byte that starts no message.
    UnknownTag(u8),
    /// A count of dots or marks out of range.
    BadCount(u8),
}

/// Writes `r` into `buf` (at least `2 + 4 MAX_DOTS` bytes); its length.
pub fn encode_request(r: &Request, buf: &mut [u8]) -> usize {
    match *r {
        Request::Free => {
            buf[0] = b'F';
            1
        }
        Request::Blocked => {
            buf[0] = b'B';
            1
        }
        Request::Dots { dots, s_m } => {
            let n = usize::from(dots).min(MAX_DOTS);
            buf[0] = b'D';
            buf[1] = n as u8;
            for (k, s) in s_m[..n].iter().enumerate() {
                buf[2 + 4 * k..6 + 4 * k].copy_from_slice(&s.to_le_bytes());
            }
            2 + 4 * n
        }
    }
}

/// Writes `e` into `buf` (at least `6 + 4 MAX_MARKS` bytes); its length.
pub fn encode_event(e: &Event, buf: &mut [u8]) -> usize {
    match *e {
        Event::Camera { tick, marks, y_m } => {
            let n = usize::from(marks).min(MAX_MARKS);
            buf[0] = CAMERA_TAG;
            buf[1..5].copy_from_slice(&tick.to_le_bytes());
            buf[5] = n as u8;
            for (k, y) in y_m[..n].iter().enumerate() {
                buf[6 + 4 * k..10 + 4 * k].copy_from_slice(&y.to_le_bytes());
            }
            6 + 4 * n
        }
        Event::Onset { tick } => {
            buf[0] = ONSET_TAG;
            buf[1..5].copy_from_slice(&tick.to_le_bytes());
            5
        }
        Event::Clamped { tick, free } => {
            buf[0] = CLAMPED_TAG;
            buf[1..5].copy_from_slice(&tick.to_le_bytes());
            buf[5] = u8::from(free);
            6
        }
    }
}

/// Bytes of the longest message.
const LONGEST: usize = 6 + 4 * MAX_MARKS;

/// Reassembles messages from bytes as they come.
#[derive(Clone, Debug)]
struct Assembler {
    buf: [u8; LONGEST],
    len: usize,
}

impl Assembler {
    const fn new() -> Self {
        Self {
            buf: [0; LONGEST],
            len: 0,
        }
    }

    /// Adds `b`; the whole message once its length (told by `need` from
    /// the bytes so far) is reached.
    fn push(
        &mut self,
        b: u8,
        need: impl Fn(&[u8]) -> Result<Option<usize>, WorldError>,
    ) -> Option<Result<&[u8], WorldError>> {
        self.buf[self.len] = b;
        self.len += 1;
        match need(&self.buf[..self.len]) {
            Err(e) => {
                self.len = 0;
                Some(Err(e))
            }
            Ok(Some(n)) if self.len >= n => {
                self.len = 0;
                Some(Ok(&self.buf[..n]))
            }
            Ok(_) => None,
        }
    }
}

fn f32_at(bytes: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

/// The plant's side: requests from bytes.
#[derive(Clone, Debug)]
pub struct RequestDecoder(Assembler);

impl Default for RequestDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RequestDecoder {
    /// Between messages.
    pub const fn new() -> Self {
        Self(Assembler::new())
    }

    /// Takes one byte; a request (or a refusal) when one is complete.
    pub fn push(&mut self, b: u8) -> Option<Result<Request, WorldError>> {
        let need = |m: &[u8]| match m[0] {
            b'F' | b'B' => Ok(Some(1)),
            b'D' if m.len() < 2 => Ok(None),
            b'D' if (1..=MAX_DOTS as u8).contains(&m[1]) => Ok(Some(2 + 4 * usize::from(m[1]))),
            b'D' => Err(WorldError::BadCount(m[1])),
            t => Err(WorldError::UnknownTag(t)),
        };
        Some(self.0.push(b, need)?.map(|m| match m[0] {
            b'F' => Request::Free,
            b'B' => Request::Blocked,
            _ => {
                let mut s_m = [0.0; MAX_DOTS];
                for (k, s) in s_m[..usize::from(m[1])].iter_mut().enumerate() {
                    *s = f32_at(m, 2 + 4 * k);
                }
                Request::Dots { dots: m[1], s_m }
            }
        }))
    }
}

/// The host's side: events from bytes.
#[derive(Clone, Debug)]
pub struct EventDecoder(Assembler);

impl Default for EventDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl EventDecoder {
    /// Between messages.
    pub const fn new() -> Self {
        Self(Assembler::new())
    }

    /// Takes one byte; an event (or a refusal) when one is complete.
    pub fn push(&mut self, b: u8) -> Option<Result<Event, WorldError>> {
        let need = |m: &[u8]| match m[0] {
            ONSET_TAG => Ok(Some(5)),
            CLAMPED_TAG => Ok(Some(6)),
            CAMERA_TAG if m.len() < 6 => Ok(None),
            CAMERA_TAG if (1..=MAX_MARKS as u8).contains(&m[5]) => {
                Ok(Some(6 + 4 * usize::from(m[5])))
            }
            CAMERA_TAG => Err(WorldError::BadCount(m[5])),
            t => Err(WorldError::UnknownTag(t)),
        };
        Some(self.0.push(b, need)?.map(|m| {
            let tick = u32::from_le_bytes([m[1], m[2], m[3], m[4]]);
            match m[0] {
                ONSET_TAG => return Event::Onset { tick },
                CLAMPED_TAG => {
                    return Event::Clamped {
                        tick,
                        free: m[5] != 0,
                    }
                }
                _ => {}
            }
            let mut y_m = [0.0; MAX_MARKS];
            for (k, y) in y_m[..usize::from(m[5])].iter_mut().enumerate() {
                *y = f32_at(m, 6 + 4 * k);
            }
            Event::Camera {
                tick,
                marks: m[5],
                y_m,
            }
        }))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn request() -> impl Strategy<Value = Request> {
        prop_oneof![
            Just(Request::Free),
            Just(Request::Blocked),
            (
                1u8..=MAX_DOTS as u8,
                proptest::array::uniform8(-1.0f32..1.0)
            )
                .prop_map(|(dots, s_m)| Request::Dots { dots, s_m }),
        ]
    }

    fn event() -> impl Strategy<Value = Event> {
        prop_oneof![
            any::<u32>().prop_map(|tick| Event::Onset { tick }),
            (any::<u32>(), any::<bool>()).prop_map(|(tick, free)| Event::Clamped { tick, free }),
            (
                any::<u32>(),
                1u8..=MAX_MARKS as u8,
                proptest::array::uniform9(-1.0f32..1.0)
            )
                .prop_map(|(tick, marks, y_m)| Event::Camera { tick, marks, y_m }),
        ]
    }

    /// What the decoder gives back equals what was sent, the unused tail
    /// of the arrays zero.
    fn trimmed_request(r: Request) -> Request {
        match r {
            Request::Dots { dots, mut s_m } => {
                s_m[usize::from(dots)..].fill(0.0);
                Request::Dots { dots, s_m }
            }
            r => r,
        }
    }

    fn trimmed_event(e: Event) -> Event {
        match e {
            Event::Camera {
                tick,
                marks,
                mut y_m,
            } => {
                y_m[usize::from(marks)..].fill(0.0);
                Event::Camera { tick, marks, y_m }
            }
            e => e,
        }
    }

    proptest! {
        /// Any sequence of messages, a garbage byte between some, comes
        /// back in order, each garbage byte refused once.
        #[test]
        fn messages_round_trip(reqs in proptest::collection::vec((request(), any::<bool>()), 0..20),
                               evs in proptest::collection::vec((event(), any::<bool>()), 0..20)) {
            let mut bytes = Vec::new();
            let mut buf = [0u8; 64];
            for (r, garbage) in &reqs {
                if *garbage { bytes.push(0x00); }
                let n = encode_request(r, &mut buf);
                bytes.extend_from_slice(&buf[..n]);
            }
            let mut d = RequestDecoder::new();
            let got: Vec<_> = bytes.iter().filter_map(|&b| d.push(b)).collect();
            let want: Vec<_> = reqs.iter().flat_map(|(r, garbage)| {
                let mut v = Vec::new();
                if *garbage { v.push(Err(WorldError::UnknownTag(0))); }
                v.push(Ok(trimmed_request(*r)));
                v
            }).collect();
            prop_assert_eq!(got, want);

            bytes.clear();
            for (e, garbage) in &evs {
                if *garbage { bytes.push(0x77); }
                let n = encode_event(e, &mut buf);
                bytes.extend_from_slice(&buf[..n]);
            }
            let mut d = EventDecoder::new();
            let got: Vec<_> = bytes.iter().filter_map(|&b| d.push(b)).collect();
            let want: Vec<_> = evs.iter().flat_map(|(e, garbage)| {
                let mut v = Vec::new();
                if *garbage { v.push(Err(WorldError::UnknownTag(0x77))); }
                v.push(Ok(trimmed_event(*e)));
                v
            }).collect();
            prop_assert_eq!(got, want);
        }
    }

    #[test]
    fn a_count_out_of_range_is_refused() {
        let mut d = RequestDecoder::new();
        assert_eq!(d.push(b'D'), None);
        assert_eq!(d.push(0), Some(Err(WorldError::BadCount(0))));
        assert_eq!(d.push(b'F'), Some(Ok(Request::Free)));
        let mut d = EventDecoder::new();
        for b in [CAMERA_TAG, 0, 0, 0, 0] {
            assert_eq!(d.push(b), None);
        }
        assert_eq!(
            d.push(MAX_MARKS as u8 + 1),
            Some(Err(WorldError::BadCount(MAX_MARKS as u8 + 1)))
        );
    }
}
