//! The camera's sync mark: an LED the firmware lights when a drive starts
//! after a rest, for the camera to see and `finrs merge-camera` to align
//! its frames to the recording's rows (the recording's own mark is the
//! same onset in its voltage columns, at the same threshold).
//!
//! Lit on the first period whose applied voltage exceeds [`ONSET_V`] on any
//! segment after at least [`ARM_PERIODS`] periods below it on all, and
//! held for [`LIT_PERIODS`]: a recording opens with at least 1 s at rest
//! (the format's rule), so each recording's wave lights it once, and a
//! wave's own zero crossings (a sine on one segment) do not.
//!
//! ```
//! use finrs_firmware_support::sync::{SyncMark, LIT_PERIODS};
//!
//! let mut mark = SyncMark::new();
//! assert!(!mark.update(&[0.0, 0.0]).lit);
//! let first = mark.update(&[0.5, 0.0]);
//! assert!(first.lit && first.onset);
//! // Held, then dark while the drive goes on.
//! for _ in 1..LIT_PERIODS {
//!     assert!(mark.update(&[0.5, 0.0]).lit);
//! }
//! assert!(!mark.update(&[0.5, 0.0]).lit);
//! ```

use crate::config::SAMPLE_HZ;

/// A drive above this magnitude on any segment has started, V: the rule
/// `finrs merge-camera` applies to the recording's voltage columns.
pub const ONSET_V: f32 = 0.05;

/// Periods at rest (every segment at or below [`ONSET_V`]) that arm the
/// mark: half a second, shorter than any recording's opening rest and
/// longer than a wave's zero crossing stays below the threshold (a 1 Hz,
/// 2.5 V sine: 6 ms). A sine slower than `0.03/A` Hz at amplitude `A` V
/// lingers longer and is marked at each crossing; `finrs merge-camera`
/// takes the first mark.
pub const ARM_PERIODS: u32 = SAMPLE_HZ / 2;

/// Periods the LED stays lit: 100 ms, three frames of a 30 frames/s
/// camera, so that every camera sees it in at least two whole frames.
pub const LIT_PERIODS: u32 = SAMPLE_HZ / 10;

/// What one period does to the mark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mark {
    /// The LED is lit this period.
    pub lit: bool,
    /// It was lit at this period, the drive's onset.
    pub onset: bool,
}

/// The mark's state: periods at rest so far, and periods still to light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncMark {
    quiet: u32,
    lit_left: u32,
}

impl Default for SyncMark {
    fn default() -> Self {
        Self::new()
    }
}

impl SyncMark {
    /// Armed: a board boots at rest, and its first wave is marked.
    pub const fn new() -> Self {
        Self {
            quiet: ARM_PERIODS,
            lit_left: 0,
        }
    }

    /// One period with `applied` on the segments, V (what the outputs
    /// drive: 0 where they are off).
    pub fn update(&mut self, applied: &[f32]) -> Mark {
        let driving = applied.iter().any(|v| v.abs() > ONSET_V);
        let onset = driving && self.quiet >= ARM_PERIODS;
        if onset {
            self.lit_left = LIT_PERIODS;
        }
        self.quiet = if driving {
            0
        } else {
            self.quiet.saturating_add(1)
        };
        let lit = self.lit_left > 0;
        self.lit_left = self.lit_left.saturating_sub(1);
        Mark { lit, onset }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    extern crate std;
    use std::vec::Vec;

    /// Periods at which the mark's onset fired, and how many were lit.
    fn run(volts: impl Iterator<Item = f32>) -> (Vec<usize>, u32) {
        let mut mark = SyncMark::new();
        let mut onsets = Vec::new();
        let mut lit = 0;
        for (k, v) in volts.enumerate() {
            let m = mark.update(&[0.0, v, 0.0]);
            if m.onset {
                onsets.push(k);
            }
            lit += u32::from(m.lit);
        }
        (onsets, lit)
    }

    #[test]
    fn a_recording_of_rest_then_sine_is_marked_once_at_its_onset() {
        // 1.2 s at rest, then a 1 Hz, 2.5 V sine on one segment for 4 s:
        // four periods of zero crossings, then 2 s at rest.
        let volts = (0..7200).map(|k| {
            let t = k as f32 / SAMPLE_HZ as f32;
            if (1.2..5.2).contains(&t) {
                2.5 * (2.0 * core::f32::consts::PI * (t - 1.2)).sin()
            } else {
                0.0
            }
        });
        let (onsets, lit) = run(volts);
        // The sine's first sample is 0 V: it passes 0.05 V at its 4th
        // period (2.5 sin(2π·0.003) = 0.047, ·0.004 = 0.063).
        assert_eq!(onsets, [1204]);
        assert_eq!(lit, LIT_PERIODS);
    }

    #[test]
    fn each_recording_after_a_rest_is_marked_and_a_short_pause_is_not() {
        let step =
            |on: core::ops::Range<usize>| move |k: usize| if on.contains(&k) { 1.0 } else { 0.0 };
        // Two steps 1 s apart, then one 0.2 s after the second ends.
        let a = step(1000..2000);
        let b = step(3000..4000);
        let c = step(4200..4500);
        let (onsets, lit) = run((0..5000).map(|k| a(k) + b(k) + c(k)));
        assert_eq!(onsets, [1000, 3000]);
        assert_eq!(lit, 2 * LIT_PERIODS);
    }

    #[test]
    fn a_negative_drive_is_a_drive_and_the_threshold_is_strict() {
        let mut mark = SyncMark::new();
        assert!(!mark.update(&[ONSET_V, -ONSET_V]).lit);
        assert!(mark.update(&[0.0, -0.06]).onset);
        // Not re-armed while driving, however long.
        let mut again = 0;
        for _ in 0..10 * ARM_PERIODS {
            again += u32::from(mark.update(&[-1.0, 0.0]).onset);
        }
        assert_eq!(again, 0);
    }
}
