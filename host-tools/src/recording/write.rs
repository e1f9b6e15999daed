//! Writing a recording, after checking it against the same rules.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::error::RecordingError;
use super::float::{Formatter, WIDEST};
use super::meta::Metadata;
use super::output::Output;
use super::read::{column_name, lines, read_head, voltage, BadNumber, RowRules};
use super::rest::{check_range, READING_LIMIT_V};
use super::{Channel, Recording, Voltages};

/// Bytes of text gathered before each write to the file: the output never
/// lies in memory whole (a 20 000-row prediction is 1.6 MB of text).
const CHUNK_BYTES: usize = 64 << 10;

/// Rows formatted together: each column's numbers first, in a loop of
/// their own (no choice of column or format per number, nothing waiting
/// on where the number before it ended), then the rows put together.
const BLOCK_ROWS: usize = 64;

/// Marks a number not written, with no separator before it: the voltages
/// of a row beyond the drive's rows ([`Recording::to_csv_string`] writes
/// what it holds).
const ABSENT: u8 = u8::MAX;

/// A block's numbers as text: column `j`'s number on the block's row `i`
/// is `text[j * BLOCK_ROWS + i][..len[j * BLOCK_ROWS + i]]` (empty for an
/// empty field).
struct Block {
    text: Vec<[u8; WIDEST]>,
    len: Vec<u8>,
}

impl Block {
    fn new(columns: usize) -> Block {
        Block {
            text: vec![[0; WIDEST]; columns * BLOCK_ROWS],
            len: vec![0; columns * BLOCK_ROWS],
        }
    }

    /// Writes column `j` from `values` (one a row, `None` for an empty
    /// field) by `format`.
    #[inline]
    fn fill(
        &mut self,
        j: usize,
        values: impl Iterator<Item = Option<f64>>,
        mut format: impl FnMut(&mut [u8; WIDEST], f64) -> usize,
    ) {
        let at = j * BLOCK_ROWS;
        let text = &mut self.text[at..at + BLOCK_ROWS];
        let len = &mut self.len[at..at + BLOCK_ROWS];
        for ((dst, n), x) in text.iter_mut().zip(len.iter_mut()).zip(values) {
            // At most WIDEST bytes: fits in a u8.
            *n = x.map_or(0, |x| format(dst, x) as u8);
        }
    }
}

/// Rows as text, formatted a block at a time and handed out in chunks of
/// about [`CHUNK_BYTES`], whole rows each: the text is never whole in
/// memory.
struct Text {
    buf: Vec<u8>,
    /// Bytes of `buf` not yet handed out.
    at: usize,
    f: Formatter,
    block: Block,
    segments: usize,
}

impl Text {
    /// Rows of `segments` voltages and `channels` measured columns, after
    /// `head`.
    fn new(head: &str, segments: usize, channels: usize) -> Text {
        let columns = 1 + segments + channels;
        // Room for a chunk and a block beyond it: each number is copied
        // as its whole slot of WIDEST bytes, then its end kept.
        let mut buf = vec![0; head.len().max(CHUNK_BYTES) + BLOCK_ROWS * columns * (WIDEST + 1)];
        buf[..head.len()].copy_from_slice(head.as_bytes());
        Text {
            buf,
            at: head.len(),
            f: Formatter::default(),
            block: Block::new(columns),
            segments,
        }
    }

