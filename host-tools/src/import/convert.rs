//! An export's cells made a recording: the mapping's columns found, the
//! data's rows found, each mapped cell read as a number, sentinels and
//! readings outside their valid range written as empty fields, values
//! scaled to SI, and the recording checked by the format's own rules
//! (`Recording::validate`), a refusal told at the export's cell.

use std::fmt::Write as _;

use super::address::column_letters;
use super::error::ImportError;
use super::mapping::{ChannelMap, ColumnRef, Mapping, Target, Time, TimeZero, Zero};
use super::table::{Cell, Row, Table};
use crate::recording::{Metadata, Recording, Voltages};

/// A recording made from an export, and what became of its cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The recording, checked by the format's rules.
    pub recording: Recording,
    /// Each mapped channel, in the mapping's order.
    pub channels: Vec<ChannelReport>,
}

/// What became of one mapped column's cells.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelReport {
    /// The column it became.
    pub to: Target,
    /// The export's column, as a person finds it: `column C ("Y axis -
    /// Voltage")`.
    pub column: String,
    /// The raw value subtracted before scaling (`zero`, or the opening's
    /// mean), in the export's units.
    pub zero_raw: f64,
    /// Empty cells, written as empty fields.
    pub empty_cells: usize,
    /// Sentinels (`out_of_range`), written as empty fields.
    pub sentinels: usize,
    /// Readings outside `valid`, written as empty fields.
    pub outside_valid: usize,
}

/// A mapped cell read, before scaling.
enum Raw {
    Value(f64),
    Empty,
    Sentinel(f64),
    OutsideValid(f64),
}

/// The recording that `mapping` makes of `table`, read from the export
/// `file`, with metadata `meta` (the mapping's for this file).
pub fn convert(
    table: &Table,
    mapping: &Mapping,
    file: &str,
    meta: Metadata,
) -> Result<Imported, ImportError> {
    if table.rows.iter().all(|r| r.cells.is_empty()) {
        return Err(ImportError::export(
            file,
            format!("{} is empty", table.what()),
        ));
    }
    let source = mapping.source();
    let time_col = match mapping.time() {
        Time::Column { column, .. } => Some(find_column(table, mapping, file, column, "time")?),
        Time::Rate { .. } => None,
    };
    let mut cols = Vec::with_capacity(mapping.channels().len());
    for (i, c) in mapping.channels().iter().enumerate() {
        let key = format!("channel[{}]", i + 1);
        cols.push(find_column(table, mapping, file, &c.column, &key)?);
    }
    let mapped: Vec<(usize, String)> = time_col
        .map(|c| (c, "t_s".to_string()))
        .into_iter()
        .chain(
            cols.iter()
                .zip(mapping.channels())
                .map(|(&c, ch)| (c, ch.to.name())),
        )
        .collect();
    // From the header on: a title merged above it is no column's.
    let from = match source.header_row {
        0 => source.first_data_row,
        header => header,
    };
    check_merged(table, file, &mapped, from)?;
    let rows = data_rows(table, file, &mapped, source.first_data_row)?;

    let t_s = times(table, mapping, file, &rows, time_col)?;
    let mut reports = Vec::with_capacity(cols.len());
    let mut voltages: Vec<(usize, Vec<f64>)> = Vec::new();
    let mut channels = Vec::new();
    for (ch, &col) in mapping.channels().iter().zip(&cols) {
        let (values, report) = channel(table, mapping, file, &rows, &t_s, ch, col)?;
        match ch.to {
            Target::Voltage(k) => {
                // Voltage cells are refused when empty: every value is there.
                voltages.push((k, values.into_iter().flatten().collect()));
            }
            Target::Measured(c) => channels.push((c, values)),
        }
        reports.push(report);
    }
    // A quote never closed took the rest of a text file for one field.
    // In a mapped column its cell is refused above; elsewhere the rows
    // it took would be lost without a word.
    if let Some((row, col)) = table.unclosed_quote {
        return Err(ImportError::at(
            file,
            table.place(row, col),
            "a quote opened in this field is never closed: the rest of the file is read as \
             this one field, its rows lost; close the quote or remove it",
        ));
    }
    voltages.sort_by_key(|(k, _)| *k);
    let segments = meta.segments;
    let v_v = Voltages::from_rows(
        segments,
        (0..rows.len()).map(|i| voltages.iter().map(|(_, v)| v[i]).collect::<Vec<f64>>()),
    );
    let recording = Recording {
        meta: with_provenance(meta, table, mapping, file),
        t_s,
        v_v,
        channels,
    };
    check_recording(&recording, table, mapping, file, &rows, time_col, &cols)?;
    Ok(Imported {
        recording,
        channels: reports,
    })
}

