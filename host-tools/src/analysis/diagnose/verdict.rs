//! What a diagnosis finds: the verdict as `VERDICT.json` holds it, and the
//! fits behind it.

use serde::Serialize;

use super::analyses;
use super::faults::FaultFinding;
use super::floors::SensorFloor;
use super::identify::Identifiability;
use super::rests::RestStructure;
use crate::analysis::fit::{FitResult, Score};

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
    /// The standard errors its own term had to clear: its round's share of
    /// the family-wise level, split among the round's candidates and an
    /// effect's several tests (the highest of a pair's two effects').
    pub signature_z: f64,
    /// Whether it passed both tests.
    pub passed: bool,
    /// A check after the search, not a step of it: the effect, already in
    /// the model, tested as if it joined the model of all the others last
    /// (they refitted without it). `passed` then says it stays.
    pub backward: bool,
    /// Judged on the training recordings that drive one segment alone,
    /// after the search (`segment-crosstalk`, where the search did not
    /// name it): its held-out gains are the held-out lone drives', `NaN`
    /// where none is held out.
    pub lone_drives: bool,
    /// Its fitted extra parameters.
    pub params: std::collections::BTreeMap<String, f64>,
    /// The statistics its signature reads beyond its knobs' own
    /// intervals, where its fit has them: `reaction_departure`, the
    /// steady current's departure from linear at the highest drive
    /// (`reaction.rs`), and `drying_loss`, the moment's gain lost over
    /// the session (`drying.rs`); each the value and its standard error,
    /// so that a sweep can show how far from their margins they fall.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub evidence: std::collections::BTreeMap<String, Evidence>,
}

/// A statistic and its standard error ([`Candidate::evidence`]).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Evidence {
    /// The value.
    pub value: f64,
    /// Its standard error (the delta method over the fit's covariance).
    pub se: f64,
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
    /// Where the final model has `damping`: how much lower, percent, the
    /// held-out RSS is with each mode's own damping ratio in place of the
    /// law's constant one (its `β` kept). Where [`each_mode_damping_kept`](super::gates::each_mode_damping_kept),
    /// the final model is the one with each mode's own ratio.
    pub each_mode_damping_gain_percent: Option<f64>,
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
    /// The final model's held-out residuals, sensor by sensor: each must
    /// be at its own noise floor for `explained` or `none`.
    pub sensors: Vec<SensorFloor>,
    /// Catalogue effects this session cannot show, not tried.
    pub untestable: Vec<Untestable>,
    /// The DAQ's channels during the opening rests: whiteness, and the
    /// bench's hum and coloured noise.
    pub rest: RestStructure,
    /// The bench's faults, recording by recording: contact faults,
    /// out-of-range stretches, clipped sensors (kept out of every fit).
    pub faults: Vec<FaultFinding>,
    /// Where the baseline's misfit lives across the session.
    pub analyses: analyses::Analyses,
    /// Per testable effect the final model lacks: whether this session's
    /// protocol could show it at a plausible strength, and which others
    /// it is confounded with.
    pub identifiability: Vec<Identifiability>,
    /// Why identifiability could not be assessed at all, if so (the final
    /// model refused a step of its own knobs).
    pub identifiability_refused: Option<String>,
}

/// A catalogue effect the session cannot show.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Untestable {
    /// The catalogue name.
    pub effect: String,
    /// Why the session cannot show it.
    pub why: String,
}

/// The verdict as `finrs diagnose` prints it: verdict and causes, the
/// held-out gain, then every candidate tried, one line each. A candidate's
/// held-out RSS gain comes first, as the rule reads it; its mean NRMSE
/// gain beside it weighs every channel alike and can differ in sign (a
/// term that halves one channel's misfit and worsens many small ones).
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
        if let Some(g) = self.each_mode_damping_gain_percent {
            if super::gates::each_mode_damping_kept(g) {
                writeln!(
                    f,
                    "damping: each mode's own ratio beside the law's β (held-out RSS {g:.2} % below the law's)"
                )?;
            } else {
                writeln!(
                    f,
                    "damping: the law (with each mode's own ratio the held-out RSS {:.2} % {})",
                    g.abs(),
                    if g >= 0.0 { "lower" } else { "higher" }
                )?;
            }
        }
        for c in &self.candidates {
            writeln!(
                f,
                "  {} {:<30} dBIC {:>12.1}  held-out RSS gain {:>8.2} %  (NRMSE {:>8.2} %)  {}",
                if c.backward {
                    "  check".to_string()
                } else if c.lone_drives {
                    "   lone".to_string()
                } else {
                    format!("round {}", c.round + 1)
                },
                c.name,
                c.delta_bic,
                c.holdout_rss_gain_percent,
                c.holdout_gain_percent,
                match (c.backward, c.passed) {
                    (false, true) => "passed",
                    (false, false) => "-",
                    (true, true) => "stays",
                    (true, false) => "leaves",
                }
            )?;
        }
        for s in self.sensors.iter().filter(|s| !s.at_floor) {
            writeln!(
                f,
                "  above its noise floor: {} at {:.2} (worst {} at {:.2})",
                s.sensor, s.rss_per_residual, s.worst_channel, s.worst_rss_per_residual
            )?;
            if let Some(st) = &s.structure {
                writeln!(f, "    there: {st}")?;
            }
        }
        for u in &self.untestable {
            writeln!(f, "  not testable here: {}: {}", u.effect, u.why)?;
        }
        for i in &self.identifiability {
            writeln!(f, "  {i}")?;
        }
        if let Some(why) = &self.identifiability_refused {
            writeln!(f, "  what the session could show was not assessed: {why}")?;
        }
        for b in &self.rest.bench {
            writeln!(f, "  bench, not the strip: {}", b.detail)?;
        }
        for b in &self.faults {
            writeln!(f, "  bench, not the strip: {}", b.detail)?;
        }
        Ok(())
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
