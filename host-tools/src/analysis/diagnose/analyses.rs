//! Where the baseline's misfit lives across a session: per recording, its
//! weighted residual and the scale from the baseline's motion to the
//! measured one (its gain); the gain against session time (a trend:
//! drying), against the drive's amplitude (nonlinearity, large
//! deflection), per segment driven alone (crosstalk, segment differences);
//! and the channels the baseline cannot move at all (motion along the
//! strip). These describe; the verdict comes from the fits.

use serde::Serialize;

use crate::analysis::fit::Score;
use crate::analysis::median::median;
use crate::recording::Channel;
use crate::session::Session;

/// The baseline's misfit in one recording.
#[derive(Clone, Debug, Serialize)]
pub struct RecordingMisfit {
    /// Recording.
    pub recording: String,
    /// Session time at its start, s, where the notes give it.
    pub t_session_s: Option<f64>,
    /// Largest |voltage| on any segment, V.
    pub max_abs_v: f64,
    /// Segments driven (1-based), from the voltages.
    pub driven: Vec<usize>,
    /// `free` or `blocked`.
    pub fixture: String,
    /// Weighted RSS per residual (1 is the noise floor).
    pub rss_per_residual: f64,
    /// Median over the mechanical channels with signal of the scale from
    /// the baseline's prediction to the data (1: amplitude right).
    pub gain: Option<f64>,
}

/// A rank correlation and what it says.
#[derive(Clone, Debug, Serialize)]
pub struct Dependence {
    /// Spearman's ρ of the recordings' gain against the quantity.
    pub spearman: f64,
    /// Recordings it was computed over.
    pub recordings: usize,
}

/// The session-wide analyses.
#[derive(Clone, Debug, Serialize)]
pub struct Analyses {
    /// Per recording, in session order.
    pub recordings: Vec<RecordingMisfit>,
    /// Gain against session time (needs the notes' start times); below
    /// zero, the strip answers less and less.
    pub trend: Option<Dependence>,
    /// Gain against the drive's amplitude, among free recordings of all
    /// segments.
    pub amplitude: Option<Dependence>,
    /// Each single-segment recording: `(segment, RSS/m, gain)`.
    pub single_segments: Vec<(usize, f64, Option<f64>)>,
    /// Channels with signal that the baseline predicts as zero throughout
    /// (`recording: channel`).
    pub immovable: Vec<String>,
}

/// Analyses the baseline's `score` over every recording of `session`.
pub fn analyse(session: &Session, score: &Score) -> Analyses {
    let mut recordings = Vec::new();
    let mut immovable = Vec::new();
    for r in &session.recordings {
        let channels: Vec<_> = score
            .channels
            .iter()
            .filter(|c| c.recording == r.name)
            .collect();
        let (sum, n) = channels.iter().fold((0.0, 0usize), |(s, n), c| {
            (
                s + c.residuals.iter().map(|x| x * x).sum::<f64>(),
                n + c.residuals.len(),
            )
        });
        for c in &channels {
            // The model's value is data − σ·residual; zero throughout means
            // the baseline has no way to move this channel.
            if c.has_signal && c.model_is_zero {
                immovable.push(format!("{}: {}", r.name, c.channel.name()));
            }
        }
        let driven: Vec<usize> = r.driven().iter().map(|s| s + 1).collect();
        let max_abs_v = r
            .rec
            .v_v
            .as_flat()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        recordings.push(RecordingMisfit {
            recording: r.name.clone(),
            t_session_s: r.t_start_s,
            max_abs_v,
            driven,
            fixture: r.rec.meta.fixture.name().to_string(),
            rss_per_residual: if n > 0 { sum / n as f64 } else { 0.0 },
            gain: median_gain(&channels),
        });
    }
    let trend = trend(&recordings);
    let amplitude = amplitude(session, &recordings);
    let single_segments = recordings
        .iter()
        .filter(|m| m.driven.len() == 1)
        .map(|m| (m.driven[0], m.rss_per_residual, m.gain))
        .collect();
    Analyses {
        recordings,
        trend,
        amplitude,
        single_segments,
        immovable,
    }
}

/// The gain against the session clock, given four recordings with both.
fn trend(recordings: &[RecordingMisfit]) -> Option<Dependence> {
    let pts: Vec<(f64, f64)> = recordings
        .iter()
        .filter_map(|m| m.t_session_s.zip(m.gain))
        .collect();
    (pts.len() >= 4).then(|| Dependence {
        spearman: spearman(&pts),
        recordings: pts.len(),
    })
}

/// The gain against the peak voltage over free recordings driving every
/// segment, given three.
fn amplitude(session: &Session, recordings: &[RecordingMisfit]) -> Option<Dependence> {
    let all_segments = |m: &RecordingMisfit| {
        let segs = session
            .recordings
            .first()
            .map_or(0, |r| r.rec.meta.segments);
        m.driven.len() == segs
    };
    let pts: Vec<(f64, f64)> = recordings
        .iter()
        .filter(|m| all_segments(m) && m.fixture == "free")
        .filter_map(|m| m.gain.map(|g| (m.max_abs_v, g)))
        .collect();
    (pts.len() >= 3).then(|| Dependence {
        spearman: spearman(&pts),
        recordings: pts.len(),
    })
}

/// Median gain over the mechanical channels that carry signal.
fn median_gain(channels: &[&crate::analysis::fit::ChannelFit]) -> Option<f64> {
    median(
        channels
            .iter()
            .filter(|c| {
                c.has_signal && !matches!(c.channel, Channel::Current(_)) && c.gain.is_finite()
            })
            .map(|c| c.gain)
            .collect(),
    )
}

/// Spearman's rank correlation of `(x, y)` pairs (ties get mean ranks).
pub fn spearman(pts: &[(f64, f64)]) -> f64 {
    let ranks = |v: Vec<f64>| -> Vec<f64> {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
        let mut r = vec![0.0; v.len()];
        let mut i = 0;
        while i < idx.len() {
            let mut j = i;
            while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
                j += 1;
            }
            for &k in &idx[i..=j] {
                r[k] = (i + j) as f64 / 2.0;
            }
            i = j + 1;
        }
        r
    };
    let rx = ranks(pts.iter().map(|p| p.0).collect());
    let ry = ranks(pts.iter().map(|p| p.1).collect());
    let n = pts.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx == 0.0 || syy == 0.0 {
        0.0
    } else {
        sxy / (sxx * syy).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::spearman;

    #[test]
    fn spearman_is_one_for_any_rising_curve_and_minus_one_falling() {
        let up: Vec<(f64, f64)> = (0..6).map(|i| (i as f64, (i as f64).exp())).collect();
        assert!((spearman(&up) - 1.0).abs() < 1e-12);
        let down: Vec<(f64, f64)> = (0..6).map(|i| (i as f64, -(i as f64).powi(3))).collect();
        assert!((spearman(&down) + 1.0).abs() < 1e-12);
        let flat = [(0.0, 1.0), (1.0, 1.0), (2.0, 1.0)];
        assert_eq!(spearman(&flat), 0.0);
    }
}
