//! Whether the session could show each catalogue effect the final model
//! lacks, and from which strength: the part of the effect's signature
//! that the model's own knobs cannot absorb, against the search's own
//! gates.
//!
//! At the fitted model (weighted residuals, in noise units), the effect at
//! strength `s` changes the outputs by `d(s)`, simulated (a ringing that
//! damping kills saturates: `d` is not linear in `s`). The model's knobs
//! absorb `J δ`, fitted as the two-stage fit fits them (the circuit's
//! knobs on the training currents, then the beam's on the training camera
//! and load cell with the circuit's change held; `J` the model's Jacobian).
//! What remains, `λ = ‖d − J δ‖²`, is the RSS an effect of that strength
//! would save. The search names an effect when it saves
//! [`HOLDOUT_RSS_GAIN`] of the held-out RSS and `ΔBIC < `[`DELTA_BIC`] on
//! training (`λ_train > 10 + k ln m`, `k` its parameters), so the smallest
//! strength it can name is where `λ` passes both; it is searched by
//! halving, doubling and bisection. Two effects whose remaining training
//! signatures point the same way (`cos² ≥` [`CONFOUNDED_SHARE`]) cannot be
//! told apart from this protocol.
//!
//! The probes' plausible strengths (docs/diagnosis.md, "What a session
//! could show") say whether the answer matters: an effect detectable only
//! beyond what a real strip has is, for this protocol, not testable.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

use super::gates::{rss_per_recording, DELTA_BIC, HOLDOUT_RSS_GAIN};
use crate::analysis::fit::{
    difference_step, normal, Effect, FitError, FitResult, Fitter, Knob, Space,
};
use crate::model::predict::ModelSpec;
use crate::recording::{Channel, Medium};
use crate::session::Session;

/// Share of one effect's remaining signature another's explains above
/// which the two are reported as confounded.
pub const CONFOUNDED_SHARE: f64 = 0.5;

/// What the session could show of one effect.
#[derive(Clone, Debug, Serialize)]
pub struct Identifiability {
    /// The catalogue name.
    pub effect: String,
    /// What the strength measures.
    pub strength: &'static str,
    /// The smallest strength the search could name (`null`: none up to
    /// [`Identifiability::ceiling`], or, for large deflection, no strength).
    pub smallest_detectable: Option<f64>,
    /// A strength a real strip plausibly has (docs/diagnosis.md says why).
    pub plausible: f64,
    /// The largest strength searched: ten times the plausible one, or the
    /// term's bound.
    pub ceiling: f64,
    /// Whether the search could name the effect at the plausible strength.
    pub detectable: bool,
    /// The strength the shares below are measured at (the smallest
    /// detectable one where there is one).
    pub assessed_at: f64,
    /// Share of the training signature there that the model's knobs
    /// absorb, percent.
    pub absorbed_percent: f64,
    /// Remaining held-out signature there, in units of the gate
    /// ([`HOLDOUT_RSS_GAIN`] of each held-out recording's RSS, averaged
    /// over them).
    pub holdout_signature_over_gate: f64,
    /// Other effects whose terms explain at least [`CONFOUNDED_SHARE`] of
    /// this one's remaining signature, with that share in percent.
    pub confounded_with: Vec<(String, f64)>,
    /// Why the model refused the effect at the strength assessed last
    /// (this fitted model cannot carry it there).
    pub refused: Option<String>,
}

/// One effect's probe: what its strength means, the strength probed, the
/// plausible one, and the model with the effect at strength `s`.
struct Probe {
    effect: Effect,
    strength: &'static str,
    probe: f64,
    plausible: f64,
    /// The search's ceiling: ten times the plausible strength, or less
    /// where the term has a bound (EI above 0, a loss below 100 %).
    ceiling: f64,
}

/// What the probes scale with: the session's largest drive, its span on
/// the session clock and the strip's width.
struct Scales {
    v_max: f64,
    span_s: f64,
    width_m: f64,
}

