//! Host commands on the down channel: encoder and streaming decoder.
//!
//! Same framing as the up-channel frames (see the crate's docs for the
//! layout of each command). Decoding checks the framing only (sync, kind,
//! length, CRC, program kind); whether the values make sense is for the
//! firmware's controller to check (`Generator::new`,
//! `Limits::set_max_abs_v_lower`), so that it can refuse a command with the
//! field and the rule it breaks.
//!
//! ```
//! use finrs_frames::{encode_command, Command, CommandDecoder, CommandEvent, MAX_COMMAND_LEN};
//!
//! let mut buf = [0u8; MAX_COMMAND_LEN];
//! let len = encode_command(&Command::SetLimit { max_abs_v: 1.5 }, &mut buf).unwrap();
//!
//! let mut decoder = CommandDecoder::new();
//! let mut got = None;
//! decoder.push(&buf[..len], &mut |e| {
//!     if let CommandEvent::Command(c) = e {
//!         got = Some(c);
//!     }
//! });
//! assert_eq!(got, Some(Command::SetLimit { max_abs_v: 1.5 }));
//! ```

use core::fmt;

use finrs_drive::{Envelope, Program};

use crate::encode::Writer;
use crate::{
    crc16, Calibration, EncodeError, ModelRecord, CALIBRATION_LEN, CRC_LEN, HEADER_LEN,
    MODEL_RECORD_LEN, SYNC,
};

const KIND_SET_WAVE: u8 = 0x81;
const KIND_TARE: u8 = 0x82;
const KIND_STOP: u8 = 0x83;
const KIND_SET_LIMIT: u8 = 0x84;
const KIND_CLEAR_FAULT: u8 = 0x85;
const KIND_REQUEST_INFO: u8 = 0x86;
const KIND_SET_CALIBRATION: u8 = 0x87;
const KIND_SET_MODEL: u8 = 0x88;
const KIND_SET_MOTION: u8 = 0x89;

const PROGRAM_TRAVELLING: u8 = 1;
const PROGRAM_STANDING: u8 = 2;
const PROGRAM_STEPS: u8 = 3;
const PROGRAM_PULSES: u8 = 4;
const PROGRAM_CHIRP: u8 = 5;
const PROGRAM_HARMONIC: u8 = 6;
const PROGRAM_HELD_STEP: u8 = 7;

const MOTION_TRAVELLING: u8 = 1;
const MOTION_STEP: u8 = 2;
const MOTION_FORCE: u8 = 3;
/// SetMotion's payload: the motion kind, its three f32, the envelope, the
/// session time, whether the tracker holds it.
const SET_MOTION_PAYLOAD_LEN: usize = 1 + 4 * 3 + ENVELOPE_LEN + 4 + 1;

/// Most f32 fields of a program: Harmonic's frequency, offset, and eight
/// amplitudes and phases.
const MAX_PROGRAM_FIELDS: usize = 18;
/// A held step's: eight levels, the rise, the pole and the zero.
const HELD_STEP_FIELDS: usize = 11;

/// The envelope's three f32 after the program's fields.
const ENVELOPE_LEN: usize = 12;
const SET_LIMIT_PAYLOAD_LEN: usize = 4;

/// Number of f32 fields of a program kind, `None` if the kind is unknown.
const fn program_fields(program_kind: u8) -> Option<usize> {
    match program_kind {
        PROGRAM_TRAVELLING => Some(4),
        PROGRAM_STANDING => Some(3),
        PROGRAM_STEPS => Some(8),
        PROGRAM_PULSES => Some(3),
        PROGRAM_CHIRP => Some(4),
        PROGRAM_HARMONIC => Some(MAX_PROGRAM_FIELDS),
        PROGRAM_HELD_STEP => Some(HELD_STEP_FIELDS),
        _ => None,
    }
}

/// SetWave's payload length for a known program kind.
const fn set_wave_payload_len(fields: usize) -> usize {
    1 + 4 * fields + ENVELOPE_LEN
}

/// Longest SetWave payload: Harmonic's 18 fields.
const SET_WAVE_MAX_PAYLOAD_LEN: usize = set_wave_payload_len(MAX_PROGRAM_FIELDS);

/// Longest command frame (a SetModel), bytes.
pub const MAX_COMMAND_LEN: usize = HEADER_LEN + MODEL_RECORD_LEN + CRC_LEN;
const _: () = assert!(SET_WAVE_MAX_PAYLOAD_LEN <= MODEL_RECORD_LEN && MODEL_RECORD_LEN <= 255);

