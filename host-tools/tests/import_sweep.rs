//! A deterministic sweep of `finrs import` over spoiled inputs, for panics
//! and for refusals that name nothing (#48: "nothing panics on the new
//! inputs"). From a mapping and exports that import cleanly, it makes
//! about a thousand spoiled variants, seeded, so the same every run:
//!
//! - mapping files (TOML): keys and tables dropped or given twice, values
//!   of the wrong type, rates, scales and zeros that are zero, negative,
//!   NaN, infinite or huge (and extremes the rules allow), columns that do
//!   not exist or lie beyond a sheet, empty strings, unicode, truncated
//!   text, unknown keys and keys in the wrong table, bytes that are not
//!   UTF-8;
//! - XLSX workbooks built with rust_xlsxwriter: an empty sheet, a header
//!   without data, columns missing, text in numeric cells, blanks, merged
//!   cells across the header and the data, formulas with cached results,
//!   huge and infinite values, very long rows, a second sheet, a damaged
//!   zip;
//! - XLSX workbooks written by hand, XML and all, as rust_xlsxwriter never
//!   writes them: cells beyond a sheet's limits, odd cell types, merges
//!   backwards or beyond the sheet, a sheet's name with a line end;
//! - CSV and TSV text: ragged rows, text in numbers, decimal commas, a
//!   byte order mark, an empty file, a header only, binary garbage,
//!   bytes that are not UTF-8, unclosed quotes.
//!
//! Each case must end in a recording whose written text reads back as the
//! same recording, or in a refusal of one line that starts with the name
//! of the mapping or of the export and says something after it; never in
//! a panic. The bulk runs in process through the library the command is a
//! thin layer over (`Mapping::read`, then `import`), each call inside
//! `catch_unwind`; every [`CLI_EVERY`]th case also runs the `finrs import`
//! binary, which must not panic (exit code 101, `panicked`) or die by a
//! signal, must end as the library did (the same refusal, or a recording
//! that reads back), and must leave nothing behind when it refuses.
//! [`regressions`] keeps what the sweep found as fixed cases, each with
//! what its refusal must say.
//!
//! A failure prints each failing case: what was done to the mapping and
//! the export, the mapping's text, and where its files were kept (the
//! sweep is deterministic: a rerun makes the same case).
//! `FINRS_IMPORT_SWEEP_SEED=N` sweeps from another seed by hand;
//! `FINRS_IMPORT_SWEEP_OUTCOMES=FILE` appends each case's outcome to FILE,
//! to see which rules the sweep reaches.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;

use finrs::import::{import, Mapping};
use finrs::recording::Recording;
use rust_xlsxwriter::{Format, Formula, Workbook};

/// The sweep's seed, unless `FINRS_IMPORT_SWEEP_SEED` gives another.
const SEED: u64 = 0x0048_1AB5;
/// Spoiled mappings: 21 or 22 of each of [`MAPPING_SPOILS`]. The sweeps
/// together take a few seconds in release.
const MAPPING_CASES: usize = 360;
/// Spoiled workbooks: 9 or 10 of each of [`SHARED_SPOILS`] and
/// [`XLSX_SPOILS`].
const XLSX_CASES: usize = 240;
/// Spoiled text exports: 10 or 11 of each of [`SHARED_SPOILS`] and
/// [`TEXT_SPOILS`].
const TEXT_CASES: usize = 300;
/// Workbooks written by hand: 4 or 5 of each of [`RAW_SPOILS`].
const RAW_CASES: usize = 110;
/// Every this many cases of a sweep also run the binary (a process each:
/// the library is the same code, the binary adds its argument handling,
/// output folders and error printing).
const CLI_EVERY: usize = 6;

// ------------------------------------------------------------ randomness

/// xorshift64*: a few lines, the same numbers on every platform and with
/// every crate version, so a case's seed reproduces it for good.
struct Rng(u64);

impl Rng {
    /// The generator of one case. The seed is mixed first (splitmix64), so
    /// that cases with neighbouring seeds draw unrelated numbers; the
    /// state is never 0, which xorshift would keep.
    fn new(seed: u64) -> Rng {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Rng((z ^ (z >> 31)) | 1)
    }

    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64) < p * (1u64 << 53) as f64
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The seed of case `index` of the sweep numbered `sweep`.
fn case_seed(sweep: u64, index: usize) -> u64 {
    let base = std::env::var("FINRS_IMPORT_SWEEP_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(SEED);
    // The base multiplied first: bases that differ by little share no case.
    base.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (sweep << 40) ^ index as u64
}

// ------------------------------------------------------------ exports

/// A cell of an export to build.
#[derive(Clone, Debug, PartialEq)]
enum Cell {
    Num(f64),
    Text(String),
    /// Text a text export writes as it is, unquoted even where it holds
    /// the delimiter or a quote (a workbook writes it as text).
    Raw(String),
    Blank,
    /// A formula and the result the spreadsheet cached for it (a text
    /// export writes the result).
    Formula(&'static str, &'static str),
    Bool(bool),
    /// A number formatted as a date: Excel's days (a text export writes
    /// the number).
    Date(f64),
}

/// The columns of the export every case starts from: time in ms, the
/// drive, a current in mA, a laser's distance in mm (with the laser's
/// sentinel where it lost the spot), a note and a derived resistance
/// that is `Inf` where the current is 0 (neither of the last two mapped).
const HEADER: [&str; 6] = ["t (ms)", "V1 (V)", "I1 (mA)", "d (mm)", "note", "R (Ohm)"];
/// The laser's "no reading".
const SENTINEL: f64 = -99.9999;

/// An export to build: a sheet's rows from the top (any title rows, the
/// header, the data), written as a workbook or as text.
#[derive(Clone, Debug)]
struct Export {
    rows: Vec<Vec<Cell>>,
    /// The header's row, 1-based (1 + the title rows above it).
    header_row: usize,
    /// Merged blocks: first row, first column, last row, last column
    /// (0-based, as rust_xlsxwriter counts).
    merged: Vec<(u32, u16, u32, u16)>,
    /// The data's sheet's name.
    sheet: String,
    /// Another sheet with a note on it, before the data's (`true`) or
    /// after it.
    other_sheet: Option<bool>,
}

/// `x` to `digits` decimals, as the bench's instruments write it (the
/// shortest double that prints so).
fn round(x: f64, digits: usize) -> f64 {
    format!("{x:.digits$}").parse().unwrap()
}

/// A clean export of 1.1 to 2.6 s at 100 rows/s: 1 s at rest, then a step
/// of 2 V; every value within the format's rules, so that a refusal in a
/// spoiled case is due to the spoiling.
fn base_export(rng: &mut Rng) -> Export {
    let n = 110 + rng.below(150);
    let mut rows = vec![HEADER.iter().map(|h| Cell::Text(h.to_string())).collect()];
    for i in 0..n {
        let on = i >= 100;
        // The read-back's rest: 0.3 to 1.1 mV.
        let v = round(
            if on { 2.0 } else { 0.0 } + (3 + rng.below(9)) as f64 * 1e-4,
            4,
        );
        let after = (i as f64 - 100.0) / 40.0;
        let noise = (rng.below(5) as f64 - 2.0) * 0.1;
        let i_ma = round(
            if on { 25.0 * (-after).exp() + 1.5 } else { 0.0 } + noise,
            1,
        );
        let tip_mm = if on {
            2.0 * (1.0 - (-after).exp())
        } else {
            0.0
        };
        // No sentinel in the opening: its mean is the laser's zero.
        let d = if i >= 60 && rng.chance(0.03) {
            SENTINEL
        } else {
            round(30.0 - tip_mm + rng.below(9) as f64 * 1e-4, 4)
        };
        let note = if rng.chance(0.05) {
            Cell::Text("spot lost?".into())
        } else {
            Cell::Blank
        };
        let r = if i_ma == 0.0 {
            Cell::Text("Inf".into())
        } else {
            Cell::Num(round(v / (i_ma * 1e-3), 2))
        };
        rows.push(vec![
            Cell::Num((10 * i) as f64),
            Cell::Num(v),
            Cell::Num(i_ma),
            Cell::Num(d),
            note,
            r,
        ]);
    }
    Export {
        rows,
        header_row: 1,
        merged: Vec::new(),
        sheet: "Sheet1".into(),
        other_sheet: None,
    }
}

impl Export {
    /// The header's index in `rows`.
    fn header(&self) -> usize {
        self.header_row - 1
    }

    /// A data row's index in `rows`, if there is data.
    fn data_row(&self, rng: &mut Rng) -> Option<usize> {
        let first = self.header_row;
        (self.rows.len() > first).then(|| first + rng.below(self.rows.len() - first))
    }

    /// Sets a cell, widening its row as needed.
    fn set(&mut self, row: usize, col: usize, cell: Cell) {
        if row >= self.rows.len() {
            self.rows.resize(row + 1, Vec::new());
        }
        let cells = &mut self.rows[row];
        if cells.len() <= col {
            cells.resize(col + 1, Cell::Blank);
        }
        cells[col] = cell;
    }

    /// The workbook's bytes; what rust_xlsxwriter refuses to write (a
    /// string over 32 767 characters, overlapping merges) is left out,
    /// and said in `done`.
    fn xlsx(&self, done: &mut Vec<String>) -> Vec<u8> {
        let mut book = Workbook::new();
        let note = |book: &mut Workbook| {
            let ws = book.add_worksheet();
            ws.set_name("Notes").unwrap();
            ws.write_string(0, 0, "bench notes").unwrap();
        };
        if self.other_sheet == Some(true) {
            note(&mut book);
        }
        let ws = book.add_worksheet();
        if let Err(e) = ws.set_name(&self.sheet) {
            done.push(format!("(the writer refused the sheet's name: {e})"));
        }
        let mut refused = 0;
        for (r, row) in self.rows.iter().enumerate() {
            for (c, cell) in row.iter().enumerate() {
                let (r, c) = (r as u32, c as u16);
                let written = match cell {
                    Cell::Num(x) => ws.write_number(r, c, *x).map(|_| ()),
                    Cell::Text(s) | Cell::Raw(s) => ws.write_string(r, c, s).map(|_| ()),
                    Cell::Blank => Ok(()),
                    Cell::Formula(f, result) => ws
                        .write_formula(r, c, Formula::new(*f).set_result(*result))
                        .map(|_| ()),
                    Cell::Bool(b) => ws.write_boolean(r, c, *b).map(|_| ()),
                    Cell::Date(days) => {
                        let date = Format::new().set_num_format("yyyy-mm-dd hh:mm");
                        ws.write_number_with_format(r, c, *days, &date).map(|_| ())
                    }
                };
                refused += usize::from(written.is_err());
            }
        }
        for &(r0, c0, r1, c1) in &self.merged {
            // The block keeps its first cell's text, as a spreadsheet does.
            let first = match self.rows.get(r0 as usize).and_then(|r| r.get(c0 as usize)) {
                Some(Cell::Text(s)) => s.clone(),
                _ => String::new(),
            };
            refused += usize::from(
                ws.merge_range(r0, c0, r1, c1, &first, &Format::new())
                    .is_err(),
            );
        }
        if refused > 0 {
            done.push(format!(
                "(the writer refused {refused} cell(s) or merge(s))"
            ));
        }
        if self.other_sheet == Some(false) {
            note(&mut book);
        }
        book.save_to_buffer().unwrap()
    }

    /// The text export's bytes, fields separated by `style.delimiter`.
    fn text(&self, style: &TextStyle) -> Vec<u8> {
        let delimiter = style.delimiter as char;
        let number = |x: f64| {
            let s = format!("{x}");
            if style.decimal_comma {
                s.replace('.', ",")
            } else {
                s
            }
        };
        // CSV's quoting, where a field needs it.
        let quoted = |s: &str| {
            if s.contains([delimiter, '"', '\n', '\r']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_string()
            }
        };
        let mut out = String::new();
        for row in &self.rows {
            let fields: Vec<String> = row
                .iter()
                .map(|cell| match cell {
                    Cell::Num(x) | Cell::Date(x) => number(*x),
                    Cell::Text(s) => quoted(s),
                    Cell::Raw(s) => s.clone(),
                    Cell::Blank => String::new(),
                    Cell::Formula(_, result) => quoted(result),
                    Cell::Bool(b) => if *b { "TRUE" } else { "FALSE" }.to_string(),
                })
                .collect();
            out.push_str(&fields.join(&delimiter.to_string()));
            out.push_str(style.line_end);
        }
        out.into_bytes()
    }
}

/// How a text export is written.
#[derive(Clone, Debug)]
struct TextStyle {
    delimiter: u8,
    decimal_comma: bool,
    line_end: &'static str,
}

// ------------------------------------------------------------ the mapping

/// How an export is laid out, and so how the mapping that reads it
/// cleanly reads it.
#[derive(Clone, Debug)]
struct Layout {
    /// The export's file name: its extension says how it is read.
    name: String,
    /// A text export's delimiter and decimal comma; `None` for a workbook.
    text: Option<(u8, bool)>,
    /// The mapping gives `delimiter` (else the extension's is taken).
    say_delimiter: bool,
    header_row: usize,
    /// `source.sheet`, if given.
    sheet: Option<String>,
    /// Time from `rate_hz` rather than the `t (ms)` column.
    rate: bool,
}

impl Layout {
    /// A layout drawn at random: a workbook or one of the text exports.
    fn random(rng: &mut Rng, workbook: bool) -> Layout {
        let rate = rng.chance(0.4);
        if workbook {
            let sheet = rng.chance(0.5).then(|| "Sheet1".to_string());
            return Layout {
                name: "sweep.xlsx".into(),
                text: None,
                say_delimiter: false,
                header_row: 1,
                sheet,
                rate,
            };
        }
        let (name, delimiter, decimal_comma, say) = *rng.pick(&[
            ("sweep.csv", b',', false, false),
            ("sweep.csv", b',', false, true),
            ("sweep.csv", b';', true, true),
            ("sweep.tsv", b'\t', false, false),
            ("sweep.tsv", b'\t', true, false),
            ("sweep.txt", b'\t', false, true),
            ("sweep.dat", b'|', false, true),
        ]);
        Layout {
            name: name.into(),
            text: Some((delimiter, decimal_comma)),
            say_delimiter: say,
            header_row: 1,
            sheet: None,
            rate,
        }
    }
}

/// The mapping that reads an export of `layout` cleanly: every key of
/// `finrs-import/1` used somewhere, so that each can be spoiled.
fn mapping_text(layout: &Layout) -> String {
    let mut source = format!(
        "header_row = {}\nfirst_data_row = {}\n",
        layout.header_row,
        layout.header_row + 1
    );
    if let Some(sheet) = &layout.sheet {
        writeln!(source, "sheet = {sheet:?}").unwrap();
    }
    if let Some((delimiter, decimal_comma)) = layout.text {
        if layout.say_delimiter {
            writeln!(source, "delimiter = {:?}", (delimiter as char).to_string()).unwrap();
        }
        writeln!(source, "decimal_comma = {decimal_comma}").unwrap();
    }
    let time = if layout.rate {
        "rate_hz = 100.0\nstart_s = 0.0"
    } else {
        "column = \"t (ms)\"\nscale = 0.001\nzero = \"first\"\nstart_s = 0.0"
    };
    format!(
        r#"format = "finrs-import/1"

[source]
{source}
[time]
{time}

[[channel]]
to = "v1_V"
column = "V1 (V)"

[[channel]]
to = "i1_A"
letter = "C"
scale = 0.001
valid = [-50.0, 50.0]

[[channel]]
to = "tip_y_m"
index = 4
scale = 0.001
sign = -1
zero = "opening"
opening_s = 0.5
out_of_range = [-99.9999, inf]

[metadata]
segments = 1
length_m = 0.03
width_m = 0.005
thickness_m = 0.0002
fixture = "free"
medium = "air"
sample = "SWEEP-1"
cation = "Na+"
dots_s_m = [0.015, 0.03]
notes = "the import sweep's export"

[files."{name}"]
t_session_start_s = 12.5
notes = "this export's own"
"#,
        name = layout.name
    )
}

/// What is done to a mapping; each case does one (counted), then up to
/// two more at random.
const MAPPING_SPOILS: [&str; 17] = [
    "an extreme value the rules allow",
    "drop a line",
    "a line twice",
    "a value of the wrong type",
    "a bad number",
    "a column that does not exist or lies out of range",
    "an empty string",
    "unicode",
    "truncated",
    "an unknown key",
    "a key in the wrong table",
    "a table added",
    "the source changed",
    "the metadata changed",
    "the time changed",
    "a garbage line",
    "bytes: not UTF-8, a BOM, CRLF, NUL",
];

/// The mapping spoil done to the joined bytes, not to the lines.
const BYTE_SPOIL: &str = "bytes: not UTF-8, a BOM, CRLF, NUL";

/// Values a numeric key takes that pass the mapping's rules yet push the
/// arithmetic of an import: the largest and smallest doubles, subnormals,
/// ranges and sentinels that take in everything or nothing.
fn extreme_values(key: &str) -> Option<&'static [&'static str]> {
    Some(match key {
        "scale" => &[
            "1e308", "-1e308", "1e-308", "5e-324", "1e18", "-1e-18", "1e19", "0.1",
        ],
        "zero" => &["1e308", "-1e308", "5e-324", "-0.0", "30"],
        "rate_hz" => &["1e308", "5e-324", "1e-300", "1e9", "0.001"],
        "start_s" => &["1e300", "5e-324", "1e15", "4294967296.5"],
        "opening_s" => &["5e-324", "1e308", "1e-9", "100"],
        "valid" => &[
            "[-inf, inf]",
            "[1e308, inf]",
            "[0.0, 5e-324]",
            "[-1e308, 1e308]",
        ],
        "out_of_range" => &[
            "[nan]",
            "[inf, -inf]",
            "[0.0]",
            "[-0.0]",
            "[1e308]",
            "[30.0]",
            "[]",
        ],
        "t_session_start_s" => &["1e308", "5e-324", "0"],
        "length_m" | "width_m" | "thickness_m" => &["1e308", "5e-324"],
        _ => return None,
    })
}

