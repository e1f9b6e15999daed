//! `finrs simulate`: what the model predicts for a recording's drive.
//!
//! The prediction is itself a recording of the same fixture, so measured
//! and simulated files are read by the same code: currents on every row,
//! and for a free tip the camera channels (tip and any tracked dots), for a
//! blocked tip the load cell's force.

use super::predict::{predict, ModelSpec, PredictError};
use crate::recording::{Channel, Fixture, Recording, SampleTimeError};

pub use super::predict::ELEMENTS;

/// Why a simulation was refused.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The recording has no single sample time.
    #[error("{name}: {source}")]
    Timing {
        /// The recording.
        name: String,
        /// The rule broken.
        source: SampleTimeError,
    },
    /// The engine refused the model or the mesh.
    #[error("{name}: {source}")]
    Model {
        /// The recording.
        name: String,
        /// The rule broken.
        source: PredictError,
    },
}

/// Simulates the drive of `input` with `model`, `elements` per segment,
/// calling `progress(rows_done)` now and then. The recording's session
/// start time (its `notes`, `t_session_start_s = …`) sets the dehydration
/// clock; without one it starts at 0.
pub fn simulate(
    name: &str,
    input: &Recording,
    model: &ModelSpec,
    elements: usize,
    progress: &mut dyn FnMut(u64),
) -> Result<Recording, SimulateError> {
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

    let mut out = Recording {
        meta: input.meta.clone(),
        t_s: input.t_s.clone(),
        v_v: input.v_v.clone(),
        channels: Vec::new(),
    };
    out.meta.notes = Some(format!(
        "simulated by finrs {} ({} element(s) per segment) from {name}",
        env!("CARGO_PKG_VERSION"),
        elements
    ));
    let some = |v: Vec<f64>| v.into_iter().map(Some).collect::<Vec<_>>();
    for (k, c) in traces.currents_a.into_iter().enumerate() {
        out.channels.push((Channel::Current(k), some(c)));
    }
    match input.meta.fixture {
        Fixture::Free => {
            out.channels.push((Channel::TipY, some(traces.tip_y_m)));
            out.channels.push((Channel::TipX, some(traces.tip_x_m)));
            for (j, (y, x)) in traces.dots_y_m.into_iter().zip(traces.dots_x_m).enumerate() {
                out.channels.push((Channel::DotY(j), some(y)));
                out.channels.push((Channel::DotX(j), some(x)));
            }
        }
        Fixture::Blocked => out.channels.push((Channel::Force, some(traces.force_n))),
    }
    Ok(out)
}
