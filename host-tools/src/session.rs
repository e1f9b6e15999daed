//! A session: every recording of one sample from one day, in one folder
//! (`docs/FORMAT.md`). Fitting and diagnosis work on sessions.

use std::path::{Path, PathBuf};

use crate::recording::{Geometry, Recording, RecordingError};

/// A recording of a session, with what the fit needs to know of it.
#[derive(Clone, Debug)]
pub struct SessionRecording {
    /// File name (no folder), as reports name it.
    pub name: String,
    /// The recording.
    pub rec: Recording,
    /// Sample time, s.
    pub dt_s: f64,
    /// Session time at the recording's start, s (its `notes`).
    pub t_start_s: Option<f64>,
    /// Rows of the opening rest (all voltages zero), at least 1 s of them.
    pub rest_rows: usize,
}

impl SessionRecording {
    /// The segments the recording drives (0-based): those whose voltage
    /// is non-zero at some sample.
    pub fn driven(&self) -> Vec<usize> {
        (0..self.rec.meta.segments)
            .filter(|&k| self.rec.v_v.rows().any(|v| v[k] != 0.0))
            .collect()
    }
}

/// All recordings of a session, in file-name order (the session's order).
#[derive(Clone, Debug)]
pub struct Session {
    /// The folder.
    pub dir: PathBuf,
    /// The recordings.
    pub recordings: Vec<SessionRecording>,
}

/// Why a session was refused.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The folder cannot be listed.
    #[error("listing the folder {dir}")]
    Io {
        /// The folder.
        dir: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// No `.csv` file in the folder.
    #[error("{0}: no recordings (*.csv) in this folder")]
    Empty(String),
    /// A recording breaks the format.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// A recording does not fit the session or the fit's needs.
    #[error("{file}: {message}")]
    Rule {
        /// The file.
        file: String,
        /// The rule broken.
        message: String,
    },
}

impl Session {
    /// Reads every `*.csv` of `dir`. All must share the sample: segments,
    /// geometry and medium; each must open with at least 1 s at zero volts
    /// (`docs/FORMAT.md`), which shows its rest and its noise.
    pub fn read(dir: &Path) -> Result<Session, SessionError> {
        let dir_name = dir.display().to_string();
        let io = |source| SessionError::Io {
            dir: dir_name.clone(),
            source,
        };
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(io)?
            .collect::<Result<Vec<_>, _>>()
            .map_err(io)?
            .into_iter()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "csv"))
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(SessionError::Empty(dir_name));
        }
        let mut recordings = Vec::with_capacity(files.len());
        for path in &files {
            let rec = Recording::read(path)?;
            recordings.push(Self::prepare(path, rec)?);
        }
        let first = &recordings[0];
        for r in &recordings[1..] {
            let (a, b) = (&first.rec.meta, &r.rec.meta);
            let same = a.segments == b.segments
                && a.length_m == b.length_m
                && a.width_m == b.width_m
                && a.thickness_m == b.thickness_m
                && a.medium == b.medium;
            if !same {
                return Err(SessionError::Rule {
                    file: path_name(&dir.join(&r.name)),
                    message: format!(
                        "a session is one sample: segments, length_m, width_m, thickness_m and medium must equal those of {}",
                        first.name
                    ),
                });
            }
        }
        Ok(Session {
            dir: dir.to_path_buf(),
            recordings,
        })
    }

    /// `rec`, read from `path`, as a session holds it: its sample time,
    /// session start and opening rest found, refused without 1 s of rest.
    pub fn prepare(path: &Path, rec: Recording) -> Result<SessionRecording, SessionError> {
        let file = path_name(path);
        let dt_s = rec.sample_time().map_err(|e| SessionError::Rule {
            file: file.clone(),
            message: e.to_string(),
        })?;
        let rest_rows = rec
            .v_v
            .rows()
            .position(|v| v.iter().any(|&x| x != 0.0))
            .unwrap_or(rec.v_v.len());
        let rest_s = rest_rows as f64 * dt_s;
        if rest_s < 1.0 - 0.5 * dt_s {
            let message = match rec.t_s.get(rest_rows) {
                Some(t_s) => format!(
                    "data row {} (t = {t_s} s) drives a segment after only {rest_s:.3} s at 0 V: a recording opens with at least 1 s at zero volts (docs/FORMAT.md), which the fit needs for its rest and noise",
                    rest_rows + 1,
                ),
                // Never driven: the whole recording is its opening rest.
                None => format!(
                    "the recording is {rest_s:.3} s long ({rest_rows} data rows), all at 0 V: a recording opens with at least 1 s at zero volts (docs/FORMAT.md), which the fit needs for its rest and noise",
                ),
            };
            return Err(SessionError::Rule { file, message });
        }
        Ok(SessionRecording {
            name: path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            t_start_s: rec.meta.session_start_s(),
            rec,
            dt_s,
            rest_rows,
        })
    }

    /// The sample's geometry (all recordings share it).
    pub fn geometry(&self) -> Geometry {
        self.recordings[0].rec.meta.geometry()
    }
}

fn path_name(p: &Path) -> String {
    p.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V\n";

    fn at_volts(rows: usize, volts: impl Fn(usize) -> f64) -> Recording {
        let mut text = HEAD.to_string();
        for i in 0..rows {
            text += &format!("{},{}\n", i as f64 * 1e-3, volts(i));
        }
        Recording::parse("r.csv", &text).unwrap()
    }

    // Regression: a recording never driven and shorter than 1 s indexed one
    // row past its end while saying where the drive began.
    #[test]
    fn all_rest_shorter_than_1_s_is_refused_by_name() {
        let err = Session::prepare(Path::new("s/zero.csv"), at_volts(500, |_| 0.0)).unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("s/zero.csv: "), "{text}");
        assert!(
            text.contains("0.500 s long (500 data rows), all at 0 V"),
            "{text}"
        );
        assert!(text.contains("at least 1 s at zero volts"), "{text}");
    }

    #[test]
    fn drive_before_1_s_is_refused_at_its_row() {
        let rec = at_volts(2000, |i| if i < 300 { 0.0 } else { 1.0 });
        let text = Session::prepare(Path::new("d.csv"), rec)
            .unwrap_err()
            .to_string();
        assert!(text.contains("data row 301 (t = 0.3 s)"), "{text}");
    }

    #[test]
    fn all_rest_of_1_s_is_accepted() {
        let r = Session::prepare(Path::new("z.csv"), at_volts(1001, |_| 0.0)).unwrap();
        assert_eq!(r.rest_rows, 1001);
    }
}
