//! `finrs calibrate`: measures the board's sensors through its own stream
//! and stores the result in its flash with a SetCalibration, then checks
//! the Info frame the board sends back.
//!
//! - Shunt zeros: with every output at 0 V (a Stop first), each segment's
//!   mean current over the window, in counts, moves its zero. Refused
//!   while the currents still drift (a strip discharging through the
//!   bridge): the window's first and second halves must agree.
//! - Load-cell scale: the force with no load (after a Tare) and with a
//!   reference load of known weight; the scale is rescaled so that the
//!   difference reads the reference. Refused when the difference is not
//!   clearly above the noise.
//!
//! Means and their standard errors come from block means (ten blocks per
//! window), so that coloured noise and hum do not make them look surer
//! than they are. Averaging windows count samples at the board's rate
//! (its Info frame), so that the procedure does not depend on the host's
//! clock; only the wait for an answer is wall-clock.

use std::time::{Duration, Instant};

use finrs_frames::{
    Calibration, CalibrationOrigin, Command, DecodedSample, Event, Info, ModelRecord, SampleFlags,
};

pub use crate::link::board::Board;
use crate::link::board::Frames;
use crate::link::capture::Silent;
use crate::link::probe::ProbeError;

/// Standard gravity, m/s² (a reference mass's weight unless the local
/// value is given).
pub const STANDARD_GRAVITY_M_PER_S2: f64 = 9.80665;

/// Blocks a window is cut into for the standard error of its mean.
const BLOCKS: usize = 10;

/// A drift between a window's halves larger than this many standard errors
/// (and than half a count) is a reading that has not settled.
const DRIFT_SIGMAS: f64 = 4.0;

/// A load difference must exceed its standard error this many times.
const LOAD_SIGMAS: f64 = 20.0;

/// How long to wait and average.
#[derive(Clone, Copy, Debug)]
pub struct CalibrateOptions {
    /// Longest wait for an answer (an Info, enough samples), wall-clock.
    pub timeout: Duration,
    /// Samples at 0 V to skip before averaging the shunts, s of the
    /// board's clock.
    pub settle_s: f64,
    /// Averaging window, s of the board's clock.
    pub average_s: f64,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(30),
            settle_s: 1.0,
            average_s: 2.0,
        }
    }
}

/// Why a calibration was not measured or not stored.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// The probe failed.
    #[error(transparent)]
    Probe(#[from] ProbeError),
    /// Nothing came in time.
    #[error("no {what} from the board within {timeout_s} s (is the firmware running, and is it this board's?)")]
    Timeout {
        /// What was awaited.
        what: &'static str,
        /// The wait, s.
        timeout_s: f64,
    },
    /// A fault is latched: the readings are not the sensors'.
    #[error("the board has a fault latched (seq {seq}): clear it (finrs clear-fault) and find its cause first")]
    Faulted {
        /// The Fault frame's sequence number.
        seq: u32,
    },
    /// A reading still drifts.
    #[error("{what} still drifts: {drift:.1} counts between the halves of the {window_s} s window (standard error {se:.2}); wait, or disconnect the strip, and try again")]
    Drifting {
        /// Which reading.
        what: String,
        /// Second half's mean minus the first's, counts.
        drift: f64,
        /// Its standard error, counts.
        se: f64,
        /// The window, s.
        window_s: f64,
    },
    /// The reference load did not show.
    #[error("the reference load changed the force by {delta_n:.3e} N (standard error {se_n:.1e} N): not clearly above the noise; is the mass on the load cell?")]
    NoLoad {
        /// Loaded minus unloaded, N (at the old scale).
        delta_n: f64,
        /// Its standard error, N.
        se_n: f64,
    },
    /// A value the procedure or the user gave breaks a rule.
    #[error("{field}: {rule}")]
    Invalid {
        /// The option or value.
        field: &'static str,
        /// The rule.
        rule: String,
    },
    /// The board did not confirm the new calibration.
    #[error("the board did not confirm the calibration within {timeout_s} s: it refuses one while driving or with a bad value (its defmt log says why: finrs log --elf ...)")]
    NotConfirmed {
        /// The wait, s.
        timeout_s: f64,
    },
    /// The board did not confirm the new model.
    #[error("the board did not confirm the model within {timeout_s} s: it refuses one while driving or one it cannot invert (its defmt log says why: finrs log --elf ...)")]
    NotTuned {
        /// The wait, s.
        timeout_s: f64,
    },
    /// The prompt failed (stdin closed).
    #[error("the prompt failed: {0}")]
    Prompt(String),
}