impl Scales {
    /// The drying rate, 1/s, that loses `s < 1` of the gain over the
    /// session: `e^{−r T} = 1 − s` at its end.
    fn drying_per_s(&self, s: f64) -> f64 {
        -(1.0 - s).ln() / self.span_s.max(1e-9)
    }

    /// The cubic coefficient, 1/V², that departs `s` from linear at the
    /// session's largest drive.
    fn cubic_per_v2(&self, s: f64) -> f64 {
        s / self.v_max.powi(2).max(1e-12)
    }
}

impl Probe {
    /// The probe of `e`. Large deflection has no strength: it is the arc
    /// itself, probed whole (`probe` and `plausible` 1).
    fn of(e: Effect) -> Probe {
        let (strength, probe, plausible) = match e {
            Effect::LargeDeflection => ("the arc kinematics (on or off)", 1.0, 1.0),
            Effect::BeamStiffness => ("relative departure of EI", 0.05, 0.3),
            Effect::Damping => ("constant modal damping ratio", 0.01, 0.05),
            Effect::HydrodynamicLoading => ("added mass over a plate's, rho pi w^2/4", 0.1, 1.0),
            Effect::ElectrochemicalNonlinearity => (
                "departure from linear of charge and leak at the largest drive",
                0.05,
                0.1,
            ),
            Effect::BackRelaxation => (
                "steady moment against the instant one, b/(a p) < 0",
                0.05,
                0.2,
            ),
            Effect::Dehydration => ("loss of moment gain over the session", 0.05, 0.1),
            Effect::SegmentCrosstalk => ("fraction of a moment on each neighbour", 0.02, 0.05),
            Effect::SegmentVariation => {
                ("relative departure of segment 2's R1, C and K", 0.05, 0.1)
            }
        };
        let bound = match e {
            Effect::BeamStiffness => 0.9,
            Effect::Dehydration => 0.99,
            Effect::Damping | Effect::SegmentCrosstalk => 0.9,
            _ => f64::INFINITY,
        };
        Probe {
            effect: e,
            strength,
            probe,
            plausible,
            ceiling: (10.0 * plausible).min(bound),
        }
    }

    /// `spec` with the effect at strength `s`.
    fn apply(&self, spec: &ModelSpec, s: f64, scales: &Scales) -> ModelSpec {
        let mut out = *spec;
        match self.effect {
            Effect::LargeDeflection => out.ext.large_deflection = true,
            Effect::BeamStiffness => out.params.ei_nm2 *= 1.0 - s,
            Effect::Damping => out.ext.damping_ratio += s,
            Effect::HydrodynamicLoading => {
                out.ext.added_mass_kg_per_m +=
                    s * Medium::Water.plate_added_mass_kg_per_m(scales.width_m);
            }
            Effect::ElectrochemicalNonlinearity => {
                let per_v2 = scales.cubic_per_v2(s);
                out.ext.charge_cubic_per_v2 += per_v2;
                out.ext.leak_cubic_per_v2 += per_v2;
            }
            Effect::BackRelaxation => {
                out.ext.back_relaxation = true;
                out.params.b_nm_per_c_s = -s * out.params.a_nm_per_c * out.params.p_per_s;
            }
            Effect::Dehydration => {
                out.dehydration_per_s = scales.drying_per_s(s);
                out.dehydration_curvature = 0.0;
            }
            Effect::SegmentCrosstalk => out.ext.crosstalk += s,
            Effect::SegmentVariation => {
                let v = &mut out.ext.segment_variation;
                v.r1_deviation[1] += s;
                v.c_deviation[1] += s;
                v.k_deviation[1] += s;
            }
        }
        out
    }
}

/// The term's own value at strength `s` of effect `e` in `session`: the
/// drying rate, 1/s, and the cubic coefficient, 1/V², for the two effects
/// whose strength is relative to the session (its span, its largest
/// drive); the strength itself for the others. Two sessions' strengths
/// compare through it.
pub fn term_value(e: Effect, s: f64, session: &Session) -> f64 {
    let scales = scales(session);
    match e {
        Effect::Dehydration => scales.drying_per_s(s),
        Effect::ElectrochemicalNonlinearity => scales.cubic_per_v2(s),
        _ => s,
    }
}

