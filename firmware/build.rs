//! Puts `memory.x` where the linker finds it, adds defmt's linker script,
//! and turns the segment configuration into constants.
//!
//! `-Tlink.x` comes from the target's rustflags in the workspace root's
//! `.cargo/config.toml` (cargo joins rustflags arrays of nested configs, so
//! repeating it in `firmware/.cargo/config.toml` would include it twice);
//! `-Tdefmt.x` is added here so that the firmware links whether it is built
//! from `firmware/` or from the workspace root (as the SIL test does).
//!
//! Segments: `FINRS_SEGMENTS` (1..=8, default 3) is the segment count and
//! `FINRS_DAC_SEGMENTS` (empty by default) a comma list of at most two
//! distinct segment indices below it, driven by DAC1 then DAC2 instead of an
//! H-bridge (e.g. `FINRS_DAC_SEGMENTS=0,1`). They become `N` and
//! `DAC_SEGMENTS` in `src/config.rs` through `$OUT_DIR/segments.rs`; a bad
//! value stops the build with a message naming the variable and the rule.
use std::{env, fs, path::PathBuf};

const MAX_SEGMENTS: usize = 8;

fn segments() -> Result<usize, String> {
    let Ok(text) = env::var("FINRS_SEGMENTS") else {
        return Ok(3);
    };
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_SEGMENTS).contains(&n) => Ok(n),
        _ => Err(format!(
            "FINRS_SEGMENTS = {text:?}: must be a whole number in 1..={MAX_SEGMENTS}"
        )),
    }
}

fn dac_segments(n: usize) -> Result<[Option<usize>; 2], String> {
    let text = env::var("FINRS_DAC_SEGMENTS").unwrap_or_default();
    let mut out = [None; 2];
    let items: Vec<&str> = text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    if items.len() > 2 {
        return Err(format!(
            "FINRS_DAC_SEGMENTS = {text:?}: at most 2 segments (DAC1, DAC2)"
        ));
    }
    for (slot, item) in out.iter_mut().zip(&items) {
        match item.parse::<usize>() {
            Ok(i) if i < n => *slot = Some(i),
            _ => {
                return Err(format!(
                    "FINRS_DAC_SEGMENTS = {text:?}: {item:?} must be a segment index below FINRS_SEGMENTS ({n})"
                ))
            }
        }
    }
    if out[0].is_some() && out[0] == out[1] {
        return Err(format!(
            "FINRS_DAC_SEGMENTS = {text:?}: the two segments must differ"
        ));
    }
    Ok(out)
}

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out.join("memory.x"), include_bytes!("memory.x")).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");

    println!("cargo:rerun-if-env-changed=FINRS_SEGMENTS");
    println!("cargo:rerun-if-env-changed=FINRS_DAC_SEGMENTS");
    let config = segments().and_then(|n| Ok((n, dac_segments(n)?)));
    let (n, dac) = match config {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    fs::write(
        out.join("segments.rs"),
        format!(
            "/// Segments driven (`FINRS_SEGMENTS` at build time, 3 by default).\n\
             pub const N: usize = {n};\n\
             /// Segments driven by DAC1 and DAC2 instead of an H-bridge\n\
             /// (`FINRS_DAC_SEGMENTS` at build time, none by default).\n\
             #[allow(dead_code)] // the QEMU board drives the plant, not DACs\n\
             pub const DAC_SEGMENTS: [Option<usize>; 2] = {dac:?};\n"
        ),
    )
    .expect("OUT_DIR is writable");
}
