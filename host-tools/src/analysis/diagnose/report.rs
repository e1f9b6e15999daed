//! The human report of a diagnosis: Markdown, with PNG plots beside it.

use std::fmt::Write as _;
use std::path::Path;

use super::{Diagnosis, ResidualTest, Verdict, NOISE_FLOOR_RATIO};
use crate::analysis::fit::ChannelFit;
use crate::model::simulate::{simulate, SimulateError};
use crate::plot::{self, PlotError};
use crate::session::Session;

/// A held-out channel under baseline and final model, with its whiteness.
type Tested<'a> = ((&'a ChannelFit, &'a ChannelFit), &'a ResidualTest);

/// The models in the order every plot gives them, so that each keeps its
/// colour ([`plot::model_colour`]) from plot to plot.
const MODELS: [&str; 2] = ["baseline", "final"];

/// Why the report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The folder or `REPORT.md` could not be written.
    #[error("writing {path}")]
    Io {
        /// The folder or file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A held-out recording could not be simulated for its plot.
    #[error("simulating {recording} for its plot")]
    Simulate {
        /// The recording.
        recording: String,
        /// Why.
        #[source]
        source: SimulateError,
    },
    /// A plot could not be drawn.
    #[error("plotting {path}")]
    Plot {
        /// The PNG.
        path: String,
        /// Why.
        #[source]
        source: PlotError,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn plotting(path: &Path) -> impl FnOnce(PlotError) -> ReportError + '_ {
    move |source| ReportError::Plot {
        path: path.display().to_string(),
        source,
    }
}

/// Writes `REPORT.md` and its plots into `dir`.
pub fn write(dir: &Path, session: &Session, d: &Diagnosis) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let v = &d.verdict;
    let mut s = String::new();
    summary(&mut s, session, v);
    baseline_misses(&mut s, v);
    candidates(&mut s, v);
    identifiability(&mut s, v);
    parameters(&mut s, d);
    let (b, f) = &d.holdout_scores;
    let tested: Vec<Tested> = super::tested_channels(b, f)
        .zip(&v.residual_tests)
        .collect();
    holdout_channels(&mut s, &tested);
    recording_plots(&mut s, dir, session, d)?;
    autocorrelation_plot(&mut s, dir, &tested)?;
    let md = dir.join("REPORT.md");
    std::fs::write(&md, s).map_err(io(&md))
}

