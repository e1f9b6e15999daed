//! An export read into cells: one sheet of an XLSX workbook (through
//! calamine) or the fields of a CSV or TSV file (through csv). No number
//! is parsed here: a cell is what the file holds, and `convert.rs`
//! decides what it means. Rows keep the numbers a person sees: a sheet's
//! row numbers, a text file's lines as an editor counts them.

use std::collections::BTreeMap;
use std::path::Path;

use calamine::{DataRef, Reader, Xlsx};

use super::address::{column_letters, MAX_COLUMNS, MAX_ROWS};
use super::error::ImportError;
use super::mapping::Source;

/// What a cell holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Nothing, or only spaces.
    Empty,
    /// A workbook's number.
    Number(f64),
    /// Text: every field of a text file, a workbook's string cell
    /// (trimmed of spaces).
    Text(String),
    /// A formula's error, as the spreadsheet shows it (`#DIV/0!`).
    Error(String),
    /// Something else a workbook holds, described (`a TRUE/FALSE cell`).
    Other(&'static str),
}

impl Cell {
    /// A text field or string cell, trimmed; empty if only spaces.
    fn text(s: &str) -> Cell {
        let s = s.trim();
        if s.is_empty() {
            Cell::Empty
        } else {
            Cell::Text(s.to_string())
        }
    }

    /// The cell as a header's name, if it holds one.
    pub fn name(&self) -> Option<String> {
        match self {
            Cell::Text(s) => Some(s.clone()),
            // A name typed as a number (`2`) is read back as one.
            Cell::Number(x) => Some(x.to_string()),
            _ => None,
        }
    }
}

/// One row of an export.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Its 1-based number: the sheet's row, the text file's line.
    pub number: usize,
    /// Its cells from column A; cells past the end are empty.
    pub cells: Vec<Cell>,
}

/// A block of merged cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Merged {
    /// First and last row, 1-based.
    pub rows: (usize, usize),
    /// First and last column, 0-based.
    pub columns: (usize, usize),
}

/// An export's cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The workbook's sheet read, or `None` for a text file.
    pub sheet: Option<String>,
    /// Rows holding something, by increasing number. A workbook's rows
    /// not listed are blank; a text file lists every line but those
    /// inside a quoted field that spans lines.
    pub rows: Vec<Row>,
    /// Merged cells (a workbook's).
    pub merged: Vec<Merged>,
    /// A text file's quote that is never closed: the row and column of
    /// the field it opens, which runs to the end of the file.
    pub unclosed_quote: Option<(usize, usize)>,
}

const EMPTY: Cell = Cell::Empty;

impl Table {
    /// The cell of `row` in column `col` (0-based).
    pub fn cell(row: &Row, col: usize) -> &Cell {
        row.cells.get(col).unwrap_or(&EMPTY)
    }

    /// The row numbered `number`, if listed.
    pub fn row(&self, number: usize) -> Option<&Row> {
        self.rows
            .binary_search_by_key(&number, |r| r.number)
            .ok()
            .map(|i| &self.rows[i])
    }

    /// Columns: one past the last that holds anything.
    pub fn width(&self) -> usize {
        let merged = self.merged.iter().map(|m| m.columns.1 + 1);
        let cells = self.rows.iter().map(|r| r.cells.len());
        cells.chain(merged).max().unwrap_or(0)
    }

    /// A cell as a person finds it: `Sheet1!D57`, or `line 57, field 4
    /// (D)` in a text file.
    pub fn place(&self, row: usize, col: usize) -> String {
        let letters = column_letters(col);
        match &self.sheet {
            Some(sheet) => format!("{}!{letters}{row}", sheet_ref(sheet)),
            None => format!("line {row}, field {} ({letters})", col + 1),
        }
    }

    /// A row as a person finds it: `Sheet1 row 57`, or `line 57`.
    pub fn row_place(&self, row: usize) -> String {
        match &self.sheet {
            Some(sheet) => format!("{} row {row}", sheet_ref(sheet)),
            None => format!("line {row}"),
        }
    }

    /// A block of merged cells: `Sheet1!B5:C6`.
    pub fn merged_place(&self, m: &Merged) -> String {
        let sheet = self.sheet.as_deref().unwrap_or_default();
        format!(
            "{}!{}{}:{}{}",
            sheet_ref(sheet),
            column_letters(m.columns.0),
            m.rows.0,
            column_letters(m.columns.1),
            m.rows.1
        )
    }

    /// What was read, for a refusal: `the sheet "Sheet1"` or `the file`.
    pub fn what(&self) -> String {
        match &self.sheet {
            Some(sheet) => format!("the sheet {sheet:?}"),
            None => "the file".to_string(),
        }
    }
}

