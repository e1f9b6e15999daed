//! A session: every recording of one sample from one day, in one folder
//! (`docs/FORMAT.md`). Fitting and diagnosis work on sessions.

use std::path::{Path, PathBuf};

use crate::recording::{
    Channel, Geometry, Recording, RecordingError, RestReading, REST_BAND_LIMIT_V, REST_OPENING_S,
};

pub mod faults;

pub use faults::{Fault, FaultKind};

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
    /// Rows of the opening rest (every voltage reads as its channel's
    /// rest), at least 1 s of them.
    pub rest_rows: usize,
    /// Each segment's voltage channel's reading of a rest (its offset,
    /// noise and step), measured on the opening.
    pub rests: Vec<RestReading>,
    /// The bench's faults in it: contact faults, out-of-range stretches,
    /// clipped runs ([`faults`]); found when a session is read.
    pub faults: Vec<Fault>,
    /// The drive the strip saw where a contact fault says it differs from
    /// the voltages read ([`faults::strip_drive`]); `None` where it does
    /// not.
    pub strip_drive: Option<Recording>,
}

impl SessionRecording {
    /// Its length, s: the time of its last row.
    pub fn length_s(&self) -> f64 {
        self.rec.t_s.last().copied().unwrap_or(0.0)
    }

    /// Session time at its end, s, when its notes give its start.
    pub fn end_s(&self) -> Option<f64> {
        self.t_start_s.map(|t| t + self.length_s())
    }

    /// The segments the recording drives (0-based): those whose voltage
    /// reads other than its rest at some sample.
    pub fn driven(&self) -> Vec<usize> {
        (0..self.rec.meta.segments)
            .filter(|&k| {
                let rest = &self.rests[k];
                self.rec.v_v.rows().any(|v| !rest.at_rest(v[k]))
            })
            .collect()
    }

    /// Whether segment `k`'s voltage on `row` reads as `level_v` does:
    /// within its channel's rest band of it (the DAQ's noise and step on a
    /// held voltage as on a rest; exactly equal for an exact drive).
    pub fn reads_as(&self, k: usize, row: usize, level_v: f64) -> bool {
        (self.rec.v_v[row][k] - level_v).abs() <= self.rests[k].band_v()
    }

    /// What the model is driven by: the recording, its voltages as read,
    /// except where a contact fault from the rest kept the voltage from
    /// the strip (the strip stayed at rest: [`faults::strip_drive`]).
    pub fn drive(&self) -> &Recording {
        self.strip_drive.as_ref().unwrap_or(&self.rec)
    }

    /// Per row, whether channel `ch`'s sample there stays out of the fit
    /// because of a fault ([`faults::kept_out`]).
    pub fn kept_out(&self, ch: Channel) -> Vec<bool> {
        faults::kept_out(&self.faults, ch, self.rec.t_s.len())
    }

    /// `faults` as this recording's, with the drive they imply.
    fn with_faults(mut self, faults: Vec<Fault>) -> SessionRecording {
        self.strip_drive = faults::strip_drive(&self.rec, &faults);
        self.faults = faults;
        self
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
    /// geometry and medium; each must open with at least 1 s at rest
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
        // The bench's faults, judged against the session's own currents.
        let inputs: Vec<faults::Input> = recordings
            .iter()
            .map(|r| faults::Input {
                rec: &r.rec,
                rest_rows: r.rest_rows,
                rests: &r.rests,
            })
            .collect();
        let found = faults::find(&inputs);
        let recordings = recordings
            .into_iter()
            .zip(found)
            .map(|(r, f)| r.with_faults(f))
            .collect();
        Ok(Session {
            dir: dir.to_path_buf(),
            recordings,
        })
    }