/// Whether `len` may be the payload length of a command of `kind`. For a
/// SetWave only the set of lengths is checked here; the program kind in the
/// payload must then match the length exactly.
const fn command_len_ok(kind: u8, len: usize) -> bool {
    match kind {
        KIND_SET_WAVE => {
            len == set_wave_payload_len(3)
                || len == set_wave_payload_len(4)
                || len == set_wave_payload_len(8)
                || len == set_wave_payload_len(HELD_STEP_FIELDS)
                || len == set_wave_payload_len(MAX_PROGRAM_FIELDS)
        }
        KIND_TARE | KIND_STOP | KIND_CLEAR_FAULT | KIND_REQUEST_INFO => len == 0,
        KIND_SET_LIMIT => len == SET_LIMIT_PAYLOAD_LEN,
        KIND_SET_CALIBRATION => len == CALIBRATION_LEN,
        KIND_SET_MODEL => len == MODEL_RECORD_LEN,
        KIND_SET_MOTION => len == SET_MOTION_PAYLOAD_LEN,
        _ => false,
    }
}

/// A host command. Values are carried as sent: the controller validates them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Replace the running wave; the new program starts at its own time 0.
    SetWave {
        /// What each segment does.
        program: Program,
        /// The gain over the program.
        envelope: Envelope,
    },
    /// Measure the load cell's zero again.
    Tare,
    /// Bring every output to 0 V through the slew limit and stay there (not
    /// a fault).
    Stop,
    /// Lower the voltage limit (a raise is refused by the controller).
    SetLimit {
        /// The new limit on |V|, V.
        max_abs_v: f32,
    },
    /// Clear a latched fault; outputs stay at 0 V until the next SetWave.
    ClearFault,
    /// Send an Info frame ([`Info`](crate::Info)) again.
    RequestInfo,
    /// Use this calibration from now on and store it in the board's flash
    /// (refused while a program drives the outputs).
    SetCalibration(Calibration),
    /// Use this fitted model from now on to shape motions, and store it in
    /// the board's flash (refused while a program drives the outputs).
    SetModel(ModelRecord),
    /// Replace the running wave by the voltages that make this motion on
    /// the model the board holds (refused if it holds none, or if the
    /// motion needs more than the limit).
    SetMotion {
        /// What the strip is to do.
        motion: Motion,
        /// The gain over the voltages.
        envelope: Envelope,
        /// When the motion starts on the clock of the model's drying law
        /// (the session's, from its first recording), s; NaN if unknown
        /// (a model that dries then refuses the motion).
        t_session_s: f32,
        /// Whether the board's gain tracker holds the motion against the
        /// strip's drift (`finrs_controller::tracker`); else the model's
        /// voltages are driven as they are (feed-forward only).
        tracked: bool,
    },
}

/// A motion asked of the strip, which the board turns into voltages
/// through the inverse of the model it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// A travelling bending wave of the free strip: every segment's moment
    /// of one amplitude, each `lag_deg_per_segment` behind the one before,
    /// the tip moving `tip_amp_m · sin(2π frequency_hz t)`.
    Travelling {
        /// Tip amplitude, m.
        tip_amp_m: f32,
        /// Frequency, Hz.
        frequency_hz: f32,
        /// Phase lag of each segment's moment behind the one before, degrees.
        lag_deg_per_segment: f32,
    },
    /// A step of the free tip held against the strip's relaxation: every
    /// segment's moment on the beam one and the same, the tip moving to
    /// `tip_m` over the envelope's ramp-in (its rise) and held there
    /// (`model_core::Strip::tip_step`).
    Step {
        /// The tip's deflection once settled, m.
        tip_m: f32,
    },
    /// A travelling bending wave of the strip held by the load cell: as
    /// [`Motion::Travelling`], the force on the load cell moving
    /// `force_amp_n · sin(2π frequency_hz t)`; tracked, by the load cell.
    Force {
        /// Force amplitude, N.
        force_amp_n: f32,
        /// Frequency, Hz.
        frequency_hz: f32,
        /// Phase lag of each segment's moment behind the one before, degrees.
        lag_deg_per_segment: f32,
    },
}

