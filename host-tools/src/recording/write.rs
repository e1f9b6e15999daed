//! Writing a recording, after checking it against the same rules.

use std::fmt::Write as _;
use std::path::Path;

use super::error::RecordingError;
use super::Recording;

impl Recording {
    /// The recording as `ipmc-bench/1` text. Numbers are written so that
    /// they read back exactly; `None` is an empty field. Rows or channels of
    /// the wrong length are written as they are (and refused by
    /// [`Recording::validate`]).
    pub fn to_csv_string(&self) -> String {
        let mut out = self.meta.to_lines();
        out.push_str("t_s");
        for k in 0..self.meta.segments {
            let _ = write!(out, ",v{}_V", k + 1);
        }
        for (ch, _) in &self.channels {
            let _ = write!(out, ",{}", ch.name());
        }
        out.push('\n');
        for (row, t) in self.t_s.iter().enumerate() {
            let _ = write!(out, "{t}");
            for v in self.v_v.get(row).into_iter().flatten() {
                let _ = write!(out, ",{v}");
            }
            for (_, values) in &self.channels {
                out.push(',');
                if let Some(Some(x)) = values.get(row) {
                    let _ = write!(out, "{x}");
                }
            }
            out.push('\n');
        }
        out
    }

    /// Checks the recording against every rule, as if read from a file
    /// called `name`: line numbers refer to the text it would be written as.
    pub fn validate(&self, name: &str) -> Result<(), RecordingError> {
        let rows = self.t_s.len();
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
        let back = Recording::parse(name, &self.to_csv_string())?;
        // Everything that is written is read back as it was; a difference
        // would mean the writer lost something.
        if back != *self {
            return Err(RecordingError::file(name, "does not read back as written"));
        }
        Ok(())
    }

    /// Checks and writes the recording to `path`.
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        let name = path.display().to_string();
        self.validate(&name)?;
        std::fs::write(path, self.to_csv_string())
            .map_err(|e| RecordingError::file(&name, format!("cannot write: {e}")))
    }
}