    /// `rec`, read from `path`, as a session holds it: its sample time,
    /// session start and opening rest found, refused without 1 s of rest;
    /// its faults are not looked for (a session's reading finds them,
    /// judged against all of its recordings).
    /// A rest is what the DAQ reads when nothing is applied: each voltage
    /// channel's offset and noise, measured on its opening
    /// ([`RestReading`]), not exactly 0 V.
    pub fn prepare(path: &Path, rec: Recording) -> Result<SessionRecording, SessionError> {
        let file = path_name(path);
        let dt_s = rec.sample_time().map_err(|e| SessionError::Rule {
            file: file.clone(),
            message: e.to_string(),
        })?;
        let rests: Vec<RestReading> = (0..rec.meta.segments)
            .map(|k| RestReading::measure(&rec.t_s, &rec.v_v, k))
            .collect();
        if let Some((k, rest)) = rests.iter().enumerate().find(|(_, r)| !r.is_rest()) {
            let message = format!(
                "v{}_V reads {:.4} V ± {:.4} V over its first {REST_OPENING_S} s, beyond the {REST_BAND_LIMIT_V} V a rest's offset and noise may read: a recording opens with at least 1 s at rest (docs/FORMAT.md), which the fit needs for its rest and noise",
                k + 1,
                rest.offset_v,
                rest.band_v(),
            );
            return Err(SessionError::Rule { file, message });
        }
        let rest_rows = rec
            .v_v
            .rows()
            .position(|v| v.iter().zip(&rests).any(|(&x, r)| !r.at_rest(x)))
            .unwrap_or(rec.v_v.len());
        let rest_s = rest_rows as f64 * dt_s;
        if rest_s < 1.0 - 0.5 * dt_s {
            let message = match rec.t_s.get(rest_rows) {
                Some(t_s) => format!(
                    "data row {} (t = {t_s} s) drives a segment after only {rest_s:.3} s at rest: a recording opens with at least 1 s at rest (docs/FORMAT.md), which the fit needs for its rest and noise",
                    rest_rows + 1,
                ),
                // Never driven: the whole recording is its opening rest.
                None => format!(
                    "the recording is {rest_s:.3} s long ({rest_rows} data rows), all at rest: a recording opens with at least 1 s at rest (docs/FORMAT.md), which the fit needs for its rest and noise",
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
            rests,
            faults: Vec::new(),
            strip_drive: None,
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
            text.contains("0.500 s long (500 data rows), all at rest"),
            "{text}"
        );
        assert!(text.contains("at least 1 s at rest"), "{text}");
    }

    #[test]
    fn drive_before_1_s_is_refused_at_its_row() {
        let rec = at_volts(2000, |i| if i < 300 { 0.0 } else { 1.0 });
        let text = Session::prepare(Path::new("d.csv"), rec)
            .unwrap_err()
            .to_string();
        assert!(text.contains("data row 301 (t = 0.3 s)"), "{text}");
    }

    /// A DAQ's rest: 0.3 mV counts about a 0.7 mV offset, never 0 V.
    fn daq_rest(i: usize) -> f64 {
        0.0003 * (2 + [0, 1, 0, 2, 1, 1, 3][i % 7]) as f64
    }

    #[test]
    fn a_measured_rest_is_a_rest_and_a_drive_past_4_v_by_its_offset_is_read() {
        let rec = at_volts(3000, |i| if i < 1200 { daq_rest(i) } else { 4.0007 });
        let r = Session::prepare(Path::new("daq.csv"), rec).unwrap();
        assert_eq!(r.rest_rows, 1200);
        assert_eq!(r.driven(), vec![0]);
        assert!(r.rests[0].offset_v > 0.0 && r.rests[0].is_rest());
    }

    #[test]
    fn a_rest_that_strays_is_driven_where_it_leaves_its_band() {
        let rec = at_volts(2000, |i| if i < 700 { daq_rest(i) } else { 0.05 });
        let text = Session::prepare(Path::new("d.csv"), rec)
            .unwrap_err()
            .to_string();
        assert!(text.contains("data row 701 (t = 0.70"), "{text}");
        assert!(text.contains("0.700 s at rest"), "{text}");
    }

    #[test]
    fn an_undriven_segment_reading_its_rest_is_not_driven() {
        let mut text = HEAD.replace("segments = 1", "segments = 2");
        text = text.replace("t_s,v1_V", "t_s,v1_V,v2_V");
        for i in 0..2500 {
            let v1 = if i < 1100 { daq_rest(i) } else { 2.5 };
            let _ = std::fmt::Write::write_fmt(
                &mut text,
                format_args!("{},{v1},{}\n", i as f64 * 1e-3, -daq_rest(i + 3)),
            );
        }
        let rec = Recording::parse("two.csv", &text).unwrap();
        let r = Session::prepare(Path::new("two.csv"), rec).unwrap();
        assert_eq!(r.driven(), vec![0]);
        assert!(r.rests[1].offset_v < 0.0, "{:?}", r.rests[1]);
    }

    #[test]
    fn an_opening_that_reads_more_than_a_rest_is_refused_by_channel() {
        let rec = at_volts(2000, |i| 0.02 + 0.001 * (i % 5) as f64);
        let text = Session::prepare(Path::new("o.csv"), rec)
            .unwrap_err()
            .to_string();
        assert!(
            text.starts_with("o.csv: v1_V reads 0.0220 V ± 0.0072 V over its first 0.5 s"),
            "{text}"
        );
    }

    #[test]
    fn all_rest_of_1_s_is_accepted() {
        let r = Session::prepare(Path::new("z.csv"), at_volts(1001, |_| 0.0)).unwrap();
        assert_eq!(r.rest_rows, 1001);
    }
}
