//! The Info frame: what the firmware is and how it is set up, so that a
//! recording says which firmware, configuration and reset made it.

use crate::calibration::{Calibration, CalibrationOrigin, CALIBRATION_LEN};
use crate::encode::{EncodeError, Writer};
use crate::{crc16, KIND_INFO, MAX_SEGMENTS, NO_SEGMENT};

/// Payload length of an Info frame.
pub(crate) const INFO_PAYLOAD_LEN: usize = 62;

/// Why the core last reset, as the firmware read it at boot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum ResetCause {
    /// No reset flag was set (flags cleared and no reset since, or an
    /// emulator that has none).
    Unknown = 0,
    /// Power-on or power-down.
    PowerOn = 1,
    /// Brown-out: the supply fell below its threshold.
    BrownOut = 2,
    /// The reset pin alone: a button or a debug probe's reset line.
    Pin = 3,
    /// Software: a probe's or the firmware's own reset request.
    Software = 4,
    /// The independent watchdog: the firmware hung.
    Watchdog = 5,
    /// The window watchdog.
    WindowWatchdog = 6,
    /// Low-power management: an illegal entry into Stop or Standby.
    LowPower = 7,
}

impl ResetCause {
    /// The cause for its wire value, `None` if unknown.
    pub const fn from_u8(code: u8) -> Option<Self> {
        Some(match code {
            0 => Self::Unknown,
            1 => Self::PowerOn,
            2 => Self::BrownOut,
            3 => Self::Pin,
            4 => Self::Software,
            5 => Self::Watchdog,
            6 => Self::WindowWatchdog,
            7 => Self::LowPower,
            _ => return None,
        })
    }

    /// The cause in words.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Unknown => "unknown",
            Self::PowerOn => "power-on",
            Self::BrownOut => "brown-out",
            Self::Pin => "reset pin",
            Self::Software => "software",
            Self::Watchdog => "watchdog",
            Self::WindowWatchdog => "window watchdog",
            Self::LowPower => "low-power management",
        }
    }

    /// Whether the last run ended in a hang or a fault of the firmware's
    /// own (a watchdog or low-power reset).
    pub const fn is_failure(self) -> bool {
        matches!(self, Self::Watchdog | Self::WindowWatchdog | Self::LowPower)
    }
}

/// What the firmware is and how it is set up. Sent before the first Sample
/// and again on request ([`Command::RequestInfo`](crate::Command)); it
/// takes no sequence number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Info {
    /// Firmware version: major, minor, patch.
    pub version: [u8; 3],
    /// The first 32 bits of the git commit it was built from (the first
    /// eight hex digits), 0 if unknown.
    pub git_hash: u32,
    /// Segments driven, 1..=8.
    pub segments: u8,
    /// The segments driven by DAC1 and DAC2 (below [`MAX_SEGMENTS`]), if
    /// any; the others are H-bridges.
    pub dac_segments: [Option<u8>; 2],
    /// Sample rate, Hz.
    pub sample_hz: u32,
    /// Load-cell scale and shunt zeros in force.
    pub calibration: Calibration,
    /// Shunt scale, A per count.
    pub amps_per_count: f32,
    /// The voltage limit in force when the frame was sent, V.
    pub max_abs_v: f32,
    /// The slew limit, V/s.
    pub slew_v_per_s: f32,
    /// The H-bridges' supply, V.
    pub bridge_supply_v: f32,
    /// A segment drawing more than this is a fault, A.
    pub overcurrent_a: f32,
    /// Where the calibration came from.
    pub calibration_origin: CalibrationOrigin,
    /// Why the core last reset.
    pub reset_cause: ResetCause,
    /// The fitted model the board shapes motions with, named by its
    /// record's CRC ([`ModelRecord::crc`](crate::ModelRecord::crc)); `None`
    /// if it holds none.
    pub model_crc: Option<u16>,
}

impl Info {
    /// A CRC-16 of the configuration (every field from `segments` to
    /// `overcurrent_a`, as encoded, the calibration among them): two
    /// recordings with the same value came from the same set-up. The frame
    /// carries it; the decoder checks it.
    pub fn config_crc(&self) -> Option<u16> {
        let mut buf = [0u8; INFO_PAYLOAD_LEN];
        self.payload(&mut buf)?;
        Some(crc16(&buf[CONFIG_AT..CONFIG_END]))
    }

