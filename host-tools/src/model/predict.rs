//! The one engine that runs the model over a recording's drive: used by
//! `finrs simulate` (every output on every row) and by the fit (only what
//! the recording measured, only where it measured it).

use model_core::{
    state_len, Circuit, Extensions, Fixture as CoreFixture, ParamError, Params, Strip,
};

use std::sync::Arc;

use super::{drying, kept_modes};
use crate::recording::{Channel, Fixture, Recording};

/// Elements per segment the engine supports (the seed uses 1).
pub const ELEMENTS: [usize; 3] = [1, 2, 4];

/// A whole model: the core's parameters, its optional terms, and the
/// dehydration rates that lower the moment gain and the circuit's
/// admittance over session time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelSpec {
    /// The seed's parameters (fitted or preset).
    pub params: Params,
    /// Optional terms (all off for the baseline).
    pub ext: Extensions,
    /// Dehydration: the moment gain falls at the rate `r`, 1/s, over
    /// session time `t` (see [`drying_gain`]).
    pub dehydration_per_s: f64,
    /// How drying slows as the strip loses its water, `c ≥ 0` (see
    /// [`drying_gain`]); 0 is a constant rate.
    pub dehydration_curvature: f64,
    /// Dehydration of the circuit: its admittance falls as
    /// `s = 1/(1 + r_c t)` over session time `t` (`C s`, `R1/s`, `R2/s`;
    /// see [`circuit_gain`]), 1/s. The layer's voltage is the same at any
    /// `s`, so the currents and the charge (and with it the moment) are
    /// `s` times the wet strip's.
    pub circuit_drying_per_s: f64,
    /// The bench read each row's currents before it applied the row's
    /// voltage (the finrs board samples at the start of a period, then
    /// drives): the currents are predicted under the previous row's
    /// voltage. Not the strip's but the recording's; the fit finds it in
    /// the data (`analysis::fit::sampling`).
    pub sensors_before_update: bool,
}

pub use super::drying::{circuit_gain, drying_gain};

impl ModelSpec {
    /// The baseline with these parameters.
    pub fn baseline(params: Params) -> ModelSpec {
        ModelSpec {
            params,
            ext: Extensions::NONE,
            dehydration_per_s: 0.0,
            dehydration_curvature: 0.0,
            circuit_drying_per_s: 0.0,
            sensors_before_update: false,
        }
    }
}

/// Model outputs over a recording's rows. Camera outputs are computed only
/// on the rows asked for (NaN elsewhere); the rest on every row.
#[derive(Clone, Debug, Default)]
pub struct Traces {
    /// Current per segment, A: `currents_a[segment][row]`.
    pub currents_a: Vec<Vec<f64>>,
    /// Tip across the strip, m.
    pub tip_y_m: Vec<f64>,
    /// Tip along the strip, m.
    pub tip_x_m: Vec<f64>,
    /// Dots across, m: `dots_y_m[dot][row]`.
    pub dots_y_m: Vec<Vec<f64>>,
    /// Dots along, m.
    pub dots_x_m: Vec<Vec<f64>>,
    /// Force on the load cell, N (zero for a free tip).
    pub force_n: Vec<f64>,
}

impl Traces {
    /// The trace that is `channel`'s prediction.
    pub fn channel(&self, channel: Channel) -> &[f64] {
        match channel {
            Channel::Current(k) => &self.currents_a[k],
            Channel::TipY => &self.tip_y_m,
            Channel::TipX => &self.tip_x_m,
            Channel::DotY(j) => &self.dots_y_m[j],
            Channel::DotX(j) => &self.dots_x_m[j],
            Channel::Force => &self.force_n,
        }
    }

