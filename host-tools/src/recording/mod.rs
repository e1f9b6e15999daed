//! Reading and writing recordings in the `ipmc-bench/1` format
//! (`docs/FORMAT.md`).
//!
//! Every rule of the format is enforced on reading, and again before
//! writing: a refusal names the file, the line (1-based, as an editor shows
//! it) and the rule. Nothing is guessed, nothing is dropped. A UTF-8 byte
//! order mark at the start is accepted and ignored; `\r\n` line ends are
//! accepted.
//!
//! Beyond the contract's explicit list we enforce what its prose implies
//! (`docs/FORMAT.md` states these rules too):
//! camera columns (`tip_*`, `dot*`) belong to the free fixture and
//! `force_N` to the blocked one (the load cell holds the tip there), and
//! unknown metadata keys are refused like unknown columns.

mod channel;
mod data;
mod error;
mod float;
mod geometry;
mod meta;
mod output;
mod plain_row;
mod read;
mod rest;
mod timing;
mod voltages;
mod write;

pub use channel::Channel;
pub use data::{Recording, SAFE_VOLTAGE_LIMIT_V};
pub use error::RecordingError;
pub use float::{max_written_error, MEASURED_DECIMALS, MEASURED_QUANTUM};
pub use geometry::Geometry;
pub use meta::{Fixture, Medium, Metadata, FORMAT};
pub use rest::{RestReading, REST_BAND_LIMIT_V, REST_OPENING_S, REST_SIGMAS};
pub use timing::SampleTimeError;
pub use voltages::Voltages;
pub use write::{Column, RecordingView, Streamed};
