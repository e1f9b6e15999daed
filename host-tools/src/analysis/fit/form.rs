//! How far a fit's estimates lean on the form of its damping law.
//!
//! The fit's damping is a law over all modes (`damping`: a constant ratio
//! `ζ₀` and Rayleigh's `β`; the baseline has none). A real strip damps
//! each mode by a loss of its own (a polymer's loss peak, the clamp's
//! friction), which no two-term law follows, and the misfit of a held tip
//! ringing in several modes at once leans on the other knobs. On the
//! off-class rig, which damps each mode by its own ratio, the relaxation's
//! `b` and `p` came out 0.2 to 3.4 % off the truth on clean strips (seeds
//! 10008, 10026, 10034), in intervals a third as wide; refitted with the
//! rig's own ratios held, 0.03 to 0.5 %. No estimate of the noise sees
//! this: it is a bias of the model's form, the same in every recording.
//!
//! So `finrs fit` fits the structure a second time with each mode's own
//! ratio in place of the law ([`Space::with_each_modes_damping`]), from the
//! first fit's end, and each interval spans both fits' intervals: it
//! widens by as much as the estimate moves when the law's form is freed,
//! and not where the data do not care. The other forms the fit lacks (a
//! finer mesh, a drag quadratic in speed) are not checked.

use std::f64::consts::PI;

use model_core::DAMPED_MODES;

use super::effect::Effect;
use super::error::FitError;
use super::fitter::{pool, FitResult, Fitter, FormCheck};
use super::inflation::profile_cost;
use super::modal;
use super::mode_start;
use super::space::Space;
use super::stats::Estimate;
use crate::model::predict::ModelSpec;
use crate::recording::Fixture;

/// Evaluations the check's descents may take per free knob and one, a
/// quarter of a fit's: from the law's end they take a few (0.5 to 2 s on
/// the rig's 3-minute sessions); from a model without a law, on a strip
/// the baseline cannot follow (a board strip relaxing back), a fit's
/// budget ran out after 22 s where the relaxation stood as before.
const CHECK_PATIENCE: usize = 10;

impl Fitter<'_> {
    /// `effects` fitted on `recordings` around `fixed` from either start
    /// ([`Fitter::fit_from_either_start`]), its intervals widened to hold
    /// those of the same structure fitted with each mode's own damping
    /// ratio (see the module's text); the second fit's estimates in
    /// [`FitResult::form`]. The second fit starts from the kept start's
    /// end and runs beside the first's intervals: the same numbers as one
    /// after the other, the serial parts of each overlapped (10099's fit
    /// spent 6.7 s in the check after 10.9 s).
    pub fn fit_with_form_check(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        pool().install(|| {
            let kept = self.race_starts(recordings, effects, fixed)?;
            let fitted = kept.space.spec(&kept.theta);
            let kept_effects = kept.space.effects.clone();
            let (fit, each_mode) = rayon::join(
                || self.finish(recordings, kept),
                || self.each_modes_damping_from(recordings, &kept_effects, &fitted, fixed),
            );
            Ok(spanning(fit?, each_mode?, false))
        })
    }

    /// The structure of `fit` fitted again on `recordings` with each
    /// mode's own damping ratio in place of its damping law
    /// ([`Space::with_each_modes_damping`]), from where `fit` ended.
    pub fn each_modes_damping(
        &self,
        recordings: &[usize],
        fit: &FitResult,
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        self.each_modes_damping_from(recordings, &fit.effects, &fit.spec, fixed)
    }

    /// [`Self::each_modes_damping`] of `effects` fitted to `fitted`.
    fn each_modes_damping_from(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        fitted: &ModelSpec,
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        let segments = self.session.recordings[0].rec.meta.segments;
        let space = Space::new(effects, segments, fixed).with_each_modes_damping();
        let mut start = *fitted;
        if effects.contains(&Effect::Damping) {
            // Each mode starts at the ratio the law gives it, ζ₀ + β ω/2:
            // the second fit starts where the first one ended.
            let ext = fitted.ext;
            let law = |hz: f64| ext.damping_ratio + ext.damping_stiffness_s * PI * hz;
            for (fixture, ratios) in [
                (Fixture::Free, &mut start.ext.modal_damping.free),
                (Fixture::Blocked, &mut start.ext.modal_damping.blocked),
            ] {
                for (k, hz) in modal::model_hz(fitted, fixture, DAMPED_MODES)
                    .into_iter()
                    .enumerate()
                {
                    ratios[k..].fill(law(hz));
                }
            }
        } else {
            // Without a law, every mode at what the held strip's measured
            // ringing lacks, as the diagnosis starts `damping`.
            let moves = [vec![Effect::Damping]];
            let modes = mode_start::modes(self.session, recordings, fitted, &moves);
            let zeta = mode_start::start(Effect::Damping, fitted, modes)
                .ext
                .damping_ratio;
            start.ext.modal_damping.free.fill(zeta);
            start.ext.modal_damping.blocked.fill(zeta);
        }
        start.ext.damping_ratio = 0.0;
        start.ext.damping_stiffness_s = 0.0;
        self.fit_space(recordings, space, &start, CHECK_PATIENCE)
    }
}

