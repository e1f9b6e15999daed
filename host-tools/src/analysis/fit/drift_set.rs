//! The drift terms of a set of recordings fitted together: for each
//! measured channel, its samples in every recording of the set and their
//! basis (`drift.rs`), on the session's clock where every recording gives
//! its place on it and two or more have the channel, else one recording
//! at a time.

use super::carry::CarryColumns;
use super::data::SessionTargets;
use super::drift::{DriftBasis, DriftMeasure};
use super::zero_drift::{ZeroDrift, QUIET_SETTLE_S};
use crate::recording::Channel;
use crate::session::{Session, SessionRecording};

/// One channel's drift over a set of recordings.
#[derive(Debug)]
struct Group {
    /// `(position in the set, target index in that recording)`.
    members: Vec<(usize, usize)>,
    /// The basis over the members' samples.
    basis: DriftBasis,
    /// Per member, where its recording opens while the strip still moves
    /// (and the channel is the beam's): its samples' times from the
    /// recording's first row, s, and how many lie in its opening rest.
    carry: Vec<Option<(Vec<f64>, usize)>>,
}

/// Standard errors by which a line through an opening rest must stray
/// from flat for the strip to be moving there: white noise gets that far
/// about once in 16 000 rests.
pub const MOVING_REST_Z: f64 = 4.0;

/// The drift terms of one set of recordings, and the carry-over of those
/// that open while the strip still moves.
#[derive(Debug, Default)]
pub struct DriftSet {
    groups: Vec<Group>,
    /// Each current's zero, `((position in the set, target index), its
    /// zero)`.
    zeros: Vec<((usize, usize), ZeroDrift)>,
    /// Positions in the set of the recordings that open moving.
    moving: Vec<usize>,
}

impl DriftSet {
    /// The drift terms of `recordings` (indices into `session`).
    pub fn new(session: &Session, targets: &SessionTargets, recordings: &[usize]) -> DriftSet {
        let on_session_clock = recordings
            .iter()
            .all(|&i| session.recordings[i].t_start_s.is_some());
        // Channels in the order they first appear.
        let mut channels: Vec<Channel> = Vec::new();
        for &i in recordings {
            for t in &targets.recordings[i].targets {
                if !channels.contains(&t.channel) {
                    channels.push(t.channel);
                }
            }
        }
        let times = |(k, j): (usize, usize)| -> Vec<f64> {
            let i = recordings[k];
            let r = &session.recordings[i];
            let t0 = if on_session_clock {
                r.t_start_s.unwrap_or(0.0)
            } else {
                0.0
            };
            targets.recordings[i].targets[j]
                .rows
                .iter()
                .map(|&row| t0 + r.rec.t_s[row])
                .collect()
        };
        // Samples in the recording's opening rest, which its values are
        // taken relative to (`data.rs`).
        let rest = |(k, j): (usize, usize)| -> usize {
            let i = recordings[k];
            let rest_rows = session.recordings[i].rest_rows;
            targets.recordings[i].targets[j]
                .rows
                .iter()
                .take_while(|&&row| row < rest_rows)
                .count()
        };
        // A recording whose rest shows the beam moving (a line through a
        // camera or load-cell channel's rest samples beyond
        // MOVING_REST_Z standard errors): the strip still relaxes from
        // the recording before.
        let moving: Vec<usize> = recordings
            .iter()
            .enumerate()
            .filter(|&(_, &i)| {
                let r = &session.recordings[i];
                targets.recordings[i].targets.iter().any(|t| {
                    !matches!(t.channel, Channel::Current(_))
                        && rest_slope_z(t, &r.rec.t_s, r.rest_rows).abs() > MOVING_REST_Z
                })
            })
            .map(|(k, _)| k)
            .collect();
        let carry = |(k, j): (usize, usize)| -> Option<(Vec<f64>, usize)> {
            let i = recordings[k];
            let r = &session.recordings[i];
            let t = &targets.recordings[i].targets[j];
            (moving.contains(&k) && !matches!(t.channel, Channel::Current(_))).then(|| {
                let t0 = r.rec.t_s[0];
                (
                    t.rows.iter().map(|&row| r.rec.t_s[row] - t0).collect(),
                    rest((k, j)),
                )
            })
        };
        let mut groups = Vec::new();
        let mut zeros = Vec::new();
        for ch in channels {
            let members: Vec<(usize, usize)> = recordings
                .iter()
                .enumerate()
                .filter_map(|(k, &i)| {
                    let j = targets.recordings[i]
                        .targets
                        .iter()
                        .position(|t| t.channel == ch)?;
                    Some((k, j))
                })
                .collect();
            if matches!(ch, Channel::Current(_)) {
                // A current's zero is read where none flows.
                for (k, j) in members {
                    let i = recordings[k];
                    let t = &targets.recordings[i].targets[j];
                    let r = &session.recordings[i];
                    let t_s: Vec<f64> = t.rows.iter().map(|&row| r.rec.t_s[row]).collect();
                    zeros.push(((k, j), ZeroDrift::new(&t_s, &quiet_stretches(r, &t.rows))));
                }
                continue;
            }
            // Shared only by two or more: a slope of one recording alone
            // is free to take its slow response.
            if on_session_clock && members.len() > 1 {
                let t: Vec<Vec<f64>> = members.iter().map(|&m| times(m)).collect();
                let refs: Vec<&[f64]> = t.iter().map(Vec::as_slice).collect();
                let rests: Vec<usize> = members.iter().map(|&m| rest(m)).collect();
                groups.push(Group {
                    basis: DriftBasis::new(&refs, &rests, true),
                    carry: members.iter().map(|&m| carry(m)).collect(),
                    members,
                });
            } else {
                for m in members {
                    groups.push(Group {
                        basis: DriftBasis::new(&[&times(m)], &[rest(m)], false),
                        carry: vec![carry(m)],
                        members: vec![m],
                    });
                }
            }
        }
        DriftSet {
            groups,
            zeros,
            moving,
        }
    }

