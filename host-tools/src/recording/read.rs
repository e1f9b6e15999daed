//! Parsing a recording from text, rule by rule.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use super::error::RecordingError;
use super::meta::{Fixture, MetaBuilder, Metadata};
use super::plain_row::plain_row;
use super::rest::{check_range, READING_LIMIT_V};
use super::{Channel, Recording, Voltages, SAFE_VOLTAGE_LIMIT_V};

impl Recording {
    /// Reads and checks a recording file.
    pub fn read(path: &Path) -> Result<Recording, RecordingError> {
        Self::read_keeping(path, Keep::All)
    }

    /// Reads and checks a recording file as [`Recording::read`] does,
    /// every field of every row, but keeps only its metadata, time and
    /// drive (`channels` is empty): what a simulation needs, without the
    /// memory of the measured columns.
    pub fn read_drive(path: &Path) -> Result<Recording, RecordingError> {
        Self::read_keeping(path, Keep::Drive)
    }

    fn read_keeping(path: &Path, keep: Keep) -> Result<Recording, RecordingError> {
        let name = path.display().to_string();
        let cannot = |e: std::io::Error| RecordingError::file(&name, format!("cannot read: {e}"));
        // A large file is read in chunks of whole lines, never whole in
        // memory. Whatever that refuses is read again whole and refused
        // from there: one message for a file however it is read (the
        // whole file's UTF-8 is checked before any row, for one).
        let file = std::fs::File::open(path).map_err(cannot)?;
        let len = file.metadata().map_err(cannot)?.len();
        if len > 4 * CHUNK_BYTES as u64 {
            if let Some(rec) = read_in_chunks(&name, &file, len, keep) {
                return Ok(rec);
            }
        }
        let bytes = std::fs::read(path).map_err(cannot)?;
        Self::parse_bytes_keeping(&name, &bytes, keep)
    }

    /// Parses raw bytes, refusing invalid UTF-8 with the line it is on.
    pub fn parse_bytes(name: &str, bytes: &[u8]) -> Result<Recording, RecordingError> {
        Self::parse_bytes_keeping(name, bytes, Keep::All)
    }

    fn parse_bytes_keeping(
        name: &str,
        bytes: &[u8],
        keep: Keep,
    ) -> Result<Recording, RecordingError> {
        match std::str::from_utf8(bytes) {
            Ok(text) => Self::parse_keeping(name, text, keep),
            Err(e) => {
                let line = 1 + bytes[..e.valid_up_to()]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count();
                Err(RecordingError::at(name, line, "not valid UTF-8"))
            }
        }
    }

    /// Parses and checks the text of a recording; `name` is used in messages.
    pub fn parse(name: &str, text: &str) -> Result<Recording, RecordingError> {
        Self::parse_keeping(name, text, Keep::All)
    }

    fn parse_keeping(name: &str, text: &str, keep: Keep) -> Result<Recording, RecordingError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.is_empty() {
            return Err(RecordingError::file(name, "empty file"));
        }
        let mut lines = lines(text);
        let head = read_head(name, &mut lines)?;
        let mut rows = Rows::new(name, head, text.len(), keep);
        for (line, row) in lines {
            rows.row(line, row)?;
        }
        rows.finish()
    }
}

/// Bytes read at a time from a large file.
const CHUNK_BYTES: usize = 64 << 10;

/// Reads `file` (`len` bytes) in chunks of whole lines; `None` if anything
/// is refused or cannot be read.
fn read_in_chunks(name: &str, file: &File, len: u64, keep: Keep) -> Option<Recording> {
    // The metadata and the header, up to the end of the first line that
    // is not metadata.
    let mut first = Chunks::new(file, 0, len);
    let bom = "\u{feff}".as_bytes();
    let head_end = loop {
        let held = &first.buf[..first.filled];
        let start = if held.starts_with(bom) { bom.len() } else { 0 };
        let mut at = start;
        let mut found = None;
        for nl in memchr::memchr_iter(b'\n', &held[start..]) {
            let end = start + nl;
            if !held[at..end].starts_with(b"#") {
                found = Some(end + 1);
                break;
            }
            at = end + 1;
        }
        match found {
            Some(end) => break end,
            None if first.more()? => continue,
            None => return None,
        }
    };
    let head_text = std::str::from_utf8(&first.buf[..head_end]).ok()?;
    let head_text = head_text.strip_prefix('\u{feff}').unwrap_or(head_text);
    let head = read_head(name, &mut lines(head_text)).ok()?;
    first.taken = head_end;
    let line = head.1 + 1;
    let mut rows = Rows::new(name, head, len as usize, keep);
    read_rows(&mut first, line, &mut rows)?;
    rows.finish().ok()
}