    /// Formats the rows of times `t_s`, their voltages `drive` (row after
    /// row; rows past its end have none) and `channels` (each from the
    /// same first row; empty fields past a column's end), handing each
    /// full chunk to `sink`.
    fn rows(
        &mut self,
        t_s: &[f64],
        drive: &[f64],
        channels: &[Column],
        sink: &mut impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let n = self.segments;
        let columns = 1 + n + channels.len();
        let (block, f, buf) = (&mut self.block, &mut self.f, &mut self.buf);
        let rows = t_s.len();
        let drive_rows = drive.len() / n;
        for start in (0..rows).step_by(BLOCK_ROWS) {
            let end = rows.min(start + BLOCK_ROWS);
            let t = t_s[start..end].iter().map(|&t| Some(t));
            block.fill(0, t, |dst, x| f.exact(dst, x));
            let driven = end.min(drive_rows.max(start));
            for k in 0..n {
                let v = drive[(start * n + k).min(drive.len())..].iter().step_by(n);
                let v = v.take(driven - start).map(|&v| Some(v));
                block.fill(1 + k, v, |dst, x| f.exact(dst, x));
                let beyond = &mut block.len[(1 + k) * BLOCK_ROWS..][driven - start..end - start];
                beyond.fill(ABSENT);
            }
            for (j, values) in channels.iter().enumerate() {
                let format = |dst: &mut [u8; WIDEST], x| f.measured(dst, x);
                // Past a column's end (unchecked text): empty fields.
                let past = std::iter::repeat(None);
                match values {
                    Column::Every(v) => {
                        let v = v[start.min(v.len())..end.min(v.len())].iter();
                        block.fill(1 + n + j, v.map(|&x| Some(x)).chain(past), format)
                    }
                    Column::Sampled(v) => {
                        let v = v[start.min(v.len())..end.min(v.len())].iter();
                        block.fill(1 + n + j, v.copied().chain(past), format)
                    }
                }
            }
            let mut at = self.at;
            for i in 0..end - start {
                for j in 0..columns {
                    let slot = j * BLOCK_ROWS + i;
                    let len = block.len[slot];
                    if len == ABSENT {
                        continue;
                    }
                    buf[at..at + WIDEST].copy_from_slice(&block.text[slot]);
                    at += usize::from(len);
                    buf[at] = b',';
                    at += 1;
                }
                // Time is never absent: the row's last separator ends it.
                buf[at - 1] = b'\n';
            }
            self.at = at;
            if at >= CHUNK_BYTES {
                sink(&buf[..at])?;
                self.at = 0;
            }
        }
        Ok(())
    }

    /// Hands out the rest.
    fn end(&mut self, sink: &mut impl FnMut(&[u8]) -> std::io::Result<()>) -> std::io::Result<()> {
        sink(&self.buf[..self.at])?;
        self.at = 0;
        Ok(())
    }
}

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

/// A checked recording's head, for messages about its rows.
struct Head {
    header_line: usize,
    segments: usize,
    columns: Vec<Channel>,
}

impl Head {
    /// `x` on data row `row` (from 0), column `j`, is not finite: as the
    /// reader would say it.
    fn not_finite(&self, name: &str, row: usize, j: usize, x: f64) -> RecordingError {
        BadNumber::NotFinite.at(
            name,
            self.header_line + 1 + row,
            &column_name(self.segments, &self.columns, j),
            &x.to_string(),
        )
    }
}

