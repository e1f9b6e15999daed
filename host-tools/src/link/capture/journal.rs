//! The capture's journal: every byte of the force stream, appended to
//! `OUT.frames` as it comes, so that a capture that dies (killed, a crash,
//! a power cut) leaves its data on disk, recoverable by the same recorder
//! with `finrs log --from-bytes OUT.frames --out OUT`: the same rows, gaps,
//! faults and Info as a capture that finished. Each chunk goes to the
//! system at once (a killed process loses nothing it has read), and the
//! file is synced to the disk every [`SYNC_EVERY`] (a power cut loses at
//! most that). Removed once the recording is written.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::CaptureError;

/// Longest time between syncs of the journal to the disk.
pub const SYNC_EVERY: Duration = Duration::from_secs(1);

/// The journal of one capture.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
    last_sync: Instant,
    bytes: u64,
}

/// The journal's path for the recording `out`: `out` with `.frames` added.
pub fn path_for(out: &Path) -> PathBuf {
    let mut name = out.as_os_str().to_os_string();
    name.push(".frames");
    PathBuf::from(name)
}

impl Journal {
    /// Creates the journal for `out`, its folder with it. Refused if one is
    /// there already: it is what a capture that died left, and is not
    /// overwritten.
    pub fn create(out: &Path) -> Result<Self, CaptureError> {
        let path = path_for(out);
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| CaptureError::Folder {
                dir: dir.to_path_buf(),
                source,
            })?;
        }
        let file = File::options()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|source| {
                if source.kind() == std::io::ErrorKind::AlreadyExists {
                    CaptureError::JournalExists {
                        journal: path.clone(),
                        out: out.to_path_buf(),
                    }
                } else {
                    CaptureError::Journal {
                        journal: path.clone(),
                        source,
                    }
                }
            })?;
        Ok(Self {
            path,
            file,
            last_sync: Instant::now(),
            bytes: 0,
        })
    }

    /// Where it is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes written so far.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Appends `bytes`, and syncs if the last sync is [`SYNC_EVERY`] old.
    pub fn append(&mut self, bytes: &[u8]) -> Result<(), CaptureError> {
        let failed = |source| CaptureError::Journal {
            journal: self.path.clone(),
            source,
        };
        if !bytes.is_empty() {
            self.file.write_all(bytes).map_err(failed)?;
            self.bytes += bytes.len() as u64;
        }
        if self.last_sync.elapsed() >= SYNC_EVERY {
            self.file.sync_data().map_err(failed)?;
            self.last_sync = Instant::now();
        }
        Ok(())
    }

    /// The recording is written: the journal goes.
    pub fn remove(self) -> Result<(), CaptureError> {
        drop(self.file);
        std::fs::remove_file(&self.path).map_err(|source| CaptureError::Journal {
            journal: self.path,
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_journal_keeps_every_byte_and_refuses_to_overwrite_one_left_behind() {
        let dir = std::env::temp_dir().join(format!("finrs-journal-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let out = dir.join("rec/blocked-01.csv");
        let mut j = Journal::create(&out).unwrap();
        assert_eq!(j.path(), dir.join("rec/blocked-01.csv.frames"));
        j.append(&[1, 2, 3]).unwrap();
        j.append(&[]).unwrap();
        j.append(&[4]).unwrap();
        assert_eq!(j.bytes(), 4);
        // On the system at once, before any sync or drop.
        assert_eq!(std::fs::read(j.path()).unwrap(), [1, 2, 3, 4]);
        let e = Journal::create(&out).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("finrs log --from-bytes"), "{text}");
        assert!(text.contains("blocked-01.csv.frames"), "{text}");
        let path = j.path().to_path_buf();
        j.remove().unwrap();
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