/// Checks and keeps the rows `chunks` holds, the first on `line`; `None`
/// if any is refused or the file cannot be read.
fn read_rows(chunks: &mut Chunks, mut line: usize, rows: &mut Rows) -> Option<()> {
    while let Some(text) = chunks.lines()? {
        for (_, row) in lines(text) {
            rows.row(line, row).ok()?;
            line += 1;
        }
    }
    Some(())
}

/// Bytes `at..end` of a file read a chunk at a time, handed out as whole
/// lines (the last at `end` without its line end, if it has none).
struct Chunks<'f> {
    file: &'f File,
    /// The next byte of the file to read.
    at: u64,
    /// Where to stop reading.
    end: u64,
    /// The bytes read and not yet dropped: `buf[..filled]`.
    buf: Vec<u8>,
    filled: usize,
    /// How many of them were handed out.
    taken: usize,
}

impl<'f> Chunks<'f> {
    fn new(file: &'f File, at: u64, end: u64) -> Chunks<'f> {
        Chunks {
            file,
            at,
            end,
            // Zeroed once; each read lands in it (no growing per chunk).
            buf: vec![0; 2 * CHUNK_BYTES],
            filled: 0,
            taken: 0,
        }
    }

    /// Reads the next chunk after the bytes held, dropping those handed
    /// out: `Some(false)` at `end`, `None` if the file cannot be read or
    /// ends first.
    fn more(&mut self) -> Option<bool> {
        if self.at >= self.end {
            return Some(false);
        }
        self.buf.copy_within(self.taken..self.filled, 0);
        self.filled -= self.taken;
        self.taken = 0;
        let want = (self.end - self.at).min(CHUNK_BYTES as u64) as usize;
        if self.buf.len() < self.filled + want {
            // A line longer than a chunk.
            self.buf.resize(self.filled + want, 0);
        }
        // The one reader of a file just opened: its cursor is at `self.at`
        // (a plain read, so that this builds off Unix too, as output.rs).
        let n = (&mut &*self.file)
            .read(&mut self.buf[self.filled..self.filled + want])
            .ok()?;
        if n == 0 {
            return None;
        }
        self.at += n as u64;
        self.filled += n;
        Some(true)
    }

    /// The next whole lines as text, ending at a line end (or at `end`);
    /// `Some(None)` once every byte is handed out, `None` if the file
    /// cannot be read or is not UTF-8 there.
    fn lines(&mut self) -> Option<Option<&str>> {
        loop {
            let held = &self.buf[self.taken..self.filled];
            let complete = if self.at >= self.end {
                held.len()
            } else {
                memchr::memrchr(b'\n', held).map_or(0, |nl| nl + 1)
            };
            if complete > 0 {
                let start = self.taken;
                self.taken += complete;
                return std::str::from_utf8(&self.buf[start..start + complete])
                    .ok()
                    .map(Some);
            }
            if !self.more()? {
                return Some(None);
            }
        }
    }
}

/// The data rows of a recording as they are read, checked one by one.
struct Rows<'a> {
    name: &'a str,
    header_line: usize,
    columns: Vec<Channel>,
    rules: RowRules,
    v: Vec<f64>,
    /// A row's values as [`plain_row`] reads them.
    plain: Vec<f64>,
    rec: Recording,
}