/// Why bytes on the down channel were not a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CommandError {
    /// Bytes before the next sync pair (or before the end of the stream).
    NoSync {
        /// How many.
        skipped_bytes: usize,
    },
    /// The header's kind is not a command kind (0x81..=0x89).
    UnknownKind(u8),
    /// The payload length does not fit the kind (or, for a SetWave, its
    /// program kind).
    BadLength {
        /// The command kind.
        kind: u8,
        /// The length the frame claims.
        len: u8,
    },
    /// The CRC does not match: the frame was damaged or cut short.
    BadCrc {
        /// The command kind in the (possibly damaged) header.
        kind: u8,
    },
    /// A SetWave's program kind is not 1..=7.
    BadProgramKind(u8),
    /// A SetMotion's motion kind is not 1..=3.
    BadMotionKind(u8),
    /// A SetMotion's motion (its kind) has non-zero bytes in a field its
    /// kind does not use.
    MotionUnused(u8),
    /// A SetMotion's tracking byte is neither 0 nor 1.
    BadTracking(u8),
    /// The stream ended ([`CommandDecoder::finish`]) inside a frame.
    Truncated {
        /// The command kind in the header.
        kind: u8,
    },
}

impl fmt::Display for CommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoSync { skipped_bytes } => {
                write!(f, "{skipped_bytes} bytes without a sync pair skipped")
            }
            Self::UnknownKind(k) => write!(f, "kind {k:#04x} is not a command (0x81..=0x89)"),
            Self::BadLength { kind, len } => {
                write!(f, "length {len} does not fit command kind {kind:#04x}")
            }
            Self::BadCrc { kind } => write!(f, "CRC mismatch in command kind {kind:#04x}"),
            Self::BadProgramKind(p) => write!(f, "program kind {p} is not 1..=7"),
            Self::BadMotionKind(m) => write!(f, "motion kind {m} is not 1..=3"),
            Self::MotionUnused(m) => {
                write!(
                    f,
                    "motion kind {m} carries values in fields it does not use"
                )
            }
            Self::BadTracking(t) => write!(f, "motion tracking byte {t} is neither 0 nor 1"),
            Self::Truncated { kind } => write!(f, "command kind {kind:#04x} cut short"),
        }
    }
}

impl core::error::Error for CommandError {}

/// What the command decoder found.
// A SetModel's record (254 bytes) is carried by value: there is no heap,
// and an event is handed over once, not stored.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CommandEvent {
    /// A well-framed command.
    Command(Command),
    /// Bytes that were not a command, and why.
    Refused(CommandError),
}

/// Writes `c` as a command frame at the start of `out`; returns its length
/// (at most [`MAX_COMMAND_LEN`]).
pub fn encode_command(c: &Command, out: &mut [u8]) -> Result<usize, EncodeError> {
    match *c {
        Command::SetWave { program, envelope } => {
            let (program_kind, fields, n) = program_to_fields(&program);
            let mut w = Writer::start(out, KIND_SET_WAVE, set_wave_payload_len(n))?;
            w.put(&[program_kind]);
            for v in &fields[..n] {
                w.put(&v.to_le_bytes());
            }
            for v in [envelope.ramp_in_s, envelope.hold_s, envelope.ramp_out_s] {
                w.put(&v.to_le_bytes());
            }
            Ok(w.finish())
        }
        Command::Tare => Ok(Writer::start(out, KIND_TARE, 0)?.finish()),
        Command::Stop => Ok(Writer::start(out, KIND_STOP, 0)?.finish()),
        Command::SetLimit { max_abs_v } => {
            let mut w = Writer::start(out, KIND_SET_LIMIT, SET_LIMIT_PAYLOAD_LEN)?;
            w.put(&max_abs_v.to_le_bytes());
            Ok(w.finish())
        }
        Command::ClearFault => Ok(Writer::start(out, KIND_CLEAR_FAULT, 0)?.finish()),
        Command::RequestInfo => Ok(Writer::start(out, KIND_REQUEST_INFO, 0)?.finish()),
        Command::SetCalibration(c) => {
            let mut w = Writer::start(out, KIND_SET_CALIBRATION, CALIBRATION_LEN)?;
            w.put(&c.to_bytes());
            Ok(w.finish())
        }
        Command::SetModel(record) => {
            let mut w = Writer::start(out, KIND_SET_MODEL, MODEL_RECORD_LEN)?;
            w.put(&record.0);
            Ok(w.finish())
        }
        Command::SetMotion {
            motion,
            envelope,
            t_session_s,
            tracked,
        } => {
            // A step's two unused fields go as zeros.
            let (motion_kind, [a, b, c]) = match motion {
                Motion::Travelling {
                    tip_amp_m,
                    frequency_hz,
                    lag_deg_per_segment,
                } => (
                    MOTION_TRAVELLING,
                    [tip_amp_m, frequency_hz, lag_deg_per_segment],
                ),
                Motion::Step { tip_m } => (MOTION_STEP, [tip_m, 0.0, 0.0]),
                Motion::Force {
                    force_amp_n,
                    frequency_hz,
                    lag_deg_per_segment,
                } => (
                    MOTION_FORCE,
                    [force_amp_n, frequency_hz, lag_deg_per_segment],
                ),
            };
            let mut w = Writer::start(out, KIND_SET_MOTION, SET_MOTION_PAYLOAD_LEN)?;
            w.put(&[motion_kind]);
            for v in [
                a,
                b,
                c,
                envelope.ramp_in_s,
                envelope.hold_s,
                envelope.ramp_out_s,
                t_session_s,
            ] {
                w.put(&v.to_le_bytes());
            }
            w.put(&[u8::from(tracked)]);
            Ok(w.finish())
        }
    }
}

