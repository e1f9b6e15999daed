//! `finrs diagnose`: what the baseline gets wrong in a session, which
//! effects of the catalogue explain it, and how much they gain on
//! recordings the fit did not see.
//!
//! The session is split: about a third of the recordings (every third,
//! from the second, keeping each fixture in the training part) are held
//! out. The baseline is fitted on the rest; then each effect of the
//! catalogue is added in turn and fitted. An effect is accepted only when
//! the evidence punishing its extra parameters favours it strongly
//! (`ΔBIC < −10` on the training part) *and* it lowers the held-out error
//! (weighted residual sum of squares by at least 1 %) *and* the term that
//! makes it that effect is significant (its 95 % interval excludes "off":
//! hydrodynamic loading needs added mass, since its drag alone is
//! damping; back-relaxation needs the zero below zero). The best accepted
//! effect joins the model and the search repeats on top of it, so several
//! causes can be named, strongest first. The verdict:
//! - `none`: nothing accepted and the held-out residuals are at the noise
//!   floor (weighted RSS per residual below [`NOISE_FLOOR_RATIO`]);
//! - `explained`: effects accepted and the held-out residuals are at the
//!   noise floor;
//! - `unexplained`: above the noise floor after the best model, with the
//!   effects that did pass (possibly none); or the DAQ's channels already
//!   carry structure while the strip rests before its drive (most
//!   rests fail a Ljung–Box test): every candidate is driven by the
//!   voltage, so nothing in the catalogue can account for that.

pub mod analyses;
pub mod report;
pub mod whiteness;

use rayon::prelude::*;
use serde::Serialize;

use crate::fit::{modal, ChannelFit, Effect, FitError, FitResult, Fitter, Knob, Score};
use crate::predict::ModelSpec;
use crate::session::Session;

/// Held-out weighted RSS per residual above which structure remains: the
/// noise levels come from about a second of rest per recording, so they
/// are known to some ten percent; the camera's whole pixels add a little.
pub const NOISE_FLOOR_RATIO: f64 = 1.5;
/// BIC improvement an effect must reach on the training recordings.
pub const DELTA_BIC: f64 = -10.0;
/// Relative drop of held-out weighted RSS an effect must reach.
pub const HOLDOUT_RSS_GAIN: f64 = 0.01;
/// Effects accepted at most (rounds of the forward search).
pub const MAX_CAUSES: usize = 3;
/// Lags of the residual–input correlation, as MATLAB's `resid` default.
pub const INPUT_LAGS: usize = 25;
/// Share of the opening rests (DAQ channels) that may fail the whiteness
/// test before the rest itself is called structured: white noise fails
/// one in a hundred.
pub const REST_STRUCTURE_SHARE: f64 = 0.5;

/// How a model does on the two parts of the session.
#[derive(Clone, Debug, Serialize)]
pub struct ModelScore {
    /// Mean NRMSE on the held-out recordings (channels with signal).
    pub holdout_nrmse: f64,
    /// Weighted RSS per residual on the held-out recordings.
    pub holdout_rss_per_residual: f64,
    /// BIC on the training recordings.
    pub bic: f64,
    /// AIC on the training recordings.
    pub aic: f64,
    /// Parameters counted.
    pub parameters: usize,
}

/// One candidate tried in one round.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// The effect's catalogue name.
    pub name: String,
    /// Round of the search (0: on top of the baseline).
    pub round: usize,
    /// BIC of the extended model minus that of the model it extends.
    pub delta_bic: f64,
    /// Reduction of held-out NRMSE, percent.
    pub holdout_gain_percent: f64,
    /// Reduction of held-out weighted RSS, percent.
    pub holdout_rss_gain_percent: f64,
    /// Whether it passed both tests.
    pub passed: bool,
    /// Its fitted extra parameters.
    pub params: std::collections::BTreeMap<String, f64>,
}

/// Residual whiteness of one channel of one held-out recording.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualTest {
    /// Recording.
    pub recording: String,
    /// Channel.
    pub channel: String,
    /// Ljung–Box `Q` over 20 lags, baseline.
    pub baseline_ljung_box: f64,
    /// The same for the final model.
    pub final_ljung_box: f64,
    /// 99 % threshold of `χ²(20)`.
    pub threshold: f64,
    /// Largest normalised cross-correlation of the baseline's residual
    /// with the input over lags 0..=25 (input leading), as MATLAB's
    /// `resid`: above the band, the residual still depends on the drive.
    pub baseline_input_correlation: f64,
    /// The same for the final model.
    pub final_input_correlation: f64,
    /// 99 % band of that correlation for a white residual, `2.58/√n`.
    pub input_band: f64,
}

