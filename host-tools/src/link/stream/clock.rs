//! The firmware's `t_us` counter, unwrapped into a time that only grows.

/// Microseconds in one turn of the firmware's 32-bit `t_us` counter
/// (2³² µs ≈ 71.6 min).
pub const WRAP_US: u64 = 1 << 32;

/// Unwraps the 32-bit `t_us` of successive Samples into a 64-bit time.
///
/// The counter wraps every [`WRAP_US`]; two successive Samples are far less
/// than half a turn (35.8 min) apart, so the forward distance between them
/// is `t_us.wrapping_sub(previous)`, whether or not the counter wrapped in
/// between. A distance of half a turn or more means the time went back, and
/// a distance of zero that it stood still: both are refused, so that the
/// unwrapped time stays strictly increasing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Clock {
    last: Option<(u32, u64)>,
}

/// Why a `t_us` was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockError {
    /// The same `t_us` as the previous Sample.
    Stalled {
        /// The previous Sample's `t_us`.
        previous_us: u32,
    },
    /// A `t_us` before the previous Sample's.
    Backwards {
        /// The previous Sample's `t_us`.
        previous_us: u32,
    },
}

impl Clock {
    /// A clock that has seen no Sample yet.
    pub const fn new() -> Self {
        Clock { last: None }
    }

    /// The unwrapped time of a Sample stamped `t_us`, µs; the clock moves to
    /// it only if it is accepted.
    pub fn unwrap(&mut self, t_us: u32) -> Result<u64, ClockError> {
        let full = match self.last {
            // The first Sample's counter has not wrapped as far as we know.
            None => u64::from(t_us),
            Some((previous_us, previous_full)) => {
                let ahead = t_us.wrapping_sub(previous_us);
                if ahead == 0 {
                    return Err(ClockError::Stalled { previous_us });
                }
                if ahead >= 1 << 31 {
                    return Err(ClockError::Backwards { previous_us });
                }
                previous_full + u64::from(ahead)
            }
        };
        self.last = Some((t_us, full));
        Ok(full)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_forward_across_the_32_bit_turn() {
        let mut c = Clock::new();
        assert_eq!(c.unwrap(u32::MAX - 999), Ok(WRAP_US - 1000));
        // 1000 µs later the counter reads 0.
        assert_eq!(c.unwrap(0), Ok(WRAP_US));
        assert_eq!(c.unwrap(1000), Ok(WRAP_US + 1000));
        // A second turn, in steps under half a turn, adds another WRAP_US.
        assert_eq!(c.unwrap(1 << 31), Ok(WRAP_US + (1 << 31)));
        assert_eq!(c.unwrap(u32::MAX), Ok(2 * WRAP_US - 1));
        assert_eq!(c.unwrap(5), Ok(2 * WRAP_US + 5));
    }

    #[test]
    fn refuses_time_that_stands_still_or_goes_back() {
        let mut c = Clock::new();
        assert_eq!(c.unwrap(5000), Ok(5000));
        assert_eq!(
            c.unwrap(5000),
            Err(ClockError::Stalled { previous_us: 5000 })
        );
        assert_eq!(
            c.unwrap(4000),
            Err(ClockError::Backwards { previous_us: 5000 })
        );
        // A refused stamp does not move the clock.
        assert_eq!(c.unwrap(6000), Ok(6000));
    }
}
