//! `finrs plan`: which further recordings would let a session show the
//! effects it cannot show now, ranked by what they would add.
//!
//! The session is fitted (the baseline and any effects asked for, on the
//! diagnosis's training recordings), and its identifiability read
//! ([`identify`](crate::analysis::diagnose::identify)): per catalogue
//! effect the model lacks, the smallest strength the diagnosis could name.
//! Then each [candidate](candidates) recording is made as the fitted model
//! predicts it, with the session's own noise per sensor
//! ([`synthetic`]), added to the session, and the identifiability read
//! again. A candidate's worth is what it changes: the effects it makes
//! detectable at a strength a real strip plausibly has, and the bits of
//! information on the others, `log2(before/after)` of the smallest
//! detectable strength (an effect not detectable up to the search's
//! ceiling counts from twice the ceiling's value). Candidates are ranked by the
//! first, then the second, and chosen in that order within a time budget
//! (one that makes nothing testable only from [`MIN_BITS`]).
//! What no recording can change (a session in air cannot show water's
//! loading) is said as advice.
//!
//! Each candidate is assessed alone: two that show the same thing are not
//! worth the sum of their gains, and the chosen list says so.

pub mod candidates;
mod proposals;
mod report;
pub mod synthetic;

pub use candidates::{candidates, Candidate};
pub use proposals::{Advice, EffectGain, Plan, Proposal};

use crate::analysis::diagnose::identify::{error_chain, identify, term_value, Identifiability};
use crate::analysis::diagnose::{split, untestable, Untestable};
use crate::analysis::fit::{Effect, FitError, FitResult, Fitter};
use crate::model::predict::ModelSpec;
use crate::session::Session;

/// Information below which a proposal that makes nothing testable is not
/// chosen, bits.
pub const MIN_BITS: f64 = 1.0;

/// Why a plan could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The session could not be fitted or assessed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The session has too few recordings to hold any out.
    #[error("a plan needs the diagnosis's split: {0} recording(s) leave none to hold out")]
    TooFew(usize),
}