/// The diagnosis, as written to `VERDICT.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Verdict {
    /// Causes named, strongest first.
    pub causes: Vec<String>,
    /// `explained`, `none` or `unexplained`.
    pub verdict: String,
    /// The baseline.
    pub baseline: ModelScore,
    /// The final model (the baseline when nothing was accepted).
    pub extended: ModelScore,
    /// Reduction of held-out NRMSE from baseline to final model, percent.
    pub gain_percent: f64,
    /// Every candidate tried.
    pub candidates: Vec<Candidate>,
    /// The final model's parameters.
    pub params: std::collections::BTreeMap<String, f64>,
    /// Recordings fitted.
    pub training: Vec<String>,
    /// Recordings held out.
    pub holdout: Vec<String>,
    /// Whiteness of the held-out residuals.
    pub residual_tests: Vec<ResidualTest>,
    /// Whiteness of the DAQ's channels during the opening rests.
    pub rest: RestStructure,
    /// Where the baseline's misfit lives across the session.
    pub analyses: analyses::Analyses,
}

/// The verdict as `finrs diagnose` prints it: verdict and causes, the
/// held-out gain, then every candidate tried, one line each.
impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let causes = if self.causes.is_empty() {
            "none".to_string()
        } else {
            self.causes.join(", ")
        };
        writeln!(f, "verdict: {}; causes: {causes}", self.verdict)?;
        writeln!(
            f,
            "held-out NRMSE {:.4} (baseline) -> {:.4} (final): {:.1} % gain; held-out RSS/m {:.3} -> {:.3}",
            self.baseline.holdout_nrmse,
            self.extended.holdout_nrmse,
            self.gain_percent,
            self.baseline.holdout_rss_per_residual,
            self.extended.holdout_rss_per_residual
        )?;
        for c in &self.candidates {
            writeln!(
                f,
                "  round {} {:<30} dBIC {:>12.1}  held-out gain {:>7.2} %  {}",
                c.round + 1,
                c.name,
                c.delta_bic,
                c.holdout_gain_percent,
                if c.passed { "passed" } else { "-" }
            )?;
        }
        Ok(())
    }
}

/// Whether the measured channels carry structure before any drive.
#[derive(Clone, Debug, Serialize)]
pub struct RestStructure {
    /// Opening rests tested (recording × current or force channel).
    pub tested: usize,
    /// Those whose Ljung–Box `Q` over 20 lags exceeds the 99 % threshold.
    pub failing: usize,
    /// Whether more than [`REST_STRUCTURE_SHARE`] of them fail.
    pub structured: bool,
}

/// Tests the opening rest of every DAQ channel (currents, load cell) for
/// whiteness; camera channels are too short there to test.
pub fn rest_structure(session: &Session) -> RestStructure {
    let (mut tested, mut failing) = (0, 0);
    for r in &session.recordings {
        for (ch, values) in &r.rec.channels {
            if ch.is_camera() {
                continue;
            }
            let rest: Option<Vec<f64>> = values[..r.rest_rows.min(values.len())]
                .iter()
                .copied()
                .collect();
            let Some(rest) = rest.filter(|v| v.len() >= 200) else {
                continue;
            };
            tested += 1;
            if whiteness::ljung_box(&rest, 20) > whiteness::chi2_99(20) {
                failing += 1;
            }
        }
    }
    RestStructure {
        tested,
        failing,
        structured: tested > 0 && failing as f64 > REST_STRUCTURE_SHARE * tested as f64,
    }
}

/// A diagnosis with the fits behind it, for the report.
pub struct Diagnosis {
    /// The verdict.
    pub verdict: Verdict,
    /// The baseline's fit.
    pub baseline: FitResult,
    /// The final model's fit.
    pub final_fit: FitResult,
    /// Held-out scores of baseline and final model.
    pub holdout_scores: (Score, Score),
    /// Indices of the held-out recordings.
    pub holdout: Vec<usize>,
}

/// Splits a session: every third recording from the second is held out,
/// unless that would leave its fixture without a training recording.
pub fn split(session: &Session) -> (Vec<usize>, Vec<usize>) {
    let n = session.recordings.len();
    let fixture = |i: usize| session.recordings[i].rec.meta.fixture;
    let mut hold = Vec::new();
    for i in (1..n).step_by(3) {
        let left = (0..n)
            .filter(|&j| j != i && !hold.contains(&j) && fixture(j) == fixture(i))
            .count();
        if left > 0 {
            hold.push(i);
        }
    }
    let train = (0..n).filter(|i| !hold.contains(i)).collect();
    (train, hold)
}