/// The program's kind and its f32 fields in declaration order (the first
/// `n` of the array).
fn program_to_fields(p: &Program) -> (u8, [f32; MAX_PROGRAM_FIELDS], usize) {
    let mut f = [0.0; MAX_PROGRAM_FIELDS];
    match *p {
        Program::Travelling {
            amplitude_v,
            frequency_hz,
            lag_deg_per_segment,
            offset_v,
        } => {
            f[..4].copy_from_slice(&[amplitude_v, frequency_hz, lag_deg_per_segment, offset_v]);
            (PROGRAM_TRAVELLING, f, 4)
        }
        Program::Standing {
            amplitude_v,
            frequency_hz,
            offset_v,
        } => {
            f[..3].copy_from_slice(&[amplitude_v, frequency_hz, offset_v]);
            (PROGRAM_STANDING, f, 3)
        }
        Program::Steps { levels_v } => {
            f[..8].copy_from_slice(&levels_v);
            (PROGRAM_STEPS, f, 8)
        }
        Program::Harmonic {
            frequency_hz,
            offset_v,
            amplitudes_v,
            phases_deg,
        } => {
            f[..2].copy_from_slice(&[frequency_hz, offset_v]);
            f[2..10].copy_from_slice(&amplitudes_v);
            f[10..].copy_from_slice(&phases_deg);
            (PROGRAM_HARMONIC, f, MAX_PROGRAM_FIELDS)
        }
        Program::Pulses {
            amplitude_v,
            on_s,
            off_s,
        } => {
            f[..3].copy_from_slice(&[amplitude_v, on_s, off_s]);
            (PROGRAM_PULSES, f, 3)
        }
        Program::Chirp {
            amplitude_v,
            start_hz,
            end_hz,
            duration_s,
        } => {
            f[..4].copy_from_slice(&[amplitude_v, start_hz, end_hz, duration_s]);
            (PROGRAM_CHIRP, f, 4)
        }
        Program::HeldStep {
            levels_v,
            rise_s,
            pole_per_s,
            zero_per_s,
        } => {
            f[..8].copy_from_slice(&levels_v);
            f[8..11].copy_from_slice(&[rise_s, pole_per_s, zero_per_s]);
            (PROGRAM_HELD_STEP, f, HELD_STEP_FIELDS)
        }
    }
}

/// Streaming decoder of the down channel: [`push`](Self::push) bytes as
/// they arrive, in chunks of any size. It holds at most one command's
/// worth of bytes and never allocates or panics.
///
/// Resynchronisation follows the up-channel [`Decoder`](crate::Decoder):
/// a bad header or CRC refuses the frame and drops only its first sync
/// byte, so a good command inside or just after a damaged one is still
/// found. Each refusal is reported where it is detected, and bytes without
/// a sync pair as one [`CommandError::NoSync`] before the next event (or
/// by [`finish`](Self::finish)): the events do not depend on how the
/// stream was split. A frame cut short is refused once the bytes that
/// follow it fill its claimed length, so a command sent after a truncated
/// one may wait for up to [`MAX_COMMAND_LEN`] more bytes (or a `finish`):
/// a host that may have cut a command short (killed mid-write, say) can
/// send [`MAX_COMMAND_LEN`] zero bytes first, which flush it (and are
/// reported as [`CommandError::NoSync`]).
#[derive(Clone, Debug)]
pub struct CommandDecoder {
    buf: [u8; MAX_COMMAND_LEN],
    len: usize,
    /// Bytes without sync not yet reported.
    skipped: usize,
}