/// The fit with the damping law and the same structure's fit with each
/// mode's own ratio ([`Fitter::each_modes_damping`]) as one result: the
/// model and estimates of the second if `each_mode_final`, else of the
/// first, every interval spanning both fits' intervals, and both fits'
/// own estimates in [`FitResult::form`].
pub fn spanning(law: FitResult, each_mode: FitResult, each_mode_final: bool) -> FitResult {
    let form = FormCheck {
        law: law.estimates.clone(),
        each_mode: each_mode.estimates.clone(),
        cost_law: profile_cost(&law.score),
        cost_each_mode: profile_cost(&each_mode.score),
        each_mode_final,
    };
    let (mut out, other) = if each_mode_final {
        (each_mode, law)
    } else {
        (law, each_mode)
    };
    widen(&mut out.estimates, &other.estimates);
    out.form = Some(form);
    out
}

/// Each of `estimates`' intervals widened to hold `other`'s interval for
/// the same knob, where `other` has it.
fn widen(estimates: &mut [Estimate], other: &[Estimate]) {
    for e in estimates {
        if let Some(o) = other.iter().find(|o| o.knob == e.knob) {
            e.low = e.low.min(o.low);
            e.high = e.high.max(o.high);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::fit::Knob;

    fn estimate(knob: Knob, value: f64, low: f64, high: f64) -> Estimate {
        Estimate {
            knob,
            value,
            low,
            high,
        }
    }

    #[test]
    fn an_interval_spans_both_fits_and_keeps_its_estimate() {
        let mut law = vec![
            estimate(Knob::P, 1.0, 0.9, 1.1),
            estimate(Knob::Zeta, 0.05, 0.04, 0.06),
        ];
        let each = vec![
            estimate(Knob::P, 1.3, 1.2, 1.4),
            estimate(Knob::FreeMode(0), 0.05, 0.04, 0.06),
        ];
        widen(&mut law, &each);
        assert_eq!(law[0], estimate(Knob::P, 1.0, 0.9, 1.4));
        // A knob the other fit has not is left as it was.
        assert_eq!(law[1], estimate(Knob::Zeta, 0.05, 0.04, 0.06));
    }

    #[test]
    fn an_unbounded_side_stays_unbounded() {
        let mut law = vec![estimate(Knob::B, 1.0, 0.5, f64::INFINITY)];
        widen(&mut law, &[estimate(Knob::B, 1.0, 0.8, 1.2)]);
        assert_eq!(law[0], estimate(Knob::B, 1.0, 0.5, f64::INFINITY));
    }
}
