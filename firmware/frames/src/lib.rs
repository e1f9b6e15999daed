//! `finrs-frames`: the binary frame format of the blocking-force stream that
//! the firmware sends to the host (over an RTT up channel on the board, over
//! semihosting in QEMU), with a `no_std`, allocation-free encoder and a
//! streaming decoder that never panics and never allocates; and the host's
//! commands to the firmware on the down channel, in the same framing
//! ([`Command`], [`encode_command`], [`CommandDecoder`]).
//!
//! # Frame format
//!
//! Little-endian throughout; `f32` is IEEE 754 binary32.
//!
//! | offset    | bytes | field |
//! |-----------|-------|-------|
//! | 0         | 2     | sync: `0xF1 0x5E` |
//! | 2         | 1     | kind: 1 Sample, 2 Dropped, 3 Fault, 4 Info, 5 Tracking |
//! | 3         | 1     | `len`: payload length in bytes |
//! | 4         | `len` | payload |
//! | 4 + `len` | 2     | CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor) over kind, `len` and payload |
//!
//! Payloads:
//!
//! - **Sample**, `len` = 13 + 8 N for N = 1..=8 segments ([`frame_len`]):
//!   `seq` u32, `t_us` u32 (µs since start), `force_n` f32 (blocking force,
//!   N), `flags` u8 ([`SampleFlags`]: the limiter clamped or slewed a
//!   voltage, a tare is under way, a fault is latched, a program runs),
//!   then N segment voltages f32 (V, as commanded), then N segment
//!   currents f32 (A).
//! - **Dropped**, `len` = 8: `first_seq` u32, `count` u32. The firmware
//!   could not send the Samples numbered `first_seq .. first_seq + count`.
//! - **Fault**, `len` = 10: `seq` u32, `t_us` u32, `code` u8 (1 overcurrent,
//!   2 ADC saturation, 3 missed deadline, 4 watchdog or other, 5 a supply
//!   out of range at boot), `segment` u8
//!   (0-based segment index, below 8; 0xFF if no segment is concerned).
//! - **Info**, `len` = 62 ([`Info`]): layout version u8 (3), firmware
//!   version u8 × 3, git hash u32 (its first eight hex digits), segments u8,
//!   DAC1's and DAC2's segment u8 (0xFF none), `sample_hz` u32, the
//!   calibration (20 bytes, [`Calibration`]: `newtons_per_count` f32, then
//!   8 shunt zeros u16, counts), `amps_per_count` f32, `max_abs_v` f32
//!   (the limit in force), `slew_v_per_s` f32, `bridge_supply_v` f32,
//!   `overcurrent_a` f32, the calibration's origin u8
//!   ([`CalibrationOrigin`]), reset cause u8 ([`ResetCause`]), the model
//!   u8 (0 none, 1 held) and its record's CRC-16 u16 (0 without one), then
//!   a CRC-16 of the configuration (segments to `overcurrent_a`) u16. Sent
//!   before the first Sample, on request, and after a SetCalibration or a
//!   SetModel; it takes no sequence number.
//! - **Tracking**, `len` = 5 + 8 N ([`Tracking`]): `t_us` u32, `flags` u8
//!   ([`TrackingFlags`]: a correction at the tracker's bound, an amplitude
//!   held at the voltage limit), then N gains f32 and N phases f32
//!   (degrees): the gain tracker's correction of each segment's voltage
//!   phasor, sent at the end of each period of a tracked motion. It takes
//!   no sequence number; one the up channel has no room for is not sent
//!   (the next period's says the same, newer).
//!
//! # Commands (down channel)
//!
//! Host commands to the firmware use the same framing (sync, kind, `len`,
//! payload, CRC-16 over kind, `len` and payload) with kinds from 0x81, so
//! that a command can never be mistaken for an up-channel frame:
//!
//! | kind | command | `len` | payload |
//! |------|---------|-------|---------|
//! | 0x81 | SetWave | 25, 29, 45, 57 or 85 | program kind u8 (1 Travelling, 2 Standing, 3 Steps, 4 Pulses, 5 Chirp, 6 Harmonic, 7 HeldStep), the program's f32 fields in declaration order, then the envelope's `ramp_in_s`, `hold_s` (may be +inf), `ramp_out_s` f32 |
//! | 0x82 | Tare | 0 | |
//! | 0x83 | Stop | 0 | |
//! | 0x84 | SetLimit | 4 | `max_abs_v` f32 (may only lower the limit) |
//! | 0x85 | ClearFault | 0 | |
//! | 0x86 | RequestInfo | 0 | |
//! | 0x87 | SetCalibration | 20 | [`Calibration`]: `newtons_per_count` f32, 8 shunt zeros u16 (counts); the board stores it in flash |
//! | 0x88 | SetModel | 254 | [`ModelRecord`]: layout version u8 (3), flags u8, 63 f32 (the fitted [`StripModel`]); the board stores it and shapes motions with it |
//! | 0x89 | SetMotion | 30 | motion kind u8 (1 Travelling: `tip_amp_m`, `frequency_hz`, `lag_deg_per_segment` f32; 2 Step: `tip_m` f32, then 8 zero bytes; 3 Force: `force_amp_n`, `frequency_hz`, `lag_deg_per_segment` f32), then the envelope's three f32, `t_session_s` f32 (the motion's start on the drying law's clock; NaN unknown), then tracked u8 (0 feed-forward only, 1 held by the gain tracker) |
//!
//! SetWave's length is fixed per program kind: Travelling (`amplitude_v`,
//! `frequency_hz`, `lag_deg_per_segment`, `offset_v`) and Chirp
//! (`amplitude_v`, `start_hz`, `end_hz`, `duration_s`) 29; Standing
//! (`amplitude_v`, `frequency_hz`, `offset_v`) and Pulses (`amplitude_v`,
//! `on_s`, `off_s`) 25; Steps (8 levels, V) 45; HeldStep (8 levels, V,
//! `rise_s`, `pole_per_s`, `zero_per_s`, which may be +inf) 57; Harmonic (`frequency_hz`,
//! `offset_v`, 8 amplitudes, V, 8 phases, degrees) 85, longer than the
//! board's 64-byte RTT down buffer: the host writes it as the buffer
//! drains, and the decoder takes it in pieces (as it takes SetModel).
//! [`CommandDecoder`] checks
//! the framing only and reports what it refuses ([`CommandError`]); the
//! firmware's controller checks the values.
//!
//! # Sequence numbers
//!
//! Every Sample takes the next sequence number (wrapping at 2³²), whether it
//! is sent or not: a Sample the firmware has to drop still consumes its
//! number, so that the host sees the hole. The firmware reports dropped
//! Samples in one Dropped frame sent before the next Sample it does send; a
//! hole that no Dropped frame covers is reported by the decoder as
//! [`Event::Gap`]. A Fault carries the number of the Sample being produced
//! when it happened and consumes none.
//!
//! # Resynchronisation
//!
//! The decoder looks for the sync pair, checks kind and `len`, then the CRC.
//! When a check fails it discards only the first sync byte and searches on
//! from the next byte, so a corrupted frame never hides a good one that
//! follows it, not even one within the length a corrupted `len` claims.
//! Discarded bytes are reported as one [`Event::Corrupt`] just before the
//! next good frame (or by [`Decoder::finish`]), so the events do not depend
//! on how the stream was split into chunks.
//!
//! ```
//! use finrs_frames::{encode_sample, Decoder, Event, Sample, SampleFlags, MAX_FRAME_LEN};
//!
//! let s = Sample::<3> {
//!     seq: 7,
//!     t_us: 7_000,
//!     force_n: 0.029,
//!     flags: SampleFlags(SampleFlags::RUNNING),
//!     voltages_v: [2.0, 1.0, -2.0],
//!     currents_a: [0.019, 0.010, -0.019],
//! };
//! let mut buf = [0u8; MAX_FRAME_LEN];
//! let len = encode_sample(&s, &mut buf).unwrap();
//!
//! let mut decoder = Decoder::new();
//! let mut got = None;
//! decoder.push(&buf[..len], &mut |e| {
//!     if let Event::Sample(d) = e {
//!         got = Some(d);
//!     }
//! });
//! let d = got.unwrap();
//! assert_eq!((d.seq, d.n, d.voltages()), (7, 3, &[2.0, 1.0, -2.0][..]));
//! assert!(d.flags.has(SampleFlags::RUNNING));
//! assert_eq!(decoder.stats().samples, 1);
//! ```
#![no_std]
#![deny(missing_docs, unsafe_code)]