/// Which residuals each part of the fit sees.
struct Rows {
    /// Held out, and a current (the circuit's stage), per residual.
    hold: Vec<bool>,
    current: Vec<bool>,
    /// Per residual, what its square counts in the held-out gain: one
    /// over the held-out recordings' count times its recording's RSS at
    /// the fitted model (0 in training). The search's gain
    /// ([`holdout_gain`](super::gates::holdout_gain)) is the geometric
    /// mean of the recordings' RSS ratios; an effect that saves `λᵣ` of
    /// recording `r`'s `Aᵣ` gains `1 − exp(mean ln(1 − λᵣ/Aᵣ))`, to first
    /// order `mean λᵣ/Aᵣ`, this weighted sum.
    hold_weight: Vec<f64>,
}

/// Identifiability of every effect in `effects` (testable, not in the
/// final model `fit`) from `session`, split into `train` and `hold`.
pub fn identify(
    session: &Session,
    fitter: &Fitter,
    fit: &FitResult,
    fixed: ModelSpec,
    effects: &[Effect],
    hold: &[usize],
) -> Result<Vec<Identifiability>, FitError> {
    if effects.is_empty() {
        return Ok(Vec::new());
    }
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let segments = session.recordings[0].rec.meta.segments;
    let space = Space::new(&fit.effects, segments, fixed);
    let theta = space.theta(&fit.spec);
    let spec = space.spec(&theta);
    let scales = scales(session);

    let base_score = fitter.score(&all, &spec)?;
    let held = |recording: &str| {
        let index = session
            .recordings
            .iter()
            .position(|r| r.name == recording)
            .unwrap_or(0);
        hold.contains(&index)
    };
    // Each held-out recording's RSS at the fitted model.
    let hold_rss: Vec<(&str, f64)> = rss_per_recording(&base_score)
        .into_iter()
        .filter(|(r, _)| held(r))
        .collect();
    let (mut hold_row, mut current, mut hold_weight) = (Vec::new(), Vec::new(), Vec::new());
    for c in &base_score.channels {
        let n = c.residuals.len();
        hold_row.extend(std::iter::repeat_n(held(&c.recording), n));
        current.extend(std::iter::repeat_n(
            matches!(c.channel, Channel::Current(_)),
            n,
        ));
        let w = match hold_rss.iter().find(|(r, _)| *r == c.recording) {
            Some(&(_, a)) if a > 0.0 => 1.0 / (hold_rss.len() as f64 * a),
            _ => 0.0,
        };
        hold_weight.extend(std::iter::repeat_n(w, n));
    }
    let rows = Rows {
        hold: hold_row,
        current,
        hold_weight,
    };
    // The weighted residuals of a model over the session, flattened.
    let flat = |spec: &ModelSpec| -> Result<Vec<f64>, FitError> {
        let s = fitter.score(&all, spec)?;
        Ok(s.channels.into_iter().flat_map(|c| c.residuals).collect())
    };
    let base: Vec<f64> = base_score
        .channels
        .iter()
        .flat_map(|c| c.residuals.iter().copied())
        .collect();
    let m_train = rows.hold.iter().filter(|&&h| !h).count();

    // The model's Jacobian, one column per knob (a session's simulation
    // each, in parallel).
    let columns: Result<Vec<Vec<f64>>, FitError> = (0..theta.len())
        .into_par_iter()
        .map(|j| {
            let h = difference_step(theta[j]);
            let mut t = theta.clone();
            t[j] += h;
            let r = flat(&space.spec(&t))?;
            Ok(r.iter().zip(&base).map(|(a, b)| (a - b) / h).collect())
        })
        .collect();
    let columns = columns?;

    let circuit: Vec<usize> = (0..space.knobs.len())
        .filter(|&j| space.knobs[j].is_circuit())
        .collect();
    let beam: Vec<usize> = (0..space.knobs.len())
        .filter(|&j| !space.knobs[j].is_circuit())
        .collect();
    let gate_hold = HOLDOUT_RSS_GAIN;
    let ctx = Context {
        flat: &flat,
        base: &base,
        spec,
        scales,
        columns: &columns,
        circuit: &circuit,
        rows: &rows,
        gate_hold,
    };
    let probes: Vec<Probe> = effects.iter().map(|&e| Probe::of(e)).collect();
    let assessed: Result<Vec<Searched>, FitError> = probes
        .par_iter()
        .map(|p| {
            // b's own column cannot follow a moment past its bound.
            let beam: Vec<usize> = if p.effect == Effect::BackRelaxation {
                beam.iter()
                    .copied()
                    .filter(|&j| space.knobs[j] != Knob::B)
                    .collect()
            } else {
                beam.clone()
            };
            let k = extra_parameters(p.effect, segments, fixed);
            let gate_train = -DELTA_BIC + k as f64 * (m_train.max(1) as f64).ln();
            // A strength the model refuses shows nothing, and says why.
            let assess = |s: f64| {
                Ok(ctx
                    .assess(p, s, &beam, gate_train)
                    .unwrap_or_else(|e| Assessment {
                        need: f64::INFINITY,
                        remainder: vec![0.0; base.len()],
                        absorbed_percent: 0.0,
                        over_gate: 0.0,
                        refused: Some(error_chain(&e)),
                    }))
            };
            if p.effect == Effect::LargeDeflection {
                let a = assess(1.0)?;
                return Ok((None, a.need <= 1.0, 1.0, a));
            }
            smallest_strength(p, &assess)
        })
        .collect();
    let assessed = assessed?;

    let mut out = Vec::new();
    for (i, (p, (smallest, detectable, at, a))) in probes.iter().zip(&assessed).enumerate() {
        let mut confounded = Vec::new();
        for (j, (_, _, _, other)) in assessed.iter().enumerate() {
            if j == i {
                continue;
            }
            let share = cos2_train(&a.remainder, &other.remainder, &rows.hold);
            if share >= CONFOUNDED_SHARE {
                confounded.push((probes[j].effect.name().to_string(), 100.0 * share));
            }
        }
        out.push(Identifiability {
            effect: p.effect.name().to_string(),
            strength: p.strength,
            smallest_detectable: *smallest,
            plausible: p.plausible,
            ceiling: p.ceiling,
            detectable: *detectable,
            assessed_at: *at,
            absorbed_percent: a.absorbed_percent,
            holdout_signature_over_gate: a.over_gate,
            confounded_with: confounded,
            refused: a.refused.clone(),
        });
    }
    Ok(out)
}

