//! The fit's report as text, for the terminal.

use std::fmt::Write as _;

use super::data::SessionTargets;
use super::fitter::FitResult;

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
    for e in &fit.estimates {
        let _ = writeln!(
            s,
            "{:<26} {:>12.5e}   [{:.4e}, {:.4e}]",
            e.knob.name(),
            e.value,
            e.low,
            e.high
        );
    }
    let _ = writeln!(s, "\nnoise per sensor (from the opening rests):");
    for (sensor, sigma) in &targets.sigma {
        let _ = writeln!(s, "  {sensor:?}: {sigma:.3e}");
    }
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