    /// Positions in the set of the recordings that open while the strip
    /// still moves.
    pub fn moving(&self) -> &[usize] {
        &self.moving
    }

    /// Removes the drift from `residuals` (per recording of the set, per
    /// target; `None` for a target left out, whose channel's drift is then
    /// left alone), and the carry-over of the recordings that open
    /// moving: the strip's relaxation left by the recording before,
    /// decaying as `e^{−p t}` under the model's pole `p_per_s` (the charge
    /// is gone within tens of milliseconds), an amplitude per channel
    /// fitted jointly with the drift.
    pub fn remove(&self, residuals: &mut [Vec<Option<Vec<f64>>>], p_per_s: f64) {
        for ((k, j), zero) in &self.zeros {
            if let Some(r) = residuals[*k][*j].as_mut() {
                zero.remove(r);
            }
        }
        for g in &self.groups {
            if g.members.iter().any(|&(k, j)| residuals[k][j].is_none()) {
                continue;
            }
            // Taken out and put back: one mutable borrow per member.
            let mut parts: Vec<Vec<f64>> = g
                .members
                .iter()
                .map(|&(k, j)| residuals[k][j].take().unwrap_or_default())
                .collect();
            let mut refs: Vec<&mut Vec<f64>> = parts.iter_mut().collect();
            g.basis.remove(&mut refs);
            let columns = CarryColumns::new(&g.basis, &g.carry, p_per_s);
            if !columns.is_empty() {
                columns.remove(&g.basis, &mut parts);
            }
            for (&(k, j), part) in g.members.iter().zip(parts) {
                residuals[k][j] = Some(part);
            }
        }
    }

    /// The carry-over each recording that opens moving shows in `raw`
    /// (per recording of the set, per target: `(ŷ − y)/σ` with nothing
    /// removed) under the pole `p_per_s`: `(position in the set, target
    /// index, the sum of squares its column takes beyond the drift, the
    /// range of what it takes, in units of σ)`.
    pub fn carried(&self, raw: &[Vec<Vec<f64>>], p_per_s: f64) -> Vec<(usize, usize, f64, f64)> {
        let mut out = Vec::new();
        for g in self
            .groups
            .iter()
            .filter(|g| g.carry.iter().any(Option::is_some))
        {
            let mut parts: Vec<Vec<f64>> =
                g.members.iter().map(|&(k, j)| raw[k][j].clone()).collect();
            let mut refs: Vec<&mut Vec<f64>> = parts.iter_mut().collect();
            g.basis.remove(&mut refs);
            let columns = CarryColumns::new(&g.basis, &g.carry, p_per_s);
            for (m, explained, range) in columns.remove(&g.basis, &mut parts) {
                let (k, j) = g.members[m];
                out.push((k, j, explained, range));
            }
        }
        out
    }