impl<'a> Rows<'a> {
    /// No rows yet, after the head `(meta, header_line, columns)`; `bytes`
    /// of text to come (a first guess at the row count saves most
    /// regrowing).
    fn new(
        name: &'a str,
        (meta, header_line, columns): (Metadata, usize, Vec<Channel>),
        bytes: usize,
        keep: Keep,
    ) -> Rows<'a> {
        let measured = columns.len();
        let rows = bytes / (8 * (1 + meta.segments + measured));
        let n = meta.segments;
        let rec = Recording {
            t_s: Vec::with_capacity(rows),
            v_v: Voltages::with_capacity(n, rows),
            meta,
            channels: match keep {
                Keep::All => columns
                    .iter()
                    .map(|&c| (c, Vec::with_capacity(rows)))
                    .collect(),
                Keep::Drive => Vec::new(),
            },
        };
        Rows {
            name,
            header_line,
            columns,
            rules: RowRules::default(),
            v: vec![0.0; n],
            plain: vec![0.0; 1 + n + measured],
            rec,
        }
    }

    /// Checks and keeps the data row `text` on line `line`.
    fn row(&mut self, line: usize, text: &str) -> Result<(), RecordingError> {
        if self.plain_row(text) {
            return Ok(());
        }
        self.any_row(line, text)
    }

    /// Keeps the row `text` if [`plain_row`] reads it and its numbers break
    /// no rule (time present, at or after 0 and later than the last row's;
    /// voltages present and within any reading of the safe range): `false`
    /// leaves it to
    /// [`Rows::any_row`], which reads it again and says what is wrong.
    fn plain_row(&mut self, text: &str) -> bool {
        let values = &mut self.plain[..];
        if plain_row(text.as_bytes(), values).is_none() {
            return false;
        }
        let n = self.rec.meta.segments;
        let t = values[0];
        // NaN (an empty field) fails each comparison.
        let ok = t >= 0.0
            && self.rules.previous_t_s.is_none_or(|previous| t > previous)
            && values[1..=n].iter().all(|v| v.abs() <= READING_LIMIT_V);
        if !ok {
            return false;
        }
        self.rules.previous_t_s = Some(t);
        self.rec.t_s.push(t);
        self.rec.v_v.push(&values[1..=n]);
        for ((_, kept), &x) in self.rec.channels.iter_mut().zip(&values[1 + n..]) {
            kept.push(Some(x).filter(|x| !x.is_nan()));
        }
        true
    }

    /// Checks and keeps any data row, refusing it with the first rule it
    /// breaks.
    fn any_row(&mut self, line: usize, text: &str) -> Result<(), RecordingError> {
        let name = self.name;
        let columns = &self.columns;
        let n = self.rec.meta.segments;
        let width = 1 + n + columns.len();
        if text.is_empty() {
            return Err(RecordingError::at(name, line, "blank line inside the data"));
        }
        if text.starts_with('#') {
            return Err(RecordingError::at(
                name,
                line,
                "metadata line after the header: metadata must come first",
            ));
        }
        // Fields are split and parsed in one pass over the row; a wrong
        // field count is what any refusal of the row reports first.
        let mut fields = Fields { text, at: 0 };
        let refuse = |e: RecordingError| {
            let count = 1 + text.bytes().filter(|&b| b == b',').count();
            if count == width {
                e
            } else {
                RecordingError::at(
                    name,
                    line,
                    format!("row has {count} fields, the header has {width}"),
                )
            }
        };
        // Column names are only built for a message.
        let column = |j: usize| column_name(n, columns, j);
        let mut next = |j: usize| match fields.next() {
            Some((field, value)) => value.map_err(|e| refuse(e.at(name, line, &column(j), field))),
            None => Err(refuse(RecordingError::at(name, line, "missing field"))),
        };
        let t = next(0)?.ok_or_else(|| {
            refuse(RecordingError::at(
                name,
                line,
                "t_s is empty: time is never missing",
            ))
        })?;
        self.rules.time(name, line, t).map_err(refuse)?;
        for (k, slot) in self.v.iter_mut().enumerate() {
            let x = next(1 + k)?.ok_or_else(|| {
                refuse(RecordingError::at(
                    name,
                    line,
                    format!("{} is empty: voltages are never missing", column(1 + k)),
                ))
            })?;
            voltage(name, line, k, x).map_err(refuse)?;
            *slot = x;
        }
        for j in 0..columns.len() {
            let value = next(1 + n + j)?;
            if let Some((_, values)) = self.rec.channels.get_mut(j) {
                values.push(value);
            }
        }
        if fields.next().is_some() {
            return Err(refuse(RecordingError::at(name, line, "extra field")));
        }
        self.rec.t_s.push(t);
        self.rec.v_v.push(&self.v);
        Ok(())
    }

    /// The recording read, if it has a data row and its voltages are
    /// within the safe range as their channels read it.
    fn finish(self) -> Result<Recording, RecordingError> {
        if self.rec.t_s.is_empty() {
            return Err(RecordingError::at(
                self.name,
                self.header_line,
                "no data rows after the header",
            ));
        }
        check_range(self.name, self.header_line, &self.rec.t_s, &self.rec.v_v)?;
        Ok(self.rec)
    }
}