/// Values of a type no key of the mapping takes, or of another key's.
const WRONG_TYPES: [&str; 12] = [
    "\"text\"",
    "\"1.5\"",
    "true",
    "[1, 2]",
    "[]",
    "[\"a\"]",
    "{ a = 1 }",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "12",
    "1.5",
    "-1",
];

/// Numbers that are zero, negative, not finite, below or beyond any range.
const NUMBERS: [&str; 26] = [
    "0",
    "-0.0",
    "-1",
    "-1e-9",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "1e-300",
    "9223372036854775807",
    "-9223372036854775808",
    "1e18",
    "1e-18",
    "1048576",
    "1048577",
    "16384",
    "16385",
    "2",
    "3",
    "8",
    "9",
    "0.001",
];

/// Unicode in TOML strings: accents, an emoji, right-to-left and
/// zero-width marks, control characters, a lone combining mark.
const UNICODE: [&str; 10] = [
    "\"Ünïcødé ✓\"",
    "\"🦀\"",
    "\"\\u202Eevil\"",
    "\"V1\\u200B (V)\"",
    "\"\\u0000\"",
    "\"a\\nb\"",
    "\"\\t\"",
    "\"\\u0301\"",
    "\"Ｖ1 (V)\"",
    "'literal \\ string'",
];

/// A column given every way a mapping can get it wrong (and a few right).
const COLUMN_REFS: [&str; 26] = [
    "index = 0",
    "index = -3",
    "index = 7",
    "index = 16384",
    "index = 16385",
    "index = 99999999999",
    "index = 1.5",
    "letter = \"G\"",
    "letter = \"XFD\"",
    "letter = \"XFE\"",
    "letter = \"ZZZZ\"",
    "letter = \"\"",
    "letter = \"a\"",
    "letter = \"Ä\"",
    "letter = \"A1\"",
    "column = \"\"",
    "column = \"   \"",
    "column = \"nope\"",
    "column = \" V1 (V) \"",
    "column = \"v1 (v)\"",
    "column = \"R (Ohm)\"",
    "column = \"note\"",
    "column = \"I1 (mA)\"",
    "column = \"t (ms)\"",
    "column = \"Ünï ✓\"",
    "column = 3",
];

/// Keys nobody reads.
const UNKNOWN_KEYS: [&str; 7] = [
    "sheeet = \"Sheet1\"",
    "unit = \"mm\"",
    "\"\" = 1",
    "\"ü\" = 2",
    "rate = 100",
    "a.b = 1",
    "Scale = 0.001",
];

/// Keys of the mapping, each with a value it may take: put in the wrong
/// table, or given twice.
const KNOWN_KEYS: [&str; 24] = [
    "format = \"finrs-import/1\"",
    "sheet = \"Sheet1\"",
    "delimiter = \";\"",
    "header_row = 1",
    "first_data_row = 2",
    "decimal_comma = true",
    "to = \"v1_V\"",
    "column = \"V1 (V)\"",
    "letter = \"B\"",
    "index = 2",
    "rate_hz = 100.0",
    "start_s = 1.0",
    "scale = 0.001",
    "sign = -1",
    "zero = \"opening\"",
    "zero = \"first\"",
    "zero = 5",
    "opening_s = 0.5",
    "out_of_range = [nan]",
    "valid = [0.0, 1.0]",
    "segments = 2",
    "fixture = \"blocked\"",
    "dots_s_m = [0.01]",
    "t_session_start_s = 1.0",
];

/// `[source]` keys with values that break a rule, or change the layout.
const SOURCE_KEYS: [&str; 22] = [
    "header_row = 0",
    "header_row = 2",
    "header_row = 1048576",
    "header_row = -1",
    "first_data_row = 1",
    "first_data_row = 3",
    "first_data_row = 1048576",
    "first_data_row = 1048577",
    "delimiter = \"\"",
    "delimiter = \",\"",
    "delimiter = \";;\"",
    "delimiter = \"\\\"\"",
    "delimiter = \"\\n\"",
    "delimiter = \"é\"",
    "delimiter = \" \"",
    "delimiter = \"1\"",
    "delimiter = \".\"",
    "decimal_comma = true",
    "decimal_comma = false",
    "sheet = \"Nope\"",
    "sheet = \"\"",
    "sheet = \"sheet1\"",
];

