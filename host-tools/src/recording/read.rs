//! Parsing a recording from text, rule by rule.

use std::path::Path;

use super::error::RecordingError;
use super::meta::{Fixture, MetaBuilder};
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
        // One final line end is allowed; anything blank before it is not.
        let body = text.strip_suffix('\n').unwrap_or(text);
        let mut lines = body
            .split('\n')
            .map(|l| l.strip_suffix('\r').unwrap_or(l))
            .enumerate()
            .map(|(i, l)| (i + 1, l));

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

        let mut rec = Recording {
            meta,
            t_s: Vec::new(),
            v_v: Vec::new(),
            channels: columns.iter().map(|&c| (c, Vec::new())).collect(),
        };
        let n = rec.meta.segments;
        let width = 1 + n + columns.len();
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
            let fields: Vec<&str> = text.split(',').collect();
            if fields.len() != width {
                return Err(RecordingError::at(
                    name,
                    line,
                    format!("row has {} fields, the header has {width}", fields.len()),
                ));
            }
            let t = number(name, line, "t_s", fields[0])?.ok_or_else(|| {
                RecordingError::at(name, line, "t_s is empty: time is never missing")
            })?;
            if t < 0.0 {
                return Err(RecordingError::at(
                    name,
                    line,
                    format!("time must start at or after 0, got {t}"),
                ));
            }
            if let Some(&prev) = rec.t_s.last() {
                if t <= prev {
                    return Err(RecordingError::at(
                        name,
                        line,
                        format!("time must be strictly increasing ({t} after {prev})"),
                    ));
                }
            }
            let mut v = Vec::with_capacity(n);
            for k in 0..n {
                let col = format!("v{}_V", k + 1);
                let x = number(name, line, &col, fields[1 + k])?.ok_or_else(|| {
                    RecordingError::at(
                        name,
                        line,
                        format!("{col} is empty: voltages are never missing"),
                    )
                })?;
                if x.abs() > SAFE_VOLTAGE_LIMIT_V {
                    return Err(RecordingError::at(
                        name,
                        line,
                        format!(
                            "{col} = {x} V is beyond the safe range of ±{SAFE_VOLTAGE_LIMIT_V} V"
                        ),
                    ));
                }
                v.push(x);
            }
            for (j, (ch, values)) in rec.channels.iter_mut().enumerate() {
                values.push(number(name, line, &ch.name(), fields[1 + n + j])?);
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

/// A field: empty is `None`; anything else must be a finite number.
fn number(
    file: &str,
    line: usize,
    column: &str,
    field: &str,
) -> Result<Option<f64>, RecordingError> {
    if field.is_empty() {
        return Ok(None);
    }
    match field.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(Some(x)),
        Ok(_) => Err(RecordingError::at(
            file,
            line,
            format!("{column} = `{field}`: NaN and infinity are not measurements"),
        )),
        Err(_) => Err(RecordingError::at(
            file,
            line,
            format!("{column} = `{field}` is not a number"),
        )),
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
