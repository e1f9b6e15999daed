//! Writing a recording, after checking it against the same rules.

use std::fmt::Write as _;
use std::path::Path;

use super::error::RecordingError;
use super::float::Formatter;
use super::read::{column_name, lines, read_head, voltage, BadNumber, RowRules};
use super::Recording;

impl Recording {
    /// The recording as `ipmc-bench/1` text, unchecked (see
    /// [`Recording::validate`]; [`Recording::write`] checks first). Time
    /// and voltages are written exactly, measured channels to
    /// [`MEASURED_DECIMALS`](super::MEASURED_DECIMALS) decimals; `None` is
    /// an empty field. Rows or channels of the wrong length are written as
    /// they are, and NaN or infinity as `NaN`, `inf`, `-inf`: the reader
    /// refuses all of them.
    pub fn to_csv_string(&self) -> String {
        String::from_utf8(self.to_csv_bytes()).expect("the writer writes ASCII and UTF-8 metadata")
    }

    /// The metadata lines and the header line.
    fn head_text(&self) -> String {
        let mut out = self.meta.to_lines();
        out.push_str("t_s");
        for k in 0..self.meta.segments {
            let _ = write!(out, ",v{}_V", k + 1);
        }
        for (ch, _) in &self.channels {
            let _ = write!(out, ",{}", ch.name());
        }
        out.push('\n');
        out
    }

    /// [`Recording::to_csv_string`] as bytes, formatted in one pass into
    /// one buffer.
    fn to_csv_bytes(&self) -> Vec<u8> {
        let head = self.head_text();
        let width = 1 + self.meta.segments + self.channels.len();
        let mut out = Vec::with_capacity(head.len() + self.t_s.len() * width * 20);
        out.extend_from_slice(head.as_bytes());
        let mut f = Formatter::default();
        for (row, &t) in self.t_s.iter().enumerate() {
            finite(&mut out, t, |out, x| f.exact(out, x));
            for &v in self.v_v.row(row).into_iter().flatten() {
                out.push(b',');
                finite(&mut out, v, |out, x| f.exact(out, x));
            }
            for (_, values) in &self.channels {
                out.push(b',');
                if let Some(&Some(x)) = values.get(row) {
                    finite(&mut out, x, |out, x| f.measured(out, x));
                }
            }
            out.push(b'\n');
        }
        out
    }

    /// Checks the recording against every rule, as if read from a file
    /// called `name`: line numbers refer to the text it would be written as.
    /// The metadata and header are checked by reading their text back; the
    /// rows by the reader's own rules, on the numbers themselves.
    pub fn validate(&self, name: &str) -> Result<(), RecordingError> {
        let rows = self.t_s.len();
        if self.v_v.segments() != self.meta.segments {
            return Err(RecordingError::file(
                name,
                format!(
                    "{} voltages per row for segments = {}",
                    self.v_v.segments(),
                    self.meta.segments
                ),
            ));
        }
        if self.v_v.len() != rows {
            return Err(RecordingError::file(
                name,
                format!("{} voltage rows for {rows} times", self.v_v.len()),
            ));
        }
        for (ch, values) in &self.channels {
            if values.len() != rows {
                return Err(RecordingError::file(
                    name,
                    format!("{} has {} values for {rows} rows", ch.name(), values.len()),
                ));
            }
        }
        let head = self.head_text();
        let (meta, header_line, columns) = read_head(name, &mut lines(&head))?;
        // Metadata is written to read back exactly; a difference would
        // mean the writer lost something.
        if meta != self.meta {
            return Err(RecordingError::file(
                name,
                "metadata does not read back as written",
            ));
        }
        if rows == 0 {
            return Err(RecordingError::at(
                name,
                header_line,
                "no data rows after the header",
            ));
        }
        let n = self.meta.segments;
        let not_finite = |row: usize, j: usize, x: f64| {
            BadNumber::NotFinite.at(
                name,
                header_line + 1 + row,
                &column_name(n, &columns, j),
                &x.to_string(),
            )
        };
        // Measured channels column by column, a tight loop each; the first
        // NaN or infinity by row, then by column, is where the reader would
        // stop, unless time or voltages break a rule on that row or before.
        let mut bad_channel: Option<(usize, usize, f64)> = None;
        for (j, (_, values)) in self.channels.iter().enumerate() {
            let rows = bad_channel.map_or(rows, |(row, _, _)| row);
            if let Some(row) = values[..rows]
                .iter()
                .position(|x| x.is_some_and(|x| !x.is_finite()))
            {
                let x = values[row].unwrap_or_default();
                bad_channel = Some((row, 1 + n + j, x));
            }
        }
        let checked_rows = bad_channel.map_or(rows, |(row, _, _)| row + 1);
        let mut rules = RowRules::default();
        for (row, (&t, v)) in self.t_s.iter().zip(self.v_v.rows()).enumerate() {
            if row == checked_rows {
                break;
            }
            let line = header_line + 1 + row;
            if !t.is_finite() {
                return Err(not_finite(row, 0, t));
            }
            rules.time(name, line, t)?;
            for (k, &x) in v.iter().enumerate() {
                if !x.is_finite() {
                    return Err(not_finite(row, 1 + k, x));
                }
                voltage(name, line, k, x)?;
            }
        }
        match bad_channel {
            Some((row, j, x)) => Err(not_finite(row, j, x)),
            None => Ok(()),
        }
    }

    /// Checks and writes the recording to `path`.
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        let name = path.display().to_string();
        self.validate(&name)?;
        std::fs::write(path, self.to_csv_bytes())
            .map_err(|e| RecordingError::file(&name, format!("cannot write: {e}")))
    }
}

/// Writes `x` with `format` if finite, else as `NaN`, `inf` or `-inf`
/// (which the reader refuses: only unchecked text can hold them).
fn finite(out: &mut Vec<u8>, x: f64, mut format: impl FnMut(&mut Vec<u8>, f64)) {
    if x.is_finite() {
        format(out, x);
    } else {
        let _ = std::io::Write::write_fmt(out, format_args!("{x}"));
    }
}