/// What a read keeps of a recording (every field is checked either way).
#[derive(Clone, Copy)]
enum Keep {
    /// Everything.
    All,
    /// Metadata, time and drive.
    Drive,
}

/// The lines of `text`, numbered from 1, without their `\r\n` or `\n`.
/// One final line end is allowed; anything blank before it is not.
/// (`memchr` finds the line ends many bytes at a time.)
pub(super) fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let body = text.strip_suffix('\n').unwrap_or(text);
    let mut start = 0;
    memchr::memchr_iter(b'\n', body.as_bytes())
        .chain(std::iter::once(body.len()))
        .enumerate()
        .map(move |(i, end)| {
            let line = &body[start..end];
            start = end + 1;
            (i + 1, line.strip_suffix('\r').unwrap_or(line))
        })
}

/// Reads the metadata and the header: the metadata, the header's line and
/// its measured channels in order.
pub(super) fn read_head<'a>(
    name: &str,
    lines: &mut impl Iterator<Item = (usize, &'a str)>,
) -> Result<(Metadata, usize, Vec<Channel>), RecordingError> {
    let mut meta = MetaBuilder::default();
    let (header_line, header) = loop {
        match lines.next() {
            None => {
                return Err(RecordingError::file(
                    name,
                    "no header line after the metadata",
                ))
            }
            Some((n, l)) if l.starts_with('#') => meta.line(name, n, l)?,
            Some((n, "")) => {
                return Err(RecordingError::at(
                    name,
                    n,
                    "blank line: metadata must be followed directly by the header",
                ))
            }
            Some(found) => break found,
        }
    };
    let meta = meta.finish(name, header_line)?;
    let columns = header_columns(name, header_line, header, &meta)?;
    Ok((meta, header_line, columns))
}

/// The name of field `j` of a row with `n` voltages and `columns`.
pub(super) fn column_name(n: usize, columns: &[Channel], j: usize) -> String {
    match j {
        0 => "t_s".to_string(),
        j if j <= n => format!("v{j}_V"),
        j => columns
            .get(j - 1 - n)
            .map_or_else(String::new, Channel::name),
    }
}

/// The rules on a row's numbers, shared by the reader and
/// [`Recording::validate`]: time starts at or after 0 and strictly
/// increases.
#[derive(Default)]
pub(super) struct RowRules {
    previous_t_s: Option<f64>,
}

impl RowRules {
    /// Checks the time `t` of the row on `line`, then remembers it.
    pub fn time(&mut self, file: &str, line: usize, t: f64) -> Result<(), RecordingError> {
        if t < 0.0 {
            return Err(RecordingError::at(
                file,
                line,
                format!("time must start at or after 0, got {t}"),
            ));
        }
        if let Some(prev) = self.previous_t_s {
            if t <= prev {
                return Err(RecordingError::at(
                    file,
                    line,
                    format!("time must be strictly increasing ({t} after {prev})"),
                ));
            }
        }
        self.previous_t_s = Some(t);
        Ok(())
    }
}

/// Voltage `x` of segment `k` (0-based) must lie within any reading of
/// the safe range ([`READING_LIMIT_V`]); nearer, its channel's rest says
/// ([`check_range`], once the rows are read).
pub(super) fn voltage(file: &str, line: usize, k: usize, x: f64) -> Result<(), RecordingError> {
    if x.abs() > READING_LIMIT_V {
        return Err(RecordingError::at(
            file,
            line,
            format!(
                "v{}_V = {x} V is beyond the safe range of ±{SAFE_VOLTAGE_LIMIT_V} V",
                k + 1
            ),
        ));
    }
    Ok(())
}

/// Why a field is not a measurement.
pub(super) enum BadNumber {
    /// Parses, but as NaN or an infinity.
    NotFinite,
    /// Does not parse.
    NotNumber,
}

impl BadNumber {
    /// The refusal of `field` in `column` on `line` of `file`.
    pub fn at(self, file: &str, line: usize, column: &str, field: &str) -> RecordingError {
        let rule = match self {
            BadNumber::NotFinite => ": NaN and infinity are not measurements",
            BadNumber::NotNumber => " is not a number",
        };
        RecordingError::at(file, line, format!("{column} = `{field}`{rule}"))
    }
}