    /// The drift in `raw` (per recording of the set, per target: `(ŷ −
    /// y)/σ` with no drift removed) as each channel of each recording
    /// shows it: `(position in the set, target index, the drift's range
    /// there in units of σ, what its channel's drift measures over the
    /// set)`.
    pub fn measure(&self, raw: &[Vec<Vec<f64>>]) -> Vec<(usize, usize, f64, DriftMeasure)> {
        let mut out: Vec<(usize, usize, f64, DriftMeasure)> = self
            .zeros
            .iter()
            .map(|((k, j), zero)| {
                let m = zero.measure(&raw[*k][*j]);
                (*k, *j, m.ranges[0], m)
            })
            .collect();
        for g in &self.groups {
            let parts: Vec<&[f64]> = g
                .members
                .iter()
                .map(|&(k, j)| raw[k][j].as_slice())
                .collect();
            let m = g.basis.measure(&parts);
            for (&(k, j), &range) in g.members.iter().zip(&m.ranges) {
                out.push((k, j, range, m.clone()));
            }
        }
        out
    }
}

/// The slope of a line through target `t`'s samples in its recording's
/// opening rest (rows before `rest_rows`, timed by `t_s`), in standard
/// errors of its noise; 0 with fewer than three samples there.
fn rest_slope_z(t: &super::data::Target, t_s: &[f64], rest_rows: usize) -> f64 {
    let (x, y): (Vec<f64>, Vec<f64>) = t
        .rows
        .iter()
        .zip(&t.values)
        .take_while(|(&row, _)| row < rest_rows)
        .map(|(&row, &v)| (t_s[row], v))
        .unzip();
    if x.len() < 3 || t.sigma <= 0.0 {
        return 0.0;
    }
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|x| (x - mx) * (x - mx)).sum();
    if sxx <= 0.0 {
        return 0.0;
    }
    let sxy: f64 = x.iter().zip(&y).map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxy / sxx) / (t.sigma / sxx.sqrt())
}

/// The stretches of `rows` (a current's samples in recording `r`) where
/// no current flows: every segment reads its rest, and has since the
/// opening or for [`QUIET_SETTLE_S`]; as sample index ranges, each of at
/// least three samples.
fn quiet_stretches(r: &SessionRecording, rows: &[usize]) -> Vec<(usize, usize)> {
    let n = r.rec.meta.segments;
    // Each row's time since the last row that was not a rest (none yet:
    // quiet since the opening).
    let mut since_s = Vec::with_capacity(r.rec.t_s.len());
    let mut last_driven: Option<f64> = None;
    for (row, &t) in r.rec.t_s.iter().enumerate() {
        let at_rest = (0..n).all(|k| r.rests[k].at_rest(r.rec.v_v[row][k]));
        if !at_rest {
            last_driven = Some(t);
        }
        since_s.push(match (at_rest, last_driven) {
            (false, _) => None,
            (true, None) => Some(f64::INFINITY),
            (true, Some(t0)) => Some(t - t0),
        });
    }
    let quiet = |row: usize| since_s[row].is_some_and(|s| s >= QUIET_SETTLE_S);
    let mut out = Vec::new();
    let mut from = None;
    for (s, &row) in rows.iter().enumerate() {
        // Consecutive samples on consecutive rows: a gap ends a stretch.
        let joined = s > 0 && rows[s - 1] + 1 == row;
        match (quiet(row), from) {
            (true, None) => from = Some(s),
            (true, Some(f)) if !joined => {
                out.push((f, s));
                from = Some(s);
            }
            (false, Some(f)) => {
                out.push((f, s));
                from = None;
            }
            _ => {}
        }
    }
    if let Some(f) = from {
        out.push((f, rows.len()));
    }
    out.retain(|(f, t)| t - f >= 3);
    out
}
