//! Puts the workspace's one `memory.x` where the linker finds it, adds
//! defmt's linker script, and sets `FINRS_GIT_HASH` (the commit the
//! firmware is built from, for its Info frame) when git can tell.
//!
//! `-Tlink.x` comes from the target's rustflags in the workspace root's
//! `.cargo/config.toml` (cargo joins rustflags arrays of nested configs, so
//! repeating it in `firmware/.cargo/config.toml` would include it twice);
//! `-Tdefmt.x` is added here so that the firmware links whether it is built
//! from `firmware/` or from the workspace root.
use std::{env, fs, path::PathBuf, process::Command};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out.join("memory.x"), include_bytes!("../memory.x")).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    git_hash();
}

/// `FINRS_GIT_HASH` from `git rev-parse HEAD`; nothing (the firmware then
/// reports 0) outside a git checkout or without git.
fn git_hash() {
    if let Some(hash) = git(&["rev-parse", "HEAD"]) {
        println!("cargo:rustc-env=FINRS_GIT_HASH={hash}");
    }
    // Rebuilt when HEAD moves: HEAD itself (a checkout), the branch it
    // names (a commit) and the packed refs, wherever git keeps them (a
    // worktree's are apart).
    let mut watched = vec!["HEAD".to_string(), "packed-refs".to_string()];
    watched.extend(git(&["symbolic-ref", "-q", "HEAD"]));
    for name in watched {
        if let Some(path) = git(&["rev-parse", "--git-path", &name]) {
            if PathBuf::from(&path).exists() {
                println!("cargo:rerun-if-changed={path}");
            }
        }
    }
}

/// What `git ARGS` prints, trimmed, if it succeeds.
fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    (out.status.success() && !text.trim().is_empty()).then(|| text.trim().to_string())
}