    /// [`Traces::channel`], taken out (left empty).
    pub fn take_channel(&mut self, channel: Channel) -> Vec<f64> {
        std::mem::take(match channel {
            Channel::Current(k) => &mut self.currents_a[k],
            Channel::TipY => &mut self.tip_y_m,
            Channel::TipX => &mut self.tip_x_m,
            Channel::DotY(j) => &mut self.dots_y_m[j],
            Channel::DotX(j) => &mut self.dots_x_m[j],
            Channel::Force => &mut self.force_n,
        })
    }

    /// Empties the traces for a block of `rows` rows of `segments`
    /// segments and `dots` dots, keeping their room: the camera's rows NaN
    /// until computed (rows it does not sample stay so).
    fn start_block(&mut self, segments: usize, dots: usize, free: bool, rows: usize) {
        let camera_rows = if free { rows } else { 0 };
        let unsampled = |v: &mut Vec<f64>| {
            v.clear();
            v.resize(camera_rows, f64::NAN);
        };
        self.currents_a.resize_with(segments, Vec::new);
        for c in &mut self.currents_a {
            c.clear();
            c.reserve(rows);
        }
        unsampled(&mut self.tip_y_m);
        unsampled(&mut self.tip_x_m);
        for d in [&mut self.dots_y_m, &mut self.dots_x_m] {
            d.resize_with(dots, Vec::new);
            d.iter_mut().for_each(unsampled);
        }
        self.force_n.clear();
        self.force_n.reserve(if free { 0 } else { rows });
    }
}

/// Runs `spec` over the drive of `rec` (sample time `dt_s`), the recording
/// starting at session time `t_start_s`. `camera_rows[row]` says where to
/// compute the camera outputs; `None` means every row.
pub fn predict(
    rec: &Recording,
    spec: &ModelSpec,
    elements: usize,
    dt_s: f64,
    t_start_s: f64,
    camera_rows: Option<&[bool]>,
    progress: &mut dyn FnMut(u64),
) -> Result<Traces, PredictError> {
    let mut whole = Traces::default();
    // One block of every row: the traces as computed, taken, not copied.
    let rows = rec.t_s.len().max(1);
    let mut take = |_: usize, t: &mut Traces| whole = std::mem::take(t);
    predict_blocks(
        rec,
        spec,
        elements,
        (dt_s, t_start_s),
        camera_rows,
        (rows, &mut take),
        progress,
    )?;
    Ok(whole)
}

/// Hands out [`Traces`] a block at a time: `(first_row, traces)`.
pub type OnBlock<'a> = &'a mut dyn FnMut(usize, &mut Traces);

/// As [`predict`], the time given as `(dt_s, t_start_s)`, the traces
/// handed to `on_block(first_row, traces)` every `block_rows` rows
/// and for the rows left (at least once): each block's traces hold only
/// its rows. What writes a prediction as it is computed, never whole in
/// memory.
pub fn predict_blocks(
    rec: &Recording,
    spec: &ModelSpec,
    elements: usize,
    (dt_s, t_start_s): (f64, f64),
    camera_rows: Option<&[bool]>,
    (block_rows, on_block): (usize, OnBlock),
    progress: &mut dyn FnMut(u64),
) -> Result<(), PredictError> {
    let fixture = match rec.meta.fixture {
        Fixture::Free => CoreFixture::Free,
        Fixture::Blocked => CoreFixture::Blocked,
    };
    let mut run = Run {
        rec,
        spec,
        fixture,
        dt_s,
        t_start_s,
        camera_rows,
        block_rows: block_rows.max(1),
        on_block,
    };
    // One monomorphisation per (segments, elements): the core is fixed-size.
    macro_rules! dispatch {
        ($($n:literal),*) => {
            match (rec.meta.segments, elements) {
                $(
                    ($n, 1) => run.fastest::<$n, 1, { state_len($n, 1) }>(progress),
                    ($n, 2) => run.fastest::<$n, 2, { state_len($n, 2) }>(progress),
                    ($n, 4) => run.fastest::<$n, 4, { state_len($n, 4) }>(progress),
                )*
                (_, e) => return Err(PredictError::Elements(e)),
            }
        };
    }
    dispatch!(1, 2, 3, 4, 5, 6, 7, 8).map_err(PredictError::Model)
}