/// A sheet's name as a cell reference writes it: quoted when it holds
/// anything but letters, digits and underscores (`'Run 2'!A1`), control
/// characters shown as escapes (see [`escape_controls`]).
fn sheet_ref(sheet: &str) -> String {
    if !sheet.is_empty() && sheet.chars().all(|c| c.is_alphanumeric() || c == '_') {
        sheet.to_string()
    } else {
        format!("'{}'", escape_controls(&sheet.replace('\'', "''")))
    }
}

/// `text` with its control characters shown as escapes (`Run\n2`): a
/// workbook's XML may put a line end in a sheet's name, and a refusal
/// stays one line.
fn escape_controls(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// How an export is read, from its extension and the mapping's source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Workbook,
    Text(u8),
}

/// Reads the export at `path` (called `file` in refusals) as `source`
/// lays it out; `mapping` names the mapping file in refusals of its keys.
pub fn read(path: &Path, file: &str, source: &Source, mapping: &str) -> Result<Table, ImportError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default()
        .to_ascii_lowercase();
    let kind =
        match (extension.as_str(), source.delimiter) {
            ("xlsx" | "xlsm", None) => Kind::Workbook,
            ("xlsx" | "xlsm", Some(_)) => {
                return Err(ImportError::mapping(
                    mapping,
                    "source.delimiter",
                    format!("applies to text exports; {file} is a workbook"),
                ))
            }
            ("xls" | "xlsb" | "ods", _) => {
                return Err(ImportError::export(
                    file,
                    format!("a .{extension} workbook is not read: save it as .xlsx, .csv or .tsv"),
                ))
            }
            (_, Some(d)) => Kind::Text(d),
            ("csv", None) => Kind::Text(b','),
            ("tsv" | "tab" | "txt", None) => Kind::Text(b'\t'),
            _ => return Err(ImportError::export(
                file,
                "unknown kind of export: .xlsx and .xlsm are workbooks, .csv is comma-separated, \
                 .tsv, .tab and .txt tab-separated; another extension needs source.delimiter",
            )),
        };
    match kind {
        Kind::Workbook => read_workbook(path, file, source.sheet.as_deref()),
        Kind::Text(delimiter) => {
            if source.sheet.is_some() {
                return Err(ImportError::mapping(
                    mapping,
                    "source.sheet",
                    format!("applies to workbooks; {file} is text"),
                ));
            }
            let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
                file: file.to_string(),
                source,
            })?;
            read_text(&bytes, file, delimiter)
        }
    }
}

/// One sheet of an XLSX workbook: `sheet`, or the first.
fn read_workbook(path: &Path, file: &str, sheet: Option<&str>) -> Result<Table, ImportError> {
    let bad = |e: calamine::XlsxError| ImportError::Workbook {
        file: file.to_string(),
        // The reader quotes the file's own text (a sheet's name) as it is.
        message: escape_controls(&e.to_string()),
    };
    if let Err(source) = std::fs::metadata(path) {
        return Err(ImportError::Io {
            file: file.to_string(),
            source,
        });
    }
    let mut book: Xlsx<_> = calamine::open_workbook(path).map_err(bad)?;
    let names = book.sheet_names();
    let sheet = match sheet {
        Some(s) if names.iter().any(|n| n == s) => s.to_string(),
        Some(s) => {
            let has = if names.is_empty() {
                "no sheet".to_string()
            } else {
                quoted_list(&names)
            };
            return Err(ImportError::export(
                file,
                format!("no sheet named {s:?} (source.sheet); the workbook has {has}"),
            ));
        }
        None => match names.first() {
            Some(first) => first.clone(),
            None => return Err(ImportError::export(file, "the workbook has no sheet")),
        },
    };
    let merged = match book.worksheet_merge_cells(&sheet) {
        None => Vec::new(),
        Some(regions) => regions
            .map_err(bad)?
            .into_iter()
            // First to last, whichever corner the file names first: a
            // block written backwards (`D5:B2`) covers B2:D5 all the same.
            .map(|d| {
                let (r0, r1) = (d.start.0.min(d.end.0), d.start.0.max(d.end.0));
                let (c0, c1) = (d.start.1.min(d.end.1), d.start.1.max(d.end.1));
                Merged {
                    rows: (r0 as usize + 1, r1 as usize + 1),
                    columns: (c0 as usize, c1 as usize),
                }
            })
            .collect(),
    };
    let mut rows: BTreeMap<usize, Vec<Cell>> = BTreeMap::new();
    let mut cells = book.worksheet_cells_reader(&sheet).map_err(bad)?;
    while let Some(cell) = cells.next_cell().map_err(bad)? {
        let (row, col) = cell.get_position();
        let (row, col) = (row as usize, col as usize);
        let value = workbook_cell(cell.get_value());
        if value == Cell::Empty {
            continue;
        }
        // A damaged file's cell at row 4 000 000 000 would otherwise make
        // every row before it.
        if row >= MAX_ROWS || col >= MAX_COLUMNS {
            return Err(ImportError::export(
                file,
                format!(
                    "a cell at row {}, column {} lies beyond a sheet's {MAX_ROWS} rows and {MAX_COLUMNS} columns",
                    row + 1,
                    col + 1
                ),
            ));
        }
        let cells = rows.entry(row + 1).or_default();
        if cells.len() <= col {
            cells.resize(col + 1, Cell::Empty);
        }
        cells[col] = value;
    }
    Ok(Table {
        sheet: Some(sheet),
        rows: rows
            .into_iter()
            .map(|(number, cells)| Row { number, cells })
            .collect(),
        merged,
        unclosed_quote: None,
    })
}