impl Default for CommandDecoder {
    fn default() -> Self {
        Self::new()
    }
}

/// What the front of the buffer holds.
#[allow(clippy::large_enum_variant)] // as CommandEvent: no heap, not stored
enum Step {
    NeedMore,
    /// Bytes with no sync pair.
    NoSync(usize),
    /// A refused frame: drop this many bytes.
    Refuse(usize, CommandError),
    /// A command frame of this length.
    Frame(usize, Command),
}

impl CommandDecoder {
    /// A decoder at the start of a stream.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_COMMAND_LEN],
            len: 0,
            skipped: 0,
        }
    }

    /// Decodes `bytes`, the next part of the stream, calling `out` for each
    /// event.
    pub fn push(&mut self, mut bytes: &[u8], out: &mut impl FnMut(CommandEvent)) {
        while !bytes.is_empty() {
            let n = bytes.len().min(MAX_COMMAND_LEN - self.len);
            self.buf[self.len..self.len + n].copy_from_slice(&bytes[..n]);
            self.len += n;
            bytes = &bytes[n..];
            // A full buffer always yields a frame, a refusal or a skip.
            self.process(out);
        }
    }

    /// Ends the stream: bytes held back waiting for the rest of a command
    /// are refused (a cut frame as [`CommandError::Truncated`]), good commands
    /// among them still decoded. The decoder then accepts a new stream.
    pub fn finish(&mut self, out: &mut impl FnMut(CommandEvent)) {
        while self.len > 0 {
            match self.step() {
                // The frame waited for cannot complete: refuse it as cut
                // short and search on past its first sync byte.
                Step::NeedMore => {
                    if self.len >= HEADER_LEN {
                        let kind = self.buf[2];
                        self.report_skipped(out);
                        self.drop_front(1);
                        out(CommandEvent::Refused(CommandError::Truncated { kind }));
                    } else {
                        self.skipped = self.skipped.saturating_add(self.len);
                        self.len = 0;
                    }
                }
                step => self.apply(step, out),
            }
        }
        self.report_skipped(out);
    }

    fn process(&mut self, out: &mut impl FnMut(CommandEvent)) {
        loop {
            match self.step() {
                Step::NeedMore => return,
                step => self.apply(step, out),
            }
        }
    }

    fn apply(&mut self, step: Step, out: &mut impl FnMut(CommandEvent)) {
        match step {
            Step::NeedMore => {}
            Step::NoSync(n) => {
                self.drop_front(n);
                self.skipped = self.skipped.saturating_add(n);
            }
            Step::Refuse(n, e) => {
                self.report_skipped(out);
                self.drop_front(n);
                out(CommandEvent::Refused(e));
            }
            Step::Frame(n, c) => {
                self.report_skipped(out);
                self.drop_front(n);
                out(CommandEvent::Command(c));
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
            None => return Step::NoSync(b.len()),
            Some(0) => {}
            Some(i) => return Step::NoSync(i),
        }
        if b.len() < HEADER_LEN {
            return Step::NeedMore;
        }
        let (kind, len) = (b[2], b[3]);
        if !(KIND_SET_WAVE..=KIND_SET_MOTION).contains(&kind) {
            return Step::Refuse(1, CommandError::UnknownKind(kind));
        }
        if !command_len_ok(kind, usize::from(len)) {
            return Step::Refuse(1, CommandError::BadLength { kind, len });
        }
        let crc_at = HEADER_LEN + usize::from(len);
        let frame_len = crc_at + CRC_LEN;
        if b.len() < frame_len {
            return Step::NeedMore;
        }
        if u16::from_le_bytes([b[crc_at], b[crc_at + 1]]) != crc16(&b[2..crc_at]) {
            return Step::Refuse(1, CommandError::BadCrc { kind });
        }
        // The CRC vouches for the frame's bounds: a refusal now skips it all.
        match parse(kind, &b[HEADER_LEN..crc_at]) {
            Ok(c) => Step::Frame(frame_len, c),
            Err(e) => Step::Refuse(frame_len, e),
        }
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    fn report_skipped(&mut self, out: &mut impl FnMut(CommandEvent)) {
        if self.skipped > 0 {
            let skipped_bytes = core::mem::take(&mut self.skipped);
            out(CommandEvent::Refused(CommandError::NoSync {
                skipped_bytes,
            }));
        }
    }
}

/// The command in a payload whose kind, length and CRC have checked.
fn parse(kind: u8, p: &[u8]) -> Result<Command, CommandError> {
    let f32_at = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
    match kind {
        KIND_SET_WAVE => {
            let program_kind = p[0];
            let n =
                program_fields(program_kind).ok_or(CommandError::BadProgramKind(program_kind))?;
            if p.len() != set_wave_payload_len(n) {
                return Err(CommandError::BadLength {
                    kind,
                    len: p.len() as u8,
                });
            }
            let field = |k: usize| f32_at(1 + 4 * k);
            let program = match program_kind {
                PROGRAM_TRAVELLING => Program::Travelling {
                    amplitude_v: field(0),
                    frequency_hz: field(1),
                    lag_deg_per_segment: field(2),
                    offset_v: field(3),
                },
                PROGRAM_STANDING => Program::Standing {
                    amplitude_v: field(0),
                    frequency_hz: field(1),
                    offset_v: field(2),
                },
                PROGRAM_STEPS => Program::Steps {
                    levels_v: core::array::from_fn(field),
                },
                PROGRAM_PULSES => Program::Pulses {
                    amplitude_v: field(0),
                    on_s: field(1),
                    off_s: field(2),
                },
                PROGRAM_CHIRP => Program::Chirp {
                    amplitude_v: field(0),
                    start_hz: field(1),
                    end_hz: field(2),
                    duration_s: field(3),
                },
                PROGRAM_HELD_STEP => Program::HeldStep {
                    levels_v: core::array::from_fn(field),
                    rise_s: field(8),
                    pole_per_s: field(9),
                    zero_per_s: field(10),
                },
                _ => Program::Harmonic {
                    frequency_hz: field(0),
                    offset_v: field(1),
                    amplitudes_v: core::array::from_fn(|k| field(2 + k)),
                    phases_deg: core::array::from_fn(|k| field(10 + k)),
                },
            };
            let envelope = Envelope {
                ramp_in_s: field(n),
                hold_s: field(n + 1),
                ramp_out_s: field(n + 2),
            };
            Ok(Command::SetWave { program, envelope })
        }
        KIND_TARE => Ok(Command::Tare),
        KIND_STOP => Ok(Command::Stop),
        KIND_SET_LIMIT => Ok(Command::SetLimit {
            max_abs_v: f32_at(0),
        }),
        KIND_CLEAR_FAULT => Ok(Command::ClearFault),
        KIND_REQUEST_INFO => Ok(Command::RequestInfo),
        KIND_SET_CALIBRATION => p
            .try_into()
            .map(|b| Command::SetCalibration(Calibration::from_bytes(b)))
            .map_err(|_| CommandError::BadLength {
                kind,
                len: p.len() as u8,
            }),
        KIND_SET_MODEL => p
            .try_into()
            .map(|b| Command::SetModel(ModelRecord(b)))
            .map_err(|_| CommandError::BadLength {
                kind,
                len: p.len() as u8,
            }),
        KIND_SET_MOTION => {
            let field = |k: usize| f32_at(1 + 4 * k);
            let motion = match p[0] {
                MOTION_TRAVELLING => Motion::Travelling {
                    tip_amp_m: field(0),
                    frequency_hz: field(1),
                    lag_deg_per_segment: field(2),
                },
                // Bits, not values: a −0.0 or NaN there is not a zero sent.
                MOTION_STEP if p[5..13].iter().all(|&b| b == 0) => Motion::Step { tip_m: field(0) },
                MOTION_STEP => return Err(CommandError::MotionUnused(MOTION_STEP)),
                MOTION_FORCE => Motion::Force {
                    force_amp_n: field(0),
                    frequency_hz: field(1),
                    lag_deg_per_segment: field(2),
                },
                m => return Err(CommandError::BadMotionKind(m)),
            };
            let tracked = match p[SET_MOTION_PAYLOAD_LEN - 1] {
                0 => false,
                1 => true,
                t => return Err(CommandError::BadTracking(t)),
            };
            Ok(Command::SetMotion {
                motion,
                envelope: Envelope {
                    ramp_in_s: field(3),
                    hold_s: field(4),
                    ramp_out_s: field(5),
                },
                t_session_s: field(6),
                tracked,
            })
        }
        _ => Err(CommandError::UnknownKind(kind)),
    }
}