/// `[metadata]` keys with values that break a rule, or change what the
/// channels may be.
const META_KEYS: [&str; 20] = [
    "segments = 0",
    "segments = 2",
    "segments = 9",
    "segments = -1",
    "length_m = 0",
    "width_m = -0.005",
    "thickness_m = nan",
    "length_m = inf",
    "fixture = \"blocked\"",
    "fixture = \"clamped\"",
    "fixture = \"\"",
    "medium = \"water\"",
    "medium = \"oil\"",
    "dots_s_m = []",
    "dots_s_m = [0.05]",
    "dots_s_m = [0.02, 0.01]",
    "t_session_start_s = -1",
    "t_session_start_s = nan",
    "t_session_start_s = 1e308",
    "notes = \"a\\nb # c\"",
];

/// Bodies of `[time]`: both a column and a rate, neither, keys of the
/// other kind, starts and zeros out of range.
const TIME_BODIES: [&str; 14] = [
    "",
    "rate_hz = 100\ncolumn = \"t (ms)\"",
    "rate_hz = 100\nscale = 0.001",
    "rate_hz = 100\nzero = \"first\"",
    "rate_hz = 1e-300",
    "rate_hz = 1e308",
    "rate_hz = 5e-324",
    "rate_hz = 100\nstart_s = 1e300",
    "rate_hz = 100\nstart_s = -1",
    "column = \"t (ms)\"\nzero = \"opening\"",
    "column = \"t (ms)\"\nscale = 1e308",
    "column = \"t (ms)\"\nzero = -1e308",
    "column = \"t (ms)\"\nscale = 0.001\nzero = 1e6",
    "index = 1\nscale = 0.001\nsign = -1",
];

/// Lines that are no TOML, or TOML of no mapping.
const GARBAGE: [&str; 8] = [
    "this is not toml",
    "= 1",
    "[",
    "[[",
    "key = \"unterminated",
    "x = 1 = 2",
    "\u{1}\u{2}\u{7f}",
    "🦀 = 🦀",
];

/// Indices of `key = value` lines.
fn key_lines(lines: &[String]) -> Vec<usize> {
    (0..lines.len())
        .filter(|&i| !lines[i].starts_with('[') && lines[i].contains(" = "))
        .collect()
}

/// Indices of table headers (`[time]`, `[[channel]]`, ...).
fn table_lines(lines: &[String]) -> Vec<usize> {
    (0..lines.len())
        .filter(|&i| lines[i].starts_with('['))
        .collect()
}

/// Sets `key = value` in the table headed `table`: in place of the key's
/// line if the table has one, else right after the header, else in a new
/// table at the end.
fn set_in_table(lines: &mut Vec<String>, table: &str, line: &str) {
    let key = line.split(" = ").next().unwrap_or(line);
    let Some(head) = lines.iter().position(|l| l == table) else {
        lines.extend([String::new(), table.to_string(), line.to_string()]);
        return;
    };
    let end = (head + 1..lines.len())
        .find(|&i| lines[i].starts_with('['))
        .unwrap_or(lines.len());
    match (head + 1..end).find(|&i| lines[i].split(" = ").next() == Some(key)) {
        Some(i) => lines[i] = line.to_string(),
        None => lines.insert(head + 1, line.to_string()),
    }
}

/// Puts `value` in place of the value of a random key line, if one is
/// there; what was done.
fn replace_value(rng: &mut Rng, lines: &mut [String], value: &str) -> String {
    let keys = key_lines(lines);
    if keys.is_empty() {
        return "nothing to replace".into();
    }
    let i = *rng.pick(&keys);
    let key = lines[i].split(" = ").next().unwrap().to_string();
    lines[i] = format!("{key} = {value}");
    format!("line {}: {key} = {value}", i + 1)
}

/// Spoils a mapping's lines by `kind` (not the byte spoils, done after
/// the lines are joined); what was done.
fn spoil_mapping(kind: &str, rng: &mut Rng, lines: &mut Vec<String>) -> String {
    let any_line = |rng: &mut Rng, lines: &[String]| rng.below(lines.len().max(1));
    match kind {
        "an extreme value the rules allow" => {
            let keys: Vec<usize> = key_lines(lines)
                .into_iter()
                .filter(|&i| extreme_values(lines[i].split(" = ").next().unwrap()).is_some())
                .collect();
            if keys.is_empty() {
                return "no numeric key".into();
            }
            let i = *rng.pick(&keys);
            let key = lines[i].split(" = ").next().unwrap().to_string();
            let value = *rng.pick(extreme_values(&key).unwrap());
            lines[i] = format!("{key} = {value}");
            format!("line {}: {key} = {value}", i + 1)
        }
        "drop a line" if !lines.is_empty() => {
            let i = any_line(rng, lines);
            format!("dropped line {}: {}", i + 1, lines.remove(i))
        }
        "a line twice" if !lines.is_empty() => {
            let i = any_line(rng, lines);
            let line = lines[i].clone();
            lines.insert(i, line.clone());
            format!("line {} twice: {line}", i + 1)
        }
        "a value of the wrong type" => {
            let v = *rng.pick(&WRONG_TYPES);
            replace_value(rng, lines, v)
        }
        "a bad number" => {
            // A numeric key's value, mostly: those the rules are about.
            let numeric: Vec<usize> = key_lines(lines)
                .into_iter()
                .filter(|&i| {
                    let v = lines[i].split(" = ").nth(1).unwrap_or("");
                    v.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '[')
                })
                .collect();
            let v = *rng.pick(&NUMBERS);
            if numeric.is_empty() {
                return replace_value(rng, lines, v);
            }
            let i = *rng.pick(&numeric);
            let key = lines[i].split(" = ").next().unwrap().to_string();
            // Half of the arrays keep their shape: [v, x].
            let value = if lines[i].contains('[') && rng.chance(0.5) {
                format!("[{v}, 1.0]")
            } else {
                v.to_string()
            };
            lines[i] = format!("{key} = {value}");
            format!("line {}: {key} = {value}", i + 1)
        }
        "a column that does not exist or lies out of range" => {
            let refs: Vec<usize> = key_lines(lines)
                .into_iter()
                .filter(|&i| {
                    ["column", "letter", "index"]
                        .contains(&lines[i].split(" = ").next().unwrap_or(""))
                })
                .collect();
            let new = rng.pick(&COLUMN_REFS).to_string();
            if refs.is_empty() {
                return format!("no column to change ({new})");
            }
            let i = *rng.pick(&refs);
            let old = std::mem::replace(&mut lines[i], new.clone());
            format!("line {}: {old} -> {new}", i + 1)
        }
        "an empty string" => replace_value(rng, lines, "\"\""),
        "unicode" => {
            let v = *rng.pick(&UNICODE);
            replace_value(rng, lines, v)
        }
        "truncated" => {
            let text = lines.join("\n");
            let cut = text
                .char_indices()
                .map(|(i, _)| i)
                .nth(rng.below(text.chars().count().max(1)))
                .unwrap_or(0);
            *lines = text[..cut].split('\n').map(String::from).collect();
            format!("truncated after {cut} bytes")
        }
        "an unknown key" | "a key in the wrong table" => {
            let line = if kind == "an unknown key" {
                *rng.pick(&UNKNOWN_KEYS)
            } else {
                *rng.pick(&KNOWN_KEYS)
            };
            let tables = table_lines(lines);
            // After a table's header, or at the top (the top level's).
            let at = if tables.is_empty() || rng.chance(0.15) {
                0
            } else {
                rng.pick(&tables) + 1
            };
            lines.insert(at.min(lines.len()), line.to_string());
            format!("line {}: {line}", at + 1)
        }
        "a table added" => {
            let to = *rng.pick(&[
                "v1_V", "v2_V", "i2_A", "tip_x_m", "dot1_y_m", "dot3_x_m", "force_N", "t_s",
                "v0_V", "V1_V", "i1_A",
            ]);
            let column = *rng.pick(&COLUMN_REFS);
            let table = match rng.below(6) {
                0 | 1 => format!("[[channel]]\nto = \"{to}\"\n{column}"),
                2 => format!(
                    "[files.\"{}\"]\n{}",
                    rng.pick(&["sweep.csv", "other.xlsx", "", "ü.xlsx"]),
                    rng.pick(&META_KEYS)
                ),
                3 => rng
                    .pick(&["[source]", "[time]", "[metadata]", "[files]"])
                    .to_string(),
                4 => rng
                    .pick(&["[bogus]", "[[time]]", "[metadata.extra]", "[[source]]"])
                    .to_string(),
                _ => "[[channel]]".to_string(),
            };
            let tables = table_lines(lines);
            let at = if tables.is_empty() || rng.chance(0.3) {
                lines.len()
            } else {
                *rng.pick(&tables)
            };
            for (k, line) in table.lines().enumerate() {
                lines.insert(at + k, line.to_string());
            }
            format!("at line {}: {}", at + 1, table.replace('\n', "; "))
        }
        "the source changed" => {
            let line = *rng.pick(&SOURCE_KEYS);
            set_in_table(lines, "[source]", line);
            format!("[source] {line}")
        }
        "the metadata changed" => {
            let line = *rng.pick(&META_KEYS);
            // Now and then the export's own [files."NAME"], if still there.
            let files = lines.iter().find(|l| l.starts_with("[files."));
            let table = match files {
                Some(files) if rng.chance(0.3) => files.clone(),
                _ => "[metadata]".to_string(),
            };
            set_in_table(lines, &table, line);
            format!("{table} {line}")
        }
        "the time changed" => {
            let body = *rng.pick(&TIME_BODIES);
            match lines.iter().position(|l| l == "[time]") {
                None => format!("no [time] to change ({body:?})"),
                Some(head) => {
                    let end = (head + 1..lines.len())
                        .find(|&i| lines[i].starts_with('['))
                        .unwrap_or(lines.len());
                    lines.splice(head + 1..end, body.lines().map(String::from));
                    format!("[time] now {body:?}")
                }
            }
        }
        "a garbage line" => {
            let line = *rng.pick(&GARBAGE);
            let at = rng.below(lines.len() + 1);
            lines.insert(at, line.to_string());
            format!("line {}: {line:?}", at + 1)
        }
        _ => format!("{kind}: nothing to do"),
    }
}

/// The byte spoils of a mapping: bytes that are not UTF-8, a byte order
/// mark, CRLF line ends, a NUL.
fn spoil_mapping_bytes(rng: &mut Rng, bytes: &mut Vec<u8>) -> String {
    let at = rng.below(bytes.len() + 1);
    match rng.below(5) {
        0 => {
            bytes.splice(at..at, [0xFF, 0xFE]);
            format!("bytes FF FE at {at}")
        }
        1 => {
            // A Latin-1 degree sign, as an old editor saves "°C".
            bytes.insert(at, 0xB0);
            format!("byte B0 at {at}")
        }
        2 => {
            bytes.splice(0..0, [0xEF, 0xBB, 0xBF]);
            "a byte order mark".into()
        }
        3 => {
            *bytes = String::from_utf8_lossy(bytes)
                .replace('\n', "\r\n")
                .into_bytes();
            "CRLF line ends".into()
        }
        _ => {
            bytes.insert(at, 0);
            format!("a NUL at {at}")
        }
    }
}

