//! The firmware's force stream turned into a recording: the pure part of
//! `finrs log` and `finrs run`, with no probe in it.
//!
//! Bytes (from the RTT up channel 1, or from a file) go through
//! [`finrs_frames::Decoder`] into a [`Recorder`], which keeps the Samples
//! as rows of an `ipmc-bench/1` blocked recording and accounts for every
//! lost or damaged frame: gaps by sequence number (reported by the
//! firmware or detected here), faults, corrupt bytes, refused Samples and a
//! firmware restart. That account goes into the file's `notes`.
//!
//! ```
//! use finrs::recording::Geometry;
//! use finrs::recording::Medium;
//! use finrs::link::stream::{Recorder, Setup};
//! use finrs_frames::{encode_dropped, encode_sample, Dropped, Sample, SampleFlags, MAX_FRAME_LEN};
//!
//! let mut bytes = Vec::new();
//! let mut buf = [0u8; MAX_FRAME_LEN];
//! for seq in [0u32, 1, 4] {
//!     if seq == 4 {
//!         let n = encode_dropped(&Dropped { first_seq: 2, count: 2 }, &mut buf).unwrap();
//!         bytes.extend_from_slice(&buf[..n]);
//!     }
//!     let s = Sample::<1> {
//!         seq,
//!         t_us: 1000 * seq,
//!         force_n: 0.01,
//!         flags: SampleFlags(SampleFlags::RUNNING),
//!         voltages_v: [1.0],
//!         currents_a: [0.01],
//!     };
//!     let n = encode_sample(&s, &mut buf).unwrap();
//!     bytes.extend_from_slice(&buf[..n]);
//! }
//! let mut rec = Recorder::new(Setup {
//!     geometry: Geometry::THESIS_2006,
//!     medium: Medium::Air,
//!     sample: None,
//!     source: "a doc example".to_string(),
//! });
//! rec.push_bytes(&bytes);
//! rec.finish();
//! let r = rec.recording("example.csv").unwrap();
//! assert_eq!(r.t_s, vec![0.0, 0.001, 0.004]);
//! assert!(r.meta.notes.unwrap().contains("2 samples lost in 1 gaps (first_seq+count): 2+2 reported"));
//! ```

mod clock;
mod recorder;
mod refusal;

pub use clock::{Clock, ClockError, WRAP_US};
pub use recorder::{Gap, GapSource, Recorder, Rejected, Restart, Setup, Summary};
pub use refusal::Refusal;

#[cfg(test)]
mod tests;
