//! Where a written recording goes: a new file beside the target, put in
//! its place only once every byte is written.
//!
//! A failed or interrupted write leaves the target as it was, never half
//! written. The old file is removed first and the new one then renamed to
//! its name, rather than renamed over it: on ext4 a rename over an
//! existing file, like truncating one, makes the kernel allocate and start
//! writing the new file's blocks before the call returns (`auto_da_alloc`),
//! and then wait for the old file's pages still being written; on the
//! 20 000-row simulation, written again over its last output, that took
//! about a third of a millisecond of CPU and over two of waiting
//! (`docs/speed-simulate-job.md`).
//!
//! Only a plain file of our own is replaced so: a symbolic link, a file
//! with other hard links, a device or pipe, a read-only file, another
//! user's file, or a folder we cannot create a file in is written in place
//! as before (opened, truncated, written). Links and owners are Unix's;
//! elsewhere a file is written in place.

#[cfg(unix)]
use std::ffi::OsString;
use std::fs::File;
#[cfg(unix)]
use std::fs::OpenOptions;
use std::io::{self, ErrorKind};
#[cfg(unix)]
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// An open output: the file being written and, unless written in place,
/// the target it replaces at [`Output::finish`].
pub(super) struct Output {
    /// Where the text is written.
    pub file: File,
    /// The new file's name and the target's, if not written in place.
    rename: Option<(PathBuf, PathBuf)>,
}

impl Output {
    /// Opens the output for `target`.
    pub fn create(target: &Path) -> io::Result<Output> {
        match Self::beside(target) {
            Some(output) => Ok(output),
            None => Ok(Output {
                file: File::create(target)?,
                rename: None,
            }),
        }
    }

    /// A new file beside `target`, if `target` may be replaced by one
    /// (never off Unix: its links and owners are not checked there).
    #[cfg(not(unix))]
    fn beside(_target: &Path) -> Option<Output> {
        None
    }

    /// A new file beside `target`, if `target` may be replaced by one.
    #[cfg(unix)]
    fn beside(target: &Path) -> Option<Output> {
        let old = match std::fs::symlink_metadata(target) {
            Ok(m) => {
                let plain = m.file_type().is_file() && m.nlink() == 1;
                if !plain || m.permissions().readonly() {
                    return None;
                }
                Some(m)
            }
            Err(e) if e.kind() == ErrorKind::NotFound => None,
            Err(_) => return None,
        };
        // Hidden, named for the target and this process: two runs writing
        // the same target never share one.
        let mut name = OsString::from(".");
        name.push(target.file_name()?);
        name.push(format!(".{}.finrs-tmp", std::process::id()));
        let temp = target.with_file_name(name);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
            .ok()?;
        // The replacement keeps the old file's owner and mode, or is not
        // made: a file we cannot give its owner is written in place.
        if let Some(old) = old {
            let kept = file.metadata().ok().and_then(|new| {
                if (new.uid(), new.gid()) != (old.uid(), old.gid()) {
                    return None;
                }
                if new.permissions() != old.permissions() {
                    file.set_permissions(old.permissions()).ok()?;
                }
                Some(())
            });
            if kept.is_none() {
                drop(file);
                let _ = std::fs::remove_file(&temp);
                return None;
            }
        }
        Some(Output {
            file,
            rename: Some((temp, target.to_path_buf())),
        })
    }

    /// Puts the written file in the target's place.
    pub fn finish(self) -> io::Result<()> {
        let Some((temp, target)) = self.rename else {
            return Ok(());
        };
        drop(self.file);
        let placed = match std::fs::remove_file(&target) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == ErrorKind::NotFound => Ok(()),
            Err(e) => Err(e),
        }
        .and_then(|()| std::fs::rename(&temp, &target));
        if placed.is_err() {
            let _ = std::fs::remove_file(&temp);
        }
        placed
    }

    /// Gives up: removes the new file; the target is as it was (unless
    /// written in place).
    pub fn abandon(self) {
        if let Some((temp, _)) = self.rename {
            drop(self.file);
            let _ = std::fs::remove_file(temp);
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::io::Write;
    use std::os::unix::fs::PermissionsExt;

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("finrs-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn write(target: &Path, text: &str) {
        let output = Output::create(target).unwrap();
        (&output.file).write_all(text.as_bytes()).unwrap();
        output.finish().unwrap();
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_file_is_replaced_whole_keeping_its_mode() {
        let dir = folder("replace");
        let target = dir.join("out.csv");
        write(&target, "new\n");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new\n");
        std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o640)).unwrap();
        write(&target, "again, longer\n");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "again, longer\n");
        let mode = std::fs::metadata(&target).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o640);
        assert_eq!(names(&dir), ["out.csv"]);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn an_abandoned_write_leaves_the_old_file() {
        let dir = folder("abandon");
        let target = dir.join("out.csv");
        write(&target, "old\n");
        let output = Output::create(&target).unwrap();
        (&output.file).write_all(b"half a ro").unwrap();
        output.abandon();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old\n");
        assert_eq!(names(&dir), ["out.csv"]);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_link_is_written_through() {
        let dir = folder("link");
        let target = dir.join("real.csv");
        let link = dir.join("link.csv");
        write(&target, "old\n");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write(&link, "through the link\n");
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "through the link\n"
        );
        let hard = dir.join("hard.csv");
        std::fs::hard_link(&target, &hard).unwrap();
        write(&hard, "through the hard link\n");
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "through the hard link\n"
        );
        assert_eq!(names(&dir), ["hard.csv", "link.csv", "real.csv"]);
        std::fs::remove_dir_all(dir).unwrap();
    }
}