/// The verdict, the split and the two models' scores.
fn summary(s: &mut String, session: &Session, v: &Verdict) {
    let _ = writeln!(s, "# Diagnosis of `{}`\n", session.dir.display());
    let causes = if v.causes.is_empty() {
        "none".to_string()
    } else {
        v.causes.join(", ")
    };
    let _ = writeln!(s, "**Verdict: {}**; causes: {causes}.\n", v.verdict);
    for u in &v.untestable {
        let _ = writeln!(s, "- Not testable here: `{}`: {}.", u.effect, u.why);
    }
    if !v.untestable.is_empty() {
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "Fitted on {} recordings ({}); scored on {} held out ({}).\n",
        v.training.len(),
        v.training.join(", "),
        v.holdout.len(),
        v.holdout.join(", ")
    );
    let _ = writeln!(
        s,
        "| model | held-out NRMSE | held-out RSS/m | BIC (training) | parameters |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (label, m) in [("baseline", &v.baseline), ("final", &v.extended)] {
        let _ = writeln!(
            s,
            "| {label} | {:.4} | {:.3} | {:.1} | {} |",
            m.holdout_nrmse, m.holdout_rss_per_residual, m.bic, m.parameters
        );
    }
    let _ = writeln!(
        s,
        "\nHeld-out error falls by {:.1} % from the baseline to the final model. \
         RSS/m is the weighted residual sum of squares per residual: 1 is the \
         noise floor measured on the recordings' opening rests.\n",
        v.gain_percent
    );
    let _ = writeln!(
        s,
        "Each sensor against its own floor (the final model, held out; `explained` \
         and `none` need every one below {NOISE_FLOOR_RATIO}):\n"
    );
    let _ = writeln!(
        s,
        "| sensor | RSS/m | residuals | at its floor | worst channel | its RSS/m |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for f in &v.sensors {
        let _ = writeln!(
            s,
            "| {} | {:.3} | {} | {} | {} | {:.3} |",
            f.sensor,
            f.rss_per_residual,
            f.residuals,
            if f.at_floor { "yes" } else { "**no**" },
            f.worst_channel,
            f.worst_rss_per_residual
        );
    }
    let _ = writeln!(s);
    for f in v.sensors.iter().filter(|f| !f.at_floor) {
        if let Some(st) = &f.structure {
            let _ = writeln!(
                s,
                "- {} above its floor, in {}: {st}.",
                f.sensor, f.worst_channel
            );
        }
    }
    if v.sensors.iter().any(|f| f.structure.is_some()) {
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "Opening rests (currents, load cell): {} of {} fail a Ljung–Box test at 99 % \
         once any mains hum is removed{}.\n",
        v.rest.failing,
        v.rest.tested,
        if v.rest.structured {
            ": the channels carry structure before any drive that neither hum \
             nor coloured noise accounts for, and no voltage-driven candidate can explain"
        } else if v.rest.failing > 0 && v.rest.failing_unexplained < v.rest.failing {
            " (on channels with coloured noise, which fails it by its nature)"
        } else {
            " (white noise fails one in a hundred)"
        }
    );
    if !v.rest.bench.is_empty() {
        let _ = writeln!(
            s,
            "The bench, not the strip (seen in the opening rests, or drift fitted beside every model; no catalogue effect is named for these):\n"
        );
        for b in &v.rest.bench {
            let _ = writeln!(s, "- {}", b.detail);
        }
        let _ = writeln!(s);
    }
    if !v.faults.is_empty() {
        let _ = writeln!(
            s,
            "The bench's faults, recording by recording (found in the data alone, kept out of every fit; no catalogue effect is named for these):\n"
        );
        let _ = writeln!(
            s,
            "| recording | fault | channel | from, s | to, s | stretches | in all, s |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for f in &v.faults {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | {:.3} | {} | {:.3} |",
                f.recording, f.kind, f.channel, f.from_s, f.to_s, f.stretches, f.total_s
            );
        }
        let _ = writeln!(s);
        for f in &v.faults {
            let _ = writeln!(s, "- {}", f.detail);
        }
        let _ = writeln!(s);
    }
}

/// Where the baseline's misfit lives across the session.
fn baseline_misses(s: &mut String, v: &Verdict) {
    let a = &v.analyses;
    let _ = writeln!(s, "## Where the baseline misses\n");
    let _ = writeln!(
        s,
        "The baseline's weighted RSS per residual in every recording (1 is the noise floor) \
         and its gain, the scale from its motion to the measured one (median over the \
         mechanical channels; 1 is right). A gain falling over the session suggests drying, \
         one changing with the amplitude a nonlinearity or large deflection, one differing \
         between segments driven alone crosstalk.\n"
    );
    let _ = writeln!(
        s,
        "| recording | session time, s | max V | driven | fixture | RSS/m | gain |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for m in &a.recordings {
        let t = m.t_session_s.map_or("-".to_string(), |t| format!("{t:.0}"));
        let driven: Vec<String> = m.driven.iter().map(|d| d.to_string()).collect();
        let _ = writeln!(
            s,
            "| {} | {t} | {:.2} | {} | {} | {:.2} | {} |",
            m.recording,
            m.max_abs_v,
            driven.join(","),
            m.fixture,
            m.rss_per_residual,
            m.gain.map_or("-".to_string(), |g| format!("{g:.3}"))
        );
    }
    let dep = |d: &Option<super::analyses::Dependence>| {
        d.as_ref().map_or("not enough recordings".to_string(), |d| {
            format!(
                "Spearman ρ = {:.2} over {} recordings",
                d.spearman, d.recordings
            )
        })
    };
    let _ = writeln!(s, "\n- Against session time: {}.", dep(&a.trend));
    let _ = writeln!(
        s,
        "- Against amplitude (free steps of all segments): {}.",
        dep(&a.amplitude)
    );
    if !a.single_segments.is_empty() {
        let segs: Vec<String> = a
            .single_segments
            .iter()
            .map(|(k, r, g)| {
                let g = g.map_or("-".to_string(), |g| format!("{g:.3}"));
                format!("segment {k}: RSS/m {r:.2}, gain {g}")
            })
            .collect();
        let _ = writeln!(s, "- Each segment alone: {}.", segs.join(", "));
    }
    if a.immovable.is_empty() {
        let _ = writeln!(
            s,
            "- Every channel with signal is one the baseline can move.\n"
        );
    } else {
        let _ = writeln!(
            s,
            "- Channels with signal that the baseline cannot move at all: {}.\n",
            a.immovable.join(", ")
        );
    }
}