/// What every assessment of a probe shares: the model's residuals and
/// Jacobian over the session, and the held-out gate.
struct Context<'c> {
    flat: &'c (dyn Fn(&ModelSpec) -> Result<Vec<f64>, FitError> + Sync),
    base: &'c [f64],
    spec: ModelSpec,
    scales: Scales,
    columns: &'c [Vec<f64>],
    circuit: &'c [usize],
    rows: &'c Rows,
    gate_hold: f64,
}

/// One effect at one strength, against the model.
struct Assessment {
    /// Both gates' shortfall: at most 1 where the search could name it.
    need: f64,
    /// The signature less what the model absorbs, every residual.
    remainder: Vec<f64>,
    absorbed_percent: f64,
    over_gate: f64,
    /// Why the model refused the effect at this strength.
    refused: Option<String>,
}

impl Context<'_> {
    /// Effect `p` at strength `s`, the beam's knobs `beam` free, against
    /// the gates.
    fn assess(
        &self,
        p: &Probe,
        s: f64,
        beam: &[usize],
        gate_train: f64,
    ) -> Result<Assessment, FitError> {
        // Back-relaxation frees b's sign: measured from the bound b = 0,
        // which the baseline cannot pass, not from the fitted b.
        let reference = if p.effect == Effect::BackRelaxation {
            let mut at_bound = self.spec;
            at_bound.params.b_nm_per_c_s = 0.0;
            at_bound.ext.back_relaxation = true;
            (self.flat)(&at_bound)?
        } else {
            self.base.to_vec()
        };
        let with = (self.flat)(&p.apply(&self.spec, s, &self.scales))?;
        let d: Vec<f64> = with.iter().zip(&reference).map(|(a, b)| a - b).collect();
        let remainder = remainder(&d, self.columns, self.circuit, beam, self.rows);
        let energy = |v: &[f64], held: bool| -> f64 {
            v.iter()
                .zip(&self.rows.hold)
                .filter(|(_, &h)| h == held)
                .map(|(x, _)| x * x)
                .sum()
        };
        let r_hold: f64 = remainder
            .iter()
            .zip(&self.rows.hold_weight)
            .map(|(x, w)| w * x * x)
            .sum();
        let (d_train, r_train) = (energy(&d, false), energy(&remainder, false));
        let need = (self.gate_hold / r_hold).max(gate_train / r_train);
        Ok(Assessment {
            // A model that overflowed at this strength shows nothing.
            need: if need.is_nan() { f64::INFINITY } else { need },
            absorbed_percent: if d_train > 0.0 {
                100.0 * (1.0 - r_train / d_train)
            } else {
                100.0
            },
            over_gate: if self.gate_hold > 0.0 {
                r_hold / self.gate_hold
            } else {
                0.0
            },
            remainder,
            refused: None,
        })
    }
}