/// The currents alone, A (`[segment][row]`): the circuit of `spec` over
/// the drive of `rec` at sample time `dt_s`, the recording starting at
/// session time `t_start_s`, without the beam. The same
/// numbers as [`predict`]'s currents, bit for bit (the circuit is upstream
/// of the beam), at a fraction of the cost: what a fit of the circuit to
/// the currents runs.
pub fn predict_currents(
    rec: &Recording,
    spec: &ModelSpec,
    dt_s: f64,
    t_start_s: f64,
) -> Result<Vec<Vec<f64>>, PredictError> {
    fn go<const N: usize>(
        rec: &Recording,
        spec: &ModelSpec,
        dt_s: f64,
        t_start_s: f64,
    ) -> Result<Vec<Vec<f64>>, ParamError> {
        let circuit = Circuit::<f64, N>::new(&spec.params, &spec.ext, dt_s)?;
        let rows = rec.t_s.len();
        let mut out = vec![Vec::with_capacity(rows); N];
        let mut x = circuit.rest();
        let mut read_under = [0.0; N];
        let admittance = circuit_gains(spec, t_start_s, &rec.t_s);
        for (row, v_row) in rec.v_v.rows().enumerate() {
            let mut v = [0.0; N];
            v.copy_from_slice(&v_row[..N]);
            if !spec.sensors_before_update || row == 0 {
                read_under = v;
            }
            let s = admittance.as_ref().map_or(1.0, |g| g[row]);
            for (c, i) in out.iter_mut().zip(circuit.currents_a(&x, &read_under)) {
                c.push(s * i);
            }
            circuit.step(&mut x, &v);
            read_under = v;
        }
        Ok(out)
    }
    match rec.meta.segments {
        1 => go::<1>(rec, spec, dt_s, t_start_s),
        2 => go::<2>(rec, spec, dt_s, t_start_s),
        3 => go::<3>(rec, spec, dt_s, t_start_s),
        4 => go::<4>(rec, spec, dt_s, t_start_s),
        5 => go::<5>(rec, spec, dt_s, t_start_s),
        6 => go::<6>(rec, spec, dt_s, t_start_s),
        7 => go::<7>(rec, spec, dt_s, t_start_s),
        8 => go::<8>(rec, spec, dt_s, t_start_s),
        n => return Err(PredictError::Segments(n)),
    }
    .map_err(PredictError::Model)
}

/// The circuit's admittance gain ([`circuit_gain`]) on every row of a
/// recording starting at session time `t_start_s`; `None` where the
/// circuit does not dry.
fn circuit_gains(spec: &ModelSpec, t_start_s: f64, times_s: &[f64]) -> Option<Arc<[f64]>> {
    (spec.circuit_drying_per_s != 0.0).then(|| {
        drying::gains(
            spec.circuit_drying_per_s,
            drying::CIRCUIT_CURVATURE,
            t_start_s,
            times_s,
        )
    })
}

/// Why the engine refused.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// Unsupported mesh.
    #[error("elements per segment must be one of {ELEMENTS:?}, got {0}")]
    Elements(usize),
    /// More segments than the model has (the recording's reader refuses
    /// them first).
    #[error("segments must be 1 to 8, got {0}")]
    Segments(usize),
    /// The model refused its parameters.
    #[error("{0}")]
    Model(ParamError),
}

struct Run<'a> {
    rec: &'a Recording,
    spec: &'a ModelSpec,
    fixture: CoreFixture,
    dt_s: f64,
    t_start_s: f64,
    camera_rows: Option<&'a [bool]>,
    block_rows: usize,
    on_block: OnBlock<'a>,
}

