//! What a fit compares: per recording, each measured channel at the rows
//! where it was sampled and no bench fault keeps it out, taken from its
//! opening rest, and its noise level.

use crate::analysis::median::median;
use crate::model::predict::Traces;
use crate::recording::Channel;
use crate::session::{Session, SessionRecording};

/// Noise classes: channels of one class share a sensor and its noise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sensor {
    /// DAQ current channels.
    Current,
    /// Camera, across the strip.
    CameraY,
    /// Camera, along the strip.
    CameraX,
    /// Load cell.
    Force,
}

impl Sensor {
    /// As reports name it.
    pub fn name(self) -> &'static str {
        match self {
            Sensor::Current => "currents",
            Sensor::CameraY => "camera across",
            Sensor::CameraX => "camera along",
            Sensor::Force => "load cell",
        }
    }

    /// The sensor of a channel.
    pub fn of(ch: Channel) -> Sensor {
        match ch {
            Channel::Current(_) => Sensor::Current,
            Channel::TipY | Channel::DotY(_) => Sensor::CameraY,
            Channel::TipX | Channel::DotX(_) => Sensor::CameraX,
            Channel::Force => Sensor::Force,
        }
    }

    /// Every sensor, in report order.
    pub const ALL: [Sensor; 4] = [
        Sensor::Current,
        Sensor::CameraY,
        Sensor::CameraX,
        Sensor::Force,
    ];
}

/// One channel of one recording, as the fit sees it.
#[derive(Clone, Debug)]
pub struct Target {
    /// The channel.
    pub channel: Channel,
    /// Rows where it was sampled, less those a bench fault keeps out.
    pub rows: Vec<usize>,
    /// Its values there, minus their mean over the opening rest.
    pub values: Vec<f64>,
    /// Noise level of its sensor (pooled over the session), in its unit.
    pub sigma: f64,
}

impl Target {
    /// The model's values at this target's rows.
    pub fn model<'a>(&'a self, t: &'a Traces) -> impl Iterator<Item = f64> + 'a {
        let series = t.channel(self.channel);
        self.rows.iter().map(move |&r| series[r])
    }
}

/// The targets of one recording.
#[derive(Clone, Debug)]
pub struct RecordingTargets {
    /// Index of the recording in its session.
    pub index: usize,
    /// Its channels.
    pub targets: Vec<Target>,
    /// Rows where any camera channel was sampled.
    pub camera_rows: Vec<bool>,
}

/// Targets of every recording of a session, with noise pooled per sensor.
#[derive(Clone, Debug)]
pub struct SessionTargets {
    /// Per recording, in session order.
    pub recordings: Vec<RecordingTargets>,
    /// Noise level per sensor (median over recordings of the rest's spread).
    pub sigma: Vec<(Sensor, f64)>,
    /// When the bench read its currents, from their steps.
    pub sampling: super::sampling::Sampling,
}

impl SessionTargets {
    /// Collects the targets of `session`.
    pub fn new(session: &Session) -> SessionTargets {
        let mut spreads: Vec<(Sensor, Vec<f64>)> =
            Sensor::ALL.iter().map(|&s| (s, Vec::new())).collect();
        let mut steps: Vec<(Sensor, Vec<f64>)> =
            Sensor::ALL.iter().map(|&s| (s, Vec::new())).collect();
        let mut recordings = Vec::new();
        for (index, r) in session.recordings.iter().enumerate() {
            let (targets, camera_rows) = targets_of(r, &mut spreads, &mut steps);
            recordings.push(RecordingTargets {
                index,
                targets,
                camera_rows,
            });
        }
        let mut sigma = Vec::new();
        for ((sensor, s), (_, q)) in spreads.into_iter().zip(steps) {
            // Never below the rounding of its own numbers: an ADC that
            // reads the same count at rest shows no spread there, yet
            // every reading is off by up to half a count (σ = step/√12).
            let rounding = median(q).unwrap_or(0.0) / 12f64.sqrt();
            if let Some(m) = median(s) {
                sigma.push((sensor, m.max(rounding)));
            }
        }
        // A tracker that reports the along-strip position as a constant
        // (no large deflection, no noise: a virtual camera, a tracker that
        // rounds) shows no spread at rest; with no scale at all, its
        // channels would get an infinite weight. The same camera's pixels
        // measure both axes: its across-strip spread stands in.
        let across = sigma
            .iter()
            .find(|(s, v)| *s == Sensor::CameraY && *v > 0.0)
            .map(|&(_, v)| v);
        if let Some(across) = across {
            match sigma.iter_mut().find(|(s, _)| *s == Sensor::CameraX) {
                Some((_, v)) if *v == 0.0 => *v = across,
                Some(_) => {}
                None => sigma.push((Sensor::CameraX, across)),
            }
        }
        for rt in &mut recordings {
            for t in &mut rt.targets {
                let sensor = Sensor::of(t.channel);
                let raw = sigma
                    .iter()
                    .find(|(s, _)| *s == sensor)
                    .map_or(0.0, |(_, v)| *v);
                // A noise-free channel still needs a scale: a millionth of
                // its range keeps the weights finite without inventing noise.
                let range = t.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                t.sigma = raw.max(1e-6 * range).max(f64::MIN_POSITIVE);
            }
        }
        SessionTargets {
            recordings,
            sigma,
            sampling: super::sampling::detect(session),
        }
    }
}

