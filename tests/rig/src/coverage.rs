//! How often `finrs fit`'s 95 % intervals hold the rig's true values.
//!
//! The rig knows every value behind a session, so an interval can be
//! scored where a fitted knob means what one of the rig's values means:
//! - the circuit, `R1`, `R2` and `C` (under the electrochemical
//!   nonlinearity too, whose leak and capacitance have these as their
//!   small-voltage values);
//! - the lead network, `a = K`, `b = K z` and `p` (both write the moment
//!   as `K (s + z)/(s + p)` on the charge), unless a back-relaxation branch
//!   adds a second network that the fitted term only approximates;
//! - `EI`, the laminate's times the strip's factor;
//! - each segment's deviations from the first, `factor − 1`;
//! - in water, the quadratic drag `c₂ = ½ ρ C_d b` (the rig's drag and
//!   the model's are both `c₂ |v| v` at the nodes).
//!
//! Damping is not scored: the off-class strip gives each mode a ratio of
//! its own, which no single `ζ` of the model is. Nor are the terms whose
//! rig forms differ from the fitted ones (crosstalk through a lag, the
//! drying's rate against its own session clock).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::sample::{Hidden, Sample, WATER_KG_M3};

/// The rig's true value of each knob (named as `finrs fit --json` names
/// it) that means the same in the rig and in the fitted model.
pub fn truth(sample: &Sample, hidden: &Hidden) -> BTreeMap<String, f64> {
    let mut t = BTreeMap::new();
    t.insert("r1_ohm".to_string(), sample.r1_ohm);
    t.insert("r2_ohm".to_string(), sample.r2_ohm);
    t.insert("c_f".to_string(), sample.c_f);
    if hidden.back_branch.is_none() {
        t.insert("a_nm_per_c".to_string(), sample.k_nm_per_c);
        t.insert(
            "b_nm_per_c_s".to_string(),
            sample.k_nm_per_c * sample.z_per_s,
        );
        t.insert("p_per_s".to_string(), sample.p_per_s);
    }
    t.insert(
        "ei_nm2".to_string(),
        sample.laminate_ei_nm2() * hidden.ei_factor.unwrap_or(1.0),
    );
    if let Some(w) = &hidden.water {
        t.insert(
            "drag_quadratic_n_s2_per_m3".to_string(),
            0.5 * WATER_KG_M3 * w.drag_coefficient * sample.width_m,
        );
    }
    if let Some(factors) = &hidden.segment_factors {
        // The first segment is the reference the others deviate from.
        for (i, f) in factors.iter().enumerate().skip(1) {
            for (what, x) in [("r1", f.r1), ("c", f.c), ("k", f.k)] {
                t.insert(format!("segment_{}_{what}_deviation", i + 1), x - 1.0);
            }
        }
    }
    t
}

/// The pseudo-true value of every knob of `twin_fit`, the `finrs fit
/// --json` document of the session's twin with its measurement errors
/// shrunk ([`crate::sweep::write_twin`]): where the strip is not the
/// model (the literature strip's lines, spectrum and measured geometry),
/// no knob has a value in the strip to be scored against, but the fit
/// still has a value it tends to on endless data, the misspecified
/// model's pseudo-truth (White, 1982). An interval that holds it is
/// honest about the noise; one that misses it too often is too narrow.
pub fn pseudo_truth(twin_fit: &serde_json::Value) -> anyhow::Result<BTreeMap<String, f64>> {
    estimates_of(twin_fit, "the twin's fit")?
        .into_iter()
        .map(|(knob, e)| {
            Ok((
                knob.to_string(),
                number(e, knob, "value", "the twin's fit")?,
            ))
        })
        .collect()
}

/// The estimates of `fit`, a `finrs fit --json` document (`what`, in
/// messages), each with its knob's name.
fn estimates_of<'a>(
    fit: &'a serde_json::Value,
    what: &str,
) -> anyhow::Result<Vec<(&'a str, &'a serde_json::Value)>> {
    let list = fit["estimates"]
        .as_array()
        .ok_or_else(|| anyhow::anyhow!("{what}'s JSON has no `estimates` list"))?;
    list.iter()
        .map(|e| {
            let knob = e["knob"]
                .as_str()
                .ok_or_else(|| anyhow::anyhow!("an estimate of {what} without a `knob`: {e}"))?;
            Ok((knob, e))
        })
        .collect()
}

/// Field `field` of the estimate `e` of `knob` in `what`: a number.
fn number(e: &serde_json::Value, knob: &str, field: &str, what: &str) -> anyhow::Result<f64> {
    e[field]
        .as_f64()
        .ok_or_else(|| anyhow::anyhow!("{what}, estimate {knob}: `{field}` is not a number"))
}