/// Applies the mapping spoil `kind` (line or byte) to `text`, then in half
/// the cases one or two more at random (at most `extra`); what was done
/// goes to `done`.
fn spoiled_mapping(
    rng: &mut Rng,
    text: &str,
    kind: &str,
    extra: usize,
    done: &mut Vec<String>,
) -> Vec<u8> {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Half the cases spoiled once only: each spoil past the first mostly
    // stops the mapping sooner, and the later checks are to be reached too.
    let mut kinds = vec![kind];
    let more = if rng.chance(0.5) {
        0
    } else {
        (1 + rng.below(2)).min(extra)
    };
    for _ in 0..more {
        kinds.push(*rng.pick(&MAPPING_SPOILS));
    }
    let bytes_too = kinds.contains(&BYTE_SPOIL);
    for kind in kinds.iter().filter(|k| **k != BYTE_SPOIL) {
        let what = spoil_mapping(kind, rng, &mut lines);
        done.push(format!("mapping, {kind}: {what}"));
    }
    let mut bytes = (lines.join("\n") + "\n").into_bytes();
    if bytes_too {
        let what = spoil_mapping_bytes(rng, &mut bytes);
        done.push(format!("mapping bytes: {what}"));
    }
    bytes
}

// ------------------------------------------------------------ export spoils

/// What is done to an export of either kind.
const SHARED_SPOILS: [&str; 15] = [
    "drop a column",
    "rename a header",
    "a header twice",
    "text in a number",
    "an odd number",
    "a blank cell",
    "a blank row",
    "a header only",
    "nothing at all",
    "a very long row",
    "time not increasing",
    "no header",
    "few rows",
    "unicode headers",
    "a voltage beyond the drive's range",
];

/// What is done to a workbook only.
const XLSX_SPOILS: [&str; 11] = [
    "merged across the header and the data",
    "merged in the data",
    "a title merged above the header",
    "a formula with a cached number",
    "a formula with a cached error or text",
    "a TRUE/FALSE cell",
    "a date cell",
    "a second sheet",
    "a cell far right or far down",
    "a damaged zip",
    "an odd sheet name",
];

/// What is done to a text export only.
const TEXT_SPOILS: [&str; 14] = [
    "ragged rows",
    "decimal commas mismatched",
    "a byte order mark",
    "CR or CRLF line ends",
    "an empty file",
    "binary garbage",
    "bytes not UTF-8",
    "an unclosed quote",
    "a quoted line end",
    "blank lines at the end",
    "NUL bytes",
    "an unquoted delimiter in text",
    "truncated mid-line",
    "another extension",
];

/// Text in a numeric cell: words, a decimal comma, two points, spelled
/// infinities and NaN, hex, a unicode minus and digits, a thousands
/// separator, half a number, a 10 000-digit number (beyond the doubles),
/// a line end, a NUL.
fn odd_text(rng: &mut Rng) -> String {
    match rng.below(30) {
        0 => "9".repeat(10_000),
        1 => format!("0.{}1", "0".repeat(5000)),
        k => [
            "n/a", "1,5", "1.5.5", "Inf", "-inf", "NaN", "nan", "+inf", "1e999", "-1e999", "0x10",
            "−1", "١٢", "1_000", ".5", "5.", "1e", "e5", " 7 ", "   ", "TRUE", "#DIV/0!",
            "2,000.5", "1 000", "½", "∞", "\u{0}", "ab\ncd",
        ][k - 2]
            .to_string(),
    }
}

/// Numbers at the edges: the largest, the smallest, subnormal, signed
/// zero, infinities, NaN, the sentinel, beyond the drive's range.
const ODD_NUMBERS: [f64; 15] = [
    1e308,
    -1e308,
    f64::MAX,
    f64::MIN_POSITIVE,
    5e-324,
    -0.0,
    0.0,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    SENTINEL,
    4.5,
    -4.0001,
    1e15,
    123_456_789.123_456_79,
];

/// A mapped column (0..4: time, voltage, current, distance) or, now and
/// then, an unmapped one.
fn a_column(rng: &mut Rng) -> usize {
    if rng.chance(0.85) {
        rng.below(4)
    } else {
        4 + rng.below(2)
    }
}

/// Spoils `export` (and the layout its mapping is made for) by `kind`;
/// what was done. Byte spoils of text exports are done by
/// [`spoil_text_bytes`], style spoils by [`spoil_style`].
fn spoil_export(kind: &str, rng: &mut Rng, e: &mut Export, layout: &mut Layout) -> String {
    let h = e.header();
    match kind {
        "drop a column" => {
            let c = rng.below(HEADER.len());
            for row in &mut e.rows {
                if c < row.len() {
                    row.remove(c);
                }
            }
            format!("column {c} ({}) removed", HEADER[c])
        }
        "rename a header" => {
            let c = rng.below(4);
            let name = match rng.below(4) {
                0 => format!("{} (renamed)", HEADER[c]),
                1 => HEADER[c].to_uppercase(),
                2 => format!("  {}  ", HEADER[c]),
                _ => HEADER[c].replace(' ', "  "),
            };
            e.set(h, c, Cell::Text(name.clone()));
            format!("header {c} is now {name:?}")
        }
        "a header twice" => {
            let (from, to) = (rng.below(4), 4 + rng.below(2));
            e.set(h, to, Cell::Text(HEADER[from].into()));
            format!("{:?} heads column {to} too", HEADER[from])
        }
        "text in a number" => match e.data_row(rng) {
            Some(r) => {
                let (c, text) = (a_column(rng), odd_text(rng));
                let what = format!("row {r} column {c}: text {:?}", cut(&text));
                e.set(r, c, Cell::Text(text));
                what
            }
            None => "no data row".into(),
        },
        "an odd number" => match e.data_row(rng) {
            Some(r) => {
                let (c, x) = (a_column(rng), *rng.pick(&ODD_NUMBERS));
                e.set(r, c, Cell::Num(x));
                format!("row {r} column {c}: {x:?}")
            }
            None => "no data row".into(),
        },
        "a blank cell" => match e.data_row(rng) {
            Some(r) => {
                let c = a_column(rng);
                e.set(r, c, Cell::Blank);
                format!("row {r} column {c} blank")
            }
            None => "no data row".into(),
        },
        "a blank row" => match e.data_row(rng) {
            Some(r) => {
                e.rows[r] = Vec::new();
                format!("row {r} blank")
            }
            None => "no data row".into(),
        },
        "a header only" => {
            e.rows.truncate(e.header_row);
            "the data removed".into()
        }
        "nothing at all" => {
            e.rows.clear();
            "every row removed".into()
        }
        "a very long row" => {
            let r = e.data_row(rng).filter(|_| rng.chance(0.8)).unwrap_or(h);
            let width = 100 + rng.below(3000);
            for c in HEADER.len()..width {
                let cell = match c % 3 {
                    0 => Cell::Num(c as f64),
                    1 => Cell::Text(format!("x{c}")),
                    _ => Cell::Blank,
                };
                e.set(r, c, cell);
            }
            format!("row {r} {width} cells wide")
        }
        "time not increasing" => match e.data_row(rng) {
            Some(r) => {
                let t = match rng.below(3) {
                    0 => 0.0,
                    1 => -10.0,
                    _ => match e.rows[r.saturating_sub(1)].first() {
                        Some(Cell::Num(t)) => *t,
                        _ => 5.0,
                    },
                };
                e.set(r, 0, Cell::Num(t));
                format!("row {r}: time {t} ms")
            }
            None => "no data row".into(),
        },
        "no header" => {
            if let Some(row) = e.rows.get_mut(h) {
                row.iter_mut().for_each(|c| *c = Cell::Blank);
            }
            "the header's cells blank".into()
        }
        "few rows" => {
            let keep = rng.below(4);
            e.rows.truncate(e.header_row + keep);
            format!("{keep} data row(s) kept")
        }
        "unicode headers" => {
            let c = rng.below(4);
            let name = match rng.below(4) {
                // A no-break space is white space: trimmed, so found.
                0 => format!("{}\u{a0}", HEADER[c]),
                1 => format!("{}\u{200b}", HEADER[c]),
                2 => HEADER[c].replace('V', "Ｖ"),
                _ => "Zeit [ms] – Ünïcødé ✓ 🦀".to_string(),
            };
            e.set(h, c, Cell::Text(name.clone()));
            format!("header {c} is now {name:?}")
        }
        "a voltage beyond the drive's range" => match e.data_row(rng) {
            Some(r) => {
                let v = *rng.pick(&[4.5, -4.2, 4.02, 4.0, -4.0251, 1e6]);
                e.set(r, 1, Cell::Num(v));
                format!("row {r}: voltage {v}")
            }
            None => "no data row".into(),
        },
        "merged across the header and the data" => {
            let c = rng.below(5) as u16;
            let (rows, cols) = (1 + rng.below(3) as u32, rng.below(2) as u16);
            let r = h as u32;
            e.merged.push((r, c, r + rows, c + cols));
            format!("merged rows {r}..={} columns {c}..={}", r + rows, c + cols)
        }
        "merged in the data" => match e.data_row(rng) {
            Some(r) => {
                let c = a_column(rng) as u16;
                let (r, rows) = (r as u32, rng.below(3) as u32);
                let cols = u16::from(rows == 0) + rng.below(2) as u16;
                e.merged.push((r, c, r + rows, c + cols));
                format!("merged rows {r}..={} columns {c}..={}", r + rows, c + cols)
            }
            None => "no data row".into(),
        },
        "a title merged above the header" => {
            e.rows
                .insert(0, vec![Cell::Text("Run 7 – step 2 V".into())]);
            e.header_row += 1;
            e.merged.iter_mut().for_each(|m| {
                m.0 += 1;
                m.2 += 1;
            });
            e.merged.push((0, 0, 0, 5));
            // Mostly the mapping says so; else it looks for names in the title.
            if rng.chance(0.8) {
                layout.header_row = e.header_row;
                "a merged title row above; the mapping's header_row follows".into()
            } else {
                "a merged title row above; the mapping still says header_row = 1".into()
            }
        }
        "a formula with a cached number" | "a formula with a cached error or text" => {
            match e.data_row(rng) {
                Some(r) => {
                    let result = if kind == "a formula with a cached number" {
                        *rng.pick(&[
                            "2.5", "0", "-0", "0.0007", "-99.9999", "1e308", "1e999", "inf", "NaN",
                        ])
                    } else {
                        *rng.pick(&[
                            "#DIV/0!", "#N/A", "#VALUE!", "#REF!", "#NUM!", "n/a", "", "TRUE",
                        ])
                    };
                    let c = a_column(rng);
                    e.set(r, c, Cell::Formula("=B2*1", result));
                    format!("row {r} column {c}: =B2*1 cached {result:?}")
                }
                None => "no data row".into(),
            }
        }
        "a TRUE/FALSE cell" | "a date cell" => match e.data_row(rng) {
            Some(r) => {
                let c = a_column(rng);
                let cell = match kind {
                    "a date cell" => Cell::Date(45_000.5),
                    _ => Cell::Bool(rng.chance(0.5)),
                };
                let what = format!("row {r} column {c}: {cell:?}");
                e.set(r, c, cell);
                what
            }
            None => "no data row".into(),
        },
        "a second sheet" => {
            let before = rng.chance(0.6);
            e.other_sheet = Some(before);
            layout.sheet = rng
                .pick(&[None, Some("Sheet1"), Some("Notes"), Some("Missing")])
                .map(String::from);
            format!(
                "a sheet \"Notes\" {} the data's; source.sheet = {:?}",
                if before { "before" } else { "after" },
                layout.sheet
            )
        }
        "a cell far right or far down" => {
            let (r, c) = match rng.below(4) {
                0 => (h, 16_383),
                1 => (e.data_row(rng).unwrap_or(h), 16_383),
                2 => (1_048_575, a_column(rng)),
                _ => (1_048_575, 16_383),
            };
            e.set(r, c, Cell::Num(1.0));
            format!("a cell at row {r} column {c}")
        }
        "an odd sheet name" => {
            let name = *rng.pick(&[
                "Run 2's ✓",
                "Данные",
                "  spaced  ",
                "a'b",
                "1",
                "Sheet1 (2)",
            ]);
            e.sheet = name.to_string();
            layout.sheet = rng.chance(0.7).then(|| name.to_string());
            format!("sheet {name:?}; source.sheet = {:?}", layout.sheet)
        }
        "ragged rows" => {
            let mut what = Vec::new();
            for _ in 0..1 + rng.below(4) {
                let Some(r) = e.data_row(rng) else { break };
                let row = &mut e.rows[r];
                if rng.chance(0.5) {
                    let keep = rng.below(row.len().max(1));
                    row.truncate(keep);
                    what.push(format!("row {r} cut to {keep} fields"));
                } else {
                    let more = 1 + rng.below(5);
                    row.extend((0..more).map(|k| Cell::Num(k as f64)));
                    what.push(format!("row {r} {more} fields longer"));
                }
            }
            if let Some(header) = e.rows.get_mut(h).filter(|_| rng.chance(0.3)) {
                header.truncate(3);
                what.push("the header 3 fields".into());
            }
            what.join(", ")
        }
        "a quoted line end" => match e.data_row(rng) {
            Some(r) => {
                let c = a_column(rng);
                e.set(r, c, Cell::Text("1\n2".into()));
                format!("row {r} column {c}: \"1\\n2\"")
            }
            None => "no data row".into(),
        },
        "an unquoted delimiter in text" => match e.data_row(rng) {
            Some(r) => {
                let c = a_column(rng);
                let text = *rng.pick(&["1,5", "1;5", "a\tb", "x|y", "\"1\"", "1\"5", "\"a\"b"]);
                e.set(r, c, Cell::Raw(text.into()));
                format!("row {r} column {c}: raw {text:?}")
            }
            None => "no data row".into(),
        },
        "another extension" => {
            let name = *rng.pick(&[
                "sweep.dat",
                "sweep.xls",
                "sweep.ods",
                "sweep",
                "sweep.CSV",
                "sweep.Tsv",
                "sweep.xlsx",
            ]);
            layout.name = name.to_string();
            format!("named {name}")
        }
        _ => unreachable!("{kind} is no spoil of an export's cells"),
    }
}

