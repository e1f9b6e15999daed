//! Each sensor's variance as the fit finds it, not below its rest noise.
//!
//! The rests give each sensor's noise; a model whose form misses something
//! leaves a sensor far above it. The load cell resolves 0.02 % of a blocked
//! step, so a ringing the model's damping cannot follow leaves it at 30 to
//! 40 times its noise, and weighed by the rests' noise alone it outweighs
//! the camera: on the off-class rig's uneven strip (seed 10007) the fit
//! moved segment 2's `K` by 2 % to shave 4 % off the load cell's misfit,
//! and the held-out travelling wave then missed by 0.55° of phase, twice
//! the camera's noise. Maximum likelihood with an unknown variance per
//! sensor, bounded below by the rests', weighs each sensor by the variance
//! it shows: `σ̂ₛ² = cₛ σ²_rest` with `cₛ` its RSS per residual `xₛ` (in
//! units of the rests' noise) kept within `[1, MAX_INFLATION]` (a feasible
//! generalised least squares over the sensors), and the cost it minimises
//! is `Σₛ mₛ (ln cₛ + xₛ/cₛ)`: `xₛ` at the floor, `1 + ln xₛ` above it, so
//! a sensor the model cannot follow counts by how many times worse it got,
//! not by its raw residuals.
//!
//! The inflation is bounded ([`MAX_INFLATION`]). Unbounded, a model far off
//! everywhere (the baseline in water, the camera at 600 times its noise)
//! weighs each sensor by its count of residuals alone, and the load cell's
//! thousand a second outvote the camera's thirty: on the off-class rig's
//! water sessions (seeds 10002, 10036) the damped, stiffer strip then fitted
//! the blocked runs and left the held-out free tip at 13 000 times its
//! noise, and only `segment-variation` was named. At ten times its noise's
//! variance a sensor still counts for a tenth of what its rests say.

use super::data::Sensor;
use super::stats::{ChannelFit, Score};

/// The most a sensor's variance is taken above its rests': every sensor
/// keeps at least a tenth of its weight, however far off the model.
pub const MAX_INFLATION: f64 = 10.0;

/// Per sensor, its variance over the rests' (at least 1), in
/// [`Sensor::ALL`] order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inflation(pub [f64; 4]);

impl Inflation {
    /// The rests' noise for every sensor.
    pub const ONE: Inflation = Inflation([1.0; 4]);

    /// Each sensor's RSS per residual over `channels` (weighed by the
    /// rests' noise), at least 1.
    pub fn of<'c>(channels: impl IntoIterator<Item = &'c ChannelFit>) -> Inflation {
        let mut out = [1.0; 4];
        for (k, (sum, n)) in per_sensor(channels).into_iter().enumerate() {
            if n > 0 {
                out[k] = (sum / n as f64).clamp(1.0, MAX_INFLATION);
            }
        }
        Inflation(out)
    }

    /// The factor on `sensor`'s noise level (the square root of its
    /// inflation).
    pub fn sigma_factor(&self, sensor: Sensor) -> f64 {
        self.0[index(sensor)].sqrt()
    }

    /// Whether `other` differs from it by more than `tol` (relative) in
    /// any sensor.
    pub fn moved(&self, other: &Inflation, tol: f64) -> bool {
        self.0
            .iter()
            .zip(&other.0)
            .any(|(a, b)| (a - b).abs() > tol * a.max(*b))
    }
}

fn index(sensor: Sensor) -> usize {
    Sensor::ALL
        .iter()
        .position(|&s| s == sensor)
        .expect("every sensor is in ALL")
}

/// Per sensor in [`Sensor::ALL`] order: the sum of squared weighted
/// residuals over `channels` and their count.
fn per_sensor<'c>(channels: impl IntoIterator<Item = &'c ChannelFit>) -> [(f64, usize); 4] {
    let mut out = [(0.0, 0usize); 4];
    for c in channels {
        let k = index(Sensor::of(c.channel));
        out[k].0 += c.residuals.iter().map(|r| r * r).sum::<f64>();
        out[k].1 += c.residuals.len();
    }
    out
}

/// The cost the fit minimises, in units of residuals at the rests' noise:
/// `Σₛ mₛ (ln cₛ + xₛ/cₛ)`, `xₛ` the sensor's RSS per residual and `cₛ` its
/// inflation ([`Inflation::of`]): minus twice the log-likelihood with each
/// sensor's variance at its most likely value within the bounds, up to a
/// constant. Compares two fits of one session: the lower is the more
/// likely.
pub fn profile_cost(score: &Score) -> f64 {
    per_sensor(&score.channels)
        .into_iter()
        .filter(|&(_, n)| n > 0)
        .map(|(sum, n)| {
            let x = sum / n as f64;
            let c = x.clamp(1.0, MAX_INFLATION);
            n as f64 * (c.ln() + x / c)
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Channel;

    fn channel(channel: Channel, level: f64, n: usize) -> ChannelFit {
        ChannelFit::alternating(channel, "r.csv", level, n)
    }

    #[test]
    fn a_sensor_above_its_rests_is_weighed_by_what_it_shows_and_none_below() {
        let score = Score::new(vec![
            channel(Channel::Current(0), 0.9, 1000),
            channel(Channel::TipY, 1.0, 100),
            channel(Channel::Force, 3.0, 500),
            channel(Channel::Force, 1.0, 500),
        ]);
        let inf = Inflation::of(&score.channels);
        // Below its rests' noise a sensor keeps it; above, its own RSS/m.
        assert_eq!(inf.sigma_factor(Sensor::Current), 1.0);
        assert_eq!(inf.sigma_factor(Sensor::CameraY), 1.0);
        assert!((inf.0[3] - 5.0).abs() < 1e-12, "{inf:?}");
        assert!((inf.sigma_factor(Sensor::Force) - 5f64.sqrt()).abs() < 1e-12);
        // Far above, at most MAX_INFLATION.
        let far = Inflation::of(&[channel(Channel::Force, 100.0, 10)]);
        assert_eq!(far.0[3], MAX_INFLATION);
        // No residuals: no inflation.
        assert_eq!(inf.sigma_factor(Sensor::CameraX), 1.0);
        assert!(inf.moved(&Inflation::ONE, 0.1));
        assert!(!inf.moved(&inf, 0.0));
    }

    #[test]
    fn the_profile_cost_counts_a_misfit_by_its_ratio_above_the_floor() {
        let at = |force: f64| {
            profile_cost(&Score::new(vec![
                channel(Channel::Current(0), 0.5, 1000),
                channel(Channel::Force, force, 1000),
            ]))
        };
        // Below the floor, the weighted RSS itself.
        assert!((at(1.0) - (250.0 + 1000.0)).abs() < 1e-9);
        // Above, three times the floor's variance costs 1 + ln 3 a residual,
        // not 3: halving a misfit's variance gains ln 2 a residual, as the
        // likelihood says, whatever its size.
        assert!((at(3f64.sqrt()) - (250.0 + 1000.0 * (1.0 + 3f64.ln()))).abs() < 1e-6);
        assert!(((at(2.0) - at(2f64.sqrt())) - 1000.0 * 2f64.ln()).abs() < 1e-6);
        // Beyond the bound, the variance held there.
        let c = MAX_INFLATION;
        assert!((at(100.0) - (250.0 + 1000.0 * (c.ln() + 1e4 / c))).abs() < 1e-6);
        // Continuous at the floor and at the bound.
        assert!((at(1.0 + 1e-9) - at(1.0)).abs() < 1e-5);
        assert!((at(c.sqrt() + 1e-9) - at(c.sqrt())).abs() < 1e-4);
    }
}
