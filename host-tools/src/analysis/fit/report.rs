//! The fit's report as text, for the terminal.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use super::data::SessionTargets;
use super::fitter::FitResult;
use super::stats::Estimate;

/// Parameters with intervals, information criteria, and fit per channel.
pub fn text(fit: &FitResult, targets: &SessionTargets) -> String {
    let mut s = String::new();
    let structure = if fit.effects.is_empty() {
        "baseline".to_string()
    } else {
        let names: Vec<&str> = fit.effects.iter().map(|e| e.name()).collect();
        format!("baseline + {}", names.join(" + "))
    };
    let _ = writeln!(s, "model: {structure}");
    let _ = writeln!(
        s,
        "\nparameter                    estimate      95 % interval"
    );
    estimate_lines(&mut s, &fit.estimates);
    if let Some(form) = &fit.form {
        let _ = writeln!(
            s,
            "\nintervals span the fit with each mode's own damping ratio in place of the law's \
             constant one, its β kept (cost {:.1} with the law, {:.1} with each mode's own; \
             lower is better):",
            form.cost_law, form.cost_each_mode
        );
        estimate_lines(&mut s, &form.each_mode);
    }
    let _ = writeln!(s, "\nnoise per sensor (from the opening rests):");
    for (sensor, sigma) in &targets.sigma {
        let _ = writeln!(s, "  {sensor:?}: {sigma:.3e}");
    }
    let _ = writeln!(s, "{}", targets.sampling);
    let _ = writeln!(
        s,
        "\nresiduals m = {}, weighted RSS/m = {:.3}, parameters k = {}, AIC = {:.1}, BIC = {:.1}",
        fit.score.m,
        fit.score.rss / fit.score.m as f64,
        fit.parameters,
        fit.aic,
        fit.bic
    );
    let _ = writeln!(
        s,
        "mean NRMSE over channels with signal: {:.4}",
        fit.score.nrmse
    );
    let _ = writeln!(
        s,
        "\nrecording                      channel      fit %   rms/noise"
    );
    for c in fit.score.channels.iter().filter(|c| c.has_signal) {
        let _ = writeln!(
            s,
            "{:<30} {:<10} {:>7.2} {:>10.2}",
            c.recording,
            c.channel.name(),
            c.fit_percent,
            c.rms_in_noise
        );
    }
    s
}

/// The fit as `finrs fit --json` writes it: what [`text`] prints, for a
/// program (a coverage run, a notebook) rather than a reader.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FitSummary {
    /// Effects on top of the baseline, catalogue names.
    pub effects: Vec<String>,
    /// Every fitted parameter with its 95 % interval.
    pub estimates: Vec<EstimateSummary>,
    /// Noise level per sensor from the opening rests, in its unit.
    pub noise: BTreeMap<String, f64>,
    /// Residuals counted.
    pub residuals: usize,
    /// Weighted RSS per residual (1 at the noise floor).
    pub rss_per_residual: f64,
    /// Parameters counted by AIC and BIC.
    pub parameters: usize,
    /// Akaike's information criterion.
    pub aic: f64,
    /// Bayesian information criterion.
    pub bic: f64,
    /// Mean NRMSE over the channels with signal.
    pub nrmse: f64,
    /// Every channel with signal: recording, channel, fit % and RMS in
    /// noise units.
    pub channels: Vec<ChannelSummary>,
    /// The structure fitted again with each mode's own damping ratio in
    /// place of the law, whose intervals `estimates`' span; absent where
    /// not checked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_form: Option<FormSummary>,
}

/// The form check of a [`FitSummary`].
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FormSummary {
    /// The cost both fits minimise, at the law's fit.
    pub cost_law: f64,
    /// The same with each mode's own ratio.
    pub cost_each_mode: f64,
    /// The estimates with each mode's own ratio, each with its own 95 %
    /// interval.
    pub estimates: Vec<EstimateSummary>,
}

/// One parameter of a [`FitSummary`].
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EstimateSummary {
    /// The knob's name (as in the parameter file).
    pub knob: String,
    /// Its estimate, SI.
    pub value: f64,
    /// Lower end of the 95 % interval.
    pub low: f64,
    /// Upper end of the 95 % interval.
    pub high: f64,
}

/// One channel of a [`FitSummary`].
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ChannelSummary {
    /// Recording's file name.
    pub recording: String,
    /// Channel's column name.
    pub channel: String,
    /// MATLAB's fit percentage.
    pub fit_percent: f64,
    /// RMS of the residual in noise units.
    pub rms_in_noise: f64,
}

impl FitSummary {
    /// The summary of `fit` over `targets`.
    pub fn new(fit: &FitResult, targets: &SessionTargets) -> FitSummary {
        FitSummary {
            effects: fit.effects.iter().map(|e| e.name().to_string()).collect(),
            estimates: summaries(&fit.estimates),
            noise: targets
                .sigma
                .iter()
                .map(|(sensor, sigma)| (sensor.name().to_string(), *sigma))
                .collect(),
            residuals: fit.score.m,
            rss_per_residual: fit.score.rss / fit.score.m.max(1) as f64,
            parameters: fit.parameters,
            aic: fit.aic,
            bic: fit.bic,
            nrmse: fit.score.nrmse,
            channels: fit
                .score
                .channels
                .iter()
                .filter(|c| c.has_signal)
                .map(|c| ChannelSummary {
                    recording: c.recording.clone(),
                    channel: c.channel.name().to_string(),
                    fit_percent: c.fit_percent,
                    rms_in_noise: c.rms_in_noise,
                })
                .collect(),
            damping_form: fit.form.as_ref().map(|f| FormSummary {
                cost_law: f.cost_law,
                cost_each_mode: f.cost_each_mode,
                estimates: summaries(&f.each_mode),
            }),
        }
    }
}

/// A line per estimate: name, value and interval.
fn estimate_lines(s: &mut String, estimates: &[Estimate]) {
    for e in estimates {
        let _ = writeln!(
            s,
            "{:<26} {:>12.5e}   [{:.4e}, {:.4e}]",
            e.knob.name(),
            e.value,
            e.low,
            e.high
        );
    }
}

fn summaries(estimates: &[Estimate]) -> Vec<EstimateSummary> {
    estimates
        .iter()
        .map(|e| EstimateSummary {
            knob: e.knob.name().to_string(),
            value: e.value,
            low: e.low,
            high: e.high,
        })
        .collect()
}