/// `e` and its sources, as the binary prints them.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out.push_str(": ");
        out.push_str(&s.to_string());
        source = s.source();
    }
    out
}

/// Where a strength search ended: the smallest detectable strength (if
/// any), whether the plausible one passes, the strength assessed last and
/// its assessment.
type Searched = (Option<f64>, bool, f64, Assessment);

/// Halvings or doublings from the probe, and bisections after, in the
/// search for the smallest strength: each is a session's simulation.
const STRENGTH_STEPS: usize = 12;

/// The smallest strength of `p` at which `assess` passes both gates (the
/// signature is not linear in the strength: a ringing that damping kills
/// saturates), searched from the probe by halving or doubling up to its
/// ceiling, then by bisection on a log scale.
/// Returns it (`None` if none up to there), whether the plausible strength
/// passes, the strength assessed last, and that assessment.
fn smallest_strength(
    p: &Probe,
    assess: &dyn Fn(f64) -> Result<Assessment, FitError>,
) -> Result<Searched, FitError> {
    let ceiling = p.ceiling;
    let (mut low, mut high) = (None, None);
    let mut s = p.probe;
    let mut last = (s, assess(s)?);
    for _ in 0..STRENGTH_STEPS {
        if last.1.need <= 1.0 {
            high = Some(last.0);
            if low.is_some() {
                break;
            }
            s = last.0 / 2.0;
        } else {
            low = Some(last.0);
            if high.is_some() || last.0 >= ceiling {
                break;
            }
            s = (last.0 * 2.0).min(ceiling);
        }
        last = (s, assess(s)?);
    }
    let Some(mut hi) = high else {
        return Ok((None, false, last.0, last.1));
    };
    let mut at = last;
    if let Some(mut lo) = low {
        for _ in 0..STRENGTH_STEPS / 2 {
            let mid = (lo * hi).sqrt();
            let a = assess(mid)?;
            if a.need <= 1.0 {
                hi = mid;
                at = (mid, a);
            } else {
                lo = mid;
            }
        }
    }
    if at.0 != hi {
        at = (hi, assess(hi)?);
    }
    Ok((Some(hi), hi <= p.plausible, at.0, at.1))
}

