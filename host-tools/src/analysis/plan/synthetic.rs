//! A proposed recording as the fitted model says it would come out: the
//! protocol step's drive, the model's outputs on the channels the session
//! already records (the camera at its frame rate), and the session's own
//! noise per sensor, so that the identifiability of a session with it
//! added is read as the diagnosis would read a real one.

use std::path::Path;

use finrs_firmware_support::sim::xorshift32;

use crate::analysis::fit::{Sensor, FIT_ELEMENTS};
use crate::model::predict::ModelSpec;
use crate::model::simulate::predict_recording;
use crate::model::synth::{self, DriveError};
use crate::protocol::Step;
use crate::recording::{Channel, Recording};
use crate::session::{Session, SessionError, SessionRecording};
use crate::wave::{Wave, WaveError, WaveOptions};

/// Why a proposed recording could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SyntheticError {
    /// The step's wave does not parse.
    #[error("proposed recording {name}")]
    Wave {
        /// The step.
        name: String,
        /// Why.
        source: WaveError,
    },
    /// The drive could not be generated.
    #[error("proposed recording {name}")]
    Drive {
        /// The step.
        name: String,
        /// Why.
        source: DriveError,
    },
    /// The model refused the drive.
    #[error("proposed recording {name}")]
    Simulate {
        /// The step.
        name: String,
        /// Why.
        source: crate::model::simulate::SimulateError,
    },
    /// The recording breaks a session's rules (its rest, its timing).
    #[error("proposed recording {name}")]
    Session {
        /// The step.
        name: String,
        /// Why.
        source: SessionError,
    },
    /// The session has no recording to take the metadata from.
    #[error("the session has no recordings")]
    Empty,
}

/// The noise to add: one standard deviation per sensor, in its SI unit.
pub type Noise = [(Sensor, f64)];

/// `step` recorded on the session's strip as `spec` predicts it, starting
/// at session time `t_start_s` (when the session has a clock), with
/// white noise of `noise` drawn from `seed`. The channels and camera
/// frames follow the session's first recording of the same fixture (or
/// its first recording, with the fixture's own sensor).
pub fn recording(
    session: &Session,
    step: &Step,
    spec: &ModelSpec,
    noise: &Noise,
    t_start_s: Option<f64>,
    seed: u32,
) -> Result<SessionRecording, SyntheticError> {
    let name = format!("plan_{}.csv", step.name);
    let template = session
        .recordings
        .iter()
        .find(|r| r.rec.meta.fixture == step.fixture)
        .or(session.recordings.first())
        .ok_or(SyntheticError::Empty)?;
    let wave = Wave::parse(&step.wave).map_err(|source| SyntheticError::Wave {
        name: name.clone(),
        source,
    })?;
    let meta = &template.rec.meta;
    let drive = synth::Drive {
        segments: meta.segments,
        fixture: step.fixture,
        rest_s: step.rest_s,
        duration_s: step.hold_s,
        off_s: step.off_s,
        rate_hz: (1.0 / template.dt_s).round(),
    };
    let options = WaveOptions {
        hold_s: step.hold_s,
        ..WaveOptions::steady(step.hold_s)
    };
    let drive_error = |source| SyntheticError::Drive {
        name: name.clone(),
        source,
    };
    let mut input =
        synth::drive_recording_shaped(&wave, &drive, &options, None).map_err(drive_error)?;
    input.meta = meta.clone();
    input.meta.fixture = step.fixture;
    input.meta.t_session_start_s = t_start_s;
    input.meta.notes = Some(format!(
        "proposed by finrs plan, as the fitted model predicts it: {}",
        step.wave
    ));
    let predicted =
        predict_recording(&name, &input, spec, FIT_ELEMENTS, &mut |_| {}).map_err(|source| {
            SyntheticError::Simulate {
                name: name.clone(),
                source,
            }
        })?;

    // The channels the session records for this fixture, the camera at its
    // own frames.
    let frame_step = camera_frame_step(&template.rec);
    let mut rng = seed.max(1);
    let mut channels = Vec::new();
    for (ch, measured) in &template.rec.channels {
        let Some((_, values)) = predicted.channels.iter().find(|(c, _)| c == ch) else {
            continue;
        };
        // A channel that shows no spread at rest in the session (a
        // tracker reporting the along position as a constant) stays so.
        let sigma = if still_at_rest(measured, template.rest_rows) {
            0.0
        } else {
            noise
                .iter()
                .find(|(s, _)| *s == Sensor::of(*ch))
                .map_or(0.0, |&(_, v)| v)
        };
        let camera = !matches!(ch, Channel::Current(_) | Channel::Force);
        let column = values
            .iter()
            .enumerate()
            .map(|(row, &y)| {
                (!camera || row % frame_step == 0).then(|| y + sigma * gaussian(&mut rng))
            })
            .collect();
        channels.push((*ch, column));
    }
    let rec = Recording { channels, ..input };
    Session::prepare(Path::new(&name), rec).map_err(|source| SyntheticError::Session {
        name: name.clone(),
        source,
    })
}

