//! Parsing a recording from text, rule by rule.

use std::path::Path;

use super::error::RecordingError;
use super::meta::{Fixture, MetaBuilder, Metadata};
use super::{Channel, Recording, SAFE_VOLTAGE_LIMIT_V};

impl Recording {
    /// Reads and checks a recording file.
    pub fn read(path: &Path) -> Result<Recording, RecordingError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path)
            .map_err(|e| RecordingError::file(&name, format!("cannot read: {e}")))?;
        Self::parse_bytes(&name, &bytes)
    }

    /// Parses raw bytes, refusing invalid UTF-8 with the line it is on.
    pub fn parse_bytes(name: &str, bytes: &[u8]) -> Result<Recording, RecordingError> {
        match std::str::from_utf8(bytes) {
            Ok(text) => Self::parse(name, text),
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
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.is_empty() {
            return Err(RecordingError::file(name, "empty file"));
        }
        let mut lines = lines(text);
        let (meta, header_line, columns) = read_head(name, &mut lines)?;
        // A first guess at the row count saves most regrowing.
        let rows = text.len() / (8 * (1 + meta.segments + columns.len()));
        let mut rec = Recording {
            meta,
            t_s: Vec::with_capacity(rows),
            v_v: Vec::with_capacity(rows),
            channels: columns
                .iter()
                .map(|&c| (c, Vec::with_capacity(rows)))
                .collect(),
        };
        let n = rec.meta.segments;
        let width = 1 + n + columns.len();
        let mut rules = RowRules::default();
        let mut fields: Vec<&str> = Vec::with_capacity(width);
        for (line, text) in lines {
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
            // Split once into a buffer reused for every row.
            fields.clear();
            let mut start = 0;
            for (i, &b) in text.as_bytes().iter().enumerate() {
                if b == b',' {
                    fields.push(&text[start..i]);
                    start = i + 1;
                }
            }
            fields.push(&text[start..]);
            if fields.len() != width {
                return Err(RecordingError::at(
                    name,
                    line,
                    format!("row has {} fields, the header has {width}", fields.len()),
                ));
            }
            // Column names are only built for a message.
            let column = |j: usize| column_name(n, &columns, j);
            let next = |j: usize| {
                let field = fields[j];
                number(field).map_err(|e| e.at(name, line, &column(j), field))
            };
            let t = next(0)?.ok_or_else(|| {
                RecordingError::at(name, line, "t_s is empty: time is never missing")
            })?;
            rules.time(name, line, t)?;
            let mut v = Vec::with_capacity(n);
            for k in 0..n {
                let x = next(1 + k)?.ok_or_else(|| {
                    RecordingError::at(
                        name,
                        line,
                        format!("{} is empty: voltages are never missing", column(1 + k)),
                    )
                })?;
                voltage(name, line, k, x)?;
                v.push(x);
            }
            for (j, (_, values)) in rec.channels.iter_mut().enumerate() {
                values.push(next(1 + n + j)?);
            }
            rec.t_s.push(t);
            rec.v_v.push(v);
        }
        if rec.t_s.is_empty() {
            return Err(RecordingError::at(
                name,
                header_line,
                "no data rows after the header",
            ));
        }
        Ok(rec)
    }
}

/// The lines of `text`, numbered from 1, without their `\r\n` or `\n`.
/// One final line end is allowed; anything blank before it is not.
pub(super) fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let body = text.strip_suffix('\n').unwrap_or(text);
    body.split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .enumerate()
        .map(|(i, l)| (i + 1, l))
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

/// Voltage `x` of segment `k` (0-based) must lie within the safe range.
pub(super) fn voltage(file: &str, line: usize, k: usize, x: f64) -> Result<(), RecordingError> {
    if x.abs() > SAFE_VOLTAGE_LIMIT_V {
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

/// A field: empty is `None`; anything else must be a finite number.
/// Parsing allocates nothing.
fn number(field: &str) -> Result<Option<f64>, BadNumber> {
    if field.is_empty() {
        return Ok(None);
    }
    if let Some(x) = short_decimal(field.as_bytes()) {
        return Ok(Some(x));
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

/// The value of a plain decimal of at most 15 digits (`-12.345`, `0.0192`,
/// `3`), or `None` for anything else (left to `str::parse`). Such a field is
/// what a DAQ writes, and its value is one correctly rounded division of two
/// numbers exact in `f64` (Clinger's fast path), so it equals what
/// `str::parse` gives, at a fraction of the cost.
fn short_decimal(field: &[u8]) -> Option<f64> {
    let (negative, digits) = match field.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, field),
    };
    let mut mantissa = 0u64;
    let mut count = 0usize;
    let mut dot = None;
    for (i, &b) in digits.iter().enumerate() {
        match b {
            b'0'..=b'9' => {
                mantissa = mantissa * 10 + u64::from(b - b'0');
                count += 1;
                if count > 15 {
                    return None;
                }
            }
            b'.' if dot.is_none() && i > 0 => dot = Some(i),
            _ => return None,
        }
    }
    let decimals = match dot {
        Some(i) if i + 1 == digits.len() => return None,
        Some(i) => digits.len() - i - 1,
        None if count == 0 => return None,
        None => 0,
    };
    let x = mantissa as f64 / POW10[decimals];
    Some(if negative { -x } else { x })
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
