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
//! ratio in place of the law's constant one, Rayleigh's `β` kept
//! ([`Space::with_each_modes_damping`]: the law is one of its points), from
//! the first fit's end, and each interval spans both fits' intervals: it
//! widens by as much as the estimate moves when the law's form is freed,
//! and not where the data do not care. The other forms the fit lacks (a
//! finer mesh, a drag quadratic in speed) are not checked.

use super::effect::Effect;
use super::error::FitError;
use super::fitter::{pool, FitResult, Fitter, FormCheck};
use super::inflation::profile_cost;
use super::mode_start;
use super::space::Space;
use super::stats::Estimate;
use crate::model::predict::ModelSpec;

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
    /// after the other, the serial parts of each overlapped.
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
        let zeta = if effects.contains(&Effect::Damping) {
            fitted.ext.damping_ratio
        } else {
            // Without a law, every mode at what the held strip's measured
            // ringing lacks, as the diagnosis starts `damping`.
            let moves = [vec![Effect::Damping]];
            let modes = mode_start::modes(self.session, recordings, fitted, &moves);
            mode_start::start(Effect::Damping, fitted, modes)
                .ext
                .damping_ratio
        };
        let start = each_mode_at(fitted, zeta);
        self.fit_space(recordings, space, &start, CHECK_PATIENCE)
    }
}

/// `fitted` with every mode's own ratio at `zeta` in place of its law's
/// constant `ζ₀`, `β` as it was. At `zeta = ζ₀` the law's fit itself, so
/// the check starts at its end and moves only as far as each mode's own
/// ratio lowers the cost. Each mode at the law's `ζ₀ + β ω/2` with `β`
/// gone (before 2026-11-27) is not the law where `β` is large: the modes
/// above the own ones then keep the first's small ratio, and 10099's check
/// crawled for 6.5 s to end at 3.2 times the law's cost.
fn each_mode_at(fitted: &ModelSpec, zeta: f64) -> ModelSpec {
    let mut start = *fitted;
    start.ext.modal_damping.free.fill(zeta);
    start.ext.modal_damping.blocked.fill(zeta);
    start.ext.damping_ratio = 0.0;
    start
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

    /// The check starts on the law's fit: through the check's knobs and
    /// back, every mode of both fixtures damped as the law damps it (to
    /// the rounding of a knob's unit and back).
    #[test]
    fn the_checks_start_is_the_laws_fit() {
        use crate::model::predict::ModelSpec;
        use model_core::{Fixture, Params};
        let mut law = ModelSpec::baseline(Params::main_m_2006());
        law.ext.damping_ratio = 0.031;
        law.ext.damping_stiffness_s = 2.7e-4;
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let space = Space::new(&[Effect::Damping], 3, fixed).with_each_modes_damping();
        let start = each_mode_at(&law, law.ext.damping_ratio);
        let round_trip = space.spec(&space.start_theta(&start));
        for fixture in [Fixture::Free, Fixture::Blocked] {
            for k in 0..12 {
                let omega = 40.0 * (k + 1) as f64 * (k + 1) as f64;
                let want = law.ext.two_zeta_omega(fixture, k, omega, 8e-3);
                let got = round_trip.ext.two_zeta_omega(fixture, k, omega, 8e-3);
                assert!(
                    (got - want).abs() <= 4.0 * f64::EPSILON * want,
                    "{fixture:?} mode {k}: {got} against {want}"
                );
            }
        }
        // And without `β` kept (the form before), the modes above the
        // first free one would be damped far less than the law damps them.
        let mut no_beta = round_trip;
        no_beta.ext.damping_stiffness_s = 0.0;
        let high = |s: &ModelSpec| s.ext.two_zeta_omega(Fixture::Free, 5, 1e4, 8e-3);
        assert!(high(&no_beta) < 0.2 * high(&law));
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