/// The first NaN or infinity among the first `rows` rows of `columns`,
/// by row, then by column: its row, column (of `columns`) and value.
fn first_not_finite(columns: &[Column], rows: usize) -> Option<(usize, usize, f64)> {
    let mut bad: Option<(usize, usize, f64)> = None;
    for (j, values) in columns.iter().enumerate() {
        let rows = bad.map_or(rows.min(values.len()), |(row, _, _)| row);
        if let Some((row, x)) = values.first_not_finite(rows) {
            bad = Some((row, j, x));
        }
    }
    bad
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
        let columns: Vec<Column> = self.channels.iter().map(|(_, c)| *c).collect();
        let mut text = Text::new(&self.head_text(), self.v_v.segments(), columns.len());
        text.rows(self.t_s, self.v_v.as_flat(), &columns, &mut sink)?;
        text.end(&mut sink)
    }

    /// As [`Recording::validate`].
    pub fn validate(&self, name: &str) -> Result<(), RecordingError> {
        let rows = self.t_s.len();
        self.check_lengths(name)?;
        for (ch, values) in &self.channels {
            if values.len() != rows {
                return Err(RecordingError::file(
                    name,
                    format!("{} has {} values for {rows} rows", ch.name(), values.len()),
                ));
            }
        }
        let head = self.check_head(name)?;
        // Measured channels column by column, a tight loop each; the first
        // NaN or infinity by row, then by column, is where the reader would
        // stop, unless time or voltages break a rule on that row or before.
        let columns: Vec<Column> = self.channels.iter().map(|(_, c)| *c).collect();
        let bad_channel = first_not_finite(&columns, rows);
        self.check_drive(name, &head, bad_channel.map_or(rows, |(row, _, _)| row + 1))?;
        match bad_channel {
            Some((row, j, x)) => Err(head.not_finite(name, row, 1 + self.meta.segments + j, x)),
            // As the reader, once every row is read.
            None => check_range(name, head.header_line, self.t_s, self.v_v),
        }
    }

    /// Time and drive of the lengths the metadata says.
    fn check_lengths(&self, name: &str) -> Result<(), RecordingError> {
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
        let rows = self.t_s.len();
        if self.v_v.len() != rows {
            return Err(RecordingError::file(
                name,
                format!("{} voltage rows for {rows} times", self.v_v.len()),
            ));
        }
        Ok(())
    }

    /// The metadata and header read back as written, and rows after them.
    fn check_head(&self, name: &str) -> Result<Head, RecordingError> {
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
        if self.t_s.is_empty() {
            return Err(RecordingError::at(
                name,
                header_line,
                "no data rows after the header",
            ));
        }
        Ok(Head {
            header_line,
            segments: self.meta.segments,
            columns,
        })
    }

    /// The rules of time and drive on the rows before `until`.
    fn check_drive(&self, name: &str, head: &Head, until: usize) -> Result<(), RecordingError> {
        // Time and drive in a tight pass each first: times finite, from 0
        // and increasing, voltages within any reading of the safe range
        // (NaN and infinity are not; nearer it, `check_range` judges). Only
        // if that fails are the rows checked one by one, for the first rule
        // broken and its message.
        let increasing = self.t_s.first().is_some_and(|&t| t >= 0.0)
            && self.t_s.windows(2).all(|w| w[1] > w[0])
            && self.t_s.iter().all(|t| t.is_finite());
        let in_range = self
            .v_v
            .as_flat()
            .iter()
            .all(|v| v.abs() <= READING_LIMIT_V);
        if increasing && in_range {
            return Ok(());
        }
        let mut rules = RowRules::default();
        for (row, (&t, v)) in self.t_s.iter().zip(self.v_v.rows()).enumerate().take(until) {
            let line = head.header_line + 1 + row;
            if !t.is_finite() {
                return Err(head.not_finite(name, row, 0, t));
            }
            rules.time(name, line, t)?;
            for (k, &x) in v.iter().enumerate() {
                if !x.is_finite() {
                    return Err(head.not_finite(name, row, 1 + k, x));
                }
                voltage(name, line, k, x)?;
            }
        }
        Ok(())
    }

    /// Checks, then writes to `path` as the text is formatted: into a new
    /// file that takes the place of any old one once complete (see
    /// `output.rs`), so a failed write leaves the old file as it was.
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        let name = path.display().to_string();
        self.validate(&name)?;
        let cannot = |e: std::io::Error| cannot_write(&name, e);
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

/// A recording written as its measured channels are computed, some rows
/// at a time (a model's prediction): they are never whole in memory. The
/// same text and the same checks as [`RecordingView::write`], but time
/// and drive checked whole first, before any channel is given (should
/// both a channel and the drive break a rule, the drive's is the one
/// told). A refusal or failure, or a write dropped before
/// [`Streamed::finish`], leaves the file as it was.
pub struct Streamed<'a> {
    name: String,
    t_s: &'a [f64],
    drive: &'a [f64],
    head: Head,
    text: Text,
    /// `None` once given up.
    output: Option<Output>,
    /// Rows written so far.
    written: usize,
}