/// The column `column` denotes in `table`; `key` names its table in the
/// mapping (`time`, `channel[2]`).
fn find_column(
    table: &Table,
    mapping: &Mapping,
    file: &str,
    column: &ColumnRef,
    key: &str,
) -> Result<usize, ImportError> {
    let width = table.width();
    match column {
        ColumnRef::Position(col) => {
            if *col >= width {
                return Err(ImportError::export(
                    file,
                    format!(
                        "{} ({} {key}) lies beyond {}'s last column, {}",
                        column.describe(),
                        mapping.name(),
                        table.what(),
                        column_letters(width.saturating_sub(1))
                    ),
                ));
            }
            Ok(*col)
        }
        ColumnRef::Name(name) => {
            let header = mapping.source().header_row;
            let found: Vec<usize> = table.row(header).map_or_else(Vec::new, |row| {
                (0..row.cells.len())
                    .filter(|&c| Table::cell(row, c).name().as_deref() == Some(name.as_str()))
                    .collect()
            });
            match found.as_slice() {
                [col] => Ok(*col),
                [] => {
                    let names: Vec<String> = table.row(header).map_or_else(Vec::new, |row| {
                        (0..row.cells.len())
                            .filter_map(|c| {
                                Table::cell(row, c)
                                    .name()
                                    .map(|n| format!("{} {n:?}", column_letters(c)))
                            })
                            .collect()
                    });
                    let holds = if names.is_empty() {
                        "the row is empty".to_string()
                    } else {
                        format!("it holds {}", names.join(", "))
                    };
                    Err(ImportError::at(
                        file,
                        format!("{} (header row)", table.row_place(header)),
                        format!(
                            "no column named {name:?} ({} {key}.column); {holds}",
                            mapping.name()
                        ),
                    ))
                }
                many => {
                    let letters: Vec<String> = many.iter().map(|&c| column_letters(c)).collect();
                    Err(ImportError::at(
                        file,
                        format!("{} (header row)", table.row_place(header)),
                        format!(
                            "{name:?} ({} {key}.column) heads columns {}: map it by `letter` or `index`",
                            mapping.name(),
                            letters.join(" and ")
                        ),
                    ))
                }
            }
        }
    }
}

/// Refuses merged cells over a mapped column from row `from` on (the
/// header's or the data's): a merged block holds one value for several
/// cells, which no reading is.
fn check_merged(
    table: &Table,
    file: &str,
    mapped: &[(usize, String)],
    from: usize,
) -> Result<(), ImportError> {
    for m in &table.merged {
        if m.rows.1 < from {
            continue;
        }
        if let Some((col, to)) = mapped
            .iter()
            .find(|(c, _)| (m.columns.0..=m.columns.1).contains(c))
        {
            return Err(ImportError::at(
                file,
                table.merged_place(m),
                format!(
                    "merged cells over column {} ({to}): a merged block holds one value for \
                     several cells; unmerge them in the export",
                    column_letters(*col)
                ),
            ));
        }
    }
    Ok(())
}

