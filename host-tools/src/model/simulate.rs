//! `finrs simulate`: what the model predicts for a recording's drive.
//!
//! The prediction is itself a recording of the same fixture, so measured
//! and simulated files are read by the same code: currents on every row,
//! and for a free tip the camera channels (tip and any tracked dots), for a
//! blocked tip the load cell's force.

use std::path::Path;

use super::predict::{predict, ModelSpec, PredictError};
use crate::recording::{
    Channel, Column, Fixture, Metadata, Recording, RecordingError, RecordingView, SampleTimeError,
};

pub use super::predict::ELEMENTS;

/// Why a simulation was refused. Each variant says which recording; the
/// rule broken is its `source()`, which the binary prints after it.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The recording has no single sample time.
    #[error("{name}")]
    Timing {
        /// The recording.
        name: String,
        /// The rule broken.
        source: SampleTimeError,
    },
    /// The engine refused the model or the mesh.
    #[error("{name}")]
    Model {
        /// The recording.
        name: String,
        /// The rule broken.
        source: PredictError,
    },
}

/// A simulation's output: a recording of the same fixture whose time and
/// drive are the input's, borrowed, and whose channels are the model's
/// traces, held as computed (a value on every row). Written as it is, or
/// made a [`Recording`] when one is needed whole (to plot it).
#[derive(Clone, Debug)]
pub struct Prediction<'a> {
    /// The recording simulated.
    pub input: &'a Recording,
    /// The input's metadata with a note saying what simulated it.
    pub meta: Metadata,
    /// Predicted channels in the order they are written.
    pub channels: Vec<(Channel, Vec<f64>)>,
}

impl Prediction<'_> {
    /// The prediction's parts, borrowed, to check and write.
    pub fn view(&self) -> RecordingView<'_> {
        RecordingView {
            meta: &self.meta,
            t_s: &self.input.t_s,
            v_v: &self.input.v_v,
            channels: self
                .channels
                .iter()
                .map(|(c, v)| (*c, Column::Every(v)))
                .collect(),
        }
    }

    /// Checks and writes the prediction to `path` (see [`Recording::write`]).
    pub fn write(&self, path: &Path) -> Result<(), RecordingError> {
        self.view().write(path)
    }

    /// Rows predicted.
    pub fn rows(&self) -> usize {
        self.input.t_s.len()
    }

    /// The prediction as a recording of its own (copies time, drive and
    /// channels).
    pub fn to_recording(&self) -> Recording {
        Recording {
            meta: self.meta.clone(),
            t_s: self.input.t_s.clone(),
            v_v: self.input.v_v.clone(),
            channels: self
                .channels
                .iter()
                .map(|(c, v)| (*c, v.iter().copied().map(Some).collect()))
                .collect(),
        }
    }
}

/// Simulates the drive of `input` with `model`, `elements` per segment,
/// calling `progress(rows_done)` now and then: [`predict_recording`] made
/// a recording of its own.
pub fn simulate(
    name: &str,
    input: &Recording,
    model: &ModelSpec,
    elements: usize,
    progress: &mut dyn FnMut(u64),
) -> Result<Recording, SimulateError> {
    predict_recording(name, input, model, elements, progress).map(|p| p.to_recording())
}

/// Simulates the drive of `input` with `model`, `elements` per segment,
/// calling `progress(rows_done)` now and then. The recording's session
/// start time (its `notes`, `t_session_start_s = …`) sets the dehydration
/// clock; without one it starts at 0.
pub fn predict_recording<'a>(
    name: &str,
    input: &'a Recording,
    model: &ModelSpec,
    elements: usize,
    progress: &mut dyn FnMut(u64),
) -> Result<Prediction<'a>, SimulateError> {
    let dt_s = input
        .sample_time()
        .map_err(|source| SimulateError::Timing {
            name: name.to_string(),
            source,
        })?;
    let t_start_s = input.meta.session_start_s().unwrap_or(0.0);
    let traces =
        predict(input, model, elements, dt_s, t_start_s, None, progress).map_err(|source| {
            SimulateError::Model {
                name: name.to_string(),
                source,
            }
        })?;

    let mut meta = input.meta.clone();
    meta.notes = Some(format!(
        "simulated by finrs {} ({} element(s) per segment) from {name}",
        env!("CARGO_PKG_VERSION"),
        elements
    ));
    let mut channels = Vec::new();
    for (k, c) in traces.currents_a.into_iter().enumerate() {
        channels.push((Channel::Current(k), c));
    }
    match input.meta.fixture {
        Fixture::Free => {
            channels.push((Channel::TipY, traces.tip_y_m));
            channels.push((Channel::TipX, traces.tip_x_m));
            for (j, (y, x)) in traces.dots_y_m.into_iter().zip(traces.dots_x_m).enumerate() {
                channels.push((Channel::DotY(j), y));
                channels.push((Channel::DotX(j), x));
            }
        }
        Fixture::Blocked => channels.push((Channel::Force, traces.force_n)),
    }
    Ok(Prediction {
        input,
        meta,
        channels,
    })
}