impl Run<'_> {
    /// [`Self::go`] in the widest vectors this machine has: AVX2 where
    /// the x86-64 processor has it (four `f64` a lane where the baseline
    /// target has SSE2's two). The same operations in the same order, so
    /// the same numbers, bit for bit (Rust never fuses a multiply and an
    /// add on its own, and no `fma` is enabled); a blocked diagnosis
    /// steps the model in most of its time.
    fn fastest<const N: usize, const E: usize, const S: usize>(
        &mut self,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), ParamError> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2, checked just above.
            return unsafe { self.go_avx2::<N, E, S>(progress) };
        }
        self.go::<N, E, S>(progress)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn go_avx2<const N: usize, const E: usize, const S: usize>(
        &mut self,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), ParamError> {
        self.run::<N, E, S>(progress)
    }

    // Never inlined: the large meshes' work arrays (N = 8, E = 4) must not
    // swell the frame of every call.
    #[inline(never)]
    fn go<const N: usize, const E: usize, const S: usize>(
        &mut self,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), ParamError> {
        self.run::<N, E, S>(progress)
    }

    /// The run itself, inlined into [`Self::go`] and [`Self::go_avx2`]
    /// so that each is compiled for its own instructions.
    #[inline(always)]
    fn run<const N: usize, const E: usize, const S: usize>(
        &mut self,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), ParamError> {
        let spec = self.spec;
        let modes = kept_modes::modes_for::<N, E, S>(&spec.params, &spec.ext, self.fixture)?;
        let mut strip =
            Strip::<f64, N, E, S>::with_modes(&modes, &spec.params, &spec.ext, self.dt_s)?;
        let rows = self.rec.t_s.len();
        let dots: &[f64] = self.rec.meta.dots_s_m.as_deref().unwrap_or(&[]);
        let free = self.fixture == CoreFixture::Free;
        let mut t = Traces::default();
        let mut first = 0;
        t.start_block(N, dots.len(), free, self.block_rows.min(rows));
        let length_m = spec.params.length_m;
        // Without the large-deflection term the tip moves straight across
        // by its node's deflection: one dot product, where the general
        // `position_at_m` interpolates two nodes (at ξ = 1, up to rounding).
        let tip_is_node = !strip.extensions().large_deflection;
        let mut x = strip.rest();
        // The voltage the currents are read under: the row's, or with
        // `sensors_before_update` the one before (the first row's own).
        let mut read_under = [0.0; N];
        let drying = (spec.dehydration_per_s != 0.0).then(|| {
            drying::gains(
                spec.dehydration_per_s,
                spec.dehydration_curvature,
                self.t_start_s,
                &self.rec.t_s,
            )
        });
        let admittance = circuit_gains(spec, self.t_start_s, &self.rec.t_s);
        for (row, v_row) in self.rec.v_v.rows().enumerate() {
            // The row within its block.
            let i = row - first;
            let mut v = [0.0; N];
            v.copy_from_slice(&v_row[..N]);
            if !spec.sensors_before_update || row == 0 {
                read_under = v;
            }
            // The circuit's drying scales the charge, so the moment too.
            let s = admittance.as_ref().map_or(1.0, |g| g[row]);
            match (&drying, &admittance) {
                (Some(gains), _) => strip.set_moment_gain(gains[row] * s),
                (None, Some(_)) => strip.set_moment_gain(s),
                (None, None) => {}
            }
            // Outputs at this row's instant, then hold its voltage to the next.
            for (c, i) in t
                .currents_a
                .iter_mut()
                .zip(strip.currents_a(&x, &read_under))
            {
                c.push(s * i);
            }
            if free {
                if self.camera_rows.is_none_or(|c| c[row]) {
                    // Every node read once for the tip and all the dots;
                    // not at all for a lone tip node.
                    let shape = (!tip_is_node || !dots.is_empty()).then(|| strip.shape(&x));
                    let (along, across) = match &shape {
                        Some(shape) if !tip_is_node => {
                            shape.position_at_m(length_m).unwrap_or((0.0, 0.0))
                        }
                        _ => (0.0, strip.tip_deflection_m(&x)),
                    };
                    t.tip_x_m[i] = along;
                    t.tip_y_m[i] = across;
                    for (j, &s) in dots.iter().enumerate() {
                        let (along, across) = shape
                            .as_ref()
                            .and_then(|shape| shape.position_at_m(s))
                            .unwrap_or((f64::NAN, f64::NAN));
                        t.dots_x_m[j][i] = along;
                        t.dots_y_m[j][i] = across;
                    }
                }
            } else {
                t.force_n.push(strip.blocking_force_n(&x));
            }
            strip.step(&mut x, &v);
            read_under = v;
            if row % 4096 == 0 {
                progress(row as u64);
            }
            if i + 1 == self.block_rows {
                (self.on_block)(first, &mut t);
                first = row + 1;
                t.start_block(N, dots.len(), free, self.block_rows.min(rows - first));
            }
        }
        if first < rows || rows == 0 {
            (self.on_block)(first, &mut t);
        }
        progress(rows as u64);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::synth::{drive_recording_shaped, limits, Drive};
    use crate::wave::{Wave, WaveOptions};

    /// A 2 V step held 2 s, `fixture`, at 1 kHz.
    fn step(fixture: Fixture) -> Recording {
        let drive = Drive {
            segments: 3,
            fixture,
            rest_s: 0.5,
            duration_s: 2.0,
            off_s: 0.5,
            rate_hz: 1000.0,
        };
        drive_recording_shaped(
            &Wave::parse("step:2").unwrap(),
            &drive,
            &WaveOptions::steady(2.0),
            Some(limits(4.0, 200.0).unwrap()),
        )
        .unwrap()
    }

    #[test]
    fn a_drying_circuit_scales_the_currents_and_the_moment_by_its_gain() {
        let wet = ModelSpec::baseline(Params::baseline_air_example());
        let dry = ModelSpec {
            circuit_drying_per_s: 4e-3,
            ..wet
        };
        let t_start_s = 100.0;
        for fixture in [Fixture::Free, Fixture::Blocked] {
            let rec = step(fixture);
            let run = |spec: &ModelSpec| {
                predict(&rec, spec, 1, 1e-3, t_start_s, None, &mut |_| {}).unwrap()
            };
            let (w, d) = (run(&wet), run(&dry));
            for (row, &t) in rec.t_s.iter().enumerate() {
                let s = circuit_gain(4e-3, t_start_s + t);
                assert!(s < 0.72 && s > 0.70, "{s}");
                for k in 0..3 {
                    let (iw, id) = (w.currents_a[k][row], d.currents_a[k][row]);
                    assert!((id - s * iw).abs() <= 1e-12 * iw.abs().max(1e-9), "{row}");
                }
            }
            // The moment follows the charge: the force and the tip, to
            // within what the gain moves over the run (the beam and the
            // relaxation answer the gain of a moment before).
            let (mw, md) = match fixture {
                Fixture::Free => (&w.tip_y_m, &d.tip_y_m),
                Fixture::Blocked => (&w.force_n, &d.force_n),
            };
            let largest = mw.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let end_s = rec.t_s[rec.t_s.len() - 1];
            let moved = circuit_gain(4e-3, t_start_s) - circuit_gain(4e-3, t_start_s + end_s);
            assert!(largest > 0.0 && moved > 0.0 && moved < 0.01);
            for (row, &t) in rec.t_s.iter().enumerate() {
                let s = circuit_gain(4e-3, t_start_s + t);
                assert!(
                    (md[row] - s * mw[row]).abs() <= moved * largest,
                    "{row} {fixture:?}"
                );
            }
            // The circuit alone gives the same currents.
            let alone = predict_currents(&rec, &dry, 1e-3, t_start_s).unwrap();
            assert_eq!(alone, d.currents_a);
        }
    }
}