/// The style spoils of a text export; `None` if `kind` is none.
fn spoil_style(kind: &str, rng: &mut Rng, style: &mut TextStyle) -> Option<String> {
    match kind {
        "decimal commas mismatched" => {
            style.decimal_comma = !style.decimal_comma;
            Some(format!(
                "written with decimal_comma = {}",
                style.decimal_comma
            ))
        }
        "CR or CRLF line ends" => {
            style.line_end = *rng.pick(&["\r\n", "\r", "\n\r"]);
            Some(format!("line ends {:?}", style.line_end))
        }
        _ => None,
    }
}

/// The byte spoils of a text export; `None` if `kind` is none.
fn spoil_text_bytes(kind: &str, rng: &mut Rng, bytes: &mut Vec<u8>) -> Option<String> {
    let at = rng.below(bytes.len() + 1);
    // The start of a random line: where a field begins.
    let line_start = |rng: &mut Rng, bytes: &[u8]| {
        let starts: Vec<usize> = std::iter::once(0)
            .chain(
                (0..bytes.len())
                    .filter(|&i| bytes[i] == b'\n')
                    .map(|i| i + 1),
            )
            .collect();
        *rng.pick(&starts)
    };
    Some(match kind {
        "a byte order mark" => {
            bytes.splice(0..0, [0xEF, 0xBB, 0xBF]);
            "a byte order mark".into()
        }
        "an empty file" => {
            bytes.clear();
            "empty".into()
        }
        "binary garbage" => {
            let n = rng.below(4000);
            let garbage: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            if rng.chance(0.5) {
                *bytes = garbage;
                format!("{n} random bytes")
            } else {
                bytes.splice(at..at, garbage);
                format!("{n} random bytes at {at}")
            }
        }
        "bytes not UTF-8" => {
            const BAD: [&[u8]; 4] = [&[0xFF, 0xFE], &[0xB0], &[0xC3], &[0xED, 0xA0, 0x80]];
            let bad = *rng.pick(&BAD);
            let at = if rng.chance(0.3) {
                3.min(bytes.len())
            } else {
                at
            };
            bytes.splice(at..at, bad.iter().copied());
            format!("bytes {bad:02X?} at {at}")
        }
        "an unclosed quote" => {
            let at = line_start(rng, bytes);
            bytes.insert(at, b'"');
            format!("a quote opened at {at}")
        }
        "blank lines at the end" => {
            bytes.extend_from_slice(b"\n\n  \n\t\n");
            "blank lines at the end".into()
        }
        "NUL bytes" => {
            bytes.splice(at..at, [0, 0]);
            format!("NUL NUL at {at}")
        }
        "truncated mid-line" => {
            bytes.truncate(at);
            format!("cut at {at}")
        }
        _ => return None,
    })
}

/// A damaged workbook: cut short, bytes flipped, or a run zeroed.
fn damage_zip(rng: &mut Rng, bytes: &mut Vec<u8>) -> String {
    let n = bytes.len();
    match rng.below(3) {
        0 => {
            let keep = rng.below(n);
            bytes.truncate(keep);
            format!("zip cut at {keep} of {n} bytes")
        }
        1 => {
            let flips = 1 + rng.below(8);
            for _ in 0..flips {
                let i = rng.below(n);
                bytes[i] ^= 1 << rng.below(8);
            }
            format!("{flips} bit(s) flipped")
        }
        _ => {
            let (at, len) = (rng.below(n), 1 + rng.below(64));
            bytes[at..(at + len).min(n)].fill(0);
            format!("{len} bytes zeroed at {at}")
        }
    }
}

/// What is done to a workbook written by hand ([`raw_xlsx`]): what
/// rust_xlsxwriter never writes.
const RAW_SPOILS: [&str; 23] = [
    "a sheet name with a line end",
    "a cell below the last row",
    "a cell right of XFD",
    "a cell at ZZZZ",
    "a merge over the whole sheet",
    "a merge written backwards",
    "a merge beyond the sheet",
    "a merge without a row",
    "a shared string that is not there",
    "an ISO date cell",
    "an unknown error",
    "a boolean of 2",
    "an unknown cell type",
    "cells and rows without references",
    "a number cell holding text",
    "a number beyond the doubles",
    "a row numbered 0",
    "the sheet's XML cut short",
    "a string not UTF-8",
    "a dimension over the whole sheet",
    "the sheet's file missing",
    "a workbook without sheets",
    "a chart sheet",
];

/// `s` as XML text.
fn xml_escape(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '&' => "&amp;".to_string(),
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '"' => "&quot;".to_string(),
            // A reference: a line end written as it is would be read as a
            // space in an attribute.
            c if c.is_control() => format!("&#{};", u32::from(c)),
            c => c.to_string(),
        })
        .collect()
}

/// The XML of one cell at `place` (`B2`).
fn raw_cell(place: &str, cell: &Cell) -> String {
    let text = |s: &str| {
        format!(
            "<c r=\"{place}\" t=\"inlineStr\"><is><t>{}</t></is></c>",
            xml_escape(s)
        )
    };
    match cell {
        Cell::Num(x) | Cell::Date(x) => format!("<c r=\"{place}\"><v>{x}</v></c>"),
        Cell::Text(s) | Cell::Raw(s) => text(s),
        Cell::Blank => String::new(),
        Cell::Formula(f, result) => format!(
            "<c r=\"{place}\" t=\"str\"><f>{}</f><v>{}</v></c>",
            xml_escape(f),
            xml_escape(result)
        ),
        Cell::Bool(b) => format!("<c r=\"{place}\" t=\"b\"><v>{}</v></c>", u8::from(*b)),
    }
}

/// The letters of the 0-based column `col` (`A`, ..., `Z`, `AA`).
fn letters(col: usize) -> String {
    let (mut n, mut out) = (col + 1, Vec::new());
    while n > 0 {
        out.push(b'A' + ((n - 1) % 26) as u8);
        n = (n - 1) / 26;
    }
    out.reverse();
    String::from_utf8(out).unwrap()
}

/// CRC-32 (the zip format's), bit by bit: a few workbooks a run.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xEDB8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}

/// A zip of `files`, stored uncompressed: what an XLSX is, without a zip
/// writer (rust_xlsxwriter writes only what Excel would).
fn stored_zip(files: &[(&str, Vec<u8>)]) -> Vec<u8> {
    let (mut out, mut central) = (Vec::new(), Vec::new());
    for (name, data) in files {
        let offset = out.len() as u32;
        let (crc, len) = (crc32(data), data.len() as u32);
        // Version 2.0, no flags, stored, 1980-01-01 00:00.
        let common = |v: &mut Vec<u8>| {
            for x in [20u16, 0, 0, 0, 0x21] {
                v.extend(x.to_le_bytes());
            }
            for x in [crc, len, len] {
                v.extend(x.to_le_bytes());
            }
            v.extend((name.len() as u16).to_le_bytes());
            v.extend(0u16.to_le_bytes());
        };
        out.extend(0x0403_4b50u32.to_le_bytes());
        common(&mut out);
        out.extend(name.as_bytes());
        out.extend(data);
        central.extend(0x0201_4b50u32.to_le_bytes());
        central.extend(20u16.to_le_bytes());
        common(&mut central);
        // Comment, disk, attributes.
        central.extend([0u8; 10]);
        central.extend(offset.to_le_bytes());
        central.extend(name.as_bytes());
    }
    let (at, size, n) = (out.len() as u32, central.len() as u32, files.len() as u16);
    out.extend(central);
    out.extend(0x0605_4b50u32.to_le_bytes());
    for x in [0u16, 0, n, n] {
        out.extend(x.to_le_bytes());
    }
    out.extend(size.to_le_bytes());
    out.extend(at.to_le_bytes());
    out.extend(0u16.to_le_bytes());
    out
}

/// The spreadsheet XML's namespace.
const NS: &str = "http://schemas.openxmlformats.org/spreadsheetml/2006/main";
/// The relationships' namespace.
const REL: &str = "http://schemas.openxmlformats.org/officeDocument/2006/relationships";

