//! Why the recorder refused a Sample that decoded: the field and the rule
//! it breaks, as the refusal list and the recording's notes say it.

use crate::recording::SAFE_VOLTAGE_LIMIT_V;

/// A Sample that decoded but cannot be a row of a valid recording.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// Another segment count than the first Sample's.
    #[error("segment count {got} differs from the first Sample's {first}")]
    SegmentCount {
        /// This Sample's.
        got: usize,
        /// The first accepted Sample's.
        first: usize,
    },
    /// NaN or infinite in a column (`force_N`, `v2_V`, `i1_A`, …).
    #[error("{column} = {value} is not a finite number")]
    NotFinite {
        /// The recording's column name.
        column: String,
        /// What the Sample carried.
        value: f32,
    },
    /// A voltage beyond [`SAFE_VOLTAGE_LIMIT_V`].
    #[error("{column} = {value_v} V is beyond the safe range of ±{SAFE_VOLTAGE_LIMIT_V} V")]
    Unsafe {
        /// The recording's column name (`v1_V`, …).
        column: String,
        /// What the Sample carried, V.
        value_v: f32,
    },
    /// The same `t_us` as the previous Sample.
    #[error("t_us = {t_us} equals the previous Sample's; time must increase")]
    Stalled {
        /// This Sample's counter, µs.
        t_us: u32,
    },
    /// A `t_us` before the previous Sample's.
    #[error("t_us = {t_us} is before the previous Sample's {previous_us}; time must increase")]
    Backwards {
        /// This Sample's counter, µs.
        t_us: u32,
        /// The previous Sample's counter, µs.
        previous_us: u32,
    },
}