/// The board's stream as the measurements read it.
struct Listener {
    frames: Frames<'static>,
}

impl Listener {
    fn new() -> Self {
        Self {
            frames: Frames::new(None),
        }
    }

    /// The next event within what is left of the wait that began at
    /// `started`, or a timeout naming `what`.
    fn next(
        &mut self,
        board: &mut impl Board,
        opts: &CalibrateOptions,
        started: Instant,
        what: &'static str,
    ) -> Result<Event, CalibrateError> {
        let timeout = || CalibrateError::Timeout {
            what,
            timeout_s: opts.timeout.as_secs_f64(),
        };
        let left = opts
            .timeout
            .checked_sub(started.elapsed())
            .ok_or_else(timeout)?;
        self.frames.next(board, left, &Silent)?.ok_or_else(timeout)
    }

    /// Drops what the board buffered while nobody read (a prompt): the
    /// samples after this are the board's present.
    fn barrier(
        &mut self,
        board: &mut impl Board,
        opts: &CalibrateOptions,
    ) -> Result<(), CalibrateError> {
        match self.frames.barrier(board, opts.timeout, &Silent)? {
            Some(_) => Ok(()),
            None => Err(CalibrateError::Timeout {
                what: "Info frame",
                timeout_s: opts.timeout.as_secs_f64(),
            }),
        }
    }

    /// `count` next samples that satisfy `keep` (others are skipped), in
    /// order; a latched fault refuses.
    fn collect(
        &mut self,
        board: &mut impl Board,
        opts: &CalibrateOptions,
        count: usize,
        keep: impl Fn(&DecodedSample) -> bool,
    ) -> Result<Vec<DecodedSample>, CalibrateError> {
        let mut kept = Vec::with_capacity(count);
        let started = Instant::now();
        while kept.len() < count {
            match self.next(board, opts, started, "samples")? {
                Event::Fault(f) => return Err(CalibrateError::Faulted { seq: f.seq }),
                Event::Sample(s) if s.flags.has(SampleFlags::FAULT) => {
                    return Err(CalibrateError::Faulted { seq: s.seq })
                }
                Event::Sample(s) if keep(&s) => kept.push(s),
                _ => {}
            }
        }
        Ok(kept)
    }
}

/// The Info frame the board sends on request.
pub fn read_info(board: &mut impl Board, opts: &CalibrateOptions) -> Result<Info, CalibrateError> {
    crate::link::board::request_info(board, opts.timeout)?.ok_or(CalibrateError::Timeout {
        what: "Info frame",
        timeout_s: opts.timeout.as_secs_f64(),
    })
}

/// A mean, its standard error, and the window's drift, from block means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mean {
    /// The mean.
    pub mean: f64,
    /// Its standard error: the block means' scatter about a straight
    /// line, over √[`BLOCKS`].
    pub se: f64,
    /// The drift across the window: the line's slope times half the
    /// window (what the second half's mean exceeds the first's by).
    pub drift: f64,
    /// The drift's standard error.
    pub drift_se: f64,
}

/// The mean of `x`, and a straight line through its [`BLOCKS`] block
/// means: a reading that drifts shows in the slope, not in the scatter, so
/// the drift is tested against the noise alone. `x` has at least
/// [`BLOCKS`] values.
pub fn block_mean(x: &[f64]) -> Mean {
    let per = x.len() / BLOCKS;
    let y: Vec<f64> = (0..BLOCKS)
        .map(|b| x[b * per..(b + 1) * per].iter().sum::<f64>() / per as f64)
        .collect();
    let mean = y.iter().sum::<f64>() / BLOCKS as f64;
    // Block positions centred on the window's middle.
    let t = |b: usize| b as f64 - (BLOCKS - 1) as f64 / 2.0;
    let sxx: f64 = (0..BLOCKS).map(|b| t(b).powi(2)).sum();
    let slope = (0..BLOCKS).map(|b| t(b) * (y[b] - mean)).sum::<f64>() / sxx;
    let resid = (0..BLOCKS)
        .map(|b| (y[b] - mean - slope * t(b)).powi(2))
        .sum::<f64>()
        / (BLOCKS - 2) as f64;
    let half = (BLOCKS / 2) as f64;
    Mean {
        mean,
        se: (resid / BLOCKS as f64).sqrt(),
        drift: slope * half,
        drift_se: (resid / sxx).sqrt() * half,
    }
}