impl<'a> Streamed<'a> {
    /// Checks the metadata, header, time and drive of a recording with
    /// measured `channels` to come, and opens `path`.
    pub fn create(
        path: &Path,
        meta: &Metadata,
        t_s: &'a [f64],
        v_v: &'a Voltages,
        channels: &[Channel],
    ) -> Result<Streamed<'a>, RecordingError> {
        let name = path.display().to_string();
        let view = RecordingView {
            meta,
            t_s,
            v_v,
            // Their names only: the values come later.
            channels: channels.iter().map(|&c| (c, Column::Every(&[]))).collect(),
        };
        view.check_lengths(&name)?;
        let head = view.check_head(&name)?;
        view.check_drive(&name, &head, t_s.len())?;
        check_range(&name, head.header_line, t_s, v_v)?;
        let output = Output::create(path).map_err(|e| cannot_write(&name, e))?;
        Ok(Streamed {
            text: Text::new(&view.head_text(), v_v.segments(), channels.len()),
            name,
            t_s,
            drive: v_v.as_flat(),
            head,
            output: Some(output),
            written: 0,
        })
    }

    /// Writes the next rows: `channels` holds each channel's values on
    /// them (as many for each, in the order given to [`Streamed::create`]).
    pub fn rows(&mut self, channels: &[&[f64]]) -> Result<(), RecordingError> {
        let result = self.try_rows(channels);
        if result.is_err() {
            self.give_up();
        }
        result
    }

    fn try_rows(&mut self, channels: &[&[f64]]) -> Result<(), RecordingError> {
        let first = self.written;
        let rows = channels.first().map_or(0, |c| c.len());
        let n = self.head.segments;
        if channels.len() != self.head.columns.len()
            || channels.iter().any(|c| c.len() != rows)
            || first + rows > self.t_s.len()
        {
            return Err(RecordingError::file(
                &self.name,
                format!(
                    "{} channels of {rows} rows from row {first} do not fit {} channels of {} rows",
                    channels.len(),
                    self.head.columns.len(),
                    self.t_s.len()
                ),
            ));
        }
        let columns: Vec<Column> = channels.iter().map(|c| Column::Every(c)).collect();
        if let Some((row, j, x)) = first_not_finite(&columns, rows) {
            return Err(self.head.not_finite(&self.name, first + row, 1 + n + j, x));
        }
        let output = self.output.as_ref().ok_or_else(|| {
            RecordingError::file(&self.name, "cannot write: an earlier write failed")
        })?;
        let t_s = &self.t_s[first..first + rows];
        let drive = &self.drive[first * n..(first + rows) * n];
        self.text
            .rows(t_s, drive, &columns, &mut |chunk| {
                (&output.file).write_all(chunk)
            })
            .map_err(|e| cannot_write(&self.name, e))?;
        self.written += rows;
        Ok(())
    }

    /// Writes what is left and puts the file in its place: every row must
    /// have been given.
    pub fn finish(mut self) -> Result<(), RecordingError> {
        let Some(output) = self.output.take() else {
            return Err(RecordingError::file(
                &self.name,
                "cannot write: an earlier write failed",
            ));
        };
        if self.written != self.t_s.len() {
            output.abandon();
            return Err(RecordingError::file(
                &self.name,
                format!("{} of {} rows given", self.written, self.t_s.len()),
            ));
        }
        match self.text.end(&mut |chunk| (&output.file).write_all(chunk)) {
            Ok(()) => output.finish(),
            Err(e) => {
                output.abandon();
                Err(e)
            }
        }
        .map_err(|e| cannot_write(&self.name, e))
    }

    fn give_up(&mut self) {
        if let Some(output) = self.output.take() {
            output.abandon();
        }
    }
}

impl Drop for Streamed<'_> {
    fn drop(&mut self) {
        self.give_up();
    }
}