/// Every candidate effect tried, with its tests.
fn candidates(s: &mut String, v: &Verdict) {
    let _ = writeln!(s, "## Candidates\n");
    let _ = writeln!(
        s,
        "An effect is accepted when ΔBIC < {} on the training recordings and the \
         held-out weighted RSS falls by more than {:.0} % (the geometric mean over the \
         held-out recordings of each one's RSS ratio) and its own term stands \
         out from \"off\" by more than its bar, in standard errors: the first round \
         spends half of {:.0} %, each later round half of what the rounds before it \
         left, shared evenly among the round's candidates and among the tests of an \
         effect that any of several may show, so that all of a search's candidates together pass on noise alone less \
         than {:.0} % of the time. After the search, each accepted effect is \
         checked (`check`) as if it joined the model of the others last, at the \
         bar it joined at; one that would not pass leaves.\n",
        super::DELTA_BIC,
        100.0 * super::HOLDOUT_RSS_GAIN,
        100.0 * super::FAMILY_ALPHA,
        100.0 * super::FAMILY_ALPHA
    );
    let _ = writeln!(s, "| round | effect | ΔBIC | held-out NRMSE gain % | held-out RSS gain % | bar (σ) | passed | fitted terms |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for c in &v.candidates {
        let terms: Vec<String> = c
            .params
            .iter()
            .map(|(k, x)| format!("{k} = {x:.4e}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.2} | {:.2} | {:.2} | {} | {} |",
            if c.backward {
                "check".to_string()
            } else if c.lone_drives {
                "lone drives".to_string()
            } else {
                (c.round + 1).to_string()
            },
            c.name,
            c.delta_bic,
            c.holdout_gain_percent,
            c.holdout_rss_gain_percent,
            c.signature_z,
            match (c.backward, c.passed) {
                (false, true) => "yes",
                (false, false) => "no",
                (true, true) => "stays",
                (true, false) => "leaves",
            },
            terms.join(", ")
        );
    }
}

/// What the session could show of each effect the final model lacks.
fn identifiability(s: &mut String, v: &Verdict) {
    if v.identifiability.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## What this session could show\n");
    let _ = writeln!(
        s,
        "Each testable effect the final model lacks, at the smallest strength the \
         search could name (both gates passed, the signature simulated and what \
         the model's own knobs absorb removed), against a strength a real strip \
         plausibly has (docs/diagnosis.md).\n"
    );
    let _ = writeln!(s, "| effect | strength | smallest detectable | plausible | could show | absorbed by the model % | confounded with |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for i in &v.identifiability {
        let smallest = match i.smallest_detectable {
            Some(x) => format!("{x:.2e}"),
            None if i.effect == "large-deflection" => {
                format!("signature {:.2} of the gate", i.holdout_signature_over_gate)
            }
            None => format!("none up to {}", i.ceiling),
        };
        let like: Vec<String> = i
            .confounded_with
            .iter()
            .map(|(n, share)| format!("{n} ({share:.0} %)"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.2} | {} |",
            i.effect,
            i.strength,
            smallest,
            i.plausible,
            if i.detectable { "yes" } else { "no" },
            i.absorbed_percent,
            like.join(", ")
        );
    }
}

/// The final model's estimates with their intervals.
fn parameters(s: &mut String, d: &Diagnosis) {
    let _ = writeln!(s, "\n## Final model's parameters (95 % intervals)\n");
    if let Some(form) = &d.final_fit.form {
        let which = if form.each_mode_final {
            "each mode's own damping ratio beside the law's β, which gained on the held-out \
             part; each interval spans it and the model with the damping law"
        } else {
            "the damping law; each interval spans it and the model with each mode's own \
             damping ratio in place of the law's constant one"
        };
        let _ = writeln!(
            s,
            "The final model has {which} (cost {:.1} with the law, {:.1} with each mode's own; \
             lower is better; see docs/model.md).\n",
            form.cost_law, form.cost_each_mode
        );
    }
    let _ = writeln!(s, "| parameter | estimate | interval |");
    let _ = writeln!(s, "|---|---|---|");
    for e in &d.final_fit.estimates {
        let _ = writeln!(
            s,
            "| {} | {:.5e} | [{:.4e}, {:.4e}] |",
            e.knob.name(),
            e.value,
            e.low,
            e.high
        );
    }
}

/// Fit and whiteness of every held-out channel.
fn holdout_channels(s: &mut String, tested: &[Tested]) {
    let _ = writeln!(s, "\n## Held-out channels\n");
    let _ = writeln!(s, "| recording | channel | baseline fit % | final fit % | Ljung–Box Q baseline | final | 99 % threshold | input correlation baseline | final | 99 % band |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for &((cb, cf), t) in tested {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.2} | {:.1} | {:.1} | {:.1} | {:.3} | {:.3} | {:.3} |",
            cb.recording,
            cb.channel.name(),
            cb.fit_percent,
            cf.fit_percent,
            t.baseline_ljung_box,
            t.final_ljung_box,
            t.threshold,
            t.baseline_input_correlation,
            t.final_input_correlation,
            t.input_band
        );
    }
}

