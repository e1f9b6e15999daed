//! A free recording from the DAQ's rows and the camera's track: the two
//! clocks aligned by a sync event both saw, positions in metres from the
//! rest frame, each camera frame on the DAQ row nearest it (no
//! interpolation: rows between frames have no position).
//!
//! The sync event: on the DAQ, the first row whose drive leaves 0 V (the
//! wave's start); on the camera, the LED the firmware lights then (the
//! track's first `sync` row) or a time given. The rest frame: each mark's
//! mean position over the frames before the sync event. Image x runs along
//! the strip from the clamp, image y across it, positive the way the strip
//! bends under a positive voltage; `flip_x`, `flip_y` turn an image that
//! runs the other way.

use std::collections::BTreeMap;

use super::track::{Mark, Track};
use crate::recording::{Channel, Fixture, Recording, RecordingError};

/// A column of positions, `None` on rows no frame fell on.
type Column = Vec<Option<f64>>;

/// How to turn pixels into the recording's columns.
#[derive(Clone, Copy, Debug)]
pub struct MergeOptions {
    /// Image scale at the strip's plane, m per pixel.
    pub m_per_px: f64,
    /// The image's x runs from the tip toward the clamp.
    pub flip_x: bool,
    /// The image's y runs opposite to the strip's positive bending.
    pub flip_y: bool,
    /// The sync event's camera time, s, in place of the track's `sync` row.
    pub sync_time_s: Option<f64>,
    /// A drive above this magnitude has started (the DAQ's sync), V.
    pub onset_v: f64,
}

impl MergeOptions {
    /// At `m_per_px`, no flips, the track's sync, 0.05 V onset.
    pub fn new(m_per_px: f64) -> Self {
        Self {
            m_per_px,
            flip_x: false,
            flip_y: false,
            sync_time_s: None,
            onset_v: 0.05,
        }
    }
}

/// Why the two could not be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A rule broken, with the file it concerns.
    #[error("{file}: {rule}")]
    Rule {
        /// The DAQ recording or the track.
        file: String,
        /// The rule.
        rule: String,
    },
    /// The merged recording breaks the format (a bug here).
    #[error(transparent)]
    Recording(#[from] RecordingError),
}

/// What the merge did.
#[derive(Clone, Debug)]
pub struct Merged {
    /// The free recording.
    pub recording: Recording,
    /// Camera time + this = DAQ time, s.
    pub offset_s: f64,
    /// Camera positions placed on a row.
    pub placed: usize,
    /// Camera positions outside the DAQ's rows (before or after).
    pub outside: usize,
}