/// The data's rows: from `first` on, up to the first row whose mapped
/// cells are all empty (or the table's end). A row after that with a
/// mapped cell filled is refused: a blank row inside the data.
fn data_rows<'t>(
    table: &'t Table,
    file: &str,
    mapped: &[(usize, String)],
    first: usize,
) -> Result<Vec<&'t Row>, ImportError> {
    let mut data = Vec::new();
    let mut ended: Option<usize> = None;
    // A workbook lists only rows holding something: one missing is blank.
    let mut next = first;
    for row in table.rows.iter().filter(|r| r.number >= first) {
        let filled = mapped
            .iter()
            .find(|(c, _)| *Table::cell(row, *c) != Cell::Empty);
        if ended.is_none() {
            if table.sheet.is_some() && row.number > next {
                ended = Some(next);
            } else if filled.is_none() {
                ended = Some(row.number);
                continue;
            } else {
                data.push(row);
                next = row.number + 1;
                continue;
            }
        }
        if let (Some(end), Some((col, to))) = (ended, filled) {
            let place = table.place(row.number, *col);
            let what = describe(Table::cell(row, *col));
            let rule = if data.is_empty() {
                format!(
                    "the first data row (source.first_data_row = {first}) has every mapped \
                     column empty, yet {place} ({to}) holds {what} after it: set \
                     first_data_row to the data's first row"
                )
            } else {
                format!(
                    "a blank row inside the data: the data end at the first row whose mapped \
                     columns are all empty, yet {place} ({to}) holds {what} after it"
                )
            };
            return Err(ImportError::at(file, table.row_place(end), rule));
        }
    }
    if data.is_empty() {
        return Err(ImportError::export(
            file,
            format!(
                "no data: from {} (source.first_data_row) on, every mapped column of {} is empty",
                table.row_place(first),
                table.what()
            ),
        ));
    }
    Ok(data)
}

/// A cell's content as a refusal quotes it (long text cut).
fn describe(cell: &Cell) -> String {
    match cell {
        Cell::Empty => "nothing".to_string(),
        Cell::Number(x) => format!("{x}"),
        Cell::Text(s) => {
            // Line ends and controls shown as escapes: one line a refusal.
            let cut: String = s.chars().take(40).collect();
            let more = if cut.len() < s.len() { "..." } else { "" };
            format!("`{}{more}`", cut.escape_debug())
        }
        Cell::Error(e) => format!("the formula error {e}"),
        Cell::Other(what) => what.to_string(),
    }
}

/// A mapped cell's number, `None` if empty; the reason it is none.
fn number(cell: &Cell, decimal_comma: bool) -> Result<Option<f64>, String> {
    let text = match cell {
        Cell::Empty => return Ok(None),
        Cell::Number(x) => return Ok(Some(*x)),
        Cell::Text(s) => s,
        Cell::Error(_) | Cell::Other(_) => {
            return Err(format!("holds {}, not a number", describe(cell)))
        }
    };
    let cell = format!("the text {}", describe(cell));
    let parsed = if decimal_comma {
        if text.contains('.') {
            return Err(format!(
                "holds {cell}: with source.decimal_comma = true a number has no `.`"
            ));
        }
        text.replacen(',', ".", 1).parse::<f64>()
    } else {
        if text.contains(',') {
            return Err(format!(
                "holds {cell}, not a number (a decimal comma? set source.decimal_comma = true)"
            ));
        }
        text.parse::<f64>()
    };
    parsed
        .map(Some)
        .map_err(|_| format!("holds {cell}, not a number"))
}

/// Each data row's time, s.
fn times(
    table: &Table,
    mapping: &Mapping,
    file: &str,
    rows: &[&Row],
    time_col: Option<usize>,
) -> Result<Vec<f64>, ImportError> {
    match (mapping.time(), time_col) {
        (Time::Rate { rate_hz, start_s }, _) => Ok((0..rows.len())
            .map(|i| start_s + i as f64 / rate_hz)
            .collect()),
        (
            Time::Column {
                scale,
                zero,
                start_s,
                ..
            },
            Some(col),
        ) => {
            let decimal_comma = mapping.source().decimal_comma;
            let mut raw = Vec::with_capacity(rows.len());
            for row in rows {
                let at = || table.place(row.number, col);
                let x = match number(Table::cell(row, col), decimal_comma) {
                    Ok(Some(x)) if x.is_finite() => x,
                    Ok(Some(x)) => {
                        return Err(ImportError::at(
                            file,
                            at(),
                            format!("t_s: time {x} is not a time"),
                        ))
                    }
                    Ok(None) => {
                        return Err(ImportError::at(
                            file,
                            at(),
                            "t_s: an empty cell; time is never empty",
                        ))
                    }
                    Err(why) => return Err(ImportError::at(file, at(), format!("t_s: {why}"))),
                };
                raw.push(x);
            }
            let zero = match zero {
                TimeZero::Raw(z) => *z,
                TimeZero::First => raw[0],
            };
            let scale = Scale::new(*scale);
            Ok(raw.iter().map(|x| start_s + scale.of(x - zero)).collect())
        }
        (Time::Column { .. }, None) => unreachable!("a time column is found before its times"),
    }
}