mod calibration;
mod command;
mod crc;
mod decode;
mod encode;
mod info;
mod model;
mod tracking;

pub use calibration::{Calibration, CalibrationOrigin, CALIBRATION_LEN};
pub use command::{
    encode_command, Command, CommandDecoder, CommandError, CommandEvent, Motion, MAX_COMMAND_LEN,
};
pub use crc::crc16;
pub use decode::{DecodedSample, Decoder, Event, Stats};
pub use encode::{encode_dropped, encode_fault, encode_sample, EncodeError};
pub use info::{encode_info, Info, ResetCause};
pub use model::{
    ModelFormatError, ModelRecord, StripModel, MODEL_FIELDS, MODEL_FIELD_NAMES, MODEL_FORMAT,
    MODEL_RECORD_LEN,
};
pub use tracking::{encode_tracking, Tracking, TrackingFlags};

/// The two bytes that start every frame.
pub const SYNC: [u8; 2] = [0xF1, 0x5E];

/// Most segments a Sample carries.
pub const MAX_SEGMENTS: usize = 8;

/// Sync, kind and `len`.
pub const HEADER_LEN: usize = 4;

/// The CRC after the payload.
pub const CRC_LEN: usize = 2;

/// Length of a whole Sample frame with `n` segments (`n` = 1..=8 in a valid
/// frame).
pub const fn frame_len(n: usize) -> usize {
    // Saturating so that no argument can make this panic.
    sample_payload_len(n).saturating_add(HEADER_LEN + CRC_LEN)
}

