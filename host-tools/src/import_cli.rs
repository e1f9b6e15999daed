//! `finrs import`: a lab's exports made `ipmc-bench/1` recordings by a
//! mapping, a recording per export. Every export is read before anything
//! is written: a session is imported whole or not at all.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use finrs::import::{self, Imported, Mapping, Zero};

use crate::cli::ImportArgs;
use crate::new_folders::{create_parent, NewFolders};

/// `finrs import`.
pub fn run(args: ImportArgs) -> anyhow::Result<()> {
    let mapping = Mapping::read(&args.mapping)?;
    let inputs = exports(&args.inputs)?;
    let outputs = outputs(&inputs, &args.out)?;
    let mut imported = Vec::with_capacity(inputs.len());
    let mut refused = Vec::new();
    for input in &inputs {
        match import::import(input, &mapping) {
            Ok(i) => imported.push(i),
            Err(e) => refused.push(e),
        }
    }
    match refused.len() {
        0 => {}
        1 if inputs.len() == 1 => return Err(refused.remove(0).into()),
        n => {
            let each: Vec<String> = refused.iter().map(|e| format!("  {e}")).collect();
            bail!(
                "{n} of {} exports refused, nothing written:\n{}",
                inputs.len(),
                each.join("\n")
            );
        }
    }
    let mut made = NewFolders::default();
    for ((input, out), imported) in inputs.iter().zip(&outputs).zip(&imported) {
        made.add(create_parent(out)?);
        imported.recording.write(out)?;
        eprint!("{}", summary(input, out, &mapping, imported));
    }
    made.keep();
    let names: Vec<String> = inputs.iter().map(|p| file_name(p)).collect();
    for file in mapping.files() {
        if !names.iter().any(|n| n == file) {
            eprintln!(
                "note: {}: [files.{file:?}] names none of the exports imported",
                mapping.name()
            );
        }
    }
    Ok(())
}

/// The exports given: files as they are, folders by their exports in
/// name order.
fn exports(inputs: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for input in inputs {
        if input.is_dir() {
            out.extend(import::exports_in(input)?);
        } else {
            out.push(input.clone());
        }
    }
    Ok(out)
}

/// Where each export's recording goes: `out` itself for one export and an
/// `out` ending in `.csv`, else `out/<the export's stem>.csv`. Two
/// exports of one stem, or an output that is an export, are refused.
fn outputs(inputs: &[PathBuf], out: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let is_file = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        && !out.is_dir();
    let outputs: Vec<PathBuf> = if is_file {
        if inputs.len() != 1 {
            bail!(
                "--out {} names one recording, but {} exports are given: give a folder",
                out.display(),
                inputs.len()
            );
        }
        vec![out.to_path_buf()]
    } else {
        let mut by_name: BTreeMap<PathBuf, &Path> = BTreeMap::new();
        for input in inputs {
            let stem = input
                .file_stem()
                .with_context(|| format!("{}: not a file's name", input.display()))?;
            let path = out.join(csv_name(stem));
            if let Some(other) = by_name.insert(path.clone(), input) {
                bail!(
                    "{} and {} would both be written to {}: rename one",
                    other.display(),
                    input.display(),
                    path.display()
                );
            }
        }
        inputs
            .iter()
            .map(|input| out.join(csv_name(input.file_stem().unwrap_or_default())))
            .collect()
    };
    for (input, output) in inputs.iter().zip(&outputs) {
        if same_file(input, output) {
            bail!(
                "{} would be written over its own export: give --out another folder",
                output.display()
            );
        }
    }
    Ok(outputs)
}

/// `<stem>.csv`: the stem whole, dots and all (`02_step_2.5V` stays
/// itself; `with_extension` would take `.5V` for an extension and write
/// `02_step_2.csv`).
fn csv_name(stem: &std::ffi::OsStr) -> std::ffi::OsString {
    let mut name = stem.to_os_string();
    name.push(".csv");
    name
}

/// Whether `a` and `b` are one existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// A path's last part, as `[files."NAME"]` names an export.
fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// What was written, and what became of each column with a zero taken
/// from the opening or cells written as empty fields.
fn summary(input: &Path, out: &Path, mapping: &Mapping, imported: &Imported) -> String {
    let rec = &imported.recording;
    let rows = rec.t_s.len();
    let span_s = rec.t_s.last().copied().unwrap_or(0.0) - rec.t_s.first().copied().unwrap_or(0.0);
    let mut text = format!(
        "wrote {} ({rows} rows over {span_s:.3} s) from {}\n",
        out.display(),
        input.display()
    );
    for (report, map) in imported.channels.iter().zip(mapping.channels()) {
        let mut parts = Vec::new();
        if let Zero::Opening { opening_s } = map.zero {
            // Nine digits: a mean's last bits are no reading's.
            let zero = format!("{:.8e}", report.zero_raw)
                .parse::<f64>()
                .unwrap_or(report.zero_raw);
            parts.push(format!("zero {zero} (mean of the first {opening_s} s)"));
        }
        for (n, what) in [
            (report.sentinels, "sentinels"),
            (report.outside_valid, "outside valid"),
            (report.empty_cells, "empty cells"),
        ] {
            if n > 0 {
                parts.push(format!("{n} {what}"));
            }
        }
        if !parts.is_empty() {
            let empty = report.sentinels + report.outside_valid + report.empty_cells;
            text.push_str(&format!(
                "  {} from {}: {}; {empty} of {rows} fields empty\n",
                report.to.name(),
                report.column,
                parts.join(", ")
            ));
        }
    }
    text
}