/// One mapped column's values (scaled, `None` where empty) and what
/// became of its cells. A voltage is refused where it would be empty.
fn channel(
    table: &Table,
    mapping: &Mapping,
    file: &str,
    rows: &[&Row],
    t_s: &[f64],
    ch: &ChannelMap,
    col: usize,
) -> Result<(Vec<Option<f64>>, ChannelReport), ImportError> {
    let decimal_comma = mapping.source().decimal_comma;
    let to = ch.to.name();
    let mut report = ChannelReport {
        to: ch.to,
        column: column_name(table, mapping, col),
        zero_raw: 0.0,
        empty_cells: 0,
        sentinels: 0,
        outside_valid: 0,
    };
    let mut raws = Vec::with_capacity(rows.len());
    for row in rows {
        let at = || table.place(row.number, col);
        let raw = match number(Table::cell(row, col), decimal_comma) {
            Err(why) => return Err(ImportError::at(file, at(), format!("{to}: {why}"))),
            Ok(None) => Raw::Empty,
            Ok(Some(x)) => {
                if let Some(s) = ch.sentinel(x) {
                    Raw::Sentinel(s)
                } else if !x.is_finite() {
                    return Err(ImportError::at(
                        file,
                        at(),
                        format!(
                            "{to}: holds {x}, not a measurement (a sensor's sentinel? list it \
                             in out_of_range: it is then written as an empty field)"
                        ),
                    ));
                } else if ch.outside_valid(x) {
                    Raw::OutsideValid(x)
                } else {
                    Raw::Value(x)
                }
            }
        };
        if let Target::Voltage(_) = ch.to {
            let why = match raw {
                Raw::Value(_) => None,
                Raw::Empty => Some("an empty cell".to_string()),
                Raw::Sentinel(s) => Some(format!("the sentinel {s} (out_of_range)")),
                Raw::OutsideValid(x) => Some(format!("{x}, outside valid")),
            };
            if let Some(why) = why {
                return Err(ImportError::at(
                    file,
                    at(),
                    format!("{to}: {why}; a voltage is never empty (docs/FORMAT.md)"),
                ));
            }
        }
        match raw {
            Raw::Value(_) => {}
            Raw::Empty => report.empty_cells += 1,
            Raw::Sentinel(_) => report.sentinels += 1,
            Raw::OutsideValid(_) => report.outside_valid += 1,
        }
        raws.push(match raw {
            Raw::Value(x) => Some(x),
            _ => None,
        });
    }
    let zero = match ch.zero {
        Zero::Raw(z) => z,
        Zero::Opening { opening_s } => {
            let t0 = t_s[0];
            let opening = t_s.iter().take_while(|&&t| t < t0 + opening_s).count();
            let read: Vec<f64> = raws[..opening].iter().flatten().copied().collect();
            if read.is_empty() {
                return Err(ImportError::at(
                    file,
                    format!(
                        "{} to {}",
                        table.place(rows[0].number, col),
                        table.place(rows[opening.max(1) - 1].number, col)
                    ),
                    format!(
                        "{to}: zero = \"opening\" takes the mean of the readings in the \
                         recording's first {opening_s} s, and there are none"
                    ),
                ));
            }
            read.iter().sum::<f64>() / read.len() as f64
        }
    };
    report.zero_raw = zero;
    let scale = Scale::new(ch.sign * ch.scale);
    let values = raws
        .into_iter()
        .map(|raw| raw.map(|x| scale.of(x - zero)))
        .collect();
    Ok((values, report))
}

/// A unit's change. A power of ten (0.001 for mV, mA, mm, ms) moves the
/// decimal point of the value's shortest decimal form, then reads it: 2000.1
/// mV is 2.0001 V, the double nearest to what the export shows, where
/// multiplying by 0.001 gives 2.0000999999999998 (voltages and times are
/// written exactly, and such digits would be read as measured). Any
/// other scale multiplies.
#[derive(Clone, Copy)]
enum Scale {
    Times(f64),
    /// Times `10^exponent`, negated if `negative`.
    Decimal {
        exponent: i32,
        negative: bool,
    },
}