/// A workbook's cell as this reader sees it.
fn workbook_cell(value: &DataRef) -> Cell {
    match value {
        DataRef::Empty => Cell::Empty,
        DataRef::Int(i) => Cell::Number(*i as f64),
        DataRef::Float(x) => Cell::Number(*x),
        DataRef::String(s) => Cell::text(s),
        DataRef::SharedString(s) => Cell::text(s),
        DataRef::Error(e) => Cell::Error(e.to_string()),
        DataRef::Bool(_) => Cell::Other("a TRUE/FALSE cell"),
        // Excel keeps a date or time as days since 1900: not seconds.
        DataRef::DateTime(_) | DataRef::DateTimeIso(_) => {
            Cell::Other("a date or time cell (days, not seconds: format the column as a number)")
        }
        DataRef::DurationIso(_) => Cell::Other("a duration cell"),
    }
}

/// A text export's fields, split at `delimiter` (fields may be quoted,
/// `"..."`, as CSV writes them).
fn read_text(bytes: &[u8], file: &str, delimiter: u8) -> Result<Table, ImportError> {
    // Taken off here, so that the reader's byte offsets are the text's.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .has_headers(false)
        .flexible(true)
        .from_reader(bytes);
    let mut record = csv::ByteRecord::new();
    let mut rows = Vec::new();
    // The line the record before ended on.
    let mut end_line = 0;
    // The last record's line, its last field's column, and whether that
    // field holds a line end.
    let mut last = None;
    loop {
        match reader.read_byte_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e
                    .position()
                    .map_or(String::new(), |p| format!("line {}: ", p.line()));
                return Err(ImportError::export(file, format!("{line}{e}")));
            }
        }
        // The reader skips blank lines without a record: its position is
        // before them (and before a CRLF's LF). The line ends from there
        // give the record's own line; the lines between the record before
        // and it are blank rows, so that a blank line inside the data is
        // refused as in a sheet, not silently closed up.
        let start = record.position().expect("a record read has a position");
        let (mut at, mut line) = (start.byte() as usize, start.line() as usize);
        while let Some(&b) = bytes.get(at).filter(|b| matches!(b, b'\n' | b'\r')) {
            if b == b'\n' {
                line += 1;
            }
            at += 1;
        }
        // Lines ended by a lone CR count none: numbered by record then.
        let line = line.max(end_line + 1);
        rows.extend((end_line + 1..line).map(|number| Row {
            number,
            cells: Vec::new(),
        }));
        let quoted_line_ends: usize = record
            .iter()
            .map(|f| f.iter().filter(|&&b| b == b'\n').count())
            .sum();
        end_line = line + quoted_line_ends;
        let spans_lines = record
            .iter()
            .next_back()
            .is_some_and(|f| f.iter().any(|b| matches!(b, b'\n' | b'\r')));
        last = Some((line, record.len().saturating_sub(1), spans_lines));
        let mut cells: Vec<Cell> = record
            .iter()
            .map(|f| Cell::text(&String::from_utf8_lossy(f)))
            .collect();
        while cells.last() == Some(&Cell::Empty) {
            cells.pop();
        }
        rows.push(Row {
            number: line,
            cells,
        });
    }
    // A quote never closed runs to the end of the file: the reader takes
    // the rest, rows and all, for the last record's last field. Closed,
    // such a field ends the file with its quote (line ends at most after).
    let end = bytes.iter().rposition(|b| !matches!(b, b'\n' | b'\r'));
    let unclosed_quote = match last {
        Some((line, col, true)) if end.is_some_and(|i| bytes[i] != b'"') => Some((line, col)),
        _ => None,
    };
    Ok(Table {
        sheet: None,
        rows,
        merged: Vec::new(),
        unclosed_quote,
    })
}