/// Longest frame: a Sample with [`MAX_SEGMENTS`] segments.
pub const MAX_FRAME_LEN: usize = frame_len(MAX_SEGMENTS);

/// Length of a whole Dropped frame.
pub const DROPPED_FRAME_LEN: usize = HEADER_LEN + DROPPED_PAYLOAD_LEN + CRC_LEN;

/// Length of a whole Fault frame.
pub const FAULT_FRAME_LEN: usize = HEADER_LEN + FAULT_PAYLOAD_LEN + CRC_LEN;

/// Length of a whole Tracking frame with `n` segments (1..=8).
pub const fn tracking_frame_len(n: usize) -> usize {
    tracking::tracking_payload_len(n).saturating_add(HEADER_LEN + CRC_LEN)
}

// The decoder's buffer holds the longest frame: a Sample's.
const _: () = assert!(tracking_frame_len(MAX_SEGMENTS) <= MAX_FRAME_LEN);

/// Length of a whole Info frame.
pub const INFO_FRAME_LEN: usize = HEADER_LEN + info::INFO_PAYLOAD_LEN + CRC_LEN;

const KIND_SAMPLE: u8 = 1;
const KIND_DROPPED: u8 = 2;
const KIND_FAULT: u8 = 3;
const KIND_INFO: u8 = 4;
const KIND_TRACKING: u8 = 5;

const SAMPLE_FIXED_LEN: usize = 13;
const DROPPED_PAYLOAD_LEN: usize = 8;
const FAULT_PAYLOAD_LEN: usize = 10;
const NO_SEGMENT: u8 = 0xFF;