impl Scale {
    fn new(scale: f64) -> Scale {
        (-18..=18)
            .find(|k| format!("1e{k}").parse::<f64>() == Ok(scale.abs()))
            .map_or(Scale::Times(scale), |exponent| Scale::Decimal {
                exponent,
                negative: scale < 0.0,
            })
    }

    fn of(self, x: f64) -> f64 {
        match self {
            Scale::Times(s) => x * s,
            Scale::Decimal { exponent, negative } => {
                // Rust writes a double's shortest round-trip digits; a
                // value beyond the doubles (`inf`) is multiplied, and
                // refused later as not finite.
                let y = format!("{x}e{exponent}")
                    .parse::<f64>()
                    .unwrap_or(x * 10f64.powi(exponent));
                if negative {
                    -y
                } else {
                    y
                }
            }
        }
    }
}

/// A column as a person finds it: `column C ("Y axis - Voltage")`.
fn column_name(table: &Table, mapping: &Mapping, col: usize) -> String {
    let name = table
        .row(mapping.source().header_row)
        .and_then(|row| Table::cell(row, col).name());
    match name {
        Some(name) => format!("column {} ({name:?})", column_letters(col)),
        None => format!("column {}", column_letters(col)),
    }
}

/// The metadata with a note of where the recording came from.
fn with_provenance(mut meta: Metadata, table: &Table, mapping: &Mapping, file: &str) -> Metadata {
    let base = |p: &str| {
        std::path::Path::new(p)
            .file_name()
            .map_or_else(|| p.to_string(), |n| n.to_string_lossy().into_owned())
    };
    let mut note = format!("imported by finrs import from {}", base(file));
    if let Some(sheet) = &table.sheet {
        let _ = write!(note, " (sheet {sheet:?})");
    }
    let _ = write!(note, " with {}", base(mapping.name()));
    meta.notes = Some(match meta.notes {
        Some(notes) => format!("{notes}; {note}"),
        None => note,
    });
    meta
}

/// The format's own rules on the recording made; a refusal of a row told
/// at the export's row, and at the cell of the column it names.
fn check_recording(
    recording: &Recording,
    table: &Table,
    mapping: &Mapping,
    file: &str,
    rows: &[&Row],
    time_col: Option<usize>,
    cols: &[usize],
) -> Result<(), ImportError> {
    let Err(e) = recording.validate(file) else {
        return Ok(());
    };
    let rule = format!("{} (docs/FORMAT.md)", e.message());
    // The written text's data rows follow the metadata and the header.
    let header_line = recording.meta.to_lines().lines().count() + 1;
    let row = e
        .line()
        .and_then(|line| line.checked_sub(header_line + 1))
        .and_then(|i| rows.get(i));
    let Some(row) = row else {
        return Err(ImportError::export(
            file,
            format!("the recording made breaks ipmc-bench/1: {rule}"),
        ));
    };
    let message = e.message();
    let col = if message.starts_with("time") || message.starts_with("t_s") {
        time_col
    } else {
        mapping
            .channels()
            .iter()
            .zip(cols)
            .find(|(ch, _)| names(message, &ch.to.name()))
            .map(|(_, &col)| col)
    };
    let at = match col {
        Some(col) => table.place(row.number, col),
        None => table.row_place(row.number),
    };
    Err(ImportError::at(file, at, rule))
}

