//! A recording in memory: metadata, time, drive and measured channels.

use super::channel::Channel;
use super::meta::Metadata;
use super::voltages::Voltages;

/// The seed's Nafion samples' safe range, V: no valid recording exceeds it.
pub const SAFE_VOLTAGE_LIMIT_V: f64 = 4.0;

/// One run of one sample: metadata, time, drive and measured channels.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The `# key = value` lines.
    pub meta: Metadata,
    /// Time of every row, s, strictly increasing from ≥ 0.
    pub t_s: Vec<f64>,
    /// Voltage per row and segment, V (`v_v[row][segment]`), never missing;
    /// as many segments as `meta.segments`.
    pub v_v: Voltages,
    /// Measured channels in header order; `None` where not sampled.
    pub channels: Vec<(Channel, Vec<Option<f64>>)>,
}

impl Recording {
    /// The values of channel `ch`, if the recording has it.
    pub fn channel(&self, ch: Channel) -> Option<&[Option<f64>]> {
        self.channels
            .iter()
            .find(|(c, _)| *c == ch)
            .map(|(_, v)| v.as_slice())
    }
}
