//! What a plan holds: per proposal its gains, the advice, the choice; and
//! the chosen proposals as a protocol.

use serde::Serialize;

use crate::analysis::diagnose::identify::Identifiability;
use crate::protocol::{Protocol, Step};
use crate::session::Session;

/// One effect's smallest detectable strength before and after a candidate.
#[derive(Clone, Debug, Serialize)]
pub struct EffectGain {
    /// The catalogue name.
    pub effect: String,
    /// Smallest detectable strength now (`null`: none up to the ceiling).
    pub before: Option<f64>,
    /// With the candidate added.
    pub after: Option<f64>,
    /// Detectable at the plausible strength now.
    pub detectable_before: bool,
    /// Detectable at the plausible strength with the candidate.
    pub detectable_after: bool,
    /// `log2(before/after)` of the term's value, an undetectable strength
    /// counted as twice the search's ceiling's.
    pub bits: f64,
}

/// One candidate, assessed.
#[derive(Clone, Debug, Serialize)]
pub struct Proposal {
    /// The recording as a protocol holds it (its fields at the top level
    /// of the JSON: `name`, `fixture`, `wave`, `rest_s`, `hold_s`, …).
    #[serde(flatten)]
    pub step: Step,
    /// Pause after the session before it, s (0: none).
    pub later_s: f64,
    /// What it is for.
    pub purpose: String,
    /// Its bench time, s.
    pub duration_s: f64,
    /// Effects it makes detectable at a plausible strength.
    pub newly_detectable: Vec<String>,
    /// Information it adds, bits, summed over the effects.
    pub bits: f64,
    /// Per effect.
    pub gains: Vec<EffectGain>,
    /// Why it could not be assessed, if it could not.
    pub refused: Option<String>,
}

/// A catalogue effect no recording of this session's kind can show.
#[derive(Clone, Debug, Serialize)]
pub struct Advice {
    /// The catalogue name.
    pub effect: String,
    /// Why it cannot be shown now.
    pub why: String,
    /// What would make it testable.
    pub change: String,
}

/// The plan for one session.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// The effects of the model assessed (beyond the baseline).
    pub effects: Vec<String>,
    /// The identifiability now, per catalogue effect the model lacks.
    pub now: Vec<Identifiability>,
    /// What the session's kind cannot show, and what would change that.
    pub advice: Vec<Advice>,
    /// Every candidate, best first.
    pub proposals: Vec<Proposal>,
    /// The budget, s of recording.
    pub budget_s: f64,
    /// Names of the proposals chosen within the budget, in rank order.
    pub chosen: Vec<String>,
}

impl Plan {
    /// The chosen proposals as a protocol for `finrs bench run`, with the
    /// session's sample, medium, geometry and dots; `None` when nothing
    /// was chosen.
    pub fn protocol(&self, session: &Session) -> Option<Protocol> {
        let first = &session.recordings.first()?.rec.meta;
        let dots = session
            .recordings
            .iter()
            .find_map(|r| r.rec.meta.dots_s_m.clone());
        let recordings: Vec<Step> = self
            .chosen
            .iter()
            .filter_map(|name| self.proposals.iter().find(|p| &p.step.name == name))
            .map(|p| Step {
                prompt: (p.later_s > 0.0)
                    .then(|| format!("wait {:.0} s after the session's last recording", p.later_s)),
                notes: Some(p.purpose.clone()),
                ..p.step.clone()
            })
            .collect();
        if recordings.is_empty() {
            return None;
        }
        Some(Protocol {
            sample: first.sample.clone(),
            medium: first.medium,
            geometry: first.geometry(),
            dots_s_m: dots,
            model: None,
            recordings,
        })
    }
}
