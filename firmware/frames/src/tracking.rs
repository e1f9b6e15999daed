//! The Tracking frame: the gain tracker's correction of a shaped motion
//! (`finrs_controller::tracker`), once per period of the wave.

use crate::encode::{EncodeError, Writer};
use crate::{KIND_TRACKING, MAX_SEGMENTS};

/// Fixed part of a Tracking payload: `t_us` u32 and the flags u8.
pub(crate) const TRACKING_FIXED_LEN: usize = 5;

/// Length of a Tracking payload for `n` segments.
pub(crate) const fn tracking_payload_len(n: usize) -> usize {
    TRACKING_FIXED_LEN.saturating_add(n.saturating_mul(8))
}

/// What limited a correction, one bit each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TrackingFlags(pub u8);

impl TrackingFlags {
    /// A segment's correction reached the tracker's bound (a strip that
    /// far from its model is not tracked further: refit it).
    pub const BOUNDED: u8 = 1 << 0;
    /// A segment's corrected amplitude reached the voltage limit and was
    /// held at it: the motion is then smaller than asked.
    pub const AT_LIMIT: u8 = 1 << 1;

    /// Whether every bit of `bits` is set.
    pub const fn has(self, bits: u8) -> bool {
        self.0 & bits == bits
    }
}

/// The gain tracker's correction at the end of a period of the wave: each
/// segment's voltage phasor is the (undried) model's times `gains[k] ·
/// e^{j phases_deg[k]}`: the ratio of the model's admittance to the one
/// measured (if tracked), times the drying law's `1/g(t)` (if the model
/// dries).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tracking {
    /// Time since start, µs.
    pub t_us: u32,
    /// What limited the correction.
    pub flags: TrackingFlags,
    /// Segment count, 1..=8.
    pub n: usize,
    /// Each segment's gain on the model's voltage amplitude; entries from
    /// `n` on are zero.
    pub gains: [f32; MAX_SEGMENTS],
    /// Each segment's phase added to the model's voltage, degrees (ahead
    /// for a positive one); entries from `n` on are zero.
    pub phases_deg: [f32; MAX_SEGMENTS],
}

/// Writes `t` as a Tracking frame at the start of `out`; returns the
/// frame's length. A segment count outside 1..=8 is refused.
pub fn encode_tracking(t: &Tracking, out: &mut [u8]) -> Result<usize, EncodeError> {
    if !(1..=MAX_SEGMENTS).contains(&t.n) {
        return Err(EncodeError::BadSegment(t.n as u8));
    }
    let mut w = Writer::start(out, KIND_TRACKING, tracking_payload_len(t.n))?;
    w.put(&t.t_us.to_le_bytes());
    w.put(&[t.flags.0]);
    for v in t.gains[..t.n].iter().chain(&t.phases_deg[..t.n]) {
        w.put(&v.to_le_bytes());
    }
    Ok(w.finish())
}

/// The Tracking in a payload whose kind, length and CRC have checked.
pub(crate) fn parse_tracking(p: &[u8]) -> Tracking {
    let f32_at = |i: usize| f32::from_le_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
    let n = (p.len() - TRACKING_FIXED_LEN) / 8;
    let mut t = Tracking {
        t_us: u32::from_le_bytes([p[0], p[1], p[2], p[3]]),
        flags: TrackingFlags(p[4]),
        n,
        gains: [0.0; MAX_SEGMENTS],
        phases_deg: [0.0; MAX_SEGMENTS],
    };
    for k in 0..n {
        t.gains[k] = f32_at(TRACKING_FIXED_LEN + 4 * k);
        t.phases_deg[k] = f32_at(TRACKING_FIXED_LEN + 4 * (n + k));
    }
    t
}
