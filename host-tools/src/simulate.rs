//! `finrs simulate`: what the model predicts for a recording's drive.
//!
//! The prediction is itself a recording of the same fixture, so measured
//! and simulated files are read by the same code: currents on every row,
//! and for a free tip the camera channels (tip and any tracked dots), for a
//! blocked tip the load cell's force.

use crate::predict::{predict, ModelSpec, PredictError};
use crate::recording::{Channel, Fixture, Recording};

pub use crate::predict::ELEMENTS;

/// Why a simulation was refused.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The recording's rows are not evenly spaced.
    #[error("{name}: row {row} (t = {t_s} s): simulation needs evenly spaced rows, Δt = {dt_s} s here against {dt0_s} s at the start")]
    UnevenTime {
        /// The recording.
        name: String,
        /// 0-based data row.
        row: usize,
        /// Its time, s.
        t_s: f64,
        /// Its interval, s.
        dt_s: f64,
        /// The first interval, s.
        dt0_s: f64,
    },
    /// Fewer than two rows: no sample time.
    #[error("{name}: simulation needs at least two rows to know the sample time")]
    TooShort {
        /// The recording.
        name: String,
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
    let dt_s = sample_time(name, &input.t_s)?;
    let t_start_s = crate::session::session_start_s(&input.meta).unwrap_or(0.0);
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

/// The recording's sample time; rows must be evenly spaced to 0.1 %.
pub(crate) fn sample_time(name: &str, t_s: &[f64]) -> Result<f64, SimulateError> {
    if t_s.len() < 2 {
        return Err(SimulateError::TooShort {
            name: name.to_string(),
        });
    }
    let dt0_s = t_s[1] - t_s[0];
    for (row, w) in t_s.windows(2).enumerate() {
        let dt_s = w[1] - w[0];
        if (dt_s - dt0_s).abs() > 1e-3 * dt0_s {
            return Err(SimulateError::UnevenTime {
                name: name.to_string(),
                row: row + 1,
                t_s: w[1],
                dt_s,
                dt0_s,
            });
        }
    }
    // The mean interval, so rounding in printed times does not accumulate.
    Ok((t_s[t_s.len() - 1] - t_s[0]) / (t_s.len() - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uneven_rows_are_named() {
        let err = sample_time("r.csv", &[0.0, 0.001, 0.002, 0.0035]).unwrap_err();
        assert!(
            err.to_string().starts_with("r.csv: row 3 (t = 0.0035 s)"),
            "{err}"
        );
        assert!(sample_time("r.csv", &[0.0]).is_err());
        let dt = sample_time("r.csv", &[0.0, 0.001, 0.002, 0.003]).unwrap();
        assert!((dt - 0.001).abs() < 1e-15);
    }
}