/// Whether `message` names the column `name` as a word of its own.
fn names(message: &str, name: &str) -> bool {
    message.match_indices(name).any(|(i, _)| {
        let word = |c: char| c.is_ascii_alphanumeric() || c == '_';
        !message[..i].ends_with(word) && !message[i + name.len()..].starts_with(word)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::table::Row;

    fn mapping(text: &str) -> Mapping {
        let head = r#"
            format = "finrs-import/1"
            [metadata]
            segments = 1
            length_m = 0.05
            width_m = 0.01
            thickness_m = 0.0003
            fixture = "free"
            medium = "air"
        "#;
        Mapping::parse("m.toml", &format!("{head}\n{text}")).unwrap()
    }

    /// A sheet `S` of `lines`, cells separated by `;` (text cells: a
    /// comma is a decimal comma).
    fn table(lines: &[&str]) -> Table {
        Table {
            sheet: Some("S".into()),
            rows: lines
                .iter()
                .enumerate()
                .map(|(i, l)| Row {
                    number: i + 1,
                    cells: l
                        .split(';')
                        .map(|f| {
                            if f.is_empty() {
                                Cell::Empty
                            } else {
                                Cell::Text(f.into())
                            }
                        })
                        .collect(),
                })
                .collect(),
            merged: vec![],
            unclosed_quote: None,
        }
    }

    fn run(m: &Mapping, t: &Table) -> Result<Imported, ImportError> {
        convert(t, m, "x.xlsx", m.metadata_for("x.xlsx").unwrap())
    }

    const RATE: &str = r#"
        [time]
        rate_hz = 100
        [[channel]]
        to = "v1_V"
        column = "V"
        [[channel]]
        to = "tip_y_m"
        column = "d"
        scale = 0.001
        sign = -1
        zero = "opening"
        opening_s = 0.02
        out_of_range = [-99.9999]
        valid = [0, 50]
    "#;

    #[test]
    fn values_are_scaled_signed_zeroed_and_sentinels_emptied() {
        let m = mapping(RATE);
        let t = table(&[
            "V;d",
            "0;30",
            "0;32",
            "1;-99.99990000001",
            "1;60",
            "1;",
            "1;29",
        ]);
        let imported = run(&m, &t).unwrap();
        let rec = &imported.recording;
        assert_eq!(rec.t_s, vec![0.0, 0.01, 0.02, 0.03, 0.04, 0.05]);
        let tip = rec.channel(crate::recording::Channel::TipY).unwrap();
        // Zero: the mean of the first 0.02 s (rows at 0 and 0.01 s), 31.
        let expect = [Some(0.001), Some(-0.001), None, None, None, Some(0.002)];
        for (got, want) in tip.iter().zip(expect) {
            match (got, want) {
                (Some(g), Some(w)) => assert!((g - w).abs() < 1e-15, "{got:?} {want:?}"),
                _ => assert_eq!(*got, want),
            }
        }
        let r = &imported.channels[1];
        assert_eq!(
            (r.zero_raw, r.sentinels, r.outside_valid, r.empty_cells),
            (31.0, 1, 1, 1)
        );
        assert_eq!(r.column, "column B (\"d\")");
        let notes = rec.meta.notes.as_deref().unwrap();
        assert_eq!(
            notes,
            "imported by finrs import from x.xlsx (sheet \"S\") with m.toml"
        );
    }

    #[test]
    fn a_power_of_ten_moves_the_decimal_point() {
        assert_eq!(Scale::new(0.001).of(2000.1), 2.0001);
        assert_eq!(Scale::new(-0.001).of(2000.1), -2.0001);
        assert_eq!(Scale::new(0.001).of(10.0), 0.01);
        assert_eq!(Scale::new(1e-6).of(-123.4), -0.0001234);
        assert_eq!(Scale::new(1000.0).of(0.0021), 2.1);
        assert_eq!(Scale::new(2.5).of(2.0), 5.0);
        assert_eq!(Scale::new(1.0).of(0.3), 0.3);
        assert_eq!(Scale::new(0.3).of(2.0), 0.6);
    }

    #[test]
    fn data_end_at_the_first_blank_row_and_nothing_mapped_may_follow() {
        let m = mapping(RATE);
        // Unmapped cells after the data, and beyond the last mapped column: fine.
        let t = table(&["V;d", "0;30", "0;30;7", ";", ";;note"]);
        assert_eq!(run(&m, &t).unwrap().recording.t_s.len(), 2);
        let t = table(&["V;d", "0;30", ";", "0;30"]);
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(
            err.starts_with("x.xlsx: S row 3: a blank row inside the data")
                && err.contains("S!A4 (v1_V) holds `0` after it"),
            "{err}"
        );
        // A sheet's row not listed is blank.
        let mut t = table(&["V;d", "0;30", "0;30"]);
        t.rows[2].number = 4;
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(
            err.contains("S row 3: a blank row inside the data"),
            "{err}"
        );
        let t = table(&["V;d", ";", "0;30"]);
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(err.contains("set first_data_row"), "{err}");
        let t = table(&["V;d", ";;x"]);
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(err.contains("no data: from S row 2"), "{err}");
    }

    #[test]
    fn bad_cells_are_refused_at_their_place_with_their_rule() {
        let m = mapping(RATE);
        for (lines, place, says) in [
            (
                &["V;d", "0;30", "x;30"][..],
                "S!A3",
                "v1_V: holds the text `x`, not a number",
            ),
            (&["V;d", "0;30", "1;3,5"], "S!B3", "a decimal comma?"),
            (
                &["V;d", "0;30", ";30"],
                "S!A3",
                "v1_V: an empty cell; a voltage is never empty",
            ),
            (
                &["V;d", "0;30", "0;inf"],
                "S!B3",
                "tip_y_m: holds inf, not a measurement",
            ),
            (
                &["V;d", "0;30", "4.5;30"],
                "S!A3",
                "v1_V = 4.5 V is beyond the safe range",
            ),
            (
                &["V;d", "0;-99.9999", "0;", "0;30"],
                "S!B2 to S!B3",
                "zero = \"opening\"",
            ),
        ] {
            let err = run(&m, &table(lines)).unwrap_err().to_string();
            assert!(err.starts_with(&format!("x.xlsx: {place}: ")), "{err}");
            assert!(err.contains(says), "{err}");
        }
        let mut t = table(&["V;d", "0;30", "0;30"]);
        t.rows[2].cells[1] = Cell::Error("#DIV/0!".into());
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(
            err.contains("S!B3: tip_y_m: holds the formula error #DIV/0!"),
            "{err}"
        );
    }

    #[test]
    fn columns_are_found_by_name_once_or_refused() {
        let m = mapping(RATE);
        let err = run(&m, &table(&["V;e", "0;1"])).unwrap_err().to_string();
        assert!(
            err.contains("S row 1 (header row): no column named \"d\" (m.toml channel[2].column); it holds A \"V\", B \"e\""),
            "{err}"
        );
        let err = run(&m, &table(&["V;d;V", "0;1;0"]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("heads columns A and C"), "{err}");
        let err = run(&m, &table(&[])).unwrap_err().to_string();
        assert_eq!(err, "x.xlsx: the sheet \"S\" is empty");
    }

    #[test]
    fn a_time_column_in_ms_with_decimal_commas() {
        let m = mapping(
            r#"
            [source]
            decimal_comma = true
            [time]
            column = "t (ms)"
            scale = 0.001
            zero = "first"
            [[channel]]
            to = "v1_V"
            index = 2
            scale = 0.001
        "#,
        );
        let mut t = table(&["t (ms);mV", "100,5;0,5", "110,5;-1"]);
        let rec = run(&m, &t).unwrap().recording;
        assert_eq!(rec.t_s, vec![0.0, 0.01]);
        assert_eq!(rec.v_v.row(0), Some(&[0.0005][..]));
        t.rows[2].cells[0] = Cell::Text("100,5".into());
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(
            err.starts_with("x.xlsx: S!A3: time must be strictly increasing"),
            "{err}"
        );
        t.rows[2].cells[0] = Cell::Text("1.5".into());
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(err.contains("has no `.`"), "{err}");
    }

    #[test]
    fn merged_cells_over_a_mapped_column_are_refused() {
        let m = mapping(RATE);
        let mut t = table(&["V;d;x", "0;30", "0;30"]);
        t.merged.push(crate::import::table::Merged {
            rows: (2, 3),
            columns: (1, 2),
        });
        let err = run(&m, &t).unwrap_err().to_string();
        assert!(
            err.contains("S!B2:C3: merged cells over column B (tip_y_m)"),
            "{err}"
        );
        // Over unmapped columns only: fine.
        t.merged[0].columns = (2, 3);
        assert!(run(&m, &t).is_ok());
        // A title merged above the header: fine.
        let m = mapping(&format!("[source]\nheader_row = 2\n{RATE}"));
        let mut t = table(&["title", "V;d", "0;30"]);
        t.merged.push(crate::import::table::Merged {
            rows: (1, 1),
            columns: (0, 2),
        });
        assert!(run(&m, &t).is_ok());
        t.merged[0].rows = (1, 2);
        assert!(run(&m, &t).is_err());
    }
}