/// A workbook written by hand: its sheet's rows as XML and the parts
/// around them, each of which a [`RAW_SPOILS`] spoil may change.
struct RawBook {
    /// `<row>` elements, one per row of the export.
    rows: Vec<String>,
    /// Merged blocks' references (`B2:C3`).
    merges: Vec<String>,
    /// A `<dimension>` element, if any.
    dimension: String,
    /// `xl/sharedStrings.xml`, if any.
    shared: String,
    /// Characters of the sheet's data kept, the rest and the sheet's end cut.
    cut: Option<usize>,
    /// `xl/worksheets/sheet1.xml` is in the zip.
    sheet_file: bool,
    /// The folder the workbook's relationship points into (`worksheets`);
    /// `None` for a workbook that lists no sheet.
    sheets: Option<&'static str>,
    /// The sheet's name in place of the export's.
    sheet_name: Option<&'static str>,
}

impl RawBook {
    /// The rows of `e`, each cell with its reference.
    fn new(e: &Export) -> RawBook {
        let rows = e
            .rows
            .iter()
            .enumerate()
            .map(|(r, row)| {
                let cells: String = row
                    .iter()
                    .enumerate()
                    .map(|(c, cell)| raw_cell(&format!("{}{}", letters(c), r + 1), cell))
                    .collect();
                format!("<row r=\"{}\">{cells}</row>", r + 1)
            })
            .collect();
        RawBook {
            rows,
            merges: Vec::new(),
            dimension: String::new(),
            shared: String::new(),
            cut: None,
            sheet_file: true,
            sheets: Some("worksheets"),
            sheet_name: None,
        }
    }

    /// Puts a cell's XML at the end of row index `r` (a row of its own if
    /// there is no such row).
    fn put(&mut self, r: usize, cell: String) {
        match self.rows.get_mut(r) {
            Some(row) if row.ends_with("</row>") => {
                row.insert_str(row.len() - "</row>".len(), &cell)
            }
            _ => self.rows.push(format!("<row>{cell}</row>")),
        }
    }

    /// Spoils the book by `kind`, a cell's spoil in row index `r` (shown
    /// as row `r + 1`); what was done.
    fn spoil(&mut self, kind: &str, rng: &mut Rng, r: usize) -> String {
        let n = r + 1;
        // A cell's XML put into row `r`; what that did.
        let put = |book: &mut RawBook, cell: String, what: String| {
            book.put(r, cell);
            what
        };
        match kind {
            "a cell below the last row" => {
                let row = "<row r=\"1048577\"><c r=\"B1048577\"><v>1</v></c></row>";
                self.rows.push(row.into());
                "B1048577 = 1".into()
            }
            "a cell right of XFD" => put(
                self,
                format!("<c r=\"XFE{n}\"><v>1</v></c>"),
                format!("XFE{n} = 1"),
            ),
            "a cell at ZZZZ" => put(
                self,
                format!("<c r=\"ZZZZ{n}\"><v>1</v></c>"),
                format!("ZZZZ{n} = 1"),
            ),
            "a merge over the whole sheet"
            | "a merge written backwards"
            | "a merge beyond the sheet"
            | "a merge without a row" => {
                let block = match kind {
                    "a merge over the whole sheet" => "A1:XFD1048576",
                    "a merge written backwards" => "D5:B2",
                    "a merge beyond the sheet" => "B2:ZZZZ4000000000",
                    _ => "B:B",
                };
                self.merges.push(block.into());
                format!("merged {block}")
            }
            "a shared string that is not there" => {
                self.shared = format!(
                    "<sst xmlns=\"{NS}\" count=\"1\" uniqueCount=\"1\"><si><t>x</t></si></sst>"
                );
                put(
                    self,
                    format!("<c r=\"C{n}\" t=\"s\"><v>99</v></c>"),
                    format!("C{n} = shared string 99 of 1"),
                )
            }
            "an ISO date cell" => put(
                self,
                format!("<c r=\"B{n}\" t=\"d\"><v>2026-11-28T12:00:00</v></c>"),
                format!("B{n} an ISO date"),
            ),
            "an unknown error" => put(
                self,
                format!("<c r=\"D{n}\" t=\"e\"><v>#BOGUS!</v></c>"),
                format!("D{n} = #BOGUS!"),
            ),
            "a boolean of 2" => put(
                self,
                format!("<c r=\"A{n}\" t=\"b\"><v>2</v></c>"),
                format!("A{n} = boolean 2"),
            ),
            "an unknown cell type" => put(
                self,
                format!("<c r=\"B{n}\" t=\"zz\"><v>1</v></c>"),
                format!("B{n} of type zz"),
            ),
            "cells and rows without references" => {
                let row = "<row><c><v>1</v></c><c><v>2</v></c><c><v>3</v></c></row>";
                self.rows.insert(r.min(self.rows.len()), row.into());
                format!("a row without references before row {n}")
            }
            "a number cell holding text" => {
                let text = *rng.pick(&["abc", " 1 ", "1,5", "", "-"]);
                put(
                    self,
                    format!("<c r=\"B{n}\" t=\"n\"><v>{text}</v></c>"),
                    format!("B{n} = number {text:?}"),
                )
            }
            "a number beyond the doubles" => {
                let x = *rng.pick(&["1e999", "-1e999", "NaN", "inf", "1e-999"]);
                put(
                    self,
                    format!("<c r=\"D{n}\"><v>{x}</v></c>"),
                    format!("D{n} = {x}"),
                )
            }
            "a row numbered 0" => {
                self.rows
                    .insert(0, "<row r=\"0\"><c r=\"A0\"><v>1</v></c></row>".into());
                "a row numbered 0".into()
            }
            "the sheet's XML cut short" => {
                let keep = rng.below(1000);
                self.cut = Some(keep);
                format!("the sheet's XML cut after {keep} characters of its data")
            }
            // U+FFFF, made bytes that are not UTF-8 when the sheet is written.
            "a string not UTF-8" => put(
                self,
                format!("<c r=\"B{n}\" t=\"inlineStr\"><is><t>\u{FFFF}</t></is></c>"),
                format!("B{n} holds bytes not UTF-8"),
            ),
            "a dimension over the whole sheet" => {
                self.dimension = "<dimension ref=\"A1:XFD1048576\"/>".into();
                "dimension A1:XFD1048576".into()
            }
            "the sheet's file missing" => {
                self.sheet_file = false;
                "no xl/worksheets/sheet1.xml".into()
            }
            "a sheet name with a line end" => {
                // What no spreadsheet lets a person type, but XML holds.
                self.sheet_name = Some(*rng.pick(&["Run\n2", "Run\r\n2", "tab\there", "\u{1}"]));
                format!("the sheet named {:?}", self.sheet_name.unwrap())
            }
            "a workbook without sheets" => {
                self.sheets = None;
                "no sheet in the workbook".into()
            }
            _ => {
                self.sheets = Some("chartsheets");
                "the sheet's target a chart sheet".into()
            }
        }
    }

    /// `xl/worksheets/sheet1.xml`.
    fn sheet_xml(&self) -> Vec<u8> {
        let merges = if self.merges.is_empty() {
            String::new()
        } else {
            let each: String = self
                .merges
                .iter()
                .map(|m| format!("<mergeCell ref=\"{m}\"/>"))
                .collect();
            format!(
                "<mergeCells count=\"{}\">{each}</mergeCells>",
                self.merges.len()
            )
        };
        let data = self.rows.concat();
        let head = format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n\
             <worksheet xmlns=\"{NS}\">{}<sheetData>",
            self.dimension
        );
        let sheet = match self.cut {
            Some(keep) => head + &data.chars().take(keep).collect::<String>(),
            None => format!("{head}{data}</sheetData>{merges}</worksheet>"),
        };
        // U+FFFF is EF BF BF in UTF-8: its last byte dropped leaves bytes
        // that are not.
        let sheet = sheet.into_bytes();
        match sheet.windows(3).position(|w| w == [0xEF, 0xBF, 0xBF]) {
            Some(i) => [&sheet[..i], &[0xEF, 0xBF][..], &sheet[i + 3..]].concat(),
            None => sheet,
        }
    }

    /// The workbook's zip, its one sheet named `sheet`.
    fn zip(&self, sheet: &str) -> Vec<u8> {
        let listed = match self.sheets {
            Some(_) => format!(
                "<sheet name=\"{}\" sheetId=\"1\" r:id=\"rId1\"/>",
                xml_escape(sheet)
            ),
            None => String::new(),
        };
        let workbook = format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
             <workbook xmlns=\"{NS}\" xmlns:r=\"{REL}\"><sheets>{listed}</sheets></workbook>"
        );
        let rels = format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships \
             xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\
             <Relationship Id=\"rId1\" Type=\"{REL}/worksheet\" Target=\"{}/sheet1.xml\"/>\
             </Relationships>",
            self.sheets.unwrap_or("worksheets")
        );
        let mut files = vec![
            ("xl/workbook.xml", workbook.into_bytes()),
            ("xl/_rels/workbook.xml.rels", rels.into_bytes()),
        ];
        if self.sheet_file {
            files.push(("xl/worksheets/sheet1.xml", self.sheet_xml()));
        }
        if !self.shared.is_empty() {
            files.push(("xl/sharedStrings.xml", self.shared.clone().into_bytes()));
        }
        stored_zip(&files)
    }
}

/// `e` as a workbook written by hand, XML and all, spoiled by `spoils` (of
/// [`RAW_SPOILS`]): cells beyond a sheet's limits, odd cell types, merges
/// and references rust_xlsxwriter never writes.
fn raw_xlsx(e: &Export, spoils: &[&str], rng: &mut Rng, done: &mut Vec<String>) -> Vec<u8> {
    let mut book = RawBook::new(e);
    for &kind in spoils {
        // A cell's spoil goes into a data row (the header's, if none).
        let r = e.data_row(rng).unwrap_or(e.header());
        let what = book.spoil(kind, rng, r);
        done.push(format!("hand-written XML, {kind}: {what}"));
    }
    book.zip(book.sheet_name.unwrap_or(&e.sheet))
}

/// A long text shown cut, for a case's description.
fn cut(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}... ({} chars)", &s[..i], s.chars().count()),
        None => s.to_string(),
    }
}

// ------------------------------------------------------------ the checks

/// How a case ended, when it ended by the rules.
#[derive(Debug)]
enum Outcome {
    /// A recording of this many rows, whose text reads back.
    Imported { rows: usize },
    /// Refused with this message (the library's Display).
    Refused(String),
}

/// `f()`, or the message of the panic it ended in.
fn caught<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into())
    })
}

/// Whether `message` starts with `file` and then says something: a place
/// or a key, and a rule (`lab.toml:7: unknown field`, `a.xlsx: Sheet1!B3:
/// ...`).
fn names(message: &str, file: &str) -> bool {
    message.strip_prefix(file).is_some_and(|rest| {
        rest.starts_with(':')
            && rest
                .trim_start_matches(|c: char| c == ':' || c == ' ' || c.is_ascii_digit())
                .chars()
                .filter(|c| c.is_alphanumeric())
                .count()
                >= 3
    })
}

/// Whether `message` is a refusal as `docs/import.md` shows them: one line
/// (a list of refusals is one line each) that starts with one of `files`
/// and says something after it.
fn judge(message: &str, files: &[&str]) -> Result<Outcome, String> {
    if !files.iter().any(|f| names(message, f)) {
        return Err(format!("the refusal names no file: {message:?}"));
    }
    if message.contains('\n') {
        return Err(format!("the refusal takes more than a line: {message:?}"));
    }
    Ok(Outcome::Refused(message.to_string()))
}

