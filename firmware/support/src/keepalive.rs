//! The bridges' keep-alive (#50): a pin that only a running sample task
//! moves, into a retriggerable monostable whose output holds the DRV8833s'
//! nSLEEP high (firmware/BOARD.md, "Lock-up"). The task writes the level
//! [`Keepalive::level`] gives every period: it flips while the board is
//! healthy, so the monostable sees a rising edge every second period, and
//! it rests low while a fault is latched. A core that stops (a stack
//! overflow that locks it up, a halt, a task that never returns) leaves the
//! pin still; the monostable's pulse then ends, nSLEEP falls and the
//! bridges' outputs open, well before the watchdog resets the core. The
//! timers alone cannot keep it alive: they run on while the core is locked.
//!
//! ```
//! use finrs_firmware_support::keepalive::Keepalive;
//!
//! let mut k = Keepalive::new();
//! let levels: Vec<bool> = (0..4).map(|_| k.level(true)).collect();
//! assert_eq!(levels, [true, false, true, false]);
//! // A latched fault: low, and no edge while it lasts.
//! assert!((0..3).all(|_| !k.level(false)));
//! // Cleared: edges again.
//! assert!(k.level(true));
//! ```

use crate::config::SAMPLE_HZ;

/// Sample periods between the keep-alive's rising edges while healthy.
pub const EDGE_PERIODS: u32 = 2;

/// The monostable's pulse, s, that BOARD.md's parts set: long enough to
/// hold through one period that overruns by a period (a missed deadline
/// is latched, and then the pin rests anyway), short against the
/// watchdog's 13.6 ms at its fastest (a locked core drives that long at
/// most without it).
pub const PULSE_S: f32 = 5e-3;

/// Rising edges come at least this often while healthy, s.
pub const EDGE_EVERY_S: f32 = EDGE_PERIODS as f32 / SAMPLE_HZ as f32;

// A pulse that ended between two edges of a healthy board would open the
// bridges while it runs.
const _: () = assert!(PULSE_S > 2.0 * EDGE_EVERY_S);

/// The keep-alive pin's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Keepalive {
    high: bool,
}

impl Keepalive {
    /// Low, as the pin comes out of reset.
    pub const fn new() -> Self {
        Self { high: false }
    }

    /// The pin's level for this period: flipped while `healthy` (no fault
    /// latched), low otherwise.
    pub fn level(&mut self, healthy: bool) -> bool {
        self.high = healthy && !self.high;
        self.high
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// Whether a monostable of `pulse_periods` holds nSLEEP high at each
    /// period, the pin written from `healthy` until `stop` (then still).
    fn awake(healthy: &[bool], stop: usize, pulse_periods: u32) -> Vec<bool> {
        let mut k = Keepalive::new();
        let (mut pin, mut since) = (false, u32::MAX);
        healthy
            .iter()
            .enumerate()
            .map(|(i, &h)| {
                let now = if i < stop { k.level(h) } else { pin };
                since = if now && !pin {
                    0
                } else {
                    since.saturating_add(1)
                };
                pin = now;
                since < pulse_periods
            })
            .collect()
    }

    fn pulse_periods() -> u32 {
        (PULSE_S * SAMPLE_HZ as f32) as u32
    }

    #[test]
    fn a_healthy_board_keeps_the_bridges_awake_and_a_fault_lets_them_sleep() {
        let pulse = pulse_periods() as usize;
        let mut run = [true; 40];
        run[20..30].fill(false);
        let a = awake(&run, run.len(), pulse as u32);
        assert!(a[..20].iter().all(|&x| x), "{a:?}");
        assert!(a[20 + pulse..30].iter().all(|&x| !x), "{a:?}");
        assert!(a[30..].iter().all(|&x| x), "{a:?}");
    }

    #[test]
    fn a_task_that_stops_lets_them_sleep_within_a_pulse_and_an_edge() {
        let pulse = pulse_periods() as usize;
        // Stopped at every phase of the pin, high or low.
        for stop in 10..10 + 2 * EDGE_PERIODS as usize {
            let a = awake(&[true; 40], stop, pulse as u32);
            let asleep_from = stop + pulse + EDGE_PERIODS as usize - 1;
            assert!(a[..stop].iter().all(|&x| x));
            assert!(a[asleep_from..].iter().all(|&x| !x), "stop {stop}: {a:?}");
        }
    }
}