/// Samples in `seconds` at the board's rate, at least [`BLOCKS`] × 10.
fn samples_in(info: &Info, seconds: f64, field: &'static str) -> Result<usize, CalibrateError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(CalibrateError::Invalid {
            field,
            rule: format!("{seconds} s: must be a positive number of seconds"),
        });
    }
    Ok(((seconds * f64::from(info.sample_hz)).round() as usize).max(BLOCKS * 10))
}

/// What the shunt measurement found.
#[derive(Clone, Debug, PartialEq)]
pub struct ShuntZeros {
    /// The board's Info before.
    pub before: Info,
    /// The new calibration (the load cell's scale unchanged).
    pub calibration: Calibration,
    /// Each driven segment's mean current at 0 V under the old zeros, A,
    /// and its standard error in counts.
    pub offsets: Vec<(f64, f64)>,
}

/// Stops the outputs, waits `settle_s` at 0 V, and averages each
/// segment's current over `average_s`: the new zero is the old one plus
/// the mean in counts.
pub fn measure_shunt_zeros(
    board: &mut impl Board,
    opts: &CalibrateOptions,
) -> Result<ShuntZeros, CalibrateError> {
    let before = read_info(board, opts)?;
    let settle = samples_in(&before, opts.settle_s, "--settle-s")?;
    let window = samples_in(&before, opts.average_s, "--average-s")?;
    board.send(&Command::Stop)?;
    let mut l = Listener::new();
    let at_rest = |s: &DecodedSample| {
        !s.flags.has(SampleFlags::RUNNING) && s.voltages().iter().all(|&v| v == 0.0)
    };
    l.collect(board, opts, settle, at_rest)?;
    let got = l.collect(board, opts, window, at_rest)?;
    let n = usize::from(before.segments);
    let amps_per_count = f64::from(before.amps_per_count);
    let mut calibration = before.calibration;
    let mut offsets = Vec::with_capacity(n);
    for k in 0..n {
        let counts: Vec<f64> = got
            .iter()
            .map(|s| f64::from(s.currents()[k]) / amps_per_count)
            .collect();
        let m = block_mean(&counts);
        if m.drift.abs() > DRIFT_SIGMAS * m.drift_se && m.drift.abs() > 0.5 {
            return Err(CalibrateError::Drifting {
                what: format!("segment {}'s current", k + 1),
                drift: m.drift,
                se: m.drift_se,
                window_s: opts.average_s,
            });
        }
        let zero = f64::from(calibration.current_zero_counts[k]) + m.mean;
        if !(0.0..=65535.0).contains(&zero.round()) {
            return Err(CalibrateError::Invalid {
                field: "shunt zero",
                rule: format!("segment {}: {zero:.0} counts is outside a u16", k + 1),
            });
        }
        calibration.current_zero_counts[k] = zero.round() as u16;
        offsets.push((m.mean * amps_per_count, m.se));
    }
    Ok(ShuntZeros {
        before,
        calibration,
        offsets,
    })
}

/// What the load-cell measurement found.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadCellScale {
    /// The board's Info before.
    pub before: Info,
    /// The new calibration (the shunt zeros unchanged).
    pub calibration: Calibration,
    /// Loaded minus unloaded force at the old scale, N, and its standard
    /// error.
    pub delta_n: Mean,
    /// The reference load, N.
    pub reference_n: f64,
}