/// The case through the library, as the command calls it: the mapping
/// read, then the export imported, then the recording's text read back.
fn library(mapping: &Path, export: &Path) -> Result<Outcome, String> {
    let (m_name, e_name) = (mapping.display().to_string(), export.display().to_string());
    let m = match caught(|| Mapping::read(mapping)) {
        Err(panic) => return Err(format!("Mapping::read panicked: {panic}")),
        Ok(Err(e)) => return judge(&e.to_string(), &[&m_name]),
        Ok(Ok(m)) => m,
    };
    let imported = match caught(|| import(export, &m)) {
        Err(panic) => return Err(format!("import panicked: {panic}")),
        Ok(Err(e)) => return judge(&e.to_string(), &[&e_name, &m_name]),
        Ok(Ok(imported)) => imported,
    };
    let rec = imported.recording;
    // What `Recording::write` would check and write, read back as a
    // recording file is read.
    let back = caught(|| {
        rec.validate(&e_name)
            .map_err(|e| format!("imported, yet the recording breaks the format: {e}"))?;
        Recording::parse("written.csv", &rec.to_csv_string())
            .map_err(|e| format!("imported, yet its text does not read back: {e}"))
    })
    .map_err(|panic| format!("writing or reading back the recording panicked: {panic}"))??;
    let same_channels = back.channels.len() == rec.channels.len()
        && back
            .channels
            .iter()
            .zip(&rec.channels)
            .all(|((c, a), (d, b))| {
                c == d
                    && a.len() == b.len()
                    && a.iter().zip(b).all(|(x, y)| x.is_some() == y.is_some())
            });
    if back.t_s != rec.t_s || back.v_v != rec.v_v || !same_channels || back.meta != rec.meta {
        return Err("imported, yet its text reads back as another recording".into());
    }
    Ok(Outcome::Imported {
        rows: rec.t_s.len(),
    })
}

/// The case through the `finrs import` binary, writing to `out` (a file in
/// a folder that does not exist yet); it must end as the library did.
fn cli(mapping: &Path, export: &Path, out: &Path, library: &Outcome) -> Result<(), String> {
    let run = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .arg("import")
        .arg(export)
        .arg("--mapping")
        .arg(mapping)
        .arg("--out")
        .arg(out)
        .env("RUST_BACKTRACE", "0")
        .output()
        .map_err(|e| format!("finrs could not be run: {e}"))?;
    let stderr = String::from_utf8_lossy(&run.stderr);
    match run.status.code() {
        None => {
            return Err(format!(
                "finrs import died by a signal ({}): {stderr}",
                run.status
            ))
        }
        Some(101) => return Err(format!("finrs import exited 101 (a panic): {stderr}")),
        _ if stderr.contains("panicked") => return Err(format!("finrs import panicked: {stderr}")),
        _ => {}
    }
    match (run.status.success(), library) {
        (true, Outcome::Imported { rows }) => match Recording::read(out) {
            Ok(rec) if rec.t_s.len() == *rows => Ok(()),
            Ok(rec) => Err(format!(
                "finrs import wrote {} rows, the library made {rows}",
                rec.t_s.len()
            )),
            Err(e) => Err(format!(
                "finrs import wrote a recording that does not read: {e}"
            )),
        },
        (false, Outcome::Refused(message)) => {
            if !stderr.contains(&format!("error: {message}")) {
                return Err(format!(
                    "finrs import's error is not the library's ({message:?}): {stderr}"
                ));
            }
            if out.parent().is_some_and(Path::exists) {
                return Err(format!("finrs import refused, yet left {}", out.display()));
            }
            Ok(())
        }
        (true, Outcome::Refused(message)) => Err(format!(
            "finrs import succeeded where the library refused: {message}"
        )),
        (false, Outcome::Imported { .. }) => Err(format!(
            "finrs import failed where the library imported: {stderr}"
        )),
    }
}

// ------------------------------------------------------------ the sweep

/// One case: a mapping and an export, and what was done to them.
struct Case {
    /// Where it comes from: `mapping 17`, `xlsx 3`, `regression: ...`.
    label: String,
    seed: u64,
    /// The spoil it was made for (counted per kind).
    kind: String,
    /// What was done to the mapping and the export, in order.
    done: Vec<String>,
    mapping: Vec<u8>,
    export_name: String,
    export: Vec<u8>,
}

/// A sweep's cases run and counted, its failures kept.
struct Sweep {
    name: &'static str,
    root: PathBuf,
    kinds: BTreeMap<String, usize>,
    imported: usize,
    refused: usize,
    cli_runs: usize,
    failures: Vec<String>,
}

