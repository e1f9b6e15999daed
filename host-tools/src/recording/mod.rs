//! Reading and writing recordings in the `ipmc-bench/1` format
//! (`shared/bench/FORMAT.md`).
//!
//! Every rule of the format is enforced on reading, and again before
//! writing: a refusal names the file, the line (1-based, as an editor shows
//! it) and the rule. Nothing is guessed, nothing is dropped. A UTF-8 byte
//! order mark at the start is accepted and ignored; `\r\n` line ends are
//! accepted.
//!
//! Beyond FORMAT.md's explicit list we enforce what its prose implies:
//! camera columns (`tip_*`, `dot*`) belong to the free fixture and
//! `force_N` to the blocked one (the load cell holds the tip there), and
//! unknown metadata keys are refused like unknown columns.

mod channel;
mod error;
mod float;
mod meta;
mod read;
mod write;

pub use channel::Channel;
pub use error::RecordingError;
pub use float::{max_written_error, MEASURED_DECIMALS, MEASURED_QUANTUM};
pub use meta::{Fixture, Medium, Metadata, FORMAT};

/// The seed's Nafion samples' safe range, V: no valid recording exceeds it.
pub const SAFE_VOLTAGE_LIMIT_V: f64 = 4.0;

/// One run of one sample: metadata, time, drive and measured channels.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The `# key = value` lines.
    pub meta: Metadata,
    /// Time of every row, s, strictly increasing from ≥ 0.
    pub t_s: Vec<f64>,
    /// Voltage per row and segment, V (`v_v[row][segment]`), never missing.
    pub v_v: Vec<Vec<f64>>,
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
