//! What the tests that run Cortex-M4F programs in QEMU share: the target,
//! where the workspace is, and building a release ELF for QEMU.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Cortex-M4F target every QEMU program is built for.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The workspace's root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Builds `package` in release for [`TARGET`] from `dir` (so that the
/// `.cargo/config.toml` there applies, as for a user) with what `configure`
/// adds (features, environment), and returns the directory holding the ELF.
///
/// The target directory is `target/qemu`, not the workspace's: cargo
/// locks a target directory while it builds or checks a build there (not
/// while the tests it built run), and `scripts/test` starts the other
/// streams' `cargo test` beside these tests: a build into the
/// workspace's would wait on them, and they on it. It is shared by every
/// QEMU test of this crate (same target, most dependencies in common);
/// cargo runs test binaries one after another, and a binary that builds
/// from several threads serialises its own builds. The host tool's
/// virtual bench, which `scripts/test` runs beside these, builds into its
/// own.
pub fn build_release(
    dir: &Path,
    package: &str,
    configure: impl FnOnce(&mut Command),
    failure: &str,
) -> PathBuf {
    let target_dir = workspace().join("target/qemu");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut command = Command::new(cargo);
    command
        .current_dir(dir)
        .args(["build", "--release", "--locked", "-p", package])
        .args(["--target", TARGET])
        .arg("--target-dir")
        .arg(&target_dir);
    configure(&mut command);
    let status = command.status().expect("cargo runs");
    assert!(status.success(), "{failure}");
    target_dir.join(TARGET).join("release")
}