/// Diagnoses `session`; `progress` hears what is being fitted.
pub fn diagnose(
    session: &Session,
    fixed: ModelSpec,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Diagnosis, FitError> {
    let fitter = Fitter::new(session);
    let (train, hold) = split(session);
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    if hold.is_empty() {
        return Err(FitError::TooFewToHoldOut(session.recordings.len()));
    }
    let name = |i: &usize| session.recordings[i.to_owned()].name.clone();
    let has_clock = session.recordings.iter().all(|r| r.t_start_s.is_some());
    progress("baseline");
    let baseline = fitter.fit(&train, &[], None, fixed)?;
    let base_hold = fitter.score(&hold, &baseline.spec)?;
    let mut current = baseline.clone();
    let mut current_hold = base_hold.clone();
    let mut candidates = Vec::new();
    let mut accepted: Vec<Effect> = Vec::new();
    for round in 0..MAX_CAUSES {
        let untried: Vec<Effect> = Effect::ALL
            .into_iter()
            .filter(|e| !current.effects.contains(e))
            .filter(|e| *e != Effect::Dehydration || has_clock)
            .collect();
        if untried.is_empty() {
            break;
        }
        progress(&format!(
            "round {}: {} candidates",
            round + 1,
            untried.len()
        ));
        // The model's and the load cell's blocked frequencies, once a round:
        // every frequency-moving candidate of the round starts from them.
        let frequencies = untried
            .iter()
            .any(|e| moves_frequency(*e))
            .then(|| blocked_frequencies(session, &train, &current.spec))
            .flatten();
        let results: Vec<Result<(Effect, FitResult, Score), FitError>> = untried
            .par_iter()
            .map(|&e| {
                let mut effects = current.effects.clone();
                effects.push(e);
                let start = frequency_start(e, &current.spec, frequencies);
                let fit = fitter.fit(&train, &effects, Some(&start), fixed)?;
                let score = fitter.score(&hold, &fit.spec)?;
                Ok((e, fit, score))
            })
            .collect();
        let mut best: Option<(f64, Effect, FitResult, Score)> = None;
        for r in results {
            let (e, fit, score) = r?;
            let delta_bic = fit.bic - current.bic;
            let gain = gain_percent(current_hold.nrmse, score.nrmse);
            let rss_gain = 1.0 - score.rss / current_hold.rss;
            let passed = delta_bic < DELTA_BIC
                && rss_gain > HOLDOUT_RSS_GAIN
                && signature_is_significant(e, &fit, &fixed);
            candidates.push(Candidate {
                name: e.name().to_string(),
                round,
                delta_bic,
                holdout_gain_percent: gain,
                holdout_rss_gain_percent: 100.0 * rss_gain,
                passed,
                params: fit
                    .estimates
                    .iter()
                    .filter(|est| !est.knob.is_baseline())
                    .map(|est| (est.knob.name().to_string(), est.value))
                    .collect(),
            });
            if passed && best.as_ref().is_none_or(|(b, ..)| delta_bic < *b) {
                best = Some((delta_bic, e, fit, score));
            }
        }
        match best {
            Some((_, e, fit, score)) => {
                accepted.push(e);
                current = fit;
                current_hold = score;
            }
            None => break,
        }
    }
    let per = |s: &Score| s.rss / s.m.max(1) as f64;
    let at_floor = per(&current_hold) < NOISE_FLOOR_RATIO;
    let causes: Vec<String> = accepted.iter().map(|e| e.name().to_string()).collect();
    let rest = rest_structure(session);
    let verdict = match (causes.is_empty(), at_floor && !rest.structured) {
        (true, true) => "none",
        (false, true) => "explained",
        (_, false) => "unexplained",
    };
    let score_of = |fit: &FitResult, hold: &Score| ModelScore {
        holdout_nrmse: hold.nrmse,
        holdout_rss_per_residual: per(hold),
        bic: fit.bic,
        aic: fit.aic,
        parameters: fit.parameters,
    };
    let residual_tests = tested_channels(&base_hold, &current_hold)
        .map(|(b, f)| ResidualTest {
            recording: b.recording.clone(),
            channel: b.channel.name(),
            baseline_ljung_box: whiteness::ljung_box(&b.residuals, 20),
            final_ljung_box: whiteness::ljung_box(&f.residuals, 20),
            threshold: whiteness::chi2_99(20),
            baseline_input_correlation: whiteness::input_correlation(
                &b.residuals,
                &b.input_v,
                INPUT_LAGS,
            )
            .0,
            final_input_correlation: whiteness::input_correlation(
                &f.residuals,
                &f.input_v,
                INPUT_LAGS,
            )
            .0,
            input_band: whiteness::input_correlation(&f.residuals, &f.input_v, INPUT_LAGS).1,
        })
        .collect();
    let verdict = Verdict {
        causes,
        verdict: verdict.to_string(),
        baseline: score_of(&baseline, &base_hold),
        extended: score_of(&current, &current_hold),
        gain_percent: gain_percent(base_hold.nrmse, current_hold.nrmse),
        candidates,
        params: current
            .estimates
            .iter()
            .map(|e| (e.knob.name().to_string(), e.value))
            .collect(),
        training: train.iter().map(name).collect(),
        holdout: hold.iter().map(name).collect(),
        residual_tests,
        rest,
        analyses: analyses::analyse(session, &fitter.score(&all, &baseline.spec)?),
    };
    Ok(Diagnosis {
        verdict,
        baseline,
        final_fit: current,
        holdout_scores: (base_hold, current_hold),
        holdout: hold,
    })
}

/// The held-out channels whose residuals are tested for whiteness (those
/// with signal, and the camera's, where motion along the strip shows),
/// baseline and final model side by side. `Verdict::residual_tests` and
/// the report's table follow this order.
pub fn tested_channels<'a>(
    baseline: &'a Score,
    last: &'a Score,
) -> impl Iterator<Item = (&'a ChannelFit, &'a ChannelFit)> {
    baseline
        .channels
        .iter()
        .zip(&last.channels)
        .filter(|(b, _)| b.has_signal || b.channel.is_camera())
}