/// Stops the outputs, tares with no load, averages the force, asks for
/// the reference load (`prompt` returns once it is on), averages again,
/// and rescales so that the difference reads `reference_n` (positive: the
/// load pushes the way the board reads as positive force; negative: the
/// other way).
pub fn measure_load_cell(
    board: &mut impl Board,
    opts: &CalibrateOptions,
    reference_n: f64,
    prompt: &mut dyn FnMut(&str) -> std::io::Result<()>,
) -> Result<LoadCellScale, CalibrateError> {
    if !(reference_n.is_finite() && reference_n != 0.0) {
        return Err(CalibrateError::Invalid {
            field: "reference load",
            rule: format!("{reference_n} N: must be finite and not 0"),
        });
    }
    let before = read_info(board, opts)?;
    let window = samples_in(&before, opts.average_s, "--average-s")?;
    // The strip must not push on the cell while it is weighed.
    board.send(&Command::Stop)?;
    let ask = |p: &mut dyn FnMut(&str) -> std::io::Result<()>, text: &str| {
        p(text).map_err(|e| CalibrateError::Prompt(e.to_string()))
    };
    ask(
        prompt,
        "take every load off the load cell, then press Enter",
    )?;
    let mut l = Listener::new();
    l.barrier(board, opts)?;
    board.send(&Command::Tare)?;
    // The tare's own samples carry its flag; the first after it is tared.
    let tared = |s: &DecodedSample| !s.flags.has(SampleFlags::TARING);
    l.collect(board, opts, 1, |s| s.flags.has(SampleFlags::TARING))?;
    let unloaded = force_mean(&l.collect(board, opts, window, tared)?);
    ask(
        prompt,
        &format!("put the reference load ({reference_n} N) on the load cell, then press Enter"),
    )?;
    // The samples the board buffered while the operator loaded the cell
    // are mostly unloaded ones: only what comes after the barrier counts.
    l.barrier(board, opts)?;
    let loaded = force_mean(&l.collect(board, opts, window, tared)?);
    let delta = Mean {
        mean: loaded.mean - unloaded.mean,
        se: loaded.se.hypot(unloaded.se),
        drift: loaded.drift,
        drift_se: loaded.drift_se,
    };
    if delta.mean.abs() < LOAD_SIGMAS * delta.se || delta.mean == 0.0 {
        return Err(CalibrateError::NoLoad {
            delta_n: delta.mean,
            se_n: delta.se,
        });
    }
    for (what, m) in [
        ("the unloaded force", unloaded),
        ("the loaded force", loaded),
    ] {
        if m.drift.abs() > DRIFT_SIGMAS * m.drift_se && m.drift.abs() > 0.01 * delta.mean.abs() {
            return Err(CalibrateError::Drifting {
                what: what.to_string(),
                drift: m.drift / f64::from(before.calibration.newtons_per_count),
                se: m.drift_se / f64::from(before.calibration.newtons_per_count),
                window_s: opts.average_s,
            });
        }
    }
    let mut calibration = before.calibration;
    let scale = f64::from(calibration.newtons_per_count) * reference_n / delta.mean;
    calibration.newtons_per_count = scale as f32;
    Ok(LoadCellScale {
        before,
        calibration,
        delta_n: delta,
        reference_n,
    })
}

fn force_mean(samples: &[DecodedSample]) -> Mean {
    let f: Vec<f64> = samples.iter().map(|s| f64::from(s.force_n)).collect();
    block_mean(&f)
}

/// Sends `calibration` and waits for the board's Info that carries it;
/// returns that Info (its origin says whether it was stored in flash).
pub fn apply(
    board: &mut impl Board,
    opts: &CalibrateOptions,
    calibration: &Calibration,
) -> Result<Info, CalibrateError> {
    let command = Command::SetCalibration(*calibration);
    confirmed(board, opts, &command, |i| {
        i.calibration == *calibration && i.calibration_origin != CalibrationOrigin::Defaults
    })
    .map_err(|e| match e {
        CalibrateError::Timeout { timeout_s, .. } => CalibrateError::NotConfirmed { timeout_s },
        e => e,
    })
}

/// Sends the fitted model `record` (`finrs tune`) and waits for the
/// board's Info that names it by its CRC; returns that Info.
pub fn apply_model(
    board: &mut impl Board,
    opts: &CalibrateOptions,
    record: &ModelRecord,
) -> Result<Info, CalibrateError> {
    let command = Command::SetModel(*record);
    confirmed(board, opts, &command, |i| i.model_crc == Some(record.crc())).map_err(|e| match e {
        CalibrateError::Timeout { timeout_s, .. } => CalibrateError::NotTuned { timeout_s },
        e => e,
    })
}

/// Sends `command` and waits for an Info frame that `done` accepts.
fn confirmed(
    board: &mut impl Board,
    opts: &CalibrateOptions,
    command: &Command,
    done: impl Fn(&Info) -> bool,
) -> Result<Info, CalibrateError> {
    let mut l = Listener::new();
    board.send(command)?;
    let started = Instant::now();
    loop {
        if let Event::Info(i) = l.next(board, opts, started, "Info frame")? {
            if done(&i) {
                return Ok(i);
            }
        }
    }
}

/// The calibration in words, for the driven segments.
pub fn describe(c: &Calibration, origin: CalibrationOrigin, segments: u8) -> String {
    let n = usize::from(segments).min(c.current_zero_counts.len());
    let zeros: Vec<String> = c.current_zero_counts[..n]
        .iter()
        .map(u16::to_string)
        .collect();
    format!(
        "load cell {:e} N/count; shunt zeros {} counts (segments 1..={n}); {}",
        c.newtons_per_count,
        zeros.join(", "),
        origin.name()
    )
}

#[cfg(test)]
mod tests;