/// One fitted knob against its true value.
#[derive(Clone, Debug, PartialEq)]
pub struct Scored {
    /// The knob's name.
    pub knob: String,
    /// The rig's value.
    pub truth: f64,
    /// The estimate.
    pub value: f64,
    /// Lower end of its 95 % interval.
    pub low: f64,
    /// Upper end.
    pub high: f64,
}

impl Scored {
    /// Whether the interval holds the truth.
    pub fn covered(&self) -> bool {
        self.low <= self.truth && self.truth <= self.high
    }

    /// The error in half-widths of the interval (within 1: covered, for a
    /// symmetric interval).
    pub fn error_in_half_widths(&self) -> f64 {
        let half = 0.5 * (self.high - self.low);
        if half > 0.0 {
            (self.value - self.truth).abs() / half
        } else {
            f64::INFINITY
        }
    }

    /// The error relative to the truth.
    pub fn relative_error(&self) -> f64 {
        (self.value - self.truth).abs() / self.truth.abs().max(f64::MIN_POSITIVE)
    }
}

/// Scores each estimate of a `finrs fit --json` document `fit` that has a
/// true value in `truth`; an estimate without one is left out.
pub fn score(
    fit: &serde_json::Value,
    truth: &BTreeMap<String, f64>,
) -> anyhow::Result<Vec<Scored>> {
    let mut out = Vec::new();
    for (knob, e) in estimates_of(fit, "the fit")? {
        let Some(&t) = truth.get(knob) else {
            continue;
        };
        let number = |field: &str| number(e, knob, field, "the fit");
        // JSON has no infinity: `finrs fit` writes an unbounded side of an
        // interval (a knob the data cannot pin, such as `p` once `b` has
        // gone to zero) as null. It covers every value on its side.
        let bound = |field: &str, unbounded: f64| {
            if e[field].is_null() {
                Ok(unbounded)
            } else {
                number(field)
            }
        };
        out.push(Scored {
            knob: knob.to_string(),
            truth: t,
            value: number("value")?,
            low: bound("low", f64::NEG_INFINITY)?,
            high: bound("high", f64::INFINITY)?,
        });
    }
    Ok(out)
}

/// Coverage of one knob over the sessions of one model structure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Sessions whose fit had the knob.
    pub sessions: usize,
    /// Of them, those whose interval held the truth.
    pub covered: usize,
    /// Errors in half-widths, one per session.
    pub errors: Vec<f64>,
    /// Relative errors, one per session.
    pub relative: Vec<f64>,
}

impl Tally {
    /// Fraction covered.
    pub fn coverage(&self) -> f64 {
        self.covered as f64 / self.sessions.max(1) as f64
    }
}

/// Per knob, the tally of `scored` (one list per session).
pub fn tally<'a>(scored: impl IntoIterator<Item = &'a [Scored]>) -> BTreeMap<String, Tally> {
    let mut out: BTreeMap<String, Tally> = BTreeMap::new();
    for session in scored {
        for s in session {
            let t = out.entry(s.knob.clone()).or_default();
            t.sessions += 1;
            t.covered += usize::from(s.covered());
            t.errors.push(s.error_in_half_widths());
            t.relative.push(s.relative_error());
        }
    }
    out
}

/// The median of `x` (finrs's: the upper of two middle values), NaN
/// when empty.
pub fn median(x: &[f64]) -> f64 {
    finrs::analysis::median::median(x.to_vec()).unwrap_or(f64::NAN)
}

