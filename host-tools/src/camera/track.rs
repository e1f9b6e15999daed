//! A tracker's CSV of dot positions per camera frame, in pixels.
//!
//! One row per dot per frame, with a header naming the columns (any
//! order, other columns ignored):
//!
//! | column | meaning |
//! |---|---|
//! | `frame` | the frame's number (whole, increasing over the file) |
//! | `time_s` | the frame's time on the camera's clock, s (optional: else `frame / fps`) |
//! | `dot` | which mark: `1`, `2`, … (dot J of the recording's `dots_s_m`), `tip`, or `sync` (the LED the firmware lights at a wave's start; its first row is the sync event) |
//! | `x_px`, `y_px` | the mark's position in the image, pixels (empty on a `sync` row, or where the tracker lost the mark) |
//!
//! This is the plain table that common tracking tools export (one mark per
//! row); a refusal names the file, the line and the rule.
//!
//! ```
//! use finrs::camera::track::{Mark, Track};
//!
//! let t = Track::parse("t.csv", "frame,time_s,dot,x_px,y_px\n0,0,tip,100,50\n1,0.0167,tip,100,52\n1,0.0167,sync,,\n", None).unwrap();
//! assert_eq!(t.points.len(), 2);
//! assert_eq!(t.points[1].mark, Mark::Tip);
//! assert_eq!(t.sync_time_s, Some(0.0167));
//! ```

/// Which mark a row is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mark {
    /// The strip's tip.
    Tip,
    /// Dot J (from 1).
    Dot(usize),
}

/// One tracked position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Camera time, s.
    pub t_s: f64,
    /// The mark.
    pub mark: Mark,
    /// Image position, pixels.
    pub x_px: f64,
    /// Image position, pixels.
    pub y_px: f64,
}

/// A whole track.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// Every tracked position, in file order.
    pub points: Vec<Point>,
    /// Camera time of the first `sync` row, if any.
    pub sync_time_s: Option<f64>,
}

/// A refused track: the file, the line and the rule.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}: {rule}")]
pub struct TrackError {
    /// The file.
    pub file: String,
    /// The line (1 for the header, 0 for the file as a whole).
    pub line: usize,
    /// The rule broken.
    pub rule: String,
}

impl Track {
    /// Reads a track; `fps` gives frame times where the file has no
    /// `time_s` column.
    pub fn read(path: &std::path::Path, fps: Option<f64>) -> Result<Self, TrackError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| TrackError {
            file: file.clone(),
            line: 0,
            rule: format!("cannot read: {e}"),
        })?;
        Self::parse(&file, &text, fps)
    }

    /// Parses `text`, named `file` in refusals.
    pub fn parse(file: &str, text: &str, fps: Option<f64>) -> Result<Self, TrackError> {
        let err = |line: usize, rule: String| TrackError {
            file: file.to_string(),
            line,
            rule,
        };
        let mut lines = text.trim_start_matches('\u{feff}').lines().enumerate();
        let Some((_, header)) = lines.next() else {
            return Err(err(0, "empty: a header line is needed".to_string()));
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        let col = |name: &str| names.iter().position(|&n| n == name);
        let need = |name: &str| {
            col(name).ok_or_else(|| err(1, format!("no `{name}` column (header: {header})")))
        };
        let (frame_c, dot_c, x_c, y_c) =
            (need("frame")?, need("dot")?, need("x_px")?, need("y_px")?);
        let time_c = col("time_s");
        let fps = match (time_c, fps) {
            (Some(_), _) => None,
            (None, Some(f)) if f.is_finite() && f > 0.0 => Some(f),
            (None, Some(f)) => return Err(err(0, format!("fps {f}: must be above 0"))),
            (None, None) => {
                return Err(err(
                    1,
                    "no `time_s` column: give the camera's frame rate (--fps)".to_string(),
                ))
            }
        };
        let mut points = Vec::new();
        let mut sync_time_s = None;
        let mut last: Option<(u64, f64)> = None;
        for (i, line) in lines {
            let n = i + 1;
            if line.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if fields.len() < names.len() {
                return Err(err(
                    n,
                    format!("{} fields, the header has {}", fields.len(), names.len()),
                ));
            }
            let frame: u64 = fields[frame_c].parse().map_err(|_| {
                err(
                    n,
                    format!("frame {:?} is not a whole number", fields[frame_c]),
                )
            })?;
            let t_s = match (time_c, fps) {
                (Some(c), _) => {
                    let t: f64 = fields[c]
                        .parse()
                        .map_err(|_| err(n, format!("time_s {:?} is not a number", fields[c])))?;
                    if !t.is_finite() {
                        return Err(err(n, format!("time_s {t} is not finite")));
                    }
                    t
                }
                (None, Some(f)) => frame as f64 / f,
                (None, None) => unreachable!("checked above"),
            };
            if let Some((last_frame, last_t)) = last {
                if frame < last_frame || (frame == last_frame) != (t_s == last_t) || t_s < last_t {
                    return Err(err(
                        n,
                        format!("frame {frame} at {t_s} s after frame {last_frame} at {last_t} s: frames and times must increase together"),
                    ));
                }
            }
            last = Some((frame, t_s));
            let dot = fields[dot_c];
            if dot == "sync" {
                sync_time_s.get_or_insert(t_s);
                continue;
            }
            let mark = match dot {
                "tip" => Mark::Tip,
                d => match d.parse::<usize>() {
                    Ok(j) if j >= 1 => Mark::Dot(j),
                    _ => {
                        return Err(err(
                            n,
                            format!("dot {d:?} is not a dot number from 1, `tip` or `sync`"),
                        ))
                    }
                },
            };
            // A mark the tracker lost in this frame: no point, no guess.
            if fields[x_c].is_empty() && fields[y_c].is_empty() {
                continue;
            }
            let px = |c: usize, name: &str| -> Result<f64, TrackError> {
                let v: f64 = fields[c]
                    .parse()
                    .map_err(|_| err(n, format!("{name} {:?} is not a number", fields[c])))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(err(n, format!("{name} {v} is not finite")))
                }
            };
            points.push(Point {
                t_s,
                mark,
                x_px: px(x_c, "x_px")?,
                y_px: px(y_c, "y_px")?,
            });
        }
        if points.is_empty() {
            return Err(err(0, "no tracked positions".to_string()));
        }
        Ok(Track {
            points,
            sync_time_s,
        })
    }
}