/// Plans further recordings for `session`, whose model is the baseline
/// with `effects` (fixed values `fixed`), within `budget_s` of recording.
/// `progress` hears what is being assessed.
pub fn plan(
    session: &Session,
    fixed: ModelSpec,
    effects: &[Effect],
    budget_s: f64,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Plan, PlanError> {
    let fitter = Fitter::new(session);
    let (train, hold) = split(session);
    if hold.is_empty() {
        return Err(PlanError::TooFew(session.recordings.len()));
    }
    progress("fitting the model");
    let fit = fitter.fit(&train, effects, None, fixed)?;
    let structural = untestable(session);
    let lacking: Vec<Effect> = Effect::ALL
        .into_iter()
        .filter(|e| !fit.effects.contains(e))
        .filter(|e| !structural.iter().any(|u| u.effect == e.name()))
        .collect();
    progress("identifiability of the session as it is");
    let now = identify(session, &fitter, &fit, fixed, &lacking, &hold)?;

    let noise = fitter.targets().sigma.clone();
    let end_s = session_end_s(session);
    let all = candidates(session, &fit.spec);
    // Proposals read as this bench reads its currents.
    let spec = ModelSpec {
        sensors_before_update: fitter.sampling().before_update,
        ..fit.spec
    };
    let mut proposals: Vec<Proposal> = all
        .iter()
        .enumerate()
        .map(|(k, c)| {
            progress(&format!("{} ({} of {})", c.step.name, k + 1, all.len()));
            let t_start_s = end_s.map(|t| t + c.later_s);
            let with =
                synthetic::recording(session, &c.step, &spec, &noise, t_start_s, k as u32 + 1)
                    .map_err(|e| error_chain(&e))
                    .and_then(|r| {
                        let mut more = session.clone();
                        more.recordings.push(r);
                        assess(&more, &fit, fixed, &lacking)
                            .map(|after| (after, more))
                            .map_err(|e| error_chain(&e))
                    });
            proposal(c, session, &now, with)
        })
        .collect();
    proposals.sort_by(|a, b| {
        b.newly_detectable
            .len()
            .cmp(&a.newly_detectable.len())
            .then(b.bits.total_cmp(&a.bits))
    });
    let mut chosen = Vec::new();
    let mut used_s = 0.0;
    for p in &proposals {
        // A bit halves one smallest detectable strength: less is within
        // what one draw of noise and a moved split change.
        let worth = !p.newly_detectable.is_empty() || p.bits >= MIN_BITS;
        if p.refused.is_none() && worth && used_s + p.duration_s <= budget_s {
            used_s += p.duration_s;
            chosen.push(p.step.name.clone());
        }
    }
    Ok(Plan {
        effects: fit.effects.iter().map(|e| e.name().to_string()).collect(),
        now,
        advice: structural.iter().map(advice).collect(),
        proposals,
        budget_s,
        chosen,
    })
}

/// The identifiability of `session` (a recording added) at the fitted
/// model, split as the diagnosis splits it.
fn assess(
    session: &Session,
    fit: &FitResult,
    fixed: ModelSpec,
    lacking: &[Effect],
) -> Result<Vec<Identifiability>, FitError> {
    let fitter = Fitter::new(session);
    let (_, hold) = split(session);
    identify(session, &fitter, fit, fixed, lacking, &hold)
}

/// A candidate's gains against `now`.
fn proposal(
    c: &Candidate,
    session: &Session,
    now: &[Identifiability],
    with: Result<(Vec<Identifiability>, Session), String>,
) -> Proposal {
    let (gains, refused) = match with {
        Ok((after, more)) => (
            now.iter()
                .filter_map(|b| {
                    let a = after.iter().find(|a| a.effect == b.effect)?;
                    let e = Effect::parse(&b.effect)?;
                    // Compared as the term's own value: drying's strength
                    // is a loss over the session, which a later recording
                    // lengthens. None up to the ceiling counts as twice the
                    // ceiling's value (twice a bounded strength, a 99 %
                    // loss, would be no strength at all).
                    let at = |i: &Identifiability, s: &Session| match i.smallest_detectable {
                        Some(x) => term_value(e, x, s),
                        None => 2.0 * term_value(e, i.ceiling, s),
                    };
                    Some(EffectGain {
                        effect: b.effect.clone(),
                        before: b.smallest_detectable,
                        after: a.smallest_detectable,
                        detectable_before: b.detectable,
                        detectable_after: a.detectable,
                        bits: (at(b, session) / at(a, &more)).log2(),
                    })
                })
                .collect(),
            None,
        ),
        Err(why) => (Vec::new(), Some(why)),
    };
    Proposal {
        step: c.step.clone(),
        later_s: c.later_s,
        purpose: c.purpose.clone(),
        duration_s: c.duration_s(),
        newly_detectable: gains
            .iter()
            .filter(|g| g.detectable_after && !g.detectable_before)
            .map(|g| g.effect.clone())
            .collect(),
        bits: gains.iter().map(|g| g.bits).sum(),
        gains,
        refused,
    }
}

/// Session time at the end of its last recording, s, when every
/// recording gives its start.
fn session_end_s(session: &Session) -> Option<f64> {
    session
        .recordings
        .iter()
        .map(|r| r.end_s())
        .try_fold(0.0f64, |end, t| t.map(|t| end.max(t)))
}

/// What would make a structurally untestable effect testable.
fn advice(u: &Untestable) -> Advice {
    let change = match Effect::parse(&u.effect) {
        Some(Effect::LargeDeflection) => {
            "record free runs with a camera on the tip and dots (a free step at the session's largest drive)"
        }
        Some(Effect::HydrodynamicLoading) => {
            "record a session of the same strip in water (`medium = \"water\"`): no recording in air shows it"
        }
        Some(Effect::SegmentVariation) => "only a strip of two or more segments can show it",
        Some(Effect::Dehydration) => {
            "give every recording its `t_session_start_s` (finrs bench run writes it) and spread the session over ten minutes or more"
        }
        _ => "see docs/diagnosis.md",
    };
    Advice {
        effect: u.effect.clone(),
        why: u.why.clone(),
        change: change.to_string(),
    }
}