fn targets_of(
    r: &SessionRecording,
    spreads: &mut [(Sensor, Vec<f64>)],
    steps: &mut [(Sensor, Vec<f64>)],
) -> (Vec<Target>, Vec<bool>) {
    let rows_total = r.rec.t_s.len();
    let mut camera_rows = vec![false; rows_total];
    let mut targets = Vec::new();
    let sampled = |ch: Channel| {
        r.rec
            .channels
            .iter()
            .any(|(c, v)| *c == ch && v.iter().any(Option::is_some))
    };
    // A dot at the tip is the tip's own measurement on a real camera (the
    // same blob tracked twice): fitted beside the tip column it would count
    // the tip's misfit and noise twice, as if two sensors had seen it.
    let at_tip = |j: usize| {
        let meta = &r.rec.meta;
        meta.dots_s_m
            .as_ref()
            .and_then(|d| d.get(j))
            .is_some_and(|&s| (s - meta.length_m).abs() <= 1e-9 * meta.length_m)
    };
    for (ch, values) in &r.rec.channels {
        let duplicate = match *ch {
            Channel::DotY(j) => at_tip(j) && sampled(Channel::TipY),
            Channel::DotX(j) => at_tip(j) && sampled(Channel::TipX),
            _ => false,
        };
        if duplicate {
            continue;
        }
        // Where it was sampled, less what a bench fault keeps out (a
        // clipped run, a contact fault's stretch: `session::faults`).
        let kept_out = r.kept_out(*ch);
        let rows: Vec<usize> = (0..rows_total)
            .filter(|&i| values[i].is_some() && !kept_out[i])
            .collect();
        if rows.is_empty() {
            continue;
        }
        let mut vals: Vec<f64> = rows.iter().map(|&i| values[i].unwrap_or(0.0)).collect();
        let rest: Vec<f64> = rows
            .iter()
            .zip(&vals)
            .filter(|(&i, _)| i < r.rest_rows)
            .map(|(_, &v)| v)
            .collect();
        let mean = if rest.is_empty() {
            0.0
        } else {
            rest.iter().sum::<f64>() / rest.len() as f64
        };
        // Every channel from its own opening rest: the camera measures
        // from a rest shape that brushing can leave off by a fraction of a
        // millimetre, a load cell from its tare, a shunt amplifier from a
        // zero that wanders; the opening rest shows each (and the drift
        // since it is fitted beside the model: `drift.rs`).
        for v in &mut vals {
            *v -= mean;
        }
        if ch.is_camera() {
            for &i in &rows {
                camera_rows[i] = true;
            }
        }
        if let Some(step) = resolution(&vals) {
            if let Some((_, q)) = steps.iter_mut().find(|(s, _)| *s == Sensor::of(*ch)) {
                q.push(step);
            }
        }
        if rest.len() >= 2 {
            let var =
                rest.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (rest.len() - 1) as f64;
            let sensor = Sensor::of(*ch);
            if let Some((_, s)) = spreads.iter_mut().find(|(s, _)| *s == sensor) {
                s.push(var.sqrt());
            }
        }
        targets.push(Target {
            channel: *ch,
            rows,
            values: vals,
            sigma: 0.0,
        });
    }
    (targets, camera_rows)
}

/// The smallest step between the distinct values of `values`: the
/// resolution the sensor (or the file's digits) rounds to. `None` for a
/// constant channel.
fn resolution(values: &[f64]) -> Option<f64> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0.0)
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Recording;

    #[test]
    fn resolution_is_the_smallest_step() {
        assert_eq!(resolution(&[0.5, 0.0, 0.25, 0.5, 1.0]), Some(0.25));
        assert_eq!(resolution(&[2.0, 2.0]), None);
        assert_eq!(resolution(&[]), None);
    }

    /// A camera whose along-strip columns are all 0 (its x has neither
    /// noise nor motion) gets the across-strip noise level for them, not an
    /// infinite weight (which made `finrs diagnose` fail on a virtual
    /// bench's session with "b_nm_per_c_s must be finite").
    #[test]
    fn a_constant_camera_axis_borrows_the_other_axis_noise() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session");
        let dir = std::env::temp_dir().join(format!("finrs-const-x-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for entry in std::fs::read_dir(&src).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "csv") {
                let mut rec = Recording::read(&path).unwrap();
                for (ch, values) in &mut rec.channels {
                    if matches!(ch, Channel::TipX | Channel::DotX(_)) {
                        for v in values.iter_mut().flatten() {
                            *v = 0.0;
                        }
                    }
                }
                rec.write(&dir.join(path.file_name().unwrap())).unwrap();
            }
        }
        let session = Session::read(&dir).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let targets = SessionTargets::new(&session);
        let of = |sensor| targets.sigma.iter().find(|(s, _)| *s == sensor).unwrap().1;
        assert!(of(Sensor::CameraY) > 1e-6, "{:?}", targets.sigma);
        assert_eq!(of(Sensor::CameraX), of(Sensor::CameraY));
        for rt in &targets.recordings {
            for t in &rt.targets {
                assert!(
                    t.sigma.is_finite() && t.sigma > 1e-9,
                    "{:?}: {}",
                    t.channel,
                    t.sigma
                );
            }
        }
    }
}
