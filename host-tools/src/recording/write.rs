//! Writing a recording, after checking it against the same rules.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::error::RecordingError;
use super::float::{window, Formatter, WIDEST};
use super::meta::Metadata;
use super::output::Output;
use super::read::{column_name, lines, read_head, voltage, BadNumber, RowRules};
use super::{Channel, Recording, Voltages, SAFE_VOLTAGE_LIMIT_V};

/// Bytes of text gathered before each write to the file: the output never
/// lies in memory whole (a 20 000-row prediction is 1.6 MB of text).
const CHUNK_BYTES: usize = 64 << 10;

/// A measured column as a [`RecordingView`] borrows it.
#[derive(Clone, Copy, Debug)]
pub enum Column<'a> {
    /// `None` where not sampled, as [`Recording::channels`] holds it.
    Sampled(&'a [Option<f64>]),
    /// A value on every row (a model's prediction).
    Every(&'a [f64]),
}

impl Column<'_> {
    /// Values held.
    fn len(&self) -> usize {
        match self {
            Column::Sampled(v) => v.len(),
            Column::Every(v) => v.len(),
        }
    }

    /// The value on `row`, `None` if not sampled or past the end.
    #[inline]
    fn get(&self, row: usize) -> Option<f64> {
        match self {
            Column::Sampled(v) => v.get(row).copied().flatten(),
            Column::Every(v) => v.get(row).copied(),
        }
    }

    /// The first of the first `rows` rows holding NaN or infinity, and it.
    fn first_not_finite(&self, rows: usize) -> Option<(usize, f64)> {
        match self {
            Column::Sampled(v) => v[..rows]
                .iter()
                .position(|x| x.is_some_and(|x| !x.is_finite()))
                .map(|row| (row, v[row].unwrap_or_default())),
            Column::Every(v) => v[..rows]
                .iter()
                .position(|x| !x.is_finite())
                .map(|row| (row, v[row])),
        }
    }
}

/// A recording to check and write whose parts are borrowed, so that a
/// prediction is written from the input's time and drive and the model's
/// traces without copying them into a [`Recording`] first.
#[derive(Clone, Debug)]
pub struct RecordingView<'a> {
    /// The `# key = value` lines.
    pub meta: &'a Metadata,
    /// Time of every row, s.
    pub t_s: &'a [f64],
    /// Voltage per row and segment, V.
    pub v_v: &'a Voltages,
    /// Measured channels in header order.
    pub channels: Vec<(Channel, Column<'a>)>,
}

impl Recording {
    /// The recording as `ipmc-bench/1` text, unchecked (see
    /// [`Recording::validate`]; [`Recording::write`] checks first). Time
    /// and voltages are written exactly, measured channels to
    /// [`MEASURED_DECIMALS`](super::MEASURED_DECIMALS) decimals; `None` is
    /// an empty field. Rows or channels of the wrong length are written as
    /// they are, and NaN or infinity as `NaN`, `inf`, `-inf`: the reader
    /// refuses all of them.
    pub fn to_csv_string(&self) -> String {
        self.view().to_csv_string()
    }

    /// The recording's parts, borrowed.
    pub fn view(&self) -> RecordingView<'_> {
        RecordingView {
            meta: &self.meta,
            t_s: &self.t_s,
            v_v: &self.v_v,
            channels: self
                .channels
                .iter()
                .map(|(c, v)| (*c, Column::Sampled(v)))
                .collect(),
        }
    }

    /// Checks the recording against every rule, as if read from a file
    /// called `name`: line numbers refer to the text it would be written as.
    /// The metadata and header are checked by reading their text back; the
    /// rows by the reader's own rules, on the numbers themselves.
    pub fn validate(&self, name: &str) -> Result<(), RecordingError> {
        self.view().validate(name)
    }

    /// Checks and writes the recording to `path`.
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        self.view().write(path)
    }
}

impl RecordingView<'_> {
    /// As [`Recording::to_csv_string`].
    pub fn to_csv_string(&self) -> String {
        let mut out = Vec::new();
        // Writing into memory cannot fail.
        let _ = self.write_text(|chunk| {
            out.extend_from_slice(chunk);
            Ok(())
        });
        String::from_utf8(out).expect("the writer writes ASCII and UTF-8 metadata")
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

    /// The text, formatted in one pass and handed to `sink` in chunks of
    /// about [`CHUNK_BYTES`], whole rows each.
    fn write_text(
        &self,
        mut sink: impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let head = self.head_text();
        // Each number is written into a window of the buffer; room for a
        // chunk and a whole row beyond it (the buffer grows if a row needs
        // more).
        let width = 1 + self.v_v.segments() + self.channels.len();
        let mut buf = vec![0; head.len().max(CHUNK_BYTES) + width * (WIDEST + 1)];
        buf[..head.len()].copy_from_slice(head.as_bytes());
        let mut at = head.len();
        let mut f = Formatter::default();
        for (row, &t) in self.t_s.iter().enumerate() {
            at += f.exact(window(&mut buf, at), t);
            for &v in self.v_v.row(row).into_iter().flatten() {
                window(&mut buf, at)[0] = b',';
                at += 1;
                at += f.exact(window(&mut buf, at), v);
            }
            for (_, values) in &self.channels {
                window(&mut buf, at)[0] = b',';
                at += 1;
                if let Some(x) = values.get(row) {
                    at += f.measured(window(&mut buf, at), x);
                }
            }
            window(&mut buf, at)[0] = b'\n';
            at += 1;
            if at >= CHUNK_BYTES {
                sink(&buf[..at])?;
                at = 0;
            }
        }
        sink(&buf[..at])
    }

    /// As [`Recording::validate`].
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
        if meta != *self.meta {
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
            if let Some((row, x)) = values.first_not_finite(rows) {
                bad_channel = Some((row, 1 + n + j, x));
            }
        }
        // Time and drive in a tight pass each first: times finite, from 0
        // and increasing, voltages within the safe range (NaN and infinity
        // are not). Only if that fails are the rows checked one by one, for
        // the first rule broken and its message.
        let increasing = self.t_s.first().is_some_and(|&t| t >= 0.0)
            && self.t_s.windows(2).all(|w| w[1] > w[0])
            && self.t_s.iter().all(|t| t.is_finite());
        let in_range = self
            .v_v
            .as_flat()
            .iter()
            .all(|v| v.abs() <= SAFE_VOLTAGE_LIMIT_V);
        let checked_rows = if increasing && in_range {
            0
        } else {
            bad_channel.map_or(rows, |(row, _, _)| row + 1)
        };
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

    /// Checks, then writes to `path` as the text is formatted: into a new
    /// file that takes the place of any old one once complete (see
    /// `output.rs`), so a failed write leaves the old file as it was.
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        let name = path.display().to_string();
        self.validate(&name)?;
        let cannot = |e: std::io::Error| RecordingError::file(&name, format!("cannot write: {e}"));
        let output = Output::create(path).map_err(cannot)?;
        match self.write_text(|chunk| (&output.file).write_all(chunk)) {
            Ok(()) => output.finish().map_err(cannot),
            Err(e) => {
                output.abandon();
                Err(cannot(e))
            }
        }
    }
}