/// Rows between camera frames in `rec`: the smallest spacing of its first
/// camera channel's samples (1 where every row is sampled or none is).
fn camera_frame_step(rec: &Recording) -> usize {
    let Some((_, values)) = rec
        .channels
        .iter()
        .find(|(c, _)| !matches!(c, Channel::Current(_) | Channel::Force))
    else {
        return 1;
    };
    let rows: Vec<usize> = (0..values.len()).filter(|&i| values[i].is_some()).collect();
    rows.windows(2)
        .map(|w| w[1] - w[0])
        .min()
        .unwrap_or(1)
        .max(1)
}

/// Whether every sample of `values` in the first `rest_rows` rows is the
/// same number.
fn still_at_rest(values: &[Option<f64>], rest_rows: usize) -> bool {
    let mut rest = values.iter().take(rest_rows).flatten();
    let first = rest.next();
    first.is_some_and(|&a| rest.all(|&b| b == a))
}

/// A standard normal draw (Box–Muller on two uniforms of the shared
/// xorshift generator, never 0 for the logarithm).
fn gaussian(state: &mut u32) -> f64 {
    let mut uniform = || (f64::from(xorshift32(state)) + 0.5) / (f64::from(u32::MAX) + 1.0);
    let (u, v) = (uniform(), uniform());
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::fit::Fitter;
    use crate::analysis::plan::candidates;
    use crate::model::params::ModelFile;

    #[test]
    fn a_proposed_recording_has_the_sessions_channels_frames_and_noise() {
        let session =
            Session::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session"))
                .unwrap();
        let fitter = Fitter::new(&session);
        let noise = fitter.targets().sigma.clone();
        let spec = ModelFile::main_m_2006()
            .spec_for(&session.geometry())
            .unwrap();
        let c = &candidates(&session, &spec)[0];
        let r = recording(&session, &c.step, &spec, &noise, Some(100.0), 3).unwrap();
        assert_eq!(r.t_start_s, Some(100.0));
        assert!((r.dt_s - session.recordings[0].dt_s).abs() < 1e-12);
        let template = &session.recordings[0].rec;
        let names =
            |rec: &Recording| -> Vec<Channel> { rec.channels.iter().map(|(c, _)| *c).collect() };
        assert_eq!(names(&r.rec), names(template));
        // The camera at the session's frame rate.
        let frames = |rec: &Recording| {
            rec.channels
                .iter()
                .find(|(c, _)| *c == Channel::TipY)
                .unwrap()
                .1
                .iter()
                .flatten()
                .count() as f64
                / rec.t_s.len() as f64
        };
        assert!((frames(&r.rec) / frames(template) - 1.0).abs() < 0.05);
        // Its rest shows the session's noise, and the session's noise
        // levels stay what they were with it added.
        let (_, i1) = r
            .rec
            .channels
            .iter()
            .find(|(c, _)| *c == Channel::Current(0))
            .unwrap();
        let rest: Vec<f64> = i1[..r.rest_rows].iter().flatten().copied().collect();
        let mean = rest.iter().sum::<f64>() / rest.len() as f64;
        let sd = (rest.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / rest.len() as f64).sqrt();
        let sigma = noise.iter().find(|(s, _)| *s == Sensor::Current).unwrap().1;
        assert!((sd / sigma - 1.0).abs() < 0.15, "{sd} against {sigma}");
        let mut more = session.clone();
        more.recordings.push(r);
        for &(sensor, before) in &noise {
            let after = Fitter::new(&more)
                .targets()
                .sigma
                .iter()
                .find(|(s, _)| *s == sensor)
                .unwrap()
                .1;
            assert!(
                (after / before - 1.0).abs() < 0.1,
                "{sensor:?}: {before} -> {after}"
            );
        }
    }

    #[test]
    fn draws_are_standard_normal() {
        let mut s = 7;
        let x: Vec<f64> = (0..200_000).map(|_| gaussian(&mut s)).collect();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        assert!(x.iter().all(|v| v.is_finite()));
    }
}