/// Parameters the search counts for `e` (as the fit's space counts them).
fn extra_parameters(e: Effect, segments: usize, fixed: ModelSpec) -> usize {
    let base = Space::new(&[], segments, fixed).counted_parameters();
    Space::new(&[e], segments, fixed).counted_parameters() - base
}

/// The session's largest drive, its span on the session clock, and the
/// strip's width.
fn scales(session: &Session) -> Scales {
    let mut v_max: f64 = 0.0;
    let mut span_s: f64 = 0.0;
    for r in &session.recordings {
        for &v in r.rec.v_v.as_flat() {
            v_max = v_max.max(v.abs());
        }
        span_s = span_s.max(r.end_s().unwrap_or(r.length_s()));
    }
    Scales {
        v_max,
        span_s,
        width_m: session.recordings[0].rec.meta.width_m,
    }
}

/// `d` less what the model's knobs absorb, fitted as the fit's two stages
/// fit them on the training rows: the circuit's knobs on the currents,
/// then the beam's on the other sensors with the circuit's change held.
fn remainder(
    d: &[f64],
    columns: &[Vec<f64>],
    circuit: &[usize],
    beam: &[usize],
    rows: &Rows,
) -> Vec<f64> {
    let train_current = |i: usize| !rows.hold[i] && rows.current[i];
    let train_beam = |i: usize| !rows.hold[i] && !rows.current[i];
    let delta_c = least_squares(d, columns, circuit, &train_current);
    let mut after_c = d.to_vec();
    subtract(&mut after_c, columns, circuit, &delta_c);
    let delta_b = least_squares(&after_c, columns, beam, &train_beam);
    subtract(&mut after_c, columns, beam, &delta_b);
    after_c
}

/// The coefficients of `columns[cols]` that best fit `d` over the rows
/// `keep` selects (least squares by a pseudo-inverse: a knob the rows do
/// not see gets no coefficient).
fn least_squares(
    d: &[f64],
    columns: &[Vec<f64>],
    cols: &[usize],
    keep: &dyn Fn(usize) -> bool,
) -> Vec<f64> {
    if cols.is_empty() {
        return Vec::new();
    }
    let picked: Vec<usize> = (0..d.len()).filter(|&i| keep(i)).collect();
    if picked.is_empty() {
        return vec![0.0; cols.len()];
    }
    // Normal equations, then solved in the columns' own scale with a
    // relative cut-off: a few knobs, many rows.
    let n = cols.len();
    let mut ata = DMatrix::<f64>::zeros(n, n);
    let mut atb = DVector::<f64>::zeros(n);
    for &i in &picked {
        for (a, &ca) in cols.iter().enumerate() {
            let xa = columns[ca][i];
            atb[a] += xa * d[i];
            for (b, &cb) in cols.iter().enumerate().skip(a) {
                ata[(a, b)] += xa * columns[cb][i];
            }
        }
    }
    for a in 0..n {
        for b in 0..a {
            ata[(a, b)] = ata[(b, a)];
        }
    }
    normal::solve(&ata, &atb)
}

/// `d -= columns[cols] · x`.
fn subtract(d: &mut [f64], columns: &[Vec<f64>], cols: &[usize], x: &[f64]) {
    for (&c, &xc) in cols.iter().zip(x) {
        for (di, ci) in d.iter_mut().zip(&columns[c]) {
            *di -= ci * xc;
        }
    }
}

/// `cos²` of the angle between `a` and `b` over the training rows.
fn cos2_train(a: &[f64], b: &[f64], hold: &[bool]) -> f64 {
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for ((x, y), &h) in a.iter().zip(b).zip(hold) {
        if !h {
            ab += x * y;
            aa += x * x;
            bb += y * y;
        }
    }
    if aa > 0.0 && bb > 0.0 {
        ab * ab / (aa * bb)
    } else {
        0.0
    }
}

