//! Why `finrs log` / `finrs run` failed: each names the file, the ELF or
//! the link, and keeps the underlying error as its source.

use std::path::PathBuf;

use crate::link::probe::ProbeError;
use crate::recording::RecordingError;

/// Why a capture failed.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The duration is not a positive number.
    #[error("duration_s must be a positive number of seconds, got {0}")]
    Duration(f64),
    /// Nothing came that makes a recording.
    #[error("nothing written; {report}")]
    NothingWritten {
        /// The account of what came.
        report: String,
        /// Why the rows make no recording.
        #[source]
        source: RecordingError,
    },
    /// The recording's folder could not be created.
    #[error("cannot create the folder {}", dir.display())]
    Folder {
        /// The folder.
        dir: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The recording could not be written.
    #[error(transparent)]
    Write(RecordingError),
    /// The byte dump could not be read from the standard input.
    #[error("reading the standard input")]
    Stdin(#[source] std::io::Error),
    /// The byte dump could not be read.
    #[error("reading {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The ELF's defmt table is unreadable.
    #[error("{elf}: bad defmt table: {reason}")]
    DefmtTable {
        /// The ELF's name.
        elf: String,
        /// defmt-decoder's reason, with its causes.
        reason: String,
    },
    /// An ELF to flash gave no RTT address.
    #[error("{}: no RTT address", elf.display())]
    NoRttAddress {
        /// The ELF.
        elf: PathBuf,
    },
    /// Finding, attaching to or setting up the target failed.
    #[error(transparent)]
    Probe(#[from] ProbeError),
    /// A journal is already where this capture's would go.
    #[error("{} exists: a capture to {} ended before it was written; recover it with `finrs log --from-bytes {} --out {}`, or remove it", journal.display(), out.display(), journal.display(), out.display())]
    JournalExists {
        /// The journal left behind.
        journal: PathBuf,
        /// The recording it was for.
        out: PathBuf,
    },
    /// The journal could not be created, written or removed.
    #[error("the capture's journal {}", journal.display())]
    Journal {
        /// The journal.
        journal: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// The link failed while recording; what came is written.
    #[error("the link failed; the samples so far are in {}", out.display())]
    LinkFailed {
        /// The recording written.
        out: PathBuf,
        /// How the link failed.
        #[source]
        source: ProbeError,
    },
    /// The link failed while recording, and writing what came failed too.
    #[error("the link failed, and {write}")]
    LinkAndWrite {
        /// Why writing failed, with its causes.
        write: String,
        /// How the link failed.
        #[source]
        source: ProbeError,
    },
}
