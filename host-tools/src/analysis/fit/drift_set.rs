//! The drift terms of a set of recordings fitted together: for each
//! measured channel, its samples in every recording of the set and their
//! basis (`drift.rs`), on the session's clock where every recording gives
//! its place on it and two or more have the channel, else one recording
//! at a time.

use super::data::SessionTargets;
use super::drift::DriftBasis;
use crate::recording::Channel;
use crate::session::Session;

/// One channel's drift over a set of recordings.
#[derive(Debug)]
struct Group {
    /// `(position in the set, target index in that recording)`.
    members: Vec<(usize, usize)>,
    /// The basis over the members' samples.
    basis: DriftBasis,
}

/// The drift terms of one set of recordings.
#[derive(Debug, Default)]
pub struct DriftSet {
    groups: Vec<Group>,
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
        let mut groups = Vec::new();
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
            // Shared only by two or more: a slope of one recording alone
            // is free to take its slow response.
            if on_session_clock && members.len() > 1 {
                let t: Vec<Vec<f64>> = members.iter().map(|&m| times(m)).collect();
                let refs: Vec<&[f64]> = t.iter().map(Vec::as_slice).collect();
                let rests: Vec<usize> = members.iter().map(|&m| rest(m)).collect();
                groups.push(Group {
                    basis: DriftBasis::new(&refs, &rests, true),
                    members,
                });
            } else {
                for m in members {
                    groups.push(Group {
                        basis: DriftBasis::new(&[&times(m)], &[rest(m)], false),
                        members: vec![m],
                    });
                }
            }
        }
        DriftSet { groups }
    }

    /// Removes the drift from `residuals` (per recording of the set, per
    /// target; `None` for a target left out, whose channel's drift is then
    /// left alone).
    pub fn remove(&self, residuals: &mut [Vec<Option<Vec<f64>>>]) {
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
            for (&(k, j), part) in g.members.iter().zip(parts) {
                residuals[k][j] = Some(part);
            }
        }
    }

    /// The drift in `raw` (per recording of the set, per target: `(ŷ −
    /// y)/σ` with no drift removed) as each channel of each recording
    /// shows it: `(position in the set, target index, the drift's range
    /// there in units of σ, whether its channel's drift stands out of the
    /// noise)`.
    pub fn measure(&self, raw: &[Vec<Vec<f64>>]) -> Vec<(usize, usize, f64, bool)> {
        let mut out = Vec::new();
        for g in &self.groups {
            let parts: Vec<&[f64]> = g
                .members
                .iter()
                .map(|&(k, j)| raw[k][j].as_slice())
                .collect();
            let (ranges, significant) = g.basis.measure(&parts);
            for (&(k, j), range) in g.members.iter().zip(ranges) {
                out.push((k, j, range, significant));
            }
        }
        out
    }
}