/// A plot of every held-out recording: measured, baseline and final model.
fn recording_plots(
    s: &mut String,
    dir: &Path,
    session: &Session,
    d: &Diagnosis,
) -> Result<(), ReportError> {
    let _ = writeln!(s, "\n## Plots\n");
    let _ = writeln!(
        s,
        "Held-out recordings: measured, the baseline and the final model (both fitted on the other recordings).\n"
    );
    for &i in &d.holdout {
        let r = &session.recordings[i];
        let stem = r.name.trim_end_matches(".csv");
        let png = format!("{stem}.png");
        let elements = crate::analysis::fit::FIT_ELEMENTS;
        let run = |spec| {
            simulate(&r.name, r.drive(), spec, elements, &mut |_| {}).map_err(|source| {
                ReportError::Simulate {
                    recording: r.name.clone(),
                    source,
                }
            })
        };
        let base = run(&d.baseline.spec)?;
        let fin = run(&d.final_fit.spec)?;
        let path = dir.join(&png);
        plot::plot_models(
            &path,
            &format!("{} (held out)", r.name),
            Some(&r.rec),
            &[(MODELS[0], &base), (MODELS[1], &fin)],
        )
        .map_err(plotting(&path))?;
        let _ = writeln!(s, "![{}]({png})\n", r.name);
    }
    Ok(())
}

/// The residual autocorrelation of the held-out channel whose baseline
/// residuals are least white, under both models.
fn autocorrelation_plot(s: &mut String, dir: &Path, tested: &[Tested]) -> Result<(), ReportError> {
    // The held-out channel whose baseline residuals are least white.
    let worst = tested
        .iter()
        .max_by(|x, y| x.1.baseline_ljung_box.total_cmp(&y.1.baseline_ljung_box));
    if let Some(&((cb, cf), _)) = worst {
        let lags = 60.min(cb.residuals.len().saturating_sub(1));
        let band = 2.58 / (cb.residuals.len().max(1) as f64).sqrt();
        let png = "residual_autocorrelation.png";
        let path = dir.join(png);
        plot::plot_autocorrelation(
            &path,
            &format!(
                "residual autocorrelation, {} {} (held out)",
                cb.recording,
                cb.channel.name()
            ),
            &[
                (
                    MODELS[0],
                    super::whiteness::autocorrelation(&cb.residuals, lags),
                ),
                (
                    MODELS[1],
                    super::whiteness::autocorrelation(&cf.residuals, lags),
                ),
            ],
            band,
        )
        .map_err(plotting(&path))?;
        let _ = writeln!(
            s,
            "The least white held-out channel under the baseline, {} of {}: residual \
             autocorrelation of baseline and final model, with the band white noise \
             stays inside 99 % of the time (dashed red).\n\n![residual autocorrelation]({png})\n",
            cb.channel.name(),
            cb.recording
        );
    }
    Ok(())
}
