//! Folders made for a command's outputs before the command's work.
//!
//! A command checks that its outputs can be written before a long run,
//! creating their folders, so that a bad path fails at once, not after
//! minutes. Should the run then fail, the folders it made are removed
//! again if still empty: a failed run leaves no empty folders behind.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

/// Folders made for outputs, each before the folders inside it: removed
/// when dropped (those still empty) unless [`NewFolders::keep`] was
/// called.
#[must_use = "dropped, the folders are removed again"]
#[derive(Debug, Default)]
pub struct NewFolders(Vec<PathBuf>);

impl NewFolders {
    /// Holds `other`'s folders too.
    pub fn add(&mut self, mut other: NewFolders) {
        self.0.append(&mut other.0);
    }

    /// Keeps the folders: the command succeeded.
    pub fn keep(mut self) {
        self.0.clear();
    }
}

impl Drop for NewFolders {
    fn drop(&mut self) {
        // Innermost first. `remove_dir` removes only an empty folder: one
        // holding an output written before the failure stays, and so do
        // the folders around it.
        for dir in self.0.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// Creates the folder a file goes into, and any around it that are
/// missing; the folders made.
pub fn create_parent(path: &Path) -> anyhow::Result<NewFolders> {
    let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) else {
        return Ok(NewFolders::default());
    };
    let mut missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|d| !d.as_os_str().is_empty() && !d.exists())
        .map(Path::to_path_buf)
        .collect();
    missing.reverse();
    // Held before they are made: whichever were made before a failure to
    // make the rest are removed again.
    let made = NewFolders(missing);
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the folder {}", dir.display()))?;
    Ok(made)
}

/// Fails, naming `path`, unless it can be written: creates its folder and
/// opens it for writing; the folders made. An existing file is left as it
/// was (not truncated); a file made only for this check is removed again,
/// so that a run that fails later leaves no empty output behind.
pub fn check_writable(path: &Path) -> anyhow::Result<NewFolders> {
    let made = create_parent(path)?;
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    if !existed {
        std::fs::remove_file(path)
            .with_context(|| format!("removing {} after checking it", path.display()))?;
    }
    Ok(made)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder for one test, removed after it.
    struct Dir(PathBuf);

    impl Dir {
        fn new(name: &str) -> Dir {
            let dir = std::env::temp_dir()
                .join(format!("finrs-new-folders-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Dir(dir)
        }
    }

    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn folders_made_for_a_failed_run_are_removed_unless_they_hold_something() {
        let dir = Dir::new("failed");
        let out = dir.0.join("a/b/c/out.csv");
        let mut made = check_writable(&out).unwrap();
        assert!(out.parent().unwrap().is_dir());
        assert!(!out.exists(), "the check leaves no file");
        // A second output beside, in a folder of its own under `a`.
        let json = dir.0.join("a/d/verdict.json");
        made.add(check_writable(&json).unwrap());
        std::fs::write(&json, "{}").unwrap();
        drop(made);
        // `a/d` holds an output: it and `a` stay; `a/b/c` was empty.
        assert!(json.exists());
        assert!(!dir.0.join("a/b").exists());
        // The folder that was there before is never removed.
        assert!(dir.0.is_dir());
    }

    #[test]
    fn folders_kept_stay_and_nothing_is_made_for_a_bare_file_name() {
        let dir = Dir::new("kept");
        let out = dir.0.join("x/y/out.csv");
        create_parent(&out).unwrap().keep();
        assert!(dir.0.join("x/y").is_dir());
        // Already there: nothing made, so nothing removed.
        drop(create_parent(&out).unwrap());
        assert!(dir.0.join("x/y").is_dir());
        drop(create_parent(Path::new("out.csv")).unwrap());
    }

    #[test]
    fn a_folder_that_cannot_be_made_is_refused_by_name_and_leaves_none() {
        let dir = Dir::new("refused");
        // A file where a folder would have to be.
        std::fs::write(dir.0.join("file"), "").unwrap();
        let err = create_parent(&dir.0.join("file/sub/out.csv")).unwrap_err();
        assert!(
            format!("{err:#}").contains("cannot create the folder"),
            "{err:#}"
        );
        assert!(!dir.0.join("file/sub").exists());
        assert!(dir.0.join("file").is_file());
    }
}
