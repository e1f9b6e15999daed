//! The camera's side of a free recording: a tracker's CSV of dot positions
//! ([`track`]) merged into the DAQ's recording ([`merge`]).

pub mod merge;
pub mod track;