/// Names as a refusal lists them: `"A", "B"`.
pub fn quoted_list(names: &[String]) -> String {
    let shown: Vec<String> = names.iter().take(20).map(|n| format!("{n:?}")).collect();
    let more = names.len().saturating_sub(shown.len());
    if more > 0 {
        format!("{} and {more} more", shown.join(", "))
    } else {
        shown.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(s: &str) -> Vec<(usize, Vec<Cell>)> {
        read_text(s.as_bytes(), "t.csv", b',')
            .unwrap()
            .rows
            .into_iter()
            .map(|r| (r.number, r.cells))
            .collect()
    }

    fn t(s: &str) -> Cell {
        Cell::Text(s.into())
    }

    #[test]
    fn text_rows_are_lines_blank_ones_kept() {
        let rows = text("\u{feff}a,b\r\n1,2\r\n\r\n\r\n3,\"x\ny\"\n4, \n  \n6,7");
        assert_eq!(
            rows,
            vec![
                (1, vec![t("a"), t("b")]),
                (2, vec![t("1"), t("2")]),
                (3, vec![]),
                (4, vec![]),
                // A quoted line end: one row over lines 5 and 6.
                (5, vec![t("3"), t("x\ny")]),
                (7, vec![t("4")]),
                (8, vec![]),
                (9, vec![t("6"), t("7")]),
            ]
        );
        // Blank lines before the first record.
        assert_eq!(
            text("\n\na\n"),
            vec![(1, vec![]), (2, vec![]), (3, vec![t("a")])]
        );
    }

    #[test]
    fn a_quote_never_closed_is_found() {
        let quote = |s: &str| {
            read_text(s.as_bytes(), "t.csv", b',')
                .unwrap()
                .unclosed_quote
        };
        // Opened on line 3 in field 2, it takes lines 4 and 5 with it.
        assert_eq!(quote("a,b\n1,2\n3,\"4\n5,6\n7,8\n"), Some((3, 1)));
        assert_eq!(quote("a,b\n1,\"2\n3\"\n"), None);
        assert_eq!(quote("a,b\n1,\"x\"\"\"\n\n"), None);
        assert_eq!(quote("a,b\n1,2\n"), None);
    }

    #[test]
    fn places_are_named_as_a_person_finds_them() {
        let mut table = Table {
            sheet: Some("Sheet1".into()),
            rows: vec![],
            merged: vec![],
            unclosed_quote: None,
        };
        assert_eq!(table.place(57, 3), "Sheet1!D57");
        assert_eq!(table.row_place(57), "Sheet1 row 57");
        let m = Merged {
            rows: (5, 6),
            columns: (1, 2),
        };
        assert_eq!(table.merged_place(&m), "Sheet1!B5:C6");
        table.sheet = Some("Run 2's".into());
        assert_eq!(table.place(1, 0), "'Run 2''s'!A1");
        table.sheet = None;
        assert_eq!(table.place(57, 3), "line 57, field 4 (D)");
        assert_eq!(table.row_place(57), "line 57");
    }

    #[test]
    fn unknown_extensions_and_old_workbooks_are_refused_by_name() {
        let source = Source {
            sheet: None,
            delimiter: None,
            header_row: 1,
            first_data_row: 2,
            decimal_comma: false,
        };
        for (name, says) in [
            ("a.dat", "unknown kind of export"),
            ("a.xls", "save it as .xlsx"),
            ("a.ods", "save it as .xlsx"),
        ] {
            let err = read(Path::new(name), name, &source, "m.toml").unwrap_err();
            assert!(err.to_string().starts_with(name), "{err}");
            assert!(err.to_string().contains(says), "{err}");
        }
        let with_delimiter = Source {
            delimiter: Some(b';'),
            ..source.clone()
        };
        let err = read(Path::new("a.xlsx"), "a.xlsx", &with_delimiter, "m.toml").unwrap_err();
        assert!(
            err.to_string().starts_with("m.toml: source.delimiter"),
            "{err}"
        );
        let with_sheet = Source {
            sheet: Some("S".into()),
            ..source
        };
        let err = read(Path::new("a.csv"), "a.csv", &with_sheet, "m.toml").unwrap_err();
        assert!(err.to_string().starts_with("m.toml: source.sheet"), "{err}");
    }
}
