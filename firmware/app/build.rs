//! Puts the workspace's one `memory.x` where the linker finds it and adds
//! defmt's linker script.
//!
//! `-Tlink.x` comes from the target's rustflags in the workspace root's
//! `.cargo/config.toml` (cargo joins rustflags arrays of nested configs, so
//! repeating it in `firmware/app/.cargo/config.toml` would include it twice);
//! `-Tdefmt.x` is added here so that the firmware links whether it is built
//! from `firmware/app/` or from the workspace root.
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out.join("memory.x"), include_bytes!("../../memory.x")).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../memory.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
