//! Each sensor against its own noise floor.
//!
//! Pooled over a session, the currents are most of the residuals (one
//! column per segment at every sample), so a camera left at five times its
//! noise still gives a pooled weighted RSS near 1 and a verdict of
//! `explained`. The final model has to reach the floor of every sensor on
//! its own, each as the fit weighs it ([`Sensor`]: one noise level each):
//! the currents, the camera across and along the strip, the load cell.

use serde::Serialize;

use super::structure::{structure, Structure};
use crate::analysis::fit::{ChannelFit, Score, Sensor};

/// Held-out weighted RSS per residual above which structure remains: the
/// noise levels come from about a second of rest per recording, so they
/// are known to some ten percent; the camera's whole pixels add a little.
pub const NOISE_FLOOR_RATIO: f64 = 1.5;

/// One sensor's held-out residuals under a model.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SensorFloor {
    /// [`Sensor::name`].
    pub sensor: String,
    /// Weighted RSS per residual over its held-out channels (1 is its
    /// noise floor).
    pub rss_per_residual: f64,
    /// Residuals counted.
    pub residuals: usize,
    /// Whether it is below [`NOISE_FLOOR_RATIO`].
    pub at_floor: bool,
    /// Its held-out channel furthest above the floor, `recording: channel`.
    pub worst_channel: String,
    /// That channel's weighted RSS per residual.
    pub worst_rss_per_residual: f64,
    /// Above the floor: what that channel's residuals hold (frequency band,
    /// correlation with the input).
    pub structure: Option<Structure>,
}

/// The floor of each sensor `hold` has residuals for, in [`Sensor::ALL`]
/// order.
pub fn sensor_floors(hold: &Score) -> Vec<SensorFloor> {
    let per = |c: &ChannelFit| c.rms_in_noise * c.rms_in_noise;
    Sensor::ALL
        .iter()
        .filter_map(|&sensor| {
            let mine: Vec<&ChannelFit> = hold
                .channels
                .iter()
                .filter(|c| Sensor::of(c.channel) == sensor && !c.residuals.is_empty())
                .collect();
            let worst = mine.iter().max_by(|a, b| per(a).total_cmp(&per(b)))?;
            let (sum, n) = mine.iter().fold((0.0, 0usize), |(s, n), c| {
                (
                    s + c.residuals.iter().map(|r| r * r).sum::<f64>(),
                    n + c.residuals.len(),
                )
            });
            let rss_per_residual = sum / n as f64;
            let at_floor = rss_per_residual < NOISE_FLOOR_RATIO;
            Some(SensorFloor {
                sensor: sensor.name().to_string(),
                rss_per_residual,
                residuals: n,
                at_floor,
                structure: (!at_floor).then(|| structure(worst)),
                worst_channel: format!("{}: {}", worst.recording, worst.channel.name()),
                worst_rss_per_residual: per(worst),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Channel;

    fn channel(channel: Channel, recording: &str, level: f64, n: usize) -> ChannelFit {
        ChannelFit::alternating(channel, recording, level, n)
    }

    #[test]
    fn a_camera_far_above_its_floor_is_not_hidden_by_many_currents_at_theirs() {
        let mut channels: Vec<ChannelFit> = (0..3)
            .map(|k| channel(Channel::Current(k), "step.csv", 1.0, 4000))
            .collect();
        channels.push(channel(Channel::TipY, "step.csv", 2.0, 400));
        channels.push(channel(Channel::DotY(0), "step.csv", 1.1, 400));
        let hold = Score::new(channels);
        // Pooled, the camera's misfit all but vanishes...
        let all: Vec<f64> = hold
            .channels
            .iter()
            .flat_map(|c| c.residuals.clone())
            .collect();
        let pooled = all.iter().map(|r| r * r).sum::<f64>() / all.len() as f64;
        assert!(pooled < NOISE_FLOOR_RATIO, "pooled {pooled}");
        // ...apart, it is above its floor, and its worst channel named.
        let floors = sensor_floors(&hold);
        let names: Vec<&str> = floors.iter().map(|f| f.sensor.as_str()).collect();
        assert_eq!(names, ["currents", "camera across"]);
        assert!(floors[0].at_floor);
        assert!(!floors[1].at_floor);
        assert!((floors[1].rss_per_residual - (4.0 + 1.21) / 2.0).abs() < 1e-12);
        assert_eq!(floors[1].worst_channel, "step.csv: tip_y_m");
        assert!((floors[1].worst_rss_per_residual - 4.0).abs() < 1e-12);
        assert_eq!(floors[1].residuals, 800);
        // Above its floor, what the worst channel holds is said; at its
        // floor, nothing.
        assert!(floors[0].structure.is_none());
        let st = floors[1].structure.as_ref().expect("described");
        // ±level alternating: all its power at the top of the band.
        assert!(st.band_percent > 90.0 && st.band_hz.1 == 500.0, "{st:?}");
    }
}
