//! A byte dump of the force stream played as a board, for `finrs bench
//! live --from-bytes`: the view and its recording from a dump (a journal
//! left by a capture, a QEMU run), at once and with no probe. Commands go
//! nowhere, and say so.

use std::path::Path;

use finrs_frames::Command;

use crate::link::board::Board;
use crate::link::capture::{CaptureError, Link};
use crate::link::probe::{ProbeError, TargetError};

/// Bytes handed out per read: about 50 ms of samples at N = 3.
const CHUNK: usize = 2048;

/// The dump, read out in chunks, then nothing.
#[derive(Clone, Debug)]
pub struct Replay {
    bytes: Vec<u8>,
    at: usize,
}

impl Replay {
    /// The dump in `path`.
    pub fn read(path: &Path) -> Result<Self, CaptureError> {
        let bytes = std::fs::read(path).map_err(|source| CaptureError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(Self { bytes, at: 0 })
    }
}

impl Link for Replay {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        let n = (self.bytes.len() - self.at).min(CHUNK).min(buf.len());
        buf[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }

    fn read_log(&mut self, _: &mut [u8]) -> Result<usize, ProbeError> {
        Ok(0)
    }
}

impl Board for Replay {
    fn send(&mut self, _: &Command) -> Result<(), ProbeError> {
        Err(ProbeError::Target(TargetError::new(
            "a replayed dump: commands go nowhere",
        )))
    }
}