/// A Markdown table of `tallies`, one per model structure (its label).
pub fn markdown(tallies: &[(&str, BTreeMap<String, Tally>)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| structure | knob | sessions | covered | coverage | median error / half-width | median relative error |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for (label, t) in tallies {
        for (knob, k) in t {
            let _ = writeln!(
                s,
                "| {label} | `{knob}` | {} | {} | {:.0} % | {:.2} | {:.2} % |",
                k.sessions,
                k.covered,
                100.0 * k.coverage(),
                median(&k.errors),
                100.0 * median(&k.relative)
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::SegmentFactors;

    fn sample() -> Sample {
        Sample {
            r1_ohm: 150.0,
            r2_ohm: 700.0,
            c_f: 1e-4,
            k_nm_per_c: 5.0,
            z_per_s: 0.2,
            p_per_s: 0.1,
            length_m: 0.05,
            width_m: 0.01,
            core_m: 2.818e-4,
            film_m: 2e-6,
        }
    }

    #[test]
    fn the_lead_network_is_the_models_a_b_p_and_segments_deviate_from_the_first() {
        let mut hidden = Hidden {
            ei_factor: Some(0.5),
            segment_factors: Some(vec![
                SegmentFactors::ONE,
                SegmentFactors {
                    r1: 1.1,
                    c: 0.9,
                    k: 1.05,
                },
            ]),
            ..Hidden::default()
        };
        let t = truth(&sample(), &hidden);
        assert_eq!(t["a_nm_per_c"], 5.0);
        assert!((t["b_nm_per_c_s"] - 1.0).abs() < 1e-12);
        assert_eq!(t["p_per_s"], 0.1);
        assert!((t["ei_nm2"] - 0.5 * sample().laminate_ei_nm2()).abs() < 1e-18);
        assert!((t["segment_2_r1_deviation"] - 0.1).abs() < 1e-12);
        assert!((t["segment_2_c_deviation"] + 0.1).abs() < 1e-12);
        assert!(!t.contains_key("segment_1_r1_deviation"));
        assert!(!t.contains_key("drag_quadratic_n_s2_per_m3"), "in air");
        // In water: ½ ρ C_d b, 10 N·s²/m³ for C_d 2 and 10 mm.
        hidden.water = Some(crate::sample::Water {
            added_mass_factor: 1.0,
            drag_coefficient: 2.0,
        });
        let t = truth(&sample(), &hidden);
        assert!((t["drag_quadratic_n_s2_per_m3"] - 10.0).abs() < 1e-12);
        // A second branch: the network is no longer the model's a, b, p.
        hidden.back_branch = Some((1.5, 3.0));
        let t = truth(&sample(), &hidden);
        assert!(!t.contains_key("a_nm_per_c") && !t.contains_key("p_per_s"));
        assert!(t.contains_key("r1_ohm"));
    }

    #[test]
    fn an_interval_is_scored_against_the_truth_and_tallied_per_knob() {
        let fit = serde_json::json!({"estimates": [
            {"knob": "r1_ohm", "value": 151.0, "low": 149.0, "high": 153.0},
            {"knob": "c_f", "value": 1.2e-4, "low": 1.1e-4, "high": 1.3e-4},
            {"knob": "damping_ratio", "value": 0.05, "low": 0.04, "high": 0.06},
        ]});
        let t = truth(&sample(), &Hidden::default());
        let s = score(&fit, &t).unwrap();
        // Damping has no truth and is left out.
        assert_eq!(s.len(), 2);
        assert!(s[0].covered());
        assert!((s[0].error_in_half_widths() - 0.5).abs() < 1e-12);
        assert!(!s[1].covered());
        assert!((s[1].relative_error() - 0.2).abs() < 1e-9);
        let tallies = tally([s.as_slice(), &s[..1]]);
        assert_eq!(tallies["r1_ohm"].sessions, 2);
        assert_eq!(tallies["r1_ohm"].covered, 2);
        assert_eq!(tallies["c_f"].coverage(), 0.0);
        let md = markdown(&[("true", tallies)]);
        assert!(
            md.contains("| true | `r1_ohm` | 2 | 2 | 100 % | 0.50 | 0.67 % |"),
            "{md}"
        );
        // A document without estimates is refused, naming what is missing.
        let err = score(&serde_json::json!({}), &t).unwrap_err();
        assert!(err.to_string().contains("estimates"), "{err}");
    }

    #[test]
    fn a_twins_estimates_are_the_truths_every_knob_of_both_fits_scored() {
        let twin = serde_json::json!({"estimates": [
            {"knob": "r1_ohm", "value": 160.0, "low": 159.9, "high": 160.1},
            {"knob": "damping_ratio", "value": 0.05, "low": 0.049, "high": 0.051},
        ]});
        let t = pseudo_truth(&twin).unwrap();
        assert_eq!(t.len(), 2);
        let fit = serde_json::json!({"estimates": [
            {"knob": "r1_ohm", "value": 151.0, "low": 149.0, "high": 153.0},
            {"knob": "damping_ratio", "value": 0.047, "low": 0.04, "high": 0.06},
            {"knob": "c_f", "value": 1.2e-4, "low": 1.1e-4, "high": 1.3e-4},
        ]});
        let s = score(&fit, &t).unwrap();
        // Damping now has a truth; C, which the twin's fit lacks, has none.
        assert_eq!(s.len(), 2);
        assert!(!s[0].covered(), "160 is beyond 149-153");
        assert!(s[1].covered());
        let err = pseudo_truth(&serde_json::json!({"estimates": [{"knob": "c_f"}]})).unwrap_err();
        assert!(err.to_string().contains("c_f: `value`"), "{err}");
    }

    #[test]
    fn a_null_bound_is_unbounded_and_a_missing_value_refused() {
        let t = truth(&sample(), &Hidden::default());
        let fit = serde_json::json!({"estimates": [
            {"knob": "p_per_s", "value": 0.002, "low": 0.0, "high": null},
        ]});
        let s = score(&fit, &t).unwrap();
        assert_eq!(s[0].high, f64::INFINITY);
        assert!(s[0].covered());
        assert_eq!(s[0].error_in_half_widths(), 0.0);
        let fit = serde_json::json!({"estimates": [
            {"knob": "p_per_s", "value": null, "low": 0.0, "high": 1.0},
        ]});
        let err = score(&fit, &t).unwrap_err();
        assert!(err.to_string().contains("`value`"), "{err}");
    }
}
