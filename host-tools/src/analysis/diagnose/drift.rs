//! Drift reported as what it is: a bench imperfection (docs/FORMAT.md),
//! the strip's own curl or a sensor's zero wandering, fitted beside every
//! model (`fit/drift.rs`) and never named as a catalogue effect, as hum
//! and coloured noise are not.

use std::collections::BTreeMap;

use super::floors::NOISE_FLOOR_RATIO;
use super::rests::BenchFinding;
use crate::analysis::fit::Drift;
use crate::recording::Channel;

/// The least range of a drift over a recording, in units of its
/// channel's noise, that is reported: over the thousands of samples of a
/// session, a slope of a tenth of the noise is significant, and a model
/// that is not the strip (every real one) leaves that much slow misfit;
/// a drift that moves a channel by less than three noise standard
/// deviations is not worth a finding.
pub const REPORTED_NOISES: f64 = 3.0;

/// The least share of what the final model leaves beyond the noise on a
/// channel that its drift must take to be reported: most of it. A model
/// that is not the strip leaves slow structure beside its fast misfit,
/// which a drift takes a little of (on the off-class rig, drifts of 3 to
/// 5 noise levels beside a model several times its floor were called the
/// bench's in 3 of 7 sessions that had none); a bench that drifts leaves
/// the drift as most of it.
pub const REPORTED_SHARE: f64 = 0.5;

/// One finding per channel whose drift stands out of the noise
/// ([`Drift::significant`]), takes most of what the model leaves
/// ([`REPORTED_SHARE`]), leaves the channel at its noise floor
/// ([`NOISE_FLOOR_RATIO`]: what the model misses beside a drift may be
/// slow too, and a drift that is not all that is left cannot be told
/// from it) and moves the channel by at least [`REPORTED_NOISES`] over
/// some recording: its largest range, where, and in how many
/// recordings.
pub fn findings(drifts: &[Drift]) -> Vec<BenchFinding> {
    let mut by_channel: BTreeMap<String, Vec<&Drift>> = BTreeMap::new();
    for d in drifts {
        by_channel.entry(d.channel.name()).or_default().push(d);
    }
    by_channel
        .into_iter()
        .filter_map(|(channel, ds)| {
            let significant: Vec<&&Drift> = ds
                .iter()
                .filter(|d| {
                    d.significant
                        && d.share >= REPORTED_SHARE
                        && d.left_per_residual < NOISE_FLOOR_RATIO
                        && d.peak_to_peak_in_noise >= REPORTED_NOISES
                })
                .collect();
            let worst = significant
                .iter()
                .max_by(|a, b| a.peak_to_peak_in_noise.total_cmp(&b.peak_to_peak_in_noise))?;
            let (scale, unit) = match worst.channel {
                Channel::Force => (1e3, "mN"),
                Channel::Current(_) => (1e3, "mA"),
                _ => (1e3, "mm"),
            };
            let minutes = worst.span_s / 60.0;
            let span = if worst.span_s < 120.0 {
                format!("{:.1} s", worst.span_s)
            } else {
                format!("{minutes:.1} min")
            };
            let detail = format!(
                "{channel} drifts by up to {:.3} {unit} ({:.1}× its noise) over {span} ({:.3} {unit}/min) in {}; in {} of {} recordings: the strip's own curl or the sensor's zero, fitted beside the model and left out of the diagnosis",
                worst.peak_to_peak * scale,
                worst.peak_to_peak_in_noise,
                worst.peak_to_peak * scale / minutes.max(f64::MIN_POSITIVE),
                worst.recording,
                significant.len(),
                ds.len(),
            );
            Some(BenchFinding {
                what: "drift".to_string(),
                channel,
                mains_hz: None,
                strength: worst.peak_to_peak_in_noise,
                detail,
            })
        })
        .collect()
}

/// The recordings that open while the strip still moves, as one finding:
/// those where the carry-over a channel takes beyond the drift
/// ([`crate::analysis::fit::Fitter::carry_overs`]) stands out of the noise
/// (its sum of squares beyond the 99.9 % point of `χ²` with one degree of
/// freedom) by at least [`REPORTED_NOISES`]: the relaxation the recording
/// before left, fitted beside the model from each one's opening rest, not
/// a rest at 0. A rest that moves with the drift alone is no carry-over.
pub fn carry_over(carried: &[(String, Channel, f64, f64)]) -> Option<BenchFinding> {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let bar = ChiSquared::new(1.0).map_or(f64::INFINITY, |d| d.inverse_cdf(0.999));
    let mut names: Vec<&str> = Vec::new();
    let mut largest: f64 = 0.0;
    for (name, _, explained, range) in carried {
        if *explained > bar && *range >= REPORTED_NOISES {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
            largest = largest.max(*range);
        }
    }
    (!names.is_empty()).then(|| BenchFinding {
        what: "carry-over".to_string(),
        channel: "camera and load cell".to_string(),
        mains_hz: None,
        strength: largest,
        detail: format!(
            "{} of the recordings open while the strip still moves ({}; up to {largest:.1}× a channel's noise): the relaxation the recording before left, decaying at the model's pole, fitted beside it from each one's opening rest",
            names.len(),
            names.join(", ")
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drift(recording: &str, channel: Channel, p2p: f64, significant: bool) -> Drift {
        Drift {
            recording: recording.to_string(),
            channel,
            peak_to_peak: p2p,
            peak_to_peak_in_noise: p2p / 5e-5,
            span_s: 240.0,
            significant,
            share: 0.9,
            left_per_residual: 1.1,
        }
    }

    #[test]
    fn each_drifting_channel_once_by_its_largest_drift() {
        let found = findings(&[
            drift("a.csv", Channel::DotY(0), 1e-3, true),
            drift("b.csv", Channel::DotY(0), 3e-3, true),
            drift("c.csv", Channel::DotY(0), 9e-3, false),
            drift("a.csv", Channel::TipX, 1e-5, false),
            // Significant over a session's samples, but a tenth of a
            // millimetre: no finding.
            drift("a.csv", Channel::DotY(1), 1e-4, true),
            // Large, but a small part of what the model leaves: no finding.
            Drift {
                share: 0.2,
                ..drift("a.csv", Channel::DotY(2), 5e-3, true)
            },
            // Most of it, but the model leaves the channel far above its
            // noise beside it: no finding.
            Drift {
                left_per_residual: 40.0,
                ..drift("a.csv", Channel::Force, 5e-3, true)
            },
        ]);
        assert_eq!(found.len(), 1);
        let f = &found[0];
        assert_eq!((f.what.as_str(), f.channel.as_str()), ("drift", "dot1_y_m"));
        assert!((f.strength - 60.0).abs() < 1e-9, "{}", f.strength);
        assert!(
            f.detail.starts_with("dot1_y_m drifts by up to 3.000 mm (60.0× its noise) over 4.0 min (0.750 mm/min) in b.csv; in 2 of 3 recordings"),
            "{}",
            f.detail
        );
    }
}
