//! `finrs simulate`: what the model predicts for a recording's drive.
//!
//! The prediction is itself a recording of the same fixture, so measured
//! and simulated files are read by the same code: currents on every row,
//! and for a free tip the camera channels (tip and any tracked dots), for a
//! blocked tip the load cell's force.

use std::path::Path;

use super::predict::{predict, predict_blocks, ModelSpec, PredictError, Traces};
use crate::recording::{
    Channel, Column, Fixture, Metadata, Recording, RecordingError, RecordingView, SampleTimeError,
    Streamed,
};

/// Rows simulated, checked and written at a time by [`write_prediction`]:
/// the prediction's memory (five channels of 4096 rows: 160 KB), for a
/// recording of any length.
pub const WRITE_BLOCK_ROWS: usize = 4096;

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
    /// The prediction could not be written (the error names the file).
    #[error(transparent)]
    Write(#[from] RecordingError),
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
    let (dt_s, t_start_s) = clock(name, input)?;
    let mut traces = predict(input, model, elements, dt_s, t_start_s, None, progress)
        .map_err(|source| model_error(name, source))?;
    let meta = predicted_meta(name, input, elements);
    let channels = predicted_channels(&input.meta)
        .into_iter()
        .map(|c| (c, traces.take_channel(c)))
        .collect();
    Ok(Prediction {
        input,
        meta,
        channels,
    })
}

/// Simulates the drive of `input` as [`predict_recording`] does and writes
/// the prediction to `path` as it is computed, [`WRITE_BLOCK_ROWS`] rows
/// at a time: the same text and checks as [`Prediction::write`], but never
/// the whole prediction in memory. With `keep`, also returns it whole (to
/// plot it). A refusal leaves the file as it was.
pub fn write_prediction<'a>(
    name: &str,
    input: &'a Recording,
    model: &ModelSpec,
    elements: usize,
    (path, keep): (&Path, bool),
    progress: &mut dyn FnMut(u64),
) -> Result<Option<Prediction<'a>>, SimulateError> {
    let (dt_s, t_start_s) = clock(name, input)?;
    let meta = predicted_meta(name, input, elements);
    let channels = predicted_channels(&input.meta);
    let mut out = Streamed::create(path, &meta, &input.t_s, &input.v_v, &channels)?;
    let mut kept: Vec<Vec<f64>> = vec![Vec::new(); if keep { channels.len() } else { 0 }];
    let mut failed = None;
    let mut on_block = |_: usize, traces: &mut Traces| {
        if failed.is_some() {
            return;
        }
        let block: Vec<&[f64]> = channels.iter().map(|&c| traces.channel(c)).collect();
        if let Err(e) = out.rows(&block) {
            failed = Some(e);
        }
        for (all, &c) in kept.iter_mut().zip(&channels) {
            all.extend_from_slice(traces.channel(c));
        }
    };
    predict_blocks(
        input,
        model,
        elements,
        (dt_s, t_start_s),
        None,
        (WRITE_BLOCK_ROWS, &mut on_block),
        progress,
    )
    .map_err(|source| model_error(name, source))?;
    if let Some(e) = failed {
        return Err(e.into());
    }
    out.finish()?;
    Ok(keep.then(|| Prediction {
        input,
        meta,
        channels: channels.into_iter().zip(kept).collect(),
    }))
}

/// The sample time of `input` and the session time it starts at (its
/// `t_session_start_s`, the dehydration clock; without one 0).
fn clock(name: &str, input: &Recording) -> Result<(f64, f64), SimulateError> {
    let dt_s = input
        .sample_time()
        .map_err(|source| SimulateError::Timing {
            name: name.to_string(),
            source,
        })?;
    Ok((dt_s, input.meta.session_start_s().unwrap_or(0.0)))
}

fn model_error(name: &str, source: PredictError) -> SimulateError {
    SimulateError::Model {
        name: name.to_string(),
        source,
    }
}

/// The input's metadata with a note saying what simulated it.
fn predicted_meta(name: &str, input: &Recording, elements: usize) -> Metadata {
    let mut meta = input.meta.clone();
    meta.notes = Some(format!(
        "simulated by finrs {} ({} element(s) per segment) from {name}",
        env!("CARGO_PKG_VERSION"),
        elements
    ));
    meta
}

/// The channels a prediction holds, in the order they are written:
/// currents on every row, and for a free tip the camera channels (tip and
/// any tracked dots), for a blocked tip the load cell's force.
fn predicted_channels(meta: &Metadata) -> Vec<Channel> {
    let mut channels: Vec<Channel> = (0..meta.segments).map(Channel::Current).collect();
    match meta.fixture {
        Fixture::Free => {
            channels.extend([Channel::TipY, Channel::TipX]);
            for j in 0..meta.dots_s_m.as_ref().map_or(0, Vec::len) {
                channels.extend([Channel::DotY(j), Channel::DotX(j)]);
            }
        }
        Fixture::Blocked => channels.push(Channel::Force),
    }
    channels
}
