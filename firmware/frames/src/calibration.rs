//! The board's calibration: what a bench measures of its own sensors
//! (the load cell's scale, each shunt's zero), as carried by the
//! SetCalibration command, the Info frame and the board's flash record.
//!
//! ```
//! use finrs_frames::{Calibration, CALIBRATION_LEN};
//!
//! let c = Calibration {
//!     newtons_per_count: 2.5e-5,
//!     current_zero_counts: [2048, 2050, 2046, 2048, 2048, 2048, 2048, 2048],
//! };
//! let bytes: [u8; CALIBRATION_LEN] = c.to_bytes();
//! assert_eq!(Calibration::from_bytes(&bytes), c);
//! ```

use crate::MAX_SEGMENTS;

/// Bytes of an encoded [`Calibration`]: the scale f32, then the
/// [`MAX_SEGMENTS`] zeros u16, little-endian.
pub const CALIBRATION_LEN: usize = 4 + 2 * MAX_SEGMENTS;

/// What a bench measures of the board's sensors. Values are carried as
/// given; the firmware's controller checks them (finite non-zero scale,
/// zeros within the ADC's range).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Load-cell scale, N per ADC count (either sign).
    pub newtons_per_count: f32,
    /// Each segment's shunt reading at 0 A, counts; entries at and beyond
    /// the board's segment count are carried but unused.
    pub current_zero_counts: [u16; MAX_SEGMENTS],
}

impl Calibration {
    /// The little-endian bytes: scale, then the zeros in segment order.
    pub fn to_bytes(&self) -> [u8; CALIBRATION_LEN] {
        let mut b = [0u8; CALIBRATION_LEN];
        b[..4].copy_from_slice(&self.newtons_per_count.to_le_bytes());
        for (k, z) in self.current_zero_counts.iter().enumerate() {
            b[4 + 2 * k..6 + 2 * k].copy_from_slice(&z.to_le_bytes());
        }
        b
    }

    /// The calibration in [`to_bytes`](Self::to_bytes)'s layout.
    pub fn from_bytes(b: &[u8; CALIBRATION_LEN]) -> Self {
        Self {
            newtons_per_count: f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            current_zero_counts: core::array::from_fn(|k| {
                u16::from_le_bytes([b[4 + 2 * k], b[5 + 2 * k]])
            }),
        }
    }
}

/// Where the calibration in force came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum CalibrationOrigin {
    /// The build's defaults: no calibration was ever stored (or the stored
    /// one was unreadable).
    Defaults = 0,
    /// Read from the board's flash at boot, or set by the host and stored
    /// there since.
    Stored = 1,
    /// Set by the host but not in flash (the write failed, or the board
    /// has no flash to keep it: QEMU): lost at the next reset.
    Unsaved = 2,
}

impl CalibrationOrigin {
    /// The origin for its wire value, `None` if unknown.
    pub const fn from_u8(code: u8) -> Option<Self> {
        Some(match code {
            0 => Self::Defaults,
            1 => Self::Stored,
            2 => Self::Unsaved,
            _ => return None,
        })
    }

    /// The origin in words.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Defaults => "build defaults",
            Self::Stored => "stored in flash",
            Self::Unsaved => "set by the host, not stored",
        }
    }
}