/// A data row's fields, split and parsed in one pass.
struct Fields<'a> {
    text: &'a str,
    /// Where the next field starts; past the end once the last is taken.
    at: usize,
}

impl<'a> Fields<'a> {
    /// The next field and its value (`None` when empty), or `None` past
    /// the last field. Parsing allocates nothing.
    fn next(&mut self) -> Option<(&'a str, Result<Option<f64>, BadNumber>)> {
        let row = self.text.as_bytes();
        let at = self.at;
        if at > row.len() {
            return None;
        }
        let (fast, end) = scan_decimal(row, at);
        self.at = end + 1;
        let field = &self.text[at..end];
        let value = match fast {
            Some(x) => Ok(Some(x)),
            None => number(field),
        };
        Some((field, value))
    }
}

/// A field that is not a short plain decimal: empty is `None`; anything
/// else must be a finite number, as `str::parse` reads it.
fn number(field: &str) -> Result<Option<f64>, BadNumber> {
    if field.is_empty() {
        return Ok(None);
    }
    match field.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(Some(x)),
        Ok(_) => Err(BadNumber::NotFinite),
        Err(_) => Err(BadNumber::NotNumber),
    }
}

/// Powers of ten exact in `f64`.
const POW10: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// The field of `row` starting at `at`: its value if it is a plain decimal
/// of at most 15 digits (`-12.345`, `0.0192`, `3`), else `None` (left to
/// `str::parse`), and where it ends (the next comma, or the row's end).
/// Such a field is what a DAQ writes, and its value is one correctly
/// rounded division of two numbers exact in `f64` (Clinger's fast path),
/// so it equals what `str::parse` gives, at a fraction of the cost.
fn scan_decimal(row: &[u8], at: usize) -> (Option<f64>, usize) {
    let negative = row.get(at) == Some(&b'-');
    let start = at + usize::from(negative);
    let mut mantissa = 0u64;
    let mut digits = |from: usize| digit_run(row, from, &mut mantissa);
    let whole = digits(start);
    let mut i = start + whole;
    let mut decimals = 0;
    let mut plain = whole > 0;
    if plain && row.get(i) == Some(&b'.') {
        decimals = digits(i + 1);
        i += 1 + decimals;
        plain = decimals > 0;
    }
    plain &= whole + decimals <= 15 && row.get(i).is_none_or(|&b| b == b',');
    if !plain {
        let end = row[at..]
            .iter()
            .position(|&b| b == b',')
            .map_or(row.len(), |p| at + p);
        return (None, end);
    }
    // Below 10^15: as i64, one instruction to convert.
    let x = mantissa as i64 as f64 / POW10[decimals];
    (Some(if negative { -x } else { x }), i)
}

/// The run of ASCII digits of `row` from `from`: its length, the digits
/// appended to `mantissa` (wrapping: more than 15 digits are refused by the
/// caller anyway). A byte at a time: this is the general path, for rows
/// [`plain_row`] leaves to it; the common row is read eight bytes at a time
/// there.
fn digit_run(row: &[u8], from: usize, mantissa: &mut u64) -> usize {
    let mut count = 0;
    for &b in row.get(from..).unwrap_or_default() {
        let d = b.wrapping_sub(b'0');
        if d >= 10 {
            break;
        }
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        count += 1;
    }
    count
}

/// [`scan_decimal`] of a whole field.
#[cfg(test)]
fn short_decimal(field: &[u8]) -> Option<f64> {
    match scan_decimal(field, 0) {
        (Some(x), end) if end == field.len() => Some(x),
        _ => None,
    }
}