impl Sweep {
    fn new(name: &'static str) -> Sweep {
        let root =
            std::env::temp_dir().join(format!("finrs-import-sweep-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        Sweep {
            name,
            root,
            kinds: BTreeMap::new(),
            imported: 0,
            refused: 0,
            cli_runs: 0,
            failures: Vec::new(),
        }
    }

    /// Runs `case` through the library, and through the binary too if
    /// `with_cli`; how it ended, if by the rules. Its files are removed
    /// unless it fails.
    fn run(&mut self, case: Case, with_cli: bool) -> Option<Outcome> {
        *self.kinds.entry(case.kind.clone()).or_default() += 1;
        let dir = self.root.join(case.label.replace([' ', ':', '/'], "_"));
        std::fs::create_dir_all(&dir).unwrap();
        let mapping = dir.join("lab.toml");
        let export = dir.join(&case.export_name);
        std::fs::write(&mapping, &case.mapping).unwrap();
        std::fs::write(&export, &case.export).unwrap();
        let result = library(&mapping, &export).and_then(|outcome| {
            if with_cli {
                self.cli_runs += 1;
                cli(&mapping, &export, &dir.join("out/recording.csv"), &outcome)?;
            }
            Ok(outcome)
        });
        log_outcome(&case, &result);
        match &result {
            Ok(Outcome::Imported { .. }) => self.imported += 1,
            Ok(Outcome::Refused(_)) => self.refused += 1,
            Err(why) => {
                self.failures.push(describe(&case, &dir, why));
                return None;
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        result.ok()
    }

    /// Says what was swept, and fails with every failing case if any.
    fn finish(self) {
        let kinds: Vec<String> = self.kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        eprintln!(
            "{} sweep: {} cases ({} imported, {} refused, {} failed; {} through the binary): {}",
            self.name,
            self.kinds.values().sum::<usize>(),
            self.imported,
            self.refused,
            self.failures.len(),
            self.cli_runs,
            kinds.join(", ")
        );
        if !self.failures.is_empty() {
            let shown: Vec<&str> = self.failures.iter().take(12).map(String::as_str).collect();
            panic!(
                "{} of the {} sweep's cases failed (the first {} below; files kept in {}):\n\n{}",
                self.failures.len(),
                self.name,
                shown.len(),
                self.root.display(),
                shown.join("\n\n")
            );
        }
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

/// With `FINRS_IMPORT_SWEEP_OUTCOMES=FILE`, appends the case's label, kind,
/// outcome and what was done to FILE: to see which rules the sweep reaches.
fn log_outcome(case: &Case, result: &Result<Outcome, String>) {
    let Some(path) = std::env::var_os("FINRS_IMPORT_SWEEP_OUTCOMES") else {
        return;
    };
    let outcome = match result {
        Ok(Outcome::Imported { rows }) => format!("imported {rows} rows"),
        Ok(Outcome::Refused(message)) => format!("refused: {}", message.escape_debug()),
        Err(why) => format!("FAILED: {}", why.escape_debug()),
    };
    let line = format!(
        "{}\t{}\t{outcome}\t{}\n",
        case.label,
        case.kind,
        case.done.join(" | ").escape_debug()
    );
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .unwrap();
    std::io::Write::write_all(&mut file, line.as_bytes()).unwrap();
}

/// A failing case, as a person reproduces it.
fn describe(case: &Case, dir: &Path, why: &str) -> String {
    let mut text = format!(
        "{} (kind: {}; seed {:#x}): {why}\n  export: {} ({} bytes)\n",
        case.label,
        case.kind,
        case.seed,
        dir.join(&case.export_name).display(),
        case.export.len()
    );
    for done in &case.done {
        writeln!(text, "  done: {done}").unwrap();
    }
    writeln!(text, "  mapping ({}):", dir.join("lab.toml").display()).unwrap();
    for line in String::from_utf8_lossy(&case.mapping).lines() {
        // Control characters shown as escapes: the report stays text.
        let shown: String = line
            .chars()
            .map(|c| {
                if c.is_control() && c != '\t' {
                    c.escape_debug().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect();
        writeln!(text, "  | {shown}").unwrap();
    }
    text
}

/// An export case of either kind: a clean export and its mapping, spoiled
/// by `kind`, in half the cases by one or two more of `spoils`, and now
/// and then by a mapping spoil too.
fn export_case(label: String, seed: u64, kind: &str, spoils: &[&str], workbook: bool) -> Case {
    let mut rng = Rng::new(seed);
    let mut layout = Layout::random(&mut rng, workbook);
    let mut export = base_export(&mut rng);
    let mut style = TextStyle {
        delimiter: layout.text.map_or(b',', |t| t.0),
        decimal_comma: layout.text.is_some_and(|t| t.1),
        line_end: "\n",
    };
    // Half the cases spoiled once only, the others twice or three times.
    let mut kinds = vec![kind];
    let more = if rng.chance(0.5) { 0 } else { 1 + rng.below(2) };
    for _ in 0..more {
        kinds.push(*rng.pick(spoils));
    }
    let mut done = vec![format!(
        "export: {} rows, {layout:?}",
        export.rows.len() - 1
    )];
    for kind in &kinds {
        if let Some(what) = spoil_style(kind, &mut rng, &mut style) {
            done.push(format!("export, {kind}: {what}"));
        } else if !is_byte_spoil(kind) {
            let what = spoil_export(kind, &mut rng, &mut export, &mut layout);
            done.push(format!("export, {kind}: {what}"));
        }
    }
    let mut bytes = if let Some(raw) = kinds.iter().find_map(|k| k.strip_prefix("hand-written: ")) {
        // Now and then a second spoil of the XML.
        let mut raws = vec![raw];
        if rng.chance(0.3) {
            raws.push(*rng.pick(&RAW_SPOILS));
        }
        raw_xlsx(&export, &raws, &mut rng, &mut done)
    } else if workbook {
        export.xlsx(&mut done)
    } else {
        export.text(&style)
    };
    for kind in &kinds {
        let what = match (workbook, *kind) {
            (true, "a damaged zip") => Some(damage_zip(&mut rng, &mut bytes)),
            (false, kind) => spoil_text_bytes(kind, &mut rng, &mut bytes),
            _ => None,
        };
        if let Some(what) = what {
            done.push(format!("export bytes, {kind}: {what}"));
        }
    }
    let text = mapping_text(&layout);
    let mapping = if rng.chance(0.1) {
        let spoil = *rng.pick(&MAPPING_SPOILS);
        spoiled_mapping(&mut rng, &text, spoil, 0, &mut done)
    } else {
        text.into_bytes()
    };
    Case {
        label,
        seed,
        kind: kind.to_string(),
        done,
        mapping,
        export_name: layout.name,
        export: bytes,
    }
}

/// Whether a spoil is done to the written bytes (a text export's, a
/// damaged zip), or is the writing itself (a workbook written by hand).
fn is_byte_spoil(kind: &str) -> bool {
    kind.starts_with("hand-written: ")
        || [
            "a damaged zip",
            "a byte order mark",
            "an empty file",
            "binary garbage",
            "bytes not UTF-8",
            "an unclosed quote",
            "blank lines at the end",
            "NUL bytes",
            "truncated mid-line",
        ]
        .contains(&kind)
}

// ------------------------------------------------------------ the tests

/// The clean exports and their mappings import, in every layout: else
/// the sweeps would test only the first refusal.
#[test]
fn the_clean_cases_import() {
    let mut sweep = Sweep::new("clean");
    for (i, workbook) in (0..24).map(|i| (i, i % 3 == 0)) {
        let seed = case_seed(0, i);
        let mut rng = Rng::new(seed);
        let layout = Layout::random(&mut rng, workbook);
        let export = base_export(&mut rng);
        let style = TextStyle {
            delimiter: layout.text.map_or(b',', |t| t.0),
            decimal_comma: layout.text.is_some_and(|t| t.1),
            line_end: "\n",
        };
        let mut done = vec![format!("{layout:?}")];
        let bytes = if workbook {
            export.xlsx(&mut done)
        } else {
            export.text(&style)
        };
        let case = Case {
            label: format!("clean {i}"),
            seed,
            kind: "clean".into(),
            done,
            mapping: mapping_text(&layout).into_bytes(),
            export_name: layout.name,
            export: bytes,
        };
        let _ = sweep.run(case, i % 4 == 0);
    }
    let (imported, total) = (sweep.imported, sweep.kinds.values().sum::<usize>());
    sweep.finish();
    assert_eq!(imported, total, "a clean case was refused");
}

/// Spoiled mappings, each over a clean export of a random layout.
#[test]
fn spoiled_mappings_are_refused_by_name_or_import() {
    let mut sweep = Sweep::new("mapping");
    for i in 0..MAPPING_CASES {
        let seed = case_seed(1, i);
        let mut rng = Rng::new(seed);
        let workbook = rng.chance(0.5);
        let layout = Layout::random(&mut rng, workbook);
        let export = base_export(&mut rng);
        let mut done = vec![format!("export: clean, {layout:?}")];
        let bytes = match layout.text {
            None => export.xlsx(&mut done),
            Some((delimiter, decimal_comma)) => export.text(&TextStyle {
                delimiter,
                decimal_comma,
                line_end: "\n",
            }),
        };
        let kind = MAPPING_SPOILS[i % MAPPING_SPOILS.len()];
        let mapping = spoiled_mapping(&mut rng, &mapping_text(&layout), kind, 2, &mut done);
        let case = Case {
            label: format!("mapping {i}"),
            seed,
            kind: kind.to_string(),
            done,
            mapping,
            export_name: layout.name,
            export: bytes,
        };
        let _ = sweep.run(case, i % CLI_EVERY == 0);
    }
    sweep.finish();
}

/// Spoiled workbooks, read by the mapping made for them.
#[test]
fn spoiled_workbooks_are_refused_by_name_or_import() {
    let spoils: Vec<&str> = SHARED_SPOILS.iter().chain(&XLSX_SPOILS).copied().collect();
    sweep_exports("xlsx", XLSX_CASES, 2, &spoils, &spoils, true);
}

/// Workbooks written by hand, spoiled as rust_xlsxwriter never writes,
/// read by the mapping made for them.
#[test]
fn hand_written_workbooks_are_refused_by_name_or_import() {
    let raws: Vec<String> = RAW_SPOILS
        .iter()
        .map(|k| format!("hand-written: {k}"))
        .collect();
    let kinds: Vec<&str> = raws.iter().map(String::as_str).collect();
    sweep_exports("raw", RAW_CASES, 4, &kinds, &SHARED_SPOILS, true);
}

/// Spoiled CSV and TSV text, read by the mapping made for it.
#[test]
fn spoiled_text_exports_are_refused_by_name_or_import() {
    let spoils: Vec<&str> = SHARED_SPOILS.iter().chain(&TEXT_SPOILS).copied().collect();
    sweep_exports("text", TEXT_CASES, 3, &spoils, &spoils, false);
}

/// `cases` exports named `name`, each spoiled in the next of `kinds` in
/// turn (with `spoils` to draw further spoils from) from seed stream
/// `stream`, every [`CLI_EVERY`]th also through the binary.
fn sweep_exports(
    name: &'static str,
    cases: usize,
    stream: u64,
    kinds: &[&str],
    spoils: &[&str],
    workbook: bool,
) {
    let mut sweep = Sweep::new(name);
    for i in 0..cases {
        let kind = kinds[i % kinds.len()];
        let case = export_case(
            format!("{name} {i}"),
            case_seed(stream, i),
            kind,
            spoils,
            workbook,
        );
        let _ = sweep.run(case, i % CLI_EVERY == 0);
    }
    sweep.finish();
}

/// The layout of the regression cases' workbooks: rate, sheet named.
fn regression_layout() -> Layout {
    Layout {
        name: "sweep.xlsx".into(),
        text: None,
        say_delimiter: false,
        header_row: 1,
        sheet: Some("Sheet1".into()),
        rate: true,
    }
}

/// A regression case over the clean workbook of `regression_layout`: its
/// mapping with `from` put `to`; the workbook written by rust_xlsxwriter,
/// or by hand and changed by `tweak`.
fn regression_case(
    label: &str,
    from: &str,
    to: &str,
    tweak: Option<&dyn Fn(&mut RawBook)>,
) -> Case {
    let layout = regression_layout();
    let seed = case_seed(5, 0);
    let export = base_export(&mut Rng::new(seed));
    let mut done = vec![format!("mapping: {from:?} -> {to:?}")];
    let bytes = match tweak {
        None => export.xlsx(&mut done),
        Some(tweak) => {
            let mut book = RawBook::new(&export);
            tweak(&mut book);
            done.push(format!(
                "written by hand: {:?}, merges {:?}",
                book.sheet_name, book.merges
            ));
            book.zip(book.sheet_name.unwrap_or(&export.sheet))
        }
    };
    let text = mapping_text(&layout);
    assert!(text.contains(from), "{label}: {from:?}");
    Case {
        label: format!("regression {label}"),
        seed,
        kind: label.to_string(),
        done,
        mapping: text.replacen(from, to, 1).into_bytes(),
        export_name: layout.name,
        export: bytes,
    }
}

/// A regression case over a clean CSV export, time by rate (its column A
/// unmapped), its bytes changed by `edit`.
fn regression_text_case(label: &str, edit: &dyn Fn(&mut Vec<u8>)) -> Case {
    let layout = Layout {
        name: "sweep.csv".into(),
        text: Some((b',', false)),
        ..regression_layout()
    };
    let seed = case_seed(5, 1);
    let export = base_export(&mut Rng::new(seed));
    let style = TextStyle {
        delimiter: b',',
        decimal_comma: false,
        line_end: "\n",
    };
    let mut bytes = export.text(&style);
    edit(&mut bytes);
    Case {
        label: format!("regression {label}"),
        seed,
        kind: label.to_string(),
        done: vec![format!("{layout:?}, edited")],
        mapping: mapping_text(&Layout {
            sheet: None,
            ..layout.clone()
        })
        .into_bytes(),
        export_name: layout.name,
        export: bytes,
    }
}

/// Puts a quote at the start of line `line` (1-based) of a text export.
fn open_quote_at(bytes: &mut Vec<u8>, line: usize) {
    let at = (0..bytes.len())
        .filter(|&i| bytes[i] == b'\n')
        .nth(line - 2)
        .unwrap();
    bytes.insert(at + 1, b'"');
}

/// A workbook whose only sheet is named with a line end.
fn named_over_lines(book: &mut RawBook) {
    book.sheet_name = Some("Run\n2");
}

/// What the sweep found, kept as fixed cases (library and binary both),
/// each with what its refusal must now say.
#[test]
fn regressions() {
    let sheet = "sheet = \"Sheet1\"\n";
    let zero = "zero = \"opening\"";
    let cases = [
        // The TOML parser says some errors over two lines; a refusal is one.
        (
            regression_case("table twice", "[time]", "[time]\nrate_hz = 1\n[time]", None),
            "invalid table header: duplicate key `time` in document root",
        ),
        (
            regression_case("number cut short", "scale = 0.001\n", "scale = 0.\n", None),
            "invalid floating-point number: expected digit",
        ),
        // A zero's string was quoted as TOML writes it, over three lines;
        // a date as the parser's own table.
        (
            regression_case("zero over lines", zero, "zero = \"a\\nb\"", None),
            "channel[3].zero: must be a number in the column's units or \"opening\", got \"a\\nb\"",
        ),
        (
            regression_case("zero of a date", zero, "zero = 1979-05-27T07:32:00Z", None),
            "channel[3].zero: must be a number (...) or \"opening\", got a table or a date",
        ),
        // A sheet's name with a line end made a refusal of two lines, in a
        // place and in the workbook reader's own message.
        (
            regression_case(
                "sheet name over lines",
                sheet,
                "",
                Some(&|b| {
                    named_over_lines(b);
                    b.merges.push("B2:B3".into());
                }),
            ),
            "'Run\\n2'!B2:B3: merged cells over column B (v1_V)",
        ),
        (
            regression_case(
                "missing sheet over lines",
                sheet,
                "",
                Some(&|b| {
                    named_over_lines(b);
                    b.sheet_file = false;
                }),
            ),
            "cannot read as an XLSX workbook: Worksheet 'Run\\n2' not found",
        ),
        // The list of a workbook's sheets, when it has none, was left empty.
        (
            regression_case("no sheet", sheet, sheet, Some(&|b| b.sheets = None)),
            "no sheet named \"Sheet1\" (source.sheet); the workbook has no sheet",
        ),
        // A quote never closed in an unmapped column took the rest of the
        // file for one field: the rows after it were silently lost.
        (
            regression_text_case("quote never closed", &|b| open_quote_at(b, 12)),
            "sweep.csv: line 12, field 1 (A): a quote opened in this field is never closed",
        ),
        // A merge written backwards was taken for no merge at all.
        (
            regression_case(
                "merge backwards",
                sheet,
                sheet,
                Some(&|b| b.merges.push("D5:B2".into())),
            ),
            "Sheet1!B2:D5: merged cells over column B (v1_V)",
        ),
    ];
    let mut sweep = Sweep::new("regression");
    let mut wrong = Vec::new();
    for (case, says) in cases {
        let label = case.label.clone();
        // `(...)` stands for what the message says there.
        let parts: Vec<&str> = says.split("(...)").collect();
        match sweep.run(case, true) {
            Some(Outcome::Refused(message)) if parts.iter().all(|p| message.contains(p)) => {}
            Some(outcome) => wrong.push(format!("{label}: {outcome:?}, not {says:?}")),
            None => {}
        }
    }
    sweep.finish();
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