/// One line: whether the session could show the effect, from which
/// strength, and what it is confounded with.
impl std::fmt::Display for Identifiability {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let could = if self.detectable {
            "could show"
        } else {
            "could not show"
        };
        write!(f, "{could} {}", self.effect)?;
        match self.smallest_detectable {
            Some(s) => write!(
                f,
                " from {s:.2e} ({}; plausible {})",
                self.strength, self.plausible
            )?,
            None if self.effect == "large-deflection" => write!(
                f,
                " (signature {:.2} of the gate)",
                self.holdout_signature_over_gate
            )?,
            None => write!(f, " at any {} up to {}", self.strength, self.ceiling)?,
        }
        // Near 100 %, the digits that remain are what the session sees.
        let digits = if self.absorbed_percent > 99.0 { 2 } else { 0 };
        write!(
            f,
            "; {:.*} % absorbed by the model",
            digits, self.absorbed_percent
        )?;
        for (name, share) in &self.confounded_with {
            write!(f, "; like {name} ({share:.0} %)")?;
        }
        if let Some(why) = &self.refused {
            write!(f, "; the model refuses it: {why}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(n: usize, hold_from: usize, current_below: usize) -> Rows {
        Rows {
            hold: (0..n).map(|i| i >= hold_from).collect(),
            current: (0..n).map(|i| i < current_below).collect(),
            hold_weight: (0..n)
                .map(|i| if i >= hold_from { 1.0 } else { 0.0 })
                .collect(),
        }
    }

    #[test]
    fn least_squares_recovers_a_combination_of_columns() {
        let n = 50;
        let c0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let c1: Vec<f64> = (0..n).map(|i| 1e6 * (i as f64 * 0.7).cos()).collect();
        let d: Vec<f64> = (0..n).map(|i| 2.0 * c0[i] - 3e-6 * c1[i]).collect();
        let x = least_squares(&d, &[c0, c1], &[0, 1], &|_| true);
        assert!(
            (x[0] - 2.0).abs() < 1e-9 && (x[1] + 3e-6).abs() < 1e-15,
            "{x:?}"
        );
    }

    #[test]
    fn the_stages_absorb_what_their_knobs_reach_and_leave_the_rest() {
        // Rows 0..20 currents, 20..40 the beam's; 30.. held out.
        let n = 40;
        let r = rows(n, 30, 20);
        let circuit: Vec<f64> = (0..n).map(|i| 1.0 + (i as f64).sin()).collect();
        let beam: Vec<f64> = (0..n)
            .map(|i| if i < 20 { 0.0 } else { (i as f64).cos() })
            .collect();
        let other: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let columns = [circuit.clone(), beam.clone()];
        // What the knobs reach is gone, held-out rows included.
        let d: Vec<f64> = (0..n).map(|i| 0.5 * circuit[i] - 2.0 * beam[i]).collect();
        let rem = remainder(&d, &columns, &[0], &[1], &r);
        assert!(rem.iter().all(|x| x.abs() < 1e-9), "{rem:?}");
        // The circuit's knob is fitted on the currents alone: a beam-only
        // signature along it is not absorbed by it.
        let rem = remainder(&other, &columns, &[0], &[], &r);
        let moved: f64 = rem.iter().zip(&other).map(|(a, b)| (a - b).abs()).sum();
        let on_currents: f64 = (0..20).map(|i| (rem[i] - other[i]).abs()).sum();
        assert!(moved > 0.0 && on_currents > 0.0);
        let beam_only: Vec<f64> = (0..n)
            .map(|i| if i < 20 { 0.0 } else { other[i] })
            .collect();
        let rem = remainder(&beam_only, &columns, &[0], &[], &r);
        assert_eq!(rem, beam_only);
    }

    #[test]
    fn cos2_reads_the_training_rows_only() {
        let hold = [false, false, true];
        assert!((cos2_train(&[1.0, 0.0, 5.0], &[2.0, 0.0, -7.0], &hold) - 1.0).abs() < 1e-12);
        assert_eq!(cos2_train(&[1.0, 0.0, 1.0], &[0.0, 1.0, 1.0], &hold), 0.0);
    }
}
