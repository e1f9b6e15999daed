//! `finrs simulate`: what the model predicts for a recording's drive.
//!
//! The prediction is itself a recording of the same fixture, so measured
//! and simulated files are read by the same code: currents on every row,
//! and for a free tip the camera channels (tip and any tracked dots), for a
//! blocked tip the load cell's force.

use model_core::{state_len, Fixture as CoreFixture, Params, Strip};

use crate::recording::{Channel, Fixture, Recording};

/// Elements per segment the simulator supports (the seed uses 1).
pub const ELEMENTS: [usize; 3] = [1, 2, 4];

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
    /// Unsupported mesh.
    #[error("elements per segment must be one of {ELEMENTS:?}, got {0}")]
    Elements(usize),
    /// The model refused its parameters.
    #[error("{name}: {source}")]
    Model {
        /// The recording.
        name: String,
        /// The rule broken.
        source: model_core::ParamError,
    },
}

/// Model outputs for every row of a recording.
struct Traces {
    currents_a: Vec<Vec<f64>>,
    tip_m: Vec<f64>,
    force_n: Vec<f64>,
    dots_m: Vec<Vec<f64>>,
}

/// Simulates the drive of `input` with `params`, `elements` per segment,
/// calling `progress(rows_done)` now and then.
pub fn simulate(
    name: &str,
    input: &Recording,
    params: &Params,
    elements: usize,
    progress: &mut dyn FnMut(u64),
) -> Result<Recording, SimulateError> {
    let dt_s = sample_time(name, &input.t_s)?;
    let fixture = match input.meta.fixture {
        Fixture::Free => CoreFixture::Free,
        Fixture::Blocked => CoreFixture::Blocked,
    };
    let dots: Vec<f64> = input.meta.dots_s_m.clone().unwrap_or_default();
    let model_err = |source| SimulateError::Model {
        name: name.to_string(),
        source,
    };
    // One monomorphisation per (segments, elements): the core is fixed-size.
    macro_rules! dispatch {
        ($($n:literal),*) => {
            match (input.meta.segments, elements) {
                $(
                    ($n, 1) => run::<$n, 1, { state_len($n, 1) }>(input, params, fixture, dt_s, &dots, progress),
                    ($n, 2) => run::<$n, 2, { state_len($n, 2) }>(input, params, fixture, dt_s, &dots, progress),
                    ($n, 4) => run::<$n, 4, { state_len($n, 4) }>(input, params, fixture, dt_s, &dots, progress),
                )*
                (_, e) => return Err(SimulateError::Elements(e)),
            }
        };
    }
    let traces = dispatch!(1, 2, 3, 4, 5, 6, 7, 8).map_err(model_err)?;

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
    for (k, c) in traces.currents_a.into_iter().enumerate() {
        out.channels
            .push((Channel::Current(k), c.into_iter().map(Some).collect()));
    }
    match fixture {
        CoreFixture::Free => {
            let zeros = vec![Some(0.0); out.t_s.len()];
            out.channels
                .push((Channel::TipY, traces.tip_m.into_iter().map(Some).collect()));
            // Small-deflection kinematics: nothing moves along the strip.
            out.channels.push((Channel::TipX, zeros.clone()));
            for (j, d) in traces.dots_m.into_iter().enumerate() {
                out.channels
                    .push((Channel::DotY(j), d.into_iter().map(Some).collect()));
                out.channels.push((Channel::DotX(j), zeros.clone()));
            }
        }
        CoreFixture::Blocked => {
            out.channels.push((
                Channel::Force,
                traces.force_n.into_iter().map(Some).collect(),
            ));
        }
    }
    Ok(out)
}

/// The recording's sample time; rows must be evenly spaced to 0.1 %.
fn sample_time(name: &str, t_s: &[f64]) -> Result<f64, SimulateError> {
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

fn run<const N: usize, const E: usize, const S: usize>(
    input: &Recording,
    params: &Params,
    fixture: CoreFixture,
    dt_s: f64,
    dots: &[f64],
    progress: &mut dyn FnMut(u64),
) -> Result<Traces, model_core::ParamError> {
    let strip = Strip::<f64, N, E, S>::new(params, fixture, dt_s)?;
    let rows = input.t_s.len();
    let mut t = Traces {
        currents_a: vec![Vec::with_capacity(rows); N],
        tip_m: Vec::with_capacity(rows),
        force_n: Vec::with_capacity(rows),
        dots_m: vec![Vec::with_capacity(rows); dots.len()],
    };
    let mut x = strip.rest();
    for (row, v_row) in input.v_v.iter().enumerate() {
        let mut v = [0.0; N];
        v.copy_from_slice(&v_row[..N]);
        // Outputs at this row's instant, then hold its voltage to the next.
        for (c, i) in t.currents_a.iter_mut().zip(strip.currents_a(&x, &v)) {
            c.push(i);
        }
        t.tip_m.push(strip.tip_deflection_m(&x));
        t.force_n.push(strip.blocking_force_n(&x));
        for (d, &s) in t.dots_m.iter_mut().zip(dots) {
            d.push(strip.deflection_at_m(&x, s).unwrap_or(f64::NAN));
        }
        strip.step(&mut x, &v);
        if row % 4096 == 0 {
            progress(row as u64);
        }
    }
    progress(rows as u64);
    Ok(t)
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