/// Checks the header and returns its measured channels in order.
fn header_columns(
    file: &str,
    line: usize,
    header: &str,
    meta: &super::Metadata,
) -> Result<Vec<Channel>, RecordingError> {
    let err = |m: String| RecordingError::at(file, line, m);
    let names: Vec<&str> = header.split(',').collect();
    if names[0] != "t_s" {
        return Err(err(format!(
            "header must start with t_s, got `{}`",
            names[0]
        )));
    }
    let n = meta.segments;
    for k in 0..n {
        let want = format!("v{}_V", k + 1);
        match names.get(1 + k) {
            Some(&got) if got == want => {}
            Some(&got) => {
                return Err(err(format!(
                    "header column {} must be {want} (segments = {n}), got `{got}`",
                    k + 2
                )))
            }
            None => return Err(err(format!("header lacks {want}: segments = {n}"))),
        }
    }
    let mut channels = Vec::new();
    for &col in &names[1 + n..] {
        let Some(ch) = Channel::parse(col) else {
            let hint = if col.starts_with('v') && col.ends_with("_V") {
                format!(" (segments = {n}: voltage columns must match it)")
            } else {
                String::new()
            };
            return Err(err(format!("unknown column `{col}`{hint}")));
        };
        if channels.contains(&ch) {
            return Err(err(format!("column `{col}` appears twice")));
        }
        match ch {
            Channel::Current(k) if k >= n => {
                return Err(err(format!("column `{col}`: there are only {n} segments")))
            }
            Channel::Force if meta.fixture == Fixture::Free => {
                return Err(err(
                    "column `force_N` needs fixture = \"blocked\" (the load cell holds the tip)"
                        .to_string(),
                ))
            }
            c if c.is_camera() && meta.fixture == Fixture::Blocked => {
                return Err(err(format!(
                "column `{col}` needs fixture = \"free\" (a blocked tip is held by the load cell)"
            )))
            }
            Channel::DotY(j) | Channel::DotX(j) => {
                let dots = meta.dots_s_m.as_ref().map_or(0, Vec::len);
                if j >= dots {
                    return Err(err(format!(
                        "column `{col}` needs dot {} in `dots_s_m` ({dots} given)",
                        j + 1
                    )));
                }
            }
            _ => {}
        }
        channels.push(ch);
    }
    Ok(channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows read as `read` does (the plain path first) and by the general
    /// path alone: the same recording, or the same refusal.
    fn both_paths(
        rows: &[String],
    ) -> (
        Result<Recording, RecordingError>,
        Result<Recording, RecordingError>,
    ) {
        let head = "# format = \"ipmc-bench/1\"\n# segments = 2\n# length_m = 0.05\n\
                    # width_m = 0.01\n# thickness_m = 0.0002858\n# fixture = \"free\"\n\
                    # medium = \"air\"\nt_s,v1_V,v2_V,i1_A,tip_y_m\n";
        let read = |plain: bool| {
            let head = read_head("x.csv", &mut lines(head)).unwrap();
            let line = head.1 + 1;
            let mut kept = Rows::new("x.csv", head, 0, Keep::All);
            for (k, row) in rows.iter().enumerate() {
                if plain {
                    kept.row(line + k, row)?;
                } else {
                    kept.any_row(line + k, row)?;
                }
            }
            kept.finish()
        };
        (read(true), read(false))
    }

    proptest::proptest! {
        /// The plain path keeps exactly what the general path keeps, and
        /// leaves to it every row it would refuse.
        #[test]
        fn the_plain_path_reads_as_the_general_path(
            rows in proptest::collection::vec(
                (
                    proptest::bool::weighted(0.9),
                    proptest::collection::vec(
                        "-?[0-9]{1,3}(\\.[0-9]{1,8})?|5|[0-9]{9}|1e-3|-|x| ?",
                        4..7,
                    ),
                ),
                1..8,
            ),
        ) {
            // Mostly a time that increases, so that rows after the first
            // are read too.
            let rows: Vec<String> = rows
                .iter()
                .enumerate()
                .map(|(k, (ordered, fields))| match ordered {
                    true => format!("{k}.25,{}", fields[1..].join(",")),
                    false => fields.join(","),
                })
                .collect();
            let (plain, general) = both_paths(&rows);
            proptest::prop_assert_eq!(plain, general, "{:?}", rows);
        }
    }

    #[test]
    fn rows_breaking_a_rule_are_refused_as_before() {
        for rows in [
            &["0,1,2,0.5,", "0,1,2,0.5,"][..],
            &["1,1,2,0.5,", "0.5,1,2,0.5,"],
            &["-1,1,2,0.5,"],
            &["0,4.5,2,0.5,"],
            &["0,,2,0.5,"],
            &[",1,2,0.5,"],
            &["0,1,2,0.5"],
            &["0,1,2,0.5,1,2"],
            &["0,1,2,1e-3,", "1,1,2,x,"],
        ] {
            let rows: Vec<String> = rows.iter().map(|r| r.to_string()).collect();
            let (plain, general) = both_paths(&rows);
            assert!(plain.is_err(), "{rows:?}");
            assert_eq!(plain, general, "{rows:?}");
        }
    }

    proptest::proptest! {
        /// Whatever the fast path reads, it reads as `str::parse` does, and
        /// it always finds the field's end.
        #[test]
        fn scanned_fields_read_as_str_parse_reads_them(
            digits in "-?[0-9]{0,17}(\\.[0-9]{0,17})?(e-?[0-9]{1,2})?",
            x in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
            decimals in 0usize..16,
        ) {
            for field in [digits, format!("{x}"), format!("{x:.decimals$}"), format!("{:.decimals$}", x % 1e4)] {
                let row = format!("{field},1");
                let (fast, end) = scan_decimal(row.as_bytes(), 0);
                proptest::prop_assert_eq!(end, field.len(), "{}", field);
                if let Some(got) = fast {
                    let want: f64 = field.parse().unwrap();
                    proptest::prop_assert_eq!(got.to_bits(), want.to_bits(), "{}", field);
                }
            }
        }
    }

    #[test]
    fn a_large_file_is_read_in_chunks_as_its_text_parses() {
        // What `read_in_chunks` returns itself, not the whole-file read it
        // falls back on: 30 000 rows in chunks of 64 KiB, CRLF, a BOM and
        // no final line end.
        let mut text = String::from(
            "\u{feff}# format = \"ipmc-bench/1\"\r\n# segments = 2\r\n# length_m = 0.05\r\n\
             # width_m = 0.01\r\n# thickness_m = 0.0002858\r\n# fixture = \"free\"\r\n\
             # medium = \"air\"\r\nt_s,v1_V,v2_V,i1_A,tip_y_m\r\n",
        );
        for k in 0..30_000 {
            let camera = if k % 3 == 0 { "0.00012" } else { "" };
            text.push_str(&format!(
                "{}.{:03},{}.5,-0.{k},0.0{k},{camera}\r\n",
                k / 1000,
                k % 1000,
                k % 3
            ));
        }
        let text = text.trim_end();
        let path =
            std::env::temp_dir().join(format!("finrs-read-chunks-{}.csv", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let file = std::fs::File::open(&path).unwrap();
        let len = text.len() as u64;
        assert!(len > 4 * CHUNK_BYTES as u64);
        let chunked = read_in_chunks("big", &file, len, Keep::All);
        std::fs::remove_file(&path).unwrap();
        let want = Recording::parse("big", text).unwrap();
        assert_eq!(want.t_s.len(), 30_000);
        assert!(
            chunked == Some(want),
            "read in chunks differs from the parsed text"
        );
    }

    #[test]
    fn short_decimals_read_as_str_parse_reads_them() {
        for field in [
            "0",
            "-0",
            "3",
            "12.345",
            "-2.4869",
            "0.0192",
            "0.000014",
            "999999999999999",
            "99999.9999999999",
            "0.1",
            "1.7976931348",
            "-0.00000000000001",
        ] {
            let x = short_decimal(field.as_bytes()).expect(field);
            let want: f64 = field.parse().unwrap();
            assert_eq!(x.to_bits(), want.to_bits(), "{field}");
        }
        for field in [
            "",
            "-",
            ".",
            "1.",
            ".5",
            "-.5",
            "+1",
            "1e3",
            "1.2.3",
            "1,2",
            "nan",
            "inf",
            " 1",
            "1234567890123456",
            "0.0000000000000001",
        ] {
            assert_eq!(short_decimal(field.as_bytes()), None, "{field}");
        }
        // Every decimal of up to 15 digits a DAQ might write.
        let mut k: u64 = 1;
        while k < 1_000_000_000_000_000 {
            for decimals in 0..=15usize {
                let s = k.to_string();
                let field = if decimals == 0 {
                    s
                } else if decimals >= s.len() {
                    format!("0.{}{s}", "0".repeat(decimals - s.len()))
                } else {
                    format!("{}.{}", &s[..s.len() - decimals], &s[s.len() - decimals..])
                };
                let want: f64 = field.parse().unwrap();
                match short_decimal(field.as_bytes()) {
                    Some(x) => assert_eq!(x.to_bits(), want.to_bits(), "{field}"),
                    None => assert!(field.len() > 16, "{field}"),
                }
            }
            k = k * 7 + 3;
        }
    }
}