const fn sample_payload_len(n: usize) -> usize {
    SAMPLE_FIXED_LEN.saturating_add(n.saturating_mul(8))
}

/// Whether `len` is a valid payload length for `kind` (false for an unknown
/// kind).
const fn payload_len_ok(kind: u8, len: usize) -> bool {
    match kind {
        KIND_SAMPLE => {
            len >= sample_payload_len(1)
                && len <= sample_payload_len(MAX_SEGMENTS)
                && (len - SAMPLE_FIXED_LEN) % 8 == 0
        }
        KIND_DROPPED => len == DROPPED_PAYLOAD_LEN,
        KIND_FAULT => len == FAULT_PAYLOAD_LEN,
        KIND_INFO => len == info::INFO_PAYLOAD_LEN,
        KIND_TRACKING => {
            len >= tracking::tracking_payload_len(1)
                && len <= tracking::tracking_payload_len(MAX_SEGMENTS)
                && (len - tracking::TRACKING_FIXED_LEN) % 8 == 0
        }
        _ => false,
    }
}

/// What the firmware was doing in a sample period, one bit each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SampleFlags(pub u8);

impl SampleFlags {
    /// The program asked for more than the voltage limit on a segment, and
    /// the limiter clamped it.
    pub const LIMITED: u8 = 1 << 0;
    /// The limiter held a segment's step to the slew limit.
    pub const SLEWED: u8 = 1 << 1;
    /// A tare is under way: the force is relative to the previous zero
    /// (or, before the first tare, to the first reading).
    pub const TARING: u8 = 1 << 2;
    /// A fault is latched: every output is 0 V.
    pub const FAULT: u8 = 1 << 3;
    /// A program drives the outputs (not stopped, not waiting for the
    /// power-up tare, no fault).
    pub const RUNNING: u8 = 1 << 4;

    /// Whether every bit of `bits` is set.
    pub const fn has(self, bits: u8) -> bool {
        self.0 & bits == bits
    }
}

/// One sample period of the blocking-force experiment, `N` = 1..=8 segments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const N: usize> {
    /// Sequence number.
    pub seq: u32,
    /// Time since start, µs.
    pub t_us: u32,
    /// Blocking force on the load cell, N.
    pub force_n: f32,
    /// What the firmware was doing.
    pub flags: SampleFlags,
    /// Segment voltages as commanded, V.
    pub voltages_v: [f32; N],
    /// Segment currents, A.
    pub currents_a: [f32; N],
}

/// In-band report of Samples the firmware could not send.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Dropped {
    /// Sequence number of the first dropped Sample.
    pub first_seq: u32,
    /// How many consecutive Samples were dropped, from `first_seq` on.
    pub count: u32,
}

/// A fault the firmware detected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Fault {
    /// Sequence number of the Sample being produced when it happened.
    pub seq: u32,
    /// Time since start, µs.
    pub t_us: u32,
    /// What happened.
    pub code: FaultCode,
    /// The 0-based segment concerned (below [`MAX_SEGMENTS`]), if any.
    pub segment: Option<u8>,
}

/// What a [`Fault`] reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FaultCode {
    /// A segment drew more current than allowed.
    Overcurrent = 1,
    /// The ADC read its full-scale value.
    AdcSaturation = 2,
    /// A sample period's work did not finish in time.
    MissedDeadline = 3,
    /// The watchdog fired, or another fault.
    Other = 4,
    /// A supply (VDDA, the bridges') was out of range at boot: the board
    /// does not drive until it restarts with good supplies.
    Supply = 5,
}

impl FaultCode {
    /// The code for its wire value, `None` if unknown.
    pub const fn from_u8(code: u8) -> Option<Self> {
        match code {
            1 => Some(Self::Overcurrent),
            2 => Some(Self::AdcSaturation),
            3 => Some(Self::MissedDeadline),
            4 => Some(Self::Other),
            5 => Some(Self::Supply),
            _ => None,
        }
    }
}