/// Whether a candidate moves the beam's natural frequencies.
fn moves_frequency(e: Effect) -> bool {
    matches!(e, Effect::BeamStiffness | Effect::HydrodynamicLoading)
}

/// `(model, measured)` first blocked frequency, Hz, the measurement
/// searched between 0.2 and 3 times the model's.
fn blocked_frequencies(
    session: &Session,
    train: &[usize],
    current: &ModelSpec,
) -> Option<(f64, f64)> {
    let model_hz = modal::model_blocked_hz(current)?;
    let data_hz = modal::measured_blocked_hz(session, train, 0.2 * model_hz, 3.0 * model_hz)?;
    Some((model_hz, data_hz))
}

/// Where a candidate that moves the beam's frequency starts: where the
/// model's first blocked mode rings at the measured frequency (`EI` for
/// beam-stiffness, added mass for hydrodynamic loading). Others start at
/// the current model, their own terms off.
fn frequency_start(e: Effect, current: &ModelSpec, frequencies: Option<(f64, f64)>) -> ModelSpec {
    let mut start = *current;
    if !moves_frequency(e) {
        return start;
    }
    let Some((model_hz, data_hz)) = frequencies else {
        return start;
    };
    // f ∝ √(EI / mass per length).
    let ratio2 = (data_hz / model_hz).powi(2);
    match e {
        Effect::BeamStiffness => start.params.ei_nm2 *= ratio2,
        _ => {
            let mass = start.params.mass_per_length_kg_per_m + start.ext.added_mass_kg_per_m;
            start.ext.added_mass_kg_per_m =
                (mass / ratio2 - start.params.mass_per_length_kg_per_m).max(0.0);
        }
    }
    start
}

/// Whether the term that makes `e` what it is differs from "off" beyond
/// its 95 % interval. Without this, an effect that contains another (linear
/// drag is mass-proportional damping) could be named for the other's work.
fn signature_is_significant(e: Effect, fit: &FitResult, fixed: &ModelSpec) -> bool {
    let excludes = |knob: Knob, off: f64| {
        fit.estimates
            .iter()
            .any(|est| est.knob == knob && (est.low > off || est.high < off))
    };
    match e {
        Effect::LargeDeflection => true,
        Effect::BeamStiffness => excludes(Knob::Ei, fixed.params.ei_nm2),
        Effect::Damping => excludes(Knob::Alpha, 0.0) || excludes(Knob::Beta, 0.0),
        // Added mass is what water adds; its drag alone is damping.
        Effect::HydrodynamicLoading => excludes(Knob::AddedMass, 0.0),
        Effect::ElectrochemicalNonlinearity => {
            excludes(Knob::ChargeCubic, 0.0) || excludes(Knob::LeakCubic, 0.0)
        }
        // The zero below zero is what makes the bending relax past the start.
        Effect::BackRelaxation => fit
            .estimates
            .iter()
            .any(|est| est.knob == Knob::Z && est.high < 0.0),
        Effect::Dehydration => excludes(Knob::Dehydration, 0.0),
        Effect::SegmentCrosstalk => excludes(Knob::Crosstalk, 0.0),
    }
}

fn gain_percent(before: f64, after: f64) -> f64 {
    if before > 0.0 {
        100.0 * (before - after) / before
    } else {
        0.0
    }
}