/// Merges `track` into the DAQ recording `daq` (named `daq_file`, the
/// track `track_file`, in refusals).
pub fn merge(
    daq: &Recording,
    daq_file: &str,
    track: &Track,
    track_file: &str,
    opts: &MergeOptions,
) -> Result<Merged, MergeError> {
    let daq_err = |rule: String| MergeError::Rule {
        file: daq_file.to_string(),
        rule,
    };
    let track_err = |rule: String| MergeError::Rule {
        file: track_file.to_string(),
        rule,
    };
    if !(opts.m_per_px.is_finite() && opts.m_per_px > 0.0) {
        return Err(track_err(format!(
            "scale {} m/px: must be above 0",
            opts.m_per_px
        )));
    }
    if daq.meta.fixture != Fixture::Free {
        return Err(daq_err(
            "a blocked recording: its tip is held, there is nothing for a camera to add"
                .to_string(),
        ));
    }
    if let Some((c, _)) = daq.channels.iter().find(|(c, _)| {
        matches!(
            c,
            Channel::TipX | Channel::TipY | Channel::DotX(_) | Channel::DotY(_) | Channel::Force
        )
    }) {
        return Err(daq_err(format!(
            "has a {} column already: merge into the DAQ's own recording",
            c.name()
        )));
    }
    let onset_row = daq
        .v_v
        .rows()
        .position(|v| v.iter().any(|x| x.abs() > opts.onset_v))
        .ok_or_else(|| {
            daq_err(format!(
                "the drive never exceeds {} V: no wave start to align the camera on",
                opts.onset_v
            ))
        })?;
    let t_sync_daq = daq.t_s[onset_row];
    let t_sync_cam = opts.sync_time_s.or(track.sync_time_s).ok_or_else(|| {
        track_err("no `sync` row and no sync time given (--sync-time-s)".to_string())
    })?;
    let offset_s = t_sync_daq - t_sync_cam;

    // Rest positions: the mean over the frames before the sync event.
    let mut rest: BTreeMap<Mark, (f64, f64, usize)> = BTreeMap::new();
    for p in &track.points {
        let r = rest.entry(p.mark).or_insert((0.0, 0.0, 0));
        if p.t_s < t_sync_cam {
            r.0 += p.x_px;
            r.1 += p.y_px;
            r.2 += 1;
        }
    }
    let dots = daq.meta.dots_s_m.as_ref().map_or(0, Vec::len);
    for (&mark, &(_, _, n)) in &rest {
        let name = mark_name(mark);
        if n == 0 {
            return Err(track_err(format!(
                "{name}: no frame before the sync event to take its rest position from"
            )));
        }
        if let Mark::Dot(j) = mark {
            if j > dots {
                return Err(track_err(format!(
                    "{name}: the recording's dots_s_m has {dots} dots"
                )));
            }
        }
    }

    // The DAQ's period: half of it is how far a frame may sit from a row.
    let mut steps: Vec<f64> = daq.t_s.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let half_period = steps.get(steps.len() / 2).copied().unwrap_or(0.0) / 2.0;
    let rows = daq.t_s.len();
    let mut columns: BTreeMap<Mark, (Column, Column)> = rest
        .keys()
        .map(|&m| (m, (vec![None; rows], vec![None; rows])))
        .collect();
    let (sx, sy) = (
        if opts.flip_x { -1.0 } else { 1.0 },
        if opts.flip_y { -1.0 } else { 1.0 },
    );
    let (mut placed, mut outside) = (0, 0);
    for p in &track.points {
        let t = p.t_s + offset_s;
        let i = daq.t_s.partition_point(|&r| r < t);
        let nearest = [i.checked_sub(1), (i < rows).then_some(i)]
            .into_iter()
            .flatten()
            .min_by(|&a, &b| (daq.t_s[a] - t).abs().total_cmp(&(daq.t_s[b] - t).abs()));
        let Some(row) = nearest.filter(|&r| (daq.t_s[r] - t).abs() <= half_period) else {
            outside += 1;
            continue;
        };
        let (x0, y0, n) = rest[&p.mark];
        let (x0, y0) = (x0 / n as f64, y0 / n as f64);
        let (xs, ys) = columns.get_mut(&p.mark).expect("every mark has columns");
        if ys[row].is_some() {
            return Err(track_err(format!(
                "{} twice on the DAQ row at {} s: the camera is faster than the DAQ, or its times repeat",
                mark_name(p.mark),
                daq.t_s[row]
            )));
        }
        xs[row] = Some(sx * (p.x_px - x0) * opts.m_per_px);
        ys[row] = Some(sy * (p.y_px - y0) * opts.m_per_px);
        placed += 1;
    }
    if placed == 0 {
        return Err(track_err(format!(
            "no frame falls within the DAQ's rows (camera offset {offset_s:.3} s)"
        )));
    }
    let mut recording = daq.clone();
    for (mark, (xs, ys)) in columns {
        let (cy, cx) = match mark {
            Mark::Tip => (Channel::TipY, Channel::TipX),
            Mark::Dot(j) => (Channel::DotY(j - 1), Channel::DotX(j - 1)),
        };
        recording.channels.push((cy, ys));
        recording.channels.push((cx, xs));
    }
    let note = format!(
        "camera merged by finrs: {placed} positions at {} m/px, aligned on the wave's start (camera + {offset_s:.4} s), rest from the frames before it",
        opts.m_per_px
    );
    recording.meta.notes = Some(match recording.meta.notes.take() {
        Some(n) if !n.is_empty() => format!("{n}; {note}"),
        _ => note,
    });
    recording.validate(daq_file)?;
    Ok(Merged {
        recording,
        offset_s,
        placed,
        outside,
    })
}

fn mark_name(mark: Mark) -> String {
    match mark {
        Mark::Tip => "the tip".to_string(),
        Mark::Dot(j) => format!("dot {j}"),
    }
}

#[cfg(test)]
mod tests;
