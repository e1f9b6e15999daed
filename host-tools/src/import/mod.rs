//! A lab's own exports made `ipmc-bench/1` recordings (`finrs import`,
//! `docs/import.md`).
//!
//! Labs export spreadsheets (LabVIEW writes XLSX: one sheet, a header row,
//! pairs of columns, often no time column) or CSV and TSV with their own
//! names, units and decimal marks. A [`Mapping`] (a TOML file,
//! `finrs-import/1`) says which column becomes which `ipmc-bench/1`
//! column, with its unit's scale, sign, zero and sentinels, where the
//! time comes from, and the recording's metadata. [`import_file`] reads
//! one export by it.
//!
//! Nothing is guessed and nothing is silently dropped: every mapped cell
//! is a number, empty, or a sentinel or out-of-range reading the mapping
//! names (those are written as empty fields, and counted); anything else
//! is refused at its cell (`Sheet1!D57`), as are a blank row inside the
//! data, a voltage that would be empty, merged cells over a mapped column
//! and a column's name that is missing or given twice. The recording made
//! is checked by the format's own rules before it is returned.
//!
//! - `mapping.rs`: the TOML mapping and its checks;
//! - `table.rs`: an export read into cells (XLSX through calamine, CSV
//!   and TSV through csv);
//! - `convert.rs`: cells to a recording;
//! - `address.rs`: column letters and a sheet's limits;
//! - `error.rs`: [`ImportError`].

mod address;
mod convert;
mod error;
mod mapping;
mod table;

use std::path::{Path, PathBuf};

pub use address::{column_letters, parse_column_letters};
pub use convert::{ChannelReport, Imported};
pub use error::ImportError;
pub use mapping::{
    ChannelMap, ColumnRef, Mapping, Source, Target, Time, TimeZero, Zero, MAPPING_FORMAT,
    SENTINEL_RELATIVE_TOLERANCE,
};

use crate::recording::Recording;

/// The extensions of the exports a folder is searched for: workbooks
/// (`xlsx`, `xlsm`) and text (`csv`, `tsv`, `tab`, `txt`).
pub const EXTENSIONS: [&str; 6] = ["xlsx", "xlsm", "csv", "tsv", "tab", "txt"];

/// The recording the export at `path` makes by `mapping`.
pub fn import_file(path: &Path, mapping: &Mapping) -> Result<Recording, ImportError> {
    import(path, mapping).map(|imported| imported.recording)
}

/// The recording the export at `path` makes by `mapping`, with what
/// became of each mapped column's cells (the zero subtracted, the empty
/// cells, sentinels and readings outside their range written as empty
/// fields).
pub fn import(path: &Path, mapping: &Mapping) -> Result<Imported, ImportError> {
    let file = path.display().to_string();
    // `[files."NAME"]` names an export without its folder.
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let meta = mapping.metadata_for(&name)?;
    let table = table::read(path, &file, mapping.source(), mapping.name())?;
    convert::convert(&table, mapping, &file, meta)
}

/// The exports in `folder` (files whose extension is one of
/// [`EXTENSIONS`], any case), by name: a session's order. A folder with
/// none is refused.
pub fn exports_in(folder: &Path) -> Result<Vec<PathBuf>, ImportError> {
    let name = folder.display().to_string();
    let io = |source| ImportError::Io {
        file: name.clone(),
        source,
    };
    let mut found = Vec::new();
    for entry in std::fs::read_dir(folder).map_err(io)? {
        let path = entry.map_err(io)?.path();
        let known = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()));
        if known && path.is_file() {
            found.push(path);
        }
    }
    if found.is_empty() {
        return Err(ImportError::export(
            &name,
            format!("the folder holds no export (.{})", EXTENSIONS.join(", .")),
        ));
    }
    found.sort();
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_s_exports_are_its_known_files_by_name() {
        let dir = std::env::temp_dir().join(format!("finrs-exports-in-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub.csv")).unwrap();
        for name in ["02.XLSX", "01.csv", "notes.md", "03.tsv", "plot.png"] {
            std::fs::write(dir.join(name), "").unwrap();
        }
        let found: Vec<String> = exports_in(&dir)
            .unwrap()
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(found, ["01.csv", "02.XLSX", "03.tsv"]);
        for name in ["02.XLSX", "01.csv", "03.tsv"] {
            std::fs::remove_file(dir.join(name)).unwrap();
        }
        let err = exports_in(&dir).unwrap_err().to_string();
        assert!(
            err.ends_with("the folder holds no export (.xlsx, .xlsm, .csv, .tsv, .tab, .txt)"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(exports_in(&dir)
            .unwrap_err()
            .to_string()
            .ends_with("cannot read"));
    }
}