/// A write that failed, told.
fn cannot_write(name: &str, e: std::io::Error) -> RecordingError {
    RecordingError::file(name, format!("cannot write: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Fixture, Geometry, Medium};

    /// The text row by row, a number at a time: what the block writer
    /// must give.
    fn row_by_row(view: &RecordingView) -> String {
        let mut out = view.head_text().into_bytes();
        let mut f = Formatter::default();
        let mut number = |out: &mut Vec<u8>, x: f64, exact: bool| {
            let mut dst = [0; WIDEST];
            let n = if exact {
                f.exact(&mut dst, x)
            } else {
                f.measured(&mut dst, x)
            };
            out.extend_from_slice(&dst[..n]);
        };
        for (row, &t) in view.t_s.iter().enumerate() {
            number(&mut out, t, true);
            for &v in view.v_v.row(row).into_iter().flatten() {
                out.push(b',');
                number(&mut out, v, true);
            }
            for (_, values) in &view.channels {
                out.push(b',');
                let x = match values {
                    Column::Sampled(v) => v.get(row).copied().flatten(),
                    Column::Every(v) => v.get(row).copied(),
                };
                if let Some(x) = x {
                    number(&mut out, x, false);
                }
            }
            out.push(b'\n');
        }
        String::from_utf8(out).unwrap()
    }

    fn meta() -> Metadata {
        Metadata::new(2, Geometry::THESIS_2006, Fixture::Free, Medium::Air)
    }

    #[test]
    fn streamed_rows_write_and_refuse_what_a_whole_recording_would() {
        let dir = std::env::temp_dir().join(format!("finrs-streamed-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.csv");
        let meta = meta();
        let rows = 1000;
        let t_s: Vec<f64> = (0..rows).map(|k| k as f64 * 1e-3).collect();
        let v_v = Voltages::from_rows(2, (0..rows).map(|k| [k as f64 * 1e-3, -1.5]));
        let i: Vec<f64> = (0..rows).map(|k| k as f64 * 1e-7).collect();
        let mut tip = i.clone();
        let channels = [Channel::Current(0), Channel::TipY];
        let whole = |tip: &[f64]| {
            let view = RecordingView {
                meta: &meta,
                t_s: &t_s,
                v_v: &v_v,
                channels: vec![
                    (channels[0], Column::Every(&i)),
                    (channels[1], Column::Every(tip)),
                ],
            };
            (
                view.validate(&path.display().to_string()),
                view.to_csv_string(),
            )
        };
        let stream = |tip: &[f64], blocks: &[usize]| {
            let mut out = Streamed::create(&path, &meta, &t_s, &v_v, &channels)?;
            let mut at = 0;
            for &n in blocks {
                out.rows(&[&i[at..at + n], &tip[at..at + n]])?;
                at += n;
            }
            out.finish()
        };
        // Written in uneven blocks: the whole recording's text.
        stream(&tip, &[1, 63, 64, 500, 372]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), whole(&tip).1);
        let before = std::fs::read(&path).unwrap();
        let only_it = || {
            let files: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
            assert_eq!(files.len(), 1, "{files:?}");
            assert_eq!(std::fs::read(&path).unwrap(), before);
        };
        // A NaN in a later block: the whole recording's refusal, and the
        // old file as it was.
        tip[700] = f64::NAN;
        let err = stream(&tip, &[500, 500]).unwrap_err();
        assert_eq!(err.to_string(), whole(&tip).0.unwrap_err().to_string());
        assert!(err.to_string().contains("tip_y_m"), "{err}");
        only_it();
        tip[700] = 0.0;
        // Rows missing at the end, too many, or of unequal lengths.
        assert!(stream(&tip, &[999]).is_err());
        only_it();
        let long = vec![0.0; rows + 1];
        for (a, b) in [(&long[..], &long[..]), (&i[..10], &tip[..9])] {
            let mut out = Streamed::create(&path, &meta, &t_s, &v_v, &channels).unwrap();
            assert!(out.rows(&[a, b]).is_err());
            assert!(out.finish().is_err());
            only_it();
        }
        // Dropped unfinished: nothing written.
        let mut out = Streamed::create(&path, &meta, &t_s, &v_v, &channels).unwrap();
        out.rows(&[&i[..10], &tip[..10]]).unwrap();
        drop(out);
        only_it();
        // The drive is checked before any channel is given.
        let bad = Voltages::from_rows(2, (0..rows).map(|k| [k as f64 * 1e-3, -15.0]));
        let Err(err) = Streamed::create(&path, &meta, &t_s, &bad, &channels) else {
            panic!("a drive out of range is written");
        };
        assert!(err.to_string().contains("safe range"), "{err}");
        only_it();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn blocks_write_what_rows_would_even_of_unchecked_parts() {
        let meta = meta();
        // Rows across several blocks and a partial last one; numbers of
        // every shape: the fast paths, ryu's, not finite, empty fields.
        let rows = 3 * BLOCK_ROWS + 17;
        let t_s: Vec<f64> = (0..rows).map(|k| k as f64 * 1e-3).collect();
        let wide = |k: usize| match k % 7 {
            0 => 1.0 / 3.0,
            1 => -2.4869,
            2 => 1e-300,
            3 => -123_456.789,
            4 => f64::NAN,
            5 => f64::NEG_INFINITY,
            _ => k as f64 * -1.25e-5,
        };
        let every: Vec<f64> = (0..rows).map(wide).collect();
        let sampled: Vec<Option<f64>> = (0..rows).map(|k| (k % 3 == 0).then(|| wide(k))).collect();
        for (drive_rows, every_rows, sampled_rows) in [
            (rows, rows, rows),
            (BLOCK_ROWS + 5, rows - 40, 2 * BLOCK_ROWS),
            (0, 0, 1),
        ] {
            let v_v = Voltages::from_rows(2, (0..drive_rows).map(|k| [wide(k + 1), wide(k + 3)]));
            let view = RecordingView {
                meta: &meta,
                t_s: &t_s,
                v_v: &v_v,
                channels: vec![
                    (Channel::Current(0), Column::Every(&every[..every_rows])),
                    (Channel::TipY, Column::Sampled(&sampled[..sampled_rows])),
                ],
            };
            assert_eq!(
                view.to_csv_string(),
                row_by_row(&view),
                "{drive_rows} drive rows"
            );
        }
    }
}