    /// Writes the payload without its trailing config CRC, `None` if a
    /// field cannot be encoded.
    fn payload(&self, p: &mut [u8; INFO_PAYLOAD_LEN]) -> Option<()> {
        if self.segments == 0 || usize::from(self.segments) > MAX_SEGMENTS {
            return None;
        }
        let dac = |d: Option<u8>| match d {
            None => Some(NO_SEGMENT),
            Some(s) if usize::from(s) < MAX_SEGMENTS => Some(s),
            Some(_) => None,
        };
        let mut at = 0;
        let mut put = |bytes: &[u8]| {
            p[at..at + bytes.len()].copy_from_slice(bytes);
            at += bytes.len();
        };
        put(&[FORMAT_VERSION]);
        put(&self.version);
        put(&self.git_hash.to_le_bytes());
        put(&[
            self.segments,
            dac(self.dac_segments[0])?,
            dac(self.dac_segments[1])?,
        ]);
        put(&self.sample_hz.to_le_bytes());
        put(&self.calibration.to_bytes());
        put(&self.amps_per_count.to_le_bytes());
        put(&self.max_abs_v.to_le_bytes());
        put(&self.slew_v_per_s.to_le_bytes());
        put(&self.bridge_supply_v.to_le_bytes());
        put(&self.overcurrent_a.to_le_bytes());
        put(&[self.calibration_origin as u8, self.reset_cause as u8]);
        put(&[u8::from(self.model_crc.is_some())]);
        put(&self.model_crc.unwrap_or(0).to_le_bytes());
        debug_assert_eq!(at + 2, INFO_PAYLOAD_LEN);
        Some(())
    }
}

/// The layout's version, first byte of the payload (2: the calibration,
/// with a zero per segment and its origin; 3: the model's CRC).
const FORMAT_VERSION: u8 = 3;
/// Where the configuration starts in the payload (after the format
/// version, the firmware version and the git hash).
const CONFIG_AT: usize = 8;
/// Where it ends: the origin, the reset cause, the model and the CRC
/// follow.
const CONFIG_END: usize = 55;

/// Writes `info` as an Info frame at the start of `out`; returns the
/// frame's length, [`INFO_FRAME_LEN`](crate::INFO_FRAME_LEN).
pub fn encode_info(info: &Info, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut p = [0u8; INFO_PAYLOAD_LEN];
    info.payload(&mut p).ok_or(EncodeError::BadInfo)?;
    let crc = crc16(&p[CONFIG_AT..CONFIG_END]);
    p[INFO_PAYLOAD_LEN - 2..].copy_from_slice(&crc.to_le_bytes());
    let mut w = Writer::start(out, KIND_INFO, INFO_PAYLOAD_LEN)?;
    w.put(&p);
    Ok(w.finish())
}

/// The Info in a payload whose kind, length and CRC have checked; `None`
/// if its content is invalid (another layout version, a bad field, a
/// config CRC that does not match).
pub(crate) fn parse_info(p: &[u8]) -> Option<Info> {
    if p.len() != INFO_PAYLOAD_LEN || p[0] != FORMAT_VERSION {
        return None;
    }
    let u16_at = |i: usize| u16::from_le_bytes([p[i], p[i + 1]]);
    let u32_at = |i: usize| u32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
    let f32_at = |i: usize| f32::from_bits(u32_at(i));
    let dac = |b: u8| match b {
        NO_SEGMENT => Some(None),
        s if usize::from(s) < MAX_SEGMENTS => Some(Some(s)),
        _ => None,
    };
    let info = Info {
        version: [p[1], p[2], p[3]],
        git_hash: u32_at(4),
        segments: p[8],
        dac_segments: [dac(p[9])?, dac(p[10])?],
        sample_hz: u32_at(11),
        calibration: Calibration::from_bytes(p[15..15 + CALIBRATION_LEN].try_into().ok()?),
        amps_per_count: f32_at(35),
        max_abs_v: f32_at(39),
        slew_v_per_s: f32_at(43),
        bridge_supply_v: f32_at(47),
        overcurrent_a: f32_at(51),
        calibration_origin: CalibrationOrigin::from_u8(p[55])?,
        reset_cause: ResetCause::from_u8(p[56])?,
        model_crc: match p[57] {
            0 if u16_at(58) == 0 => None,
            1 => Some(u16_at(58)),
            _ => return None,
        },
    };
    (info.config_crc()? == u16_at(60)).then_some(info)
}
