//! The forward search over the catalogue of effects, and the verdict.

use rayon::prelude::*;

use super::analyses;
use super::choose::{choose, Passed};
use super::drift;
use super::drying;
use super::faults;
use super::floors::sensor_floors;
use super::gates::{each_mode_damping_kept, holdout_gain, holdout_gain_passes, Bar, DELTA_BIC};
use super::identify;
use super::reaction;
use super::rests::{rest_structure, BenchFinding};
use super::verdict::{
    Candidate, Diagnosis, Evidence, ModelScore, ResidualTest, Untestable, Verdict,
};
use super::whiteness::{self, INPUT_LAGS};
use crate::analysis::fit::mode_start as starts;
use crate::analysis::fit::{above_at, below_at, beyond_at, excludes_at, Estimate};
use crate::analysis::fit::{
    form, profile_cost, session_peak_v, with_session_peak, ChannelFit, Effect, FitError, FitResult,
    Fitter, Knob, Score,
};
use crate::model::predict::ModelSpec;
use crate::recording::{Fixture, Medium};
use crate::session::Session;

/// Effects accepted at most: a damped, soft strip needs two before any
/// other (every real strip, docs/FORMAT.md), and up to three more are
/// what a session hides (the literature rig draws up to three departures
/// beside the base's two; at four, development seed 50091's drying
/// passed its round beside the reaction's and was left out when the
/// reaction took the fourth place). The rounds' shares of `α` halve and
/// stay below `α` in sum however many run
/// ([`super::gates::round_alpha`]), so a fifth round keeps the search's
/// chance of a false name below `α`.
pub const MAX_CAUSES: usize = 5;
/// The effects the blocked mode's frequency and decay speak to, tried
/// together as well as apart.
pub const MODE_PAIR: [Effect; 2] = [Effect::Damping, Effect::BeamStiffness];
/// In water, [`MODE_PAIR`] and the fluid tried together as well: the
/// fluid's added mass lowers the mode and its drag damps it, so the pair
/// alone takes the fluid's share too, and can end with a term at its
/// bound and no interval (development seed 52110: `ζ₀` at its cap of
/// 0.9 beside a reaction in water, where the fit of all three gave 0.046
/// for a true 0.053), while the fluid alone cannot move a mode that the
/// soft, damped strip holds elsewhere.
pub const FLUID_AND_PAIR: [Effect; 3] = [
    Effect::Damping,
    Effect::BeamStiffness,
    Effect::HydrodynamicLoading,
];
/// How far a segment's `R1`, `C` or `K` may lie from segment 1's with the
/// segments still alike, relative: `segment-variation` is named only where
/// some deviation's interval lies beyond it. No strip's segments are
/// exactly alike, and a model whose form is off finds differences of a
/// percent or two between them "significant" by intervals that assume it
/// is right (literature rig seeds 50010, 50034, 50082, board sessions with
/// no variation: `K` deviations of 0.9–2.2 %). The diagnosis's own probe
/// of the effect (`identify.rs`) is 5 %.
pub const SEGMENT_ALIKE: f64 = 0.05;
/// How large a neighbour's share of a segment's moment a strip without
/// crosstalk shows on the lone drives ([`Search::crosstalk_on_lone_drives`]):
/// `segment-crosstalk` is named there only where `κ`'s interval lies
/// beyond it. A lone drive bends the neighbours only through the form the
/// model lacks as well (the electrodes' resistance along a segment, the
/// large rotation): fitted beside the damped, soft pair, the lone drives
/// of the literature strip's base gave `κ` between −0.022 and 0.043, none
/// beyond 0.02 at its 95 % interval (null seeds 61000–61059); those of
/// development sessions without crosstalk, up to 0.015 significantly
/// above zero (50016). The diagnosis's own probe of the effect
/// (`identify.rs`) detects from 0.02.
pub const CROSSTALK_ALIKE: f64 = 0.02;

/// The fewest recordings a split holds out where the session allows:
/// one held-out recording tests the model on one drive alone.
pub const MIN_HELD_OUT: usize = 2;

/// Splits a session: about every third recording, from the second, is
/// held out, where it is not its kind's (fixture and segments driven)
/// first or last run in the session's order and its kind keeps a
/// training recording; in its place the next, else the one before, where
/// that one may be. A drive the training part never shows (segment 3
/// alone, the only blocked run) is not held out: its prediction would
/// test how well the other recordings pin the knobs it alone moves (each
/// segment's `K`), not the model's form. A kind's first and last runs
/// stay in training so that a change over the session (drying, a slow
/// loss of the strip's) is fitted over the whole time its held-out runs
/// lie in: a held-out run past the training's last of its kind tests an
/// extrapolation of the catalogue's law, whose form only approximates a
/// strip's (development drying seeds 54124 and 54232: the force's loss
/// seen only on held-out blocked runs, its fit worse than none on
/// training). Nor is a drive beyond every training recording's held out
/// (a step to 4 V where the others reach 2.5 V): its prediction would
/// test an extrapolation in voltage, where the reaction departs (the
/// tests' six-run protocol, `host-tools/tests/common`, with its travelling
/// sine kept as its kind's last run, held out the 4 V step and named no
/// reaction). Each fixture the session has is held out where an inner run
/// of it may be: free runs alone show the beam's stiffness, and blocked
/// ones the force a drying takes (null seed 61012 held out two blocked
/// runs and lost its `beam-stiffness`). Only an inner run of its kind is
/// held out for a fixture, as for the pattern: the ten-run protocol's
/// first blocked step, held out, left its load cell at 6.5 times the
/// floor in tests/rig's beam-stiffness session and 443 times in the
/// hydrodynamic one, and each named a false `damping`. Where that
/// holds out fewer than [`MIN_HELD_OUT`], the other recordings are taken
/// in order, by the same rules, until it does; then a kind's ends too;
/// then a drive beyond the training's, the rule that gives way last: a
/// reaction is seen only above the drives it was fitted on (development
/// seed 50074, dropping both rules at once, held out its only step above
/// 3 V, fitted the reaction's reference at 4.4 V, beyond every training
/// drive, and missed it at twice its plausible strength).
pub fn split(session: &Session) -> (Vec<usize>, Vec<usize>) {
    let n = session.recordings.len();
    let kinds: Vec<_> = session
        .recordings
        .iter()
        .map(|r| (r.rec.meta.fixture, r.driven()))
        .collect();
    let end = |i: usize| {
        !(0..i).any(|j| kinds[j] == kinds[i]) || !(i + 1..n).any(|j| kinds[j] == kinds[i])
    };
    let peaks: Vec<f64> = session
        .recordings
        .iter()
        .map(|r| {
            r.drive()
                .v_v
                .rows()
                .flat_map(|v| v.iter().map(|x| x.abs()))
                .fold(0.0, f64::max)
        })
        .collect();
    // Whether run `i` may join `hold`: one whose kind keeps a training
    // recording and, by `level`, 0: an inner run whose drive some
    // training recording reaches (within the DAQ's reading of a repeat);
    // 1: a kind's end too; 2: any drive.
    let may = |i: usize, level: u8, hold: &[usize]| {
        let training = |j: usize| j != i && !hold.contains(&j);
        i < n
            && !hold.contains(&i)
            && (level >= 1 || !end(i))
            && (0..n).any(|j| training(j) && kinds[j] == kinds[i])
            && (level >= 2 || (0..n).any(|j| training(j) && peaks[j] >= 0.99 * peaks[i]))
    };
    let mut hold: Vec<usize> = Vec::new();
    let pattern = || (1..n).step_by(3);
    for p in pattern() {
        if let Some(i) = [p, p + 1, p - 1].into_iter().find(|&i| may(i, 0, &hold)) {
            hold.push(i);
        }
    }
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let of_it = |i: &usize| kinds[*i].0 == fixture;
        if hold.iter().any(of_it) {
            continue;
        }
        // An inner run only (level 0); the doc comment says why.
        if let Some(i) = (0..n).filter(of_it).find(|&i| may(i, 0, &hold)) {
            hold.push(i);
        }
    }
    let others = || (2..n).step_by(3).chain((0..n).step_by(3));
    // Each rule given way in turn, the drive's last.
    let fallback = others().map(|i| (i, 0)).chain(
        [1, 2]
            .into_iter()
            .flat_map(|level| pattern().chain(others()).map(move |i| (i, level))),
    );
    for (i, level) in fallback {
        if hold.len() >= MIN_HELD_OUT {
            break;
        }
        if may(i, level, &hold) {
            hold.push(i);
        }
    }
    hold.sort_unstable();
    let train = (0..n).filter(|i| !hold.contains(i)).collect();
    (train, hold)
}

/// The catalogue effects `session` cannot show, and why (docs/FORMAT.md):
/// `large-deflection` needs a free recording (the board alone records
/// blocked runs only), `hydrodynamic-loading` water around the strip,
/// `segment-variation` two segments or more, `dehydration` the session
/// time of every recording. They are not tried, and the verdict says so.
pub fn untestable(session: &Session) -> Vec<Untestable> {
    let mut out = Vec::new();
    let recs = &session.recordings;
    if !recs.iter().any(|r| r.rec.meta.fixture == Fixture::Free) {
        out.push(Untestable {
            effect: Effect::LargeDeflection.name().to_string(),
            why: "every recording is blocked (`fixture`): the arc moves a free tip toward the clamp, which only a camera on a free run sees; it does not change the held tip's force".to_string(),
        });
    }
    if !recs.iter().any(|r| r.rec.meta.medium == Medium::Water) {
        out.push(Untestable {
            effect: Effect::HydrodynamicLoading.name().to_string(),
            why: "the session is in air (`medium`): air's density is 1/800 of water's, so it cannot show added mass or drag".to_string(),
        });
    }
    if recs.first().is_some_and(|r| r.rec.meta.segments < 2) {
        out.push(Untestable {
            effect: Effect::SegmentVariation.name().to_string(),
            why: "the strip has one segment: there is no other to differ from it".to_string(),
        });
    }
    let without: Vec<&str> = recs
        .iter()
        .filter(|r| r.t_start_s.is_none())
        .map(|r| r.name.as_str())
        .collect();
    if !without.is_empty() {
        out.push(Untestable {
            effect: Effect::Dehydration.name().to_string(),
            why: format!(
                "{} of {} recordings give no `t_session_start_s` ({}): drying is measured on the session's clock",
                without.len(),
                recs.len(),
                without.join(", ")
            ),
        });
    }
    out
}

/// Diagnoses `session`; `progress` hears what is being fitted.
pub fn diagnose(
    session: &Session,
    fixed: ModelSpec,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Diagnosis, FitError> {
    let fitter = Fitter::new(session);
    let (train, hold) = split(session);
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    if hold.is_empty() {
        return Err(FitError::TooFewToHoldOut(session.recordings.len()));
    }
    let name = |i: &usize| session.recordings[i.to_owned()].name.clone();
    progress("baseline");
    let baseline = fitter.fit(&train, &[], None, fixed)?;
    let base_hold = fitter.score(&hold, &baseline.spec)?;
    let search = Search {
        session,
        fitter: &fitter,
        train: &train,
        hold: &hold,
        // Carrying the session's highest drive: a reaction shows below it.
        fixed: with_session_peak(fixed, fitter.peak_drive_v()),
        alone: driven_alone(session, &train),
        span_s: span_s(session, &train),
    };
    let untestable = untestable(session);
    let mut found = search.run(&baseline, &base_hold, &untestable, progress)?;
    progress("crosstalk on the lone drives");
    let (fixed, lone_crosstalk) = search.crosstalk_on_lone_drives(&mut found)?;
    if lone_crosstalk.is_some() {
        // The search goes on beside the held crosstalk: a term that stood
        // in for it in the rounds before can now show its own.
        let held = Search { fixed, ..search };
        held.rounds(&mut found, &untestable, progress)?;
    }
    // The damping's form: the final model fitted again with each mode's
    // own ratio in place of the law. Where the model has `damping` and the
    // second fit gains on the held-out part as a candidate must, it is the
    // final model: a form of the damping, not a name, chosen after the
    // search, which it does not steer. Either way the intervals span both.
    progress("the damping law's form");
    let each_mode = fitter.each_modes_damping(&train, &found.fit, fixed)?;
    let each_hold = fitter.score(&hold, &each_mode.spec)?;
    let each_mode_gain_percent = found
        .fit
        .effects
        .contains(&Effect::Damping)
        .then(|| 100.0 * holdout_gain(&each_hold, &found.hold));
    let each_mode_final = each_mode_gain_percent.is_some_and(each_mode_damping_kept);
    let final_hold = if each_mode_final {
        each_hold
    } else {
        found.hold.clone()
    };
    let per = |s: &Score| s.rss / s.m.max(1) as f64;
    // Each sensor on its own: pooled, the currents would hide the rest.
    let sensors = sensor_floors(&final_hold);
    let at_floor = sensors.iter().all(|f| f.at_floor);
    let causes: Vec<String> = found
        .accepted()
        .iter()
        .map(|e| e.name().to_string())
        .collect();
    let mut rest = rest_structure(session);
    let sampling = fitter.sampling();
    if sampling.before_update {
        // Found in the currents and followed by every fit: said, never a
        // reason for `unexplained`.
        rest.bench.push(BenchFinding {
            what: "currents-read-before-update".to_string(),
            channel: "currents".to_string(),
            mains_hz: None,
            strength: sampling.late_share,
            detail: sampling.to_string(),
        });
    }
    let verdict = match (causes.is_empty(), at_floor && !rest.structured) {
        (true, true) => "none",
        (false, true) => "explained",
        (_, false) => "unexplained",
    };
    progress("identifiability");
    let named = found.accepted();
    let lacking: Vec<Effect> = Effect::ALL
        .into_iter()
        .filter(|e| !named.contains(e))
        .filter(|e| !untestable.iter().any(|u| u.effect == e.name()))
        .collect();
    let (identifiability, identifiability_refused) =
        match identify::identify(session, &fitter, &found.fit, fixed, &lacking, &hold) {
            Ok(v) => (v, None),
            Err(e) => (Vec::new(), Some(identify::error_chain(&e))),
        };
    let mut final_fit = form::spanning(found.fit, each_mode, each_mode_final);
    if let Some(est) = lone_crosstalk {
        final_fit = final_fit.with_held(est);
    }
    rest.bench
        .extend(drift::findings(&fitter.drifts(&all, &final_fit.spec)?));
    rest.bench.extend(drift::carry_over(
        &fitter.carry_overs(&all, &final_fit.spec)?,
    ));
    let score_of = |fit: &FitResult, hold: &Score| ModelScore {
        holdout_nrmse: hold.nrmse,
        holdout_rss_per_residual: per(hold),
        bic: fit.bic,
        aic: fit.aic,
        parameters: fit.parameters,
    };
    let verdict = Verdict {
        causes,
        verdict: verdict.to_string(),
        baseline: score_of(&baseline, &base_hold),
        extended: score_of(&final_fit, &final_hold),
        gain_percent: gain_percent(base_hold.nrmse, final_hold.nrmse),
        each_mode_damping_gain_percent: each_mode_gain_percent,
        candidates: found.candidates,
        params: final_fit
            .estimates
            .iter()
            .map(|e| (e.knob.name().to_string(), e.value))
            .collect(),
        training: train.iter().map(name).collect(),
        holdout: hold.iter().map(name).collect(),
        residual_tests: residual_tests(&base_hold, &final_hold),
        sensors,
        untestable,
        rest,
        faults: faults::findings(session),
        analyses: analyses::analyse(session, &fitter.score(&all, &baseline.spec)?),
        identifiability,
        identifiability_refused,
    };
    Ok(Diagnosis {
        verdict,
        baseline,
        final_fit,
        holdout_scores: (base_hold, final_hold),
        holdout: hold,
    })
}

impl Found {
    /// Effects accepted, in the order they joined.
    fn accepted(&self) -> Vec<Effect> {
        self.joined
            .iter()
            .flat_map(|j| j.effects.iter().copied())
            .collect()
    }
}

/// Which of a move's effects must show their own term (see
/// `signature_is_significant`).
#[derive(Clone, Copy)]
enum Signatures {
    /// Each: a move joining the model.
    Every,
    /// One: a cause checked after the search.
    Any,
}

/// What the forward search needs: the session split in two, and the
/// baseline's fixed values.
struct Search<'a> {
    session: &'a Session,
    fitter: &'a Fitter<'a>,
    train: &'a [usize],
    hold: &'a [usize],
    fixed: ModelSpec,
    /// The segments a training recording drives alone ([`driven_alone`]).
    alone: Vec<usize>,
    /// The training recordings' span on the session clock ([`span_s`]).
    span_s: f64,
}

/// Where the forward search ended.
struct Found {
    /// The final model's fit on the training part.
    fit: FitResult,
    /// Its score on the held-out part.
    hold: Score,
    /// The moves that joined, in order.
    joined: Vec<Joined>,
    /// Every candidate tried.
    candidates: Vec<Candidate>,
    /// The rounds the search started: the next round's share of `α` is
    /// one no test has spent.
    rounds: usize,
}

/// A move that joined the model.
struct Joined {
    /// An effect, or [`MODE_PAIR`].
    effects: Vec<Effect>,
    /// The bar its signature tests cleared: its round's.
    bar: Bar,
    /// Measured apart and held in the model, not one of its fitted
    /// effects (crosstalk on the lone drives): checked where it was
    /// measured, not by [`Search::prune`].
    held: bool,
}

impl Search<'_> {
    /// Adds, round by round, the best effect (or [`MODE_PAIR`]) that passes
    /// the tests, until none passes or [`MAX_CAUSES`] are in.
    fn run(
        &self,
        baseline: &FitResult,
        base_hold: &Score,
        untestable: &[Untestable],
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<Found, FitError> {
        let mut found = Found {
            fit: baseline.clone(),
            hold: base_hold.clone(),
            joined: Vec::new(),
            candidates: Vec::new(),
            rounds: 0,
        };
        self.rounds(&mut found, untestable, progress)?;
        Ok(found)
    }

    /// The search's rounds from `found.rounds` on, each adding the best
    /// passing move, then the check of every cause ([`Self::prune`]);
    /// `found.rounds` ends at the first round whose share of `α` no test
    /// spent.
    fn rounds(
        &self,
        found: &mut Found,
        untestable: &[Untestable],
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<(), FitError> {
        let mut round = found.rounds;
        while found.accepted().len() < MAX_CAUSES {
            let named = found.accepted();
            let untried: Vec<Effect> = Effect::ALL
                .into_iter()
                .filter(|e| !named.contains(e))
                .filter(|e| !untestable.iter().any(|u| u.effect == e.name()))
                .collect();
            let mut moves: Vec<Vec<Effect>> = untried.iter().map(|&e| vec![e]).collect();
            // A joint move while all its effects are untried and room is
            // left for them all.
            let joint = |m: &[Effect]| {
                m.iter().all(|e| untried.contains(e)) && named.len() + m.len() <= MAX_CAUSES
            };
            // The blocked mode's frequency and decay are read together: a
            // damped, soft strip leaves a model with either term alone off
            // in the other, and neither alone may then gain (the classic
            // trap of adding one term at a time), so the two are also
            // tried together.
            if joint(&MODE_PAIR) {
                moves.push(MODE_PAIR.to_vec());
            }
            if self.expected(Effect::HydrodynamicLoading) && joint(&FLUID_AND_PAIR) {
                moves.push(FLUID_AND_PAIR.to_vec());
            }
            if moves.is_empty() {
                break;
            }
            progress(&format!("round {}: {} candidates", round + 1, moves.len()));
            // The round's share of α, split among its candidates.
            let bar = Bar::of_round(round, moves.len());
            let mut passed: Vec<Passed<Vec<Effect>>> = Vec::new();
            // The pair, then the fluid and pair, come after the single
            // effects: a larger move is judged against the smaller that
            // passed before it.
            let mut fits = self.fit_round(&moves, &found.fit)?;
            self.members_from_pair(&mut fits, &found.fit, bar)?;
            for (m, fit, score) in fits {
                let mut candidate = self.judge(
                    &m,
                    round,
                    (&fit, &score),
                    (&found.fit, &found.hold),
                    Signatures::Every,
                    bar,
                );
                // A move of several effects must pay, on held-out data,
                // for what it adds to a smaller move of its own effects
                // that passed (the pair over a member, the fluid and pair
                // over the pair), as those effects would joining a round
                // later.
                candidate.passed &= passed
                    .iter()
                    .filter(|p| p.0.len() < m.len() && p.0.iter().all(|e| m.contains(e)))
                    .all(|p| holdout_gain_passes(holdout_gain(&score, &p.2)));
                if candidate.passed {
                    passed.push((m, fit, score));
                }
                found.candidates.push(candidate);
            }
            let Some((m, fit, score)) = choose(passed, |m| m.iter().any(|&e| self.expected(e)))
            else {
                break;
            };
            found.joined.push(Joined {
                effects: m,
                bar,
                held: false,
            });
            found.fit = fit;
            found.hold = score;
            // The model that joined, fitted again from the data's own
            // start: the next round's candidates start from it, and a
            // candidate that only finished its descent would gain for
            // nothing of its own. The lower of the two by the cost both
            // descents minimised (each sensor at its most likely
            // variance), as `Fitter::fit_from_either_start` keeps its
            // lower: by the RSS at the rests' noise, the load cell's
            // thousand residuals a second outvote the camera's thirty.
            let again = self
                .fitter
                .fit(self.train, &found.fit.effects, None, self.fixed)?;
            if profile_cost(&again.score) < profile_cost(&found.fit.score) {
                found.hold = self.fitter.score(self.hold, &again.spec)?;
                found.fit = again;
            }
            round += 1;
        }
        self.prune(found, round, progress)?;
        found.rounds = round + 1;
        Ok(())
    }

    /// After the search, each move that joined must still pay its way
    /// beside those that joined after it. One that joined early can have
    /// stood in for a later one: on the off-class rig, `segment-crosstalk`
    /// took part of a damped, soft strip's misfit in the first round,
    /// before the pair that fits it joined, and stayed (seeds 10003 and
    /// 10035). Each is judged as a candidate joining the model of all the
    /// others last, the others refitted without it from the final values,
    /// by the search's tests at the bar the move cleared when it joined,
    /// save that one term of the pair need be significant: beside a later
    /// term that shares its work, a member's interval can take in "off"
    /// while the pair still carries the fit
    /// (in water, the damping's ratio beside the fluid's drag, with 99 % of
    /// the held-out RSS on the pair; rig seed 10002). Of those that fail, the one of
    /// least held-out gain leaves, and the rest are judged again. A move
    /// the session's evidence calls for (the fluid it names) stays, as it
    /// joined ([`choose`]).
    fn prune(
        &self,
        found: &mut Found,
        round: usize,
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<(), FitError> {
        // A held move is in the model by `fixed`, not by its effects.
        let fitted = |found: &Found| -> Vec<usize> {
            (0..found.joined.len())
                .filter(|&k| !found.joined[k].held)
                .collect()
        };
        while fitted(found).len() >= 2 {
            let checked = fitted(found);
            progress(&format!("checking {} causes", checked.len()));
            let without = |k: usize| -> Vec<Effect> {
                let others = checked.iter().filter(|&&j| j != k);
                others
                    .flat_map(|&j| found.joined[j].effects.iter().copied())
                    .collect()
            };
            let trials: Vec<Result<(usize, FitResult, Score), FitError>> = checked
                .clone()
                .into_par_iter()
                .map(|k| {
                    let fit = self.fitter.fit(
                        self.train,
                        &without(k),
                        Some(&found.fit.spec),
                        self.fixed,
                    )?;
                    let hold = self.fitter.score(self.hold, &fit.spec)?;
                    Ok((k, fit, hold))
                })
                .collect();
            let mut weakest: Option<(usize, f64, FitResult, Score)> = None;
            for trial in trials {
                let (k, fit, hold) = trial?;
                let Joined {
                    effects: m, bar, ..
                } = &found.joined[k];
                // At the bar the move joined at. The check only ever takes
                // a name away, so it spends none of α: the search's
                // family-wise sum stays its rounds'. A later round's
                // smaller share would ask an early move to stay for more
                // than it had to show to join, and drop a real effect for
                // the rounds that came after it.
                let mut check = self.judge(
                    m,
                    round,
                    (&found.fit, &found.hold),
                    (&fit, &hold),
                    Signatures::Any,
                    *bar,
                );
                check.backward = true;
                check.passed |= m.iter().any(|&e| self.expected(e));
                let gain = check.holdout_rss_gain_percent;
                if !check.passed && weakest.as_ref().is_none_or(|w| gain < w.1) {
                    weakest = Some((k, gain, fit, hold));
                }
                found.candidates.push(check);
            }
            let Some((k, _, fit, hold)) = weakest else {
                break;
            };
            found.joined.remove(k);
            found.fit = fit;
            found.hold = hold;
        }
        Ok(())
    }

    /// `segment-crosstalk` measured where it shows apart from the beam's
    /// form, where the search did not name it: on the training recordings
    /// that drive one segment alone. Driven together, a neighbour's share
    /// of each segment's moment only reshapes the moment along the strip,
    /// which a strip whose form the model lacks reshapes too: on the
    /// literature strip, the blocked runs' misfit drove `κ` to −0.25 where
    /// the rig hid 0.14, while the lone steps alone fitted 0.125
    /// (development seed 50065; docs/rig.md). Alone, a segment bends its
    /// neighbours only by crosstalk or by that form.
    ///
    /// The final model's effects are fitted on the lone drives with and
    /// without `κ`, its segments' deviations held at the final fit's (not
    /// fitted: a segment never driven alone is seen there only through
    /// its neighbour's share, and its gain and `κ` trade; not dropped:
    /// lone drives of segments that differ then bend by `κ` instead,
    /// off-class rig seed 10047).
    /// Not tried where [`MAX_CAUSES`] are in. Named where `κ` lies beyond
    /// [`CROSSTALK_ALIKE`] at the share of `α`
    /// after the search's rounds (one test), BIC gains on the lone drives,
    /// and, where a lone drive is held out, the held-out one gains too.
    /// Then `κ` is held at the lone drives' value and the model fitted
    /// again on every training recording: the fixed values returned, with
    /// `κ`'s estimate to report beside the final fit's.
    fn crosstalk_on_lone_drives(
        &self,
        found: &mut Found,
    ) -> Result<(ModelSpec, Option<Estimate>), FitError> {
        let lone = |recordings: &[usize]| -> Vec<usize> {
            recordings
                .iter()
                .copied()
                .filter(|&i| self.session.recordings[i].driven().len() == 1)
                .collect()
        };
        let (lone_train, lone_hold) = (lone(self.train), lone(self.hold));
        let segments = self
            .session
            .recordings
            .first()
            .map_or(0, |r| r.rec.meta.segments);
        let named = found.accepted();
        if segments < 2
            || lone_train.is_empty()
            || named.contains(&Effect::SegmentCrosstalk)
            || named.len() >= MAX_CAUSES
        {
            return Ok((self.fixed, None));
        }
        let effects: Vec<Effect> = found
            .fit
            .effects
            .iter()
            .copied()
            .filter(|&e| e != Effect::SegmentVariation)
            .collect();
        let with_effects: Vec<Effect> = effects
            .iter()
            .copied()
            .chain([Effect::SegmentCrosstalk])
            .collect();
        let start = Some(&found.fit.spec);
        let mut lone_fixed = self.fixed;
        lone_fixed.ext.segment_variation = found.fit.spec.ext.segment_variation;
        let (without, with) = rayon::join(
            || self.fitter.fit(&lone_train, &effects, start, lone_fixed),
            || {
                self.fitter
                    .fit(&lone_train, &with_effects, start, lone_fixed)
            },
        );
        let (without, with) = (without?, with?);
        let Some(kappa) = with
            .estimates
            .iter()
            .find(|est| est.knob == Knob::Crosstalk)
            .cloned()
        else {
            return Ok((self.fixed, None));
        };
        let bar = Bar::of_round(found.rounds, 1);
        let z = bar.z();
        found.rounds += 1;
        let signature = kappa.value > 0.0 && beyond_at(&kappa, CROSSTALK_ALIKE, z);
        let delta_bic = with.bic - without.bic;
        let (gain, rss_gain) = if lone_hold.is_empty() {
            (None, None)
        } else {
            let (w, wo) = (
                self.fitter.score(&lone_hold, &with.spec)?,
                self.fitter.score(&lone_hold, &without.spec)?,
            );
            (
                Some(gain_percent(wo.nrmse, w.nrmse)),
                Some(holdout_gain(&w, &wo)),
            )
        };
        let passed = signature && delta_bic < DELTA_BIC && rss_gain.is_none_or(holdout_gain_passes);
        found.candidates.push(Candidate {
            name: Effect::SegmentCrosstalk.name().to_string(),
            round: bar.round,
            delta_bic,
            holdout_gain_percent: gain.unwrap_or(f64::NAN),
            holdout_rss_gain_percent: rss_gain.map_or(f64::NAN, |g| 100.0 * g),
            signature_z: z,
            passed,
            backward: false,
            lone_drives: true,
            params: [(Knob::Crosstalk.name().to_string(), kappa.value)].into(),
            evidence: Default::default(),
        });
        if !passed {
            return Ok((self.fixed, None));
        }
        let mut held = self.fixed;
        held.ext.crosstalk = kappa.value;
        let fit = self
            .fitter
            .fit(self.train, &found.fit.effects, start, held)?;
        found.hold = self.fitter.score(self.hold, &fit.spec)?;
        found.fit = fit;
        found.joined.push(Joined {
            effects: vec![Effect::SegmentCrosstalk],
            bar,
            held: true,
        });
        Ok((held, Some(kappa)))
    }

    /// Whether the session's own evidence calls for `e` (see
    /// [`choose`]): the fluid's loading in a session in water.
    fn expected(&self, e: Effect) -> bool {
        e == Effect::HydrodynamicLoading
            && self
                .session
                .recordings
                .iter()
                .any(|r| r.rec.meta.medium == Medium::Water)
    }

    /// Fits each move (an untried effect, or [`MODE_PAIR`]) on top of
    /// `current`, in parallel, and scores it on the held-out part.
    fn fit_round(
        &self,
        moves: &[Vec<Effect>],
        current: &FitResult,
    ) -> Result<Vec<Passed<Vec<Effect>>>, FitError> {
        // The model's and the measured blocked modes, once a round: every
        // candidate of the round that moves or damps the mode starts from
        // them.
        let modes = starts::modes(self.session, self.train, &current.spec, moves);
        let results: Vec<Result<Passed<Vec<Effect>>, FitError>> = moves
            .par_iter()
            .map(|m| {
                let mut effects = current.effects.clone();
                effects.extend(m);
                // The move's terms started on `from` (each by the modes).
                let fit_from = |from: ModelSpec, modes| {
                    let start =
                        starts::start_move(m, &from, modes, self.session.geometry().width_m);
                    self.fitter
                        .fit(self.train, &effects, Some(&start), self.fixed)
                };
                let mut fit = fit_from(current.spec, modes)?;
                if let Some(bare) =
                    starts::fluid_without_stand_ins(m, &current.effects, &current.spec, &self.fixed)
                {
                    let modes =
                        starts::modes(self.session, self.train, &bare, std::slice::from_ref(m));
                    let other = fit_from(bare, modes)?;
                    if other.bic < fit.bic {
                        fit = other;
                    }
                }
                let score = self.fitter.score(self.hold, &fit.spec)?;
                Ok((m.clone(), fit, score))
            })
            .collect();
        // In order, so that the first candidate's failure is the one named.
        results.into_iter().collect()
    }

    /// Each member of [`MODE_PAIR`] fitted alone again, from the round's
    /// pair without the other member's terms
    /// ([`starts::member_from_pair`]), where the pair cannot join because
    /// that other member's own term does not show at `bar`; the lower BIC
    /// of the member's two descents is its fit (one effect, one test, as
    /// with [`starts::fluid_without_stand_ins`]). In water, the fluid's
    /// drag can take all the damping: the pair's `ζ₀` and `β` end at zero
    /// and the pair fails, while `EI` alone, from its own start, ended
    /// where it began or at a third of the pair's (development seeds
    /// 50075, 50088). Only where the model already has the fluid.
    fn members_from_pair(
        &self,
        fits: &mut [Passed<Vec<Effect>>],
        current: &FitResult,
        bar: Bar,
    ) -> Result<(), FitError> {
        // Only beside the fluid: its drag is why the damping cannot show.
        // In air, with no damping in the data (the virtual bench's seed
        // model), `EI` alone from the pair's fit passed as significant.
        if !current.effects.contains(&Effect::HydrodynamicLoading) {
            return Ok(());
        }
        let Some(pair) = fits
            .iter()
            .find(|(m, ..)| m.as_slice() == MODE_PAIR)
            .map(|(_, fit, _)| fit.clone())
        else {
            return Ok(());
        };
        let shows =
            |e| signature_is_significant(e, &pair, &self.fixed, bar, &self.alone, self.span_s);
        let again = fits
            .par_iter()
            .enumerate()
            .map(|(k, (m, fit, _))| {
                let other = match m.as_slice() {
                    [Effect::Damping] => Effect::BeamStiffness,
                    [Effect::BeamStiffness] => Effect::Damping,
                    _ => return Ok(None),
                };
                let Some(start) = starts::member_from_pair(m, &pair.spec, &current.spec)
                    .filter(|_| !shows(other))
                else {
                    return Ok(None);
                };
                let mut effects = current.effects.clone();
                effects.extend(m);
                let refit = self
                    .fitter
                    .fit(self.train, &effects, Some(&start), self.fixed)?;
                if refit.bic >= fit.bic {
                    return Ok(None);
                }
                let score = self.fitter.score(self.hold, &refit.spec)?;
                Ok(Some((k, refit, score)))
            })
            .collect::<Result<Vec<_>, FitError>>()?;
        for (k, fit, score) in again.into_iter().flatten() {
            fits[k].1 = fit;
            fits[k].2 = score;
        }
        Ok(())
    }

    /// The candidate move `m` of round `round`, the model with it (`with`:
    /// its training fit and held-out score) against the model without it:
    /// it passes when BIC and the held-out error say so and the effects'
    /// own terms are significant at `bar`, each of them or
    /// (`Signatures::Any`) one.
    fn judge(
        &self,
        m: &[Effect],
        round: usize,
        with: (&FitResult, &Score),
        without: (&FitResult, &Score),
        signatures: Signatures,
        bar: Bar,
    ) -> Candidate {
        let ((fit, score), (base_fit, base_hold)) = (with, without);
        let delta_bic = fit.bic - base_fit.bic;
        let rss_gain = holdout_gain(score, base_hold);
        let alone = &self.alone;
        let own_term =
            |&e: &Effect| signature_is_significant(e, fit, &self.fixed, bar, alone, self.span_s);
        // The highest any of its effects' tests had to clear.
        let signature_z = m
            .iter()
            .map(|&e| bar.split(signature_tests(e, fit, alone)).z())
            .fold(0.0, f64::max);
        Candidate {
            name: m.iter().map(|e| e.name()).collect::<Vec<_>>().join("+"),
            round,
            delta_bic,
            holdout_gain_percent: gain_percent(base_hold.nrmse, score.nrmse),
            holdout_rss_gain_percent: 100.0 * rss_gain,
            signature_z,
            passed: delta_bic < DELTA_BIC
                && holdout_gain_passes(rss_gain)
                && match signatures {
                    Signatures::Every => m.iter().all(own_term),
                    Signatures::Any => m.iter().any(own_term),
                },
            backward: false,
            lone_drives: false,
            params: fit
                .estimates
                .iter()
                .filter(|est| !est.knob.is_baseline())
                .map(|est| (est.knob.name().to_string(), est.value))
                .collect(),
            evidence: evidence(fit, &self.fixed, self.span_s),
        }
    }
}

/// The statistics `fit`'s signatures read beyond its knobs' intervals
/// ([`Candidate::evidence`]).
fn evidence(
    fit: &FitResult,
    fixed: &ModelSpec,
    span_s: f64,
) -> std::collections::BTreeMap<String, Evidence> {
    [
        (
            "reaction_departure",
            reaction::departure_at(fit, session_peak_v(fixed)),
        ),
        ("drying_loss", drying::loss_over(fit, span_s)),
    ]
    .into_iter()
    .filter_map(|(name, stat)| stat.map(|(value, se)| (name.to_string(), Evidence { value, se })))
    .collect()
}

/// Whiteness of the held-out residuals, baseline and final model side by
/// side, channel by channel ([`tested_channels`]).
fn residual_tests(base_hold: &Score, final_hold: &Score) -> Vec<ResidualTest> {
    tested_channels(base_hold, final_hold)
        .map(|(b, f)| ResidualTest {
            recording: b.recording.clone(),
            channel: b.channel.name(),
            baseline_ljung_box: whiteness::ljung_box(&b.residuals, 20),
            final_ljung_box: whiteness::ljung_box(&f.residuals, 20),
            threshold: whiteness::chi2_99(20),
            baseline_input_correlation: whiteness::input_correlation(
                &b.residuals,
                &b.input_v,
                INPUT_LAGS,
            )
            .0,
            final_input_correlation: whiteness::input_correlation(
                &f.residuals,
                &f.input_v,
                INPUT_LAGS,
            )
            .0,
            input_band: whiteness::input_correlation(&f.residuals, &f.input_v, INPUT_LAGS).1,
        })
        .collect()
}

/// The held-out channels whose residuals are tested for whiteness (those
/// with signal, and the camera's, where motion along the strip shows),
/// baseline and final model side by side. `Verdict::residual_tests` and
/// the report's table follow this order.
pub fn tested_channels<'a>(
    baseline: &'a Score,
    last: &'a Score,
) -> impl Iterator<Item = (&'a ChannelFit, &'a ChannelFit)> {
    baseline
        .channels
        .iter()
        .zip(&last.channels)
        .filter(|(b, _)| b.has_signal || b.channel.is_camera())
}

/// Whether the term that makes `e` what it is differs from "off" beyond
/// its interval, at the level that keeps the whole search's chance of a
/// term standing out by the noise within
/// [`FAMILY_ALPHA`](super::gates::FAMILY_ALPHA): `bar`, the candidate's
/// share of its round's, split among the effect's tests
/// ([`signature_tests`]). Without this, an effect that contains another
/// (linear drag is mass-proportional damping) could be named for the
/// other's work. `alone`: the segments a training recording drives alone
/// ([`driven_alone`]); `span_s`: the training recordings' span on the
/// session clock ([`span_s`]).
fn signature_is_significant(
    e: Effect,
    fit: &FitResult,
    fixed: &ModelSpec,
    bar: Bar,
    alone: &[usize],
    span_s: f64,
) -> bool {
    let bar = bar.split(signature_tests(e, fit, alone));
    let (z, tail) = (bar.z(), bar.tail());
    let excludes = |knob: Knob, off: f64| {
        fit.estimates
            .iter()
            .any(|est| est.knob == knob && excludes_at(est, off, z))
    };
    // The joint test alone would lose a term that stands out on its own
    // beside one that does nothing (its two degrees of freedom ask more).
    let either_or_both = |off: &[(Knob, f64)]| {
        off.iter().any(|&(k, o)| excludes(k, o)) || fit.jointly_excludes(off, tail)
    };
    match e {
        Effect::LargeDeflection => true,
        Effect::BeamStiffness => excludes(Knob::Ei, fixed.params.ei_nm2),
        // Either term, or the two jointly: ζ₀ and β both damp the first
        // mode, so each alone can be unsure while together they are not
        // (sweep seed 10054).
        Effect::Damping => either_or_both(&[(Knob::Zeta, 0.0), (Knob::Beta, 0.0)]),
        // Added mass is what water adds; its drag alone is damping.
        Effect::HydrodynamicLoading => excludes(Knob::AddedMass, 0.0),
        Effect::ElectrochemicalNonlinearity => {
            let peak_v = session_peak_v(fixed);
            let reaction = reaction::departure_at(fit, peak_v);
            match electrochemistry_alone(&fit.estimates, z, peak_v, reaction) {
                Some(shows) => shows,
                None => {
                    fit.jointly_excludes(&[(Knob::ChargeCubic, 0.0), (Knob::LeakCubic, 0.0)], tail)
                }
            }
        }
        // b = K z below zero is what makes the bending relax past the
        // start; any z > 0 (a creep too) is the baseline's.
        Effect::BackRelaxation => fit
            .estimates
            .iter()
            .any(|est| est.knob == Knob::B && below_at(est, 0.0, z)),
        // The gain lost over the session, not the rate: the law's
        // curvature trades against its rate ([`drying`]); beyond what a
        // strip that does not dry seems to lose.
        Effect::Dehydration => {
            drying::loss_over(fit, span_s).is_some_and(|(loss, se)| drying::shows(loss, se, z))
        }
        // A neighbour bent the driven segment's way: charge reaching it
        // (through the polymer past the cut, or a shared electrode) has
        // the drive's sign. A negative κ bends the neighbours against
        // the drive, which no leak of charge does: it is the fit
        // reshaping where along the strip each segment's moment acts on
        // a strip whose form it lacks (literature null seed 60001,
        // κ = -0.11), not crosstalk.
        Effect::SegmentCrosstalk => fit
            .estimates
            .iter()
            .any(|est| est.knob == Knob::Crosstalk && above_at(est, 0.0, z)),
        // Some segment differs from the reference in some value by more
        // than a strip's segments differ when alike, in a value the
        // session shows apart from the beam's form ([`shows_apart`]).
        Effect::SegmentVariation => fit
            .estimates
            .iter()
            .any(|est| shows_apart(est.knob, alone) && beyond_at(est, SEGMENT_ALIKE, z)),
    }
}

/// Session time by which the recordings `recordings` have all ended, s
/// (their `t_session_start_s`, 0 where not given, plus their length): the
/// span over which a drying fitted on them takes its gain.
fn span_s(session: &Session, recordings: &[usize]) -> f64 {
    recordings
        .iter()
        .map(|&i| {
            let r = &session.recordings[i];
            r.end_s().unwrap_or(r.length_s())
        })
        .fold(0.0, f64::max)
}

/// The segments (from 0) that some recording of `recordings` drives alone:
/// those whose moment gain `K` the fit sees apart from the others' (see
/// [`shows_apart`]).
fn driven_alone(session: &Session, recordings: &[usize]) -> Vec<usize> {
    let mut alone: Vec<usize> = recordings
        .iter()
        .filter_map(|&i| match session.recordings[i].driven()[..] {
            [k] => Some(k),
            _ => None,
        })
        .collect();
    alone.sort_unstable();
    alone.dedup();
    alone
}

/// Whether a segment-variation knob's value shows apart from the beam's
/// form: `R1` and `C` always (each segment's current is its own channel);
/// a segment's moment gain `K` only where a recording drives that segment
/// alone (`alone`). Driven together, the segments' moments reach the
/// sensors only through the beam's shape and dynamics, and a `K` per
/// segment is then the most pliable term the fit has for a form it lacks:
/// on the literature strip's base (nothing departing), five of seven false
/// `segment-variation`s were only `K`s 9-80 % off on segments no recording
/// drove alone (null seeds 61000-61059; docs/rig.md, "Which part of the
/// base"). The knob stays in the fit; it is only not evidence. And only
/// where segment 1, the reference whose gain the deviation is relative
/// to, is driven alone too: else the deviation weighs a lone drive
/// against the gain the segments driven together set, which differ by
/// the form as well, as crosstalk's share does
/// ([`Search::crosstalk_on_lone_drives`]): null seed 61059's segment 3,
/// driven alone, took `K` 13 % below segment 1's.
fn shows_apart(knob: Knob, alone: &[usize]) -> bool {
    match knob {
        Knob::SegmentR1(_) | Knob::SegmentC(_) => true,
        Knob::SegmentK(i) => alone.contains(&i) && alone.contains(&0),
        _ => false,
    }
}

/// How many tests may show `e`'s signature, any one of them passing it:
/// each is a chance for the noise, and they share the candidate's level
/// ([`Bar::split`]). The damping's `ζ₀`, its `β`, or the two jointly; the
/// electrochemistry's leak, its reaction, its charge, or the leak and the
/// charge jointly; each knob of a
/// `segment-variation` that can show it ([`shows_apart`]). Every other
/// effect's is one term.
fn signature_tests(e: Effect, fit: &FitResult, alone: &[usize]) -> usize {
    match e {
        Effect::Damping => 3,
        Effect::ElectrochemicalNonlinearity => 4,
        Effect::SegmentVariation => fit
            .estimates
            .iter()
            .filter(|est| shows_apart(est.knob, alone))
            .count(),
        _ => 1,
    }
}

/// Whether the electrochemical terms alone show
/// `electrochemical-nonlinearity` at `z` up to the session's highest drive
/// `peak_v`: yes where the leak grows faster than the voltage, the steady
/// current of the leak and a reaction behind the double layer departs
/// from linear (`reaction`: the departure and its standard error,
/// [`reaction::departure_at`]), or the charge departs from linear either
/// way, each by more than [`reaction::REACTION_ALIKE`] beyond its
/// interval; no where the leak bends below linear; `None` where the joint
/// test of the two cubics decides, which needs one of them to depart by
/// the margin at its value. Electrolysis adds a current that grows faster
/// than the voltage (Butler–Volmer's `sinh`; docs/FORMAT.md's note on the
/// catalogue): a leak bending the other way is some other slow current (a
/// current zero wandering between rests: lab rig seed 20024, a
/// back-relaxing strip, was named so at 1.05 % held out). The charge may
/// bend either way.
fn electrochemistry_alone(
    estimates: &[Estimate],
    z: f64,
    peak_v: f64,
    reaction: Option<(f64, f64)>,
) -> Option<bool> {
    let find = |knob: Knob| estimates.iter().find(|est| est.knob == knob);
    let (up, down) = (
        reaction::cubic_at_departure(reaction::REACTION_ALIKE, peak_v),
        reaction::cubic_at_departure(-reaction::REACTION_ALIKE, peak_v),
    );
    let leak = find(Knob::LeakCubic);
    let charge = find(Knob::ChargeCubic);
    let reacts = reaction.is_some_and(|(d, se)| d - z * se > reaction::REACTION_ALIKE);
    let leak_grows = leak.is_some_and(|est| above_at(est, up, z));
    let charge_bends = charge.is_some_and(|est| above_at(est, up, z) || below_at(est, down, z));
    let departs_at_value =
        |est: Option<&Estimate>| est.is_some_and(|est| est.value > up || est.value < down);
    if leak_grows || reacts || charge_bends {
        Some(true)
    } else if leak.is_some_and(|est| est.value < 0.0)
        || !(departs_at_value(leak) || departs_at_value(charge))
    {
        Some(false)
    } else {
        None
    }
}

fn gain_percent(before: f64, after: f64) -> f64 {
    if before > 0.0 {
        100.0 * (before - after) / before
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    fn example() -> Session {
        Session::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session"))
            .unwrap()
    }

    fn names(session: &Session, idx: &[usize]) -> Vec<String> {
        idx.iter()
            .map(|&i| session.recordings[i].name.clone())
            .collect()
    }

    /// The example session with only these recordings, in this order.
    fn example_in_order(order: &[&str]) -> Session {
        let mut session = example();
        let recordings = order
            .iter()
            .map(|name| {
                session
                    .recordings
                    .iter()
                    .find(|r| r.name == *name)
                    .unwrap_or_else(|| panic!("{name} not in the example"))
                    .clone()
            })
            .collect();
        session.recordings = recordings;
        session
    }

    #[test]
    fn only_a_leak_growing_faster_than_the_voltage_is_electrolysis() {
        let est = |knob, value: f64, half: f64| Estimate {
            knob,
            value,
            low: value - half,
            high: value + half,
        };
        let z = Bar::of_round(0, 8).z();
        let peak_v = 4.0;
        let alone = |e: &[Estimate], r| electrochemistry_alone(e, z, peak_v, r);
        // A leak bending up beyond its interval; one bending down as far.
        let up = [
            est(Knob::ChargeCubic, 0.0, 1e-3),
            est(Knob::LeakCubic, 2e-2, 1e-3),
        ];
        let down = [
            est(Knob::ChargeCubic, 0.0, 1e-3),
            est(Knob::LeakCubic, -2e-2, 1e-3),
        ];
        assert_eq!(alone(&up, None), Some(true));
        assert_eq!(alone(&down, None), Some(false));
        // A charge off linear shows it whichever way the leak bends.
        let charge = [
            est(Knob::ChargeCubic, -2e-2, 1e-3),
            est(Knob::LeakCubic, -2e-2, 1e-3),
        ];
        assert_eq!(alone(&charge, None), Some(true));
        // Sure, but within the margin at the highest drive: 2e-3 /V² is a
        // 2.4 % departure at 4 V. The same cubics show it at a drive
        // twice as high, where they depart by 9 %.
        let slight = [
            est(Knob::ChargeCubic, 2e-3, 1e-4),
            est(Knob::LeakCubic, 2e-3, 1e-4),
        ];
        assert_eq!(alone(&slight, None), Some(false));
        assert_eq!(
            electrochemistry_alone(&slight, z, 2.0 * peak_v, None),
            Some(true)
        );
        // Beyond the margin at their values but not beyond their
        // intervals, the joint test decides; within it, nothing does.
        let unsure = [
            est(Knob::ChargeCubic, 1e-2, 1e-2),
            est(Knob::LeakCubic, 1e-2, 1e-2),
        ];
        assert_eq!(alone(&unsure, None), None);
        let unsure_and_slight = [
            est(Knob::ChargeCubic, 1e-4, 1e-3),
            est(Knob::LeakCubic, 1e-4, 1e-3),
        ];
        assert_eq!(alone(&unsure_and_slight, None), Some(false));
        // A steady current half again over linear at the highest drive,
        // sure to a hundredth, whichever way the leak's cubic bends;
        // one within its interval of the margin is no evidence.
        assert_eq!(alone(&down, Some((0.5, 0.01))), Some(true));
        let unsure_reaction = Some((super::reaction::REACTION_ALIKE + 0.1, 0.1));
        assert_eq!(alone(&down, unsure_reaction), Some(false));
        assert_eq!(alone(&unsure, unsure_reaction), None);
    }

    #[test]
    fn a_segments_moment_gain_is_evidence_only_where_a_recording_drives_it_alone() {
        // Each segment's R1 and C have its own current channel.
        assert!(shows_apart(Knob::SegmentR1(2), &[]));
        assert!(shows_apart(Knob::SegmentC(1), &[]));
        // Its K, only where it and segment 1, the reference, are driven
        // alone.
        assert!(!shows_apart(Knob::SegmentK(2), &[0, 1]));
        assert!(!shows_apart(Knob::SegmentK(2), &[2]));
        assert!(!shows_apart(Knob::SegmentK(2), &[1, 2]));
        assert!(shows_apart(Knob::SegmentK(2), &[0, 2]));
        assert!(!shows_apart(Knob::Ei, &[0, 1, 2]));
        // The example drives each of its segments alone (06-08), the
        // others all three together.
        let session = example();
        let all: Vec<usize> = (0..session.recordings.len()).collect();
        assert_eq!(driven_alone(&session, &all), [0, 1, 2]);
        let without_seg3: Vec<usize> = all
            .iter()
            .copied()
            .filter(|&i| session.recordings[i].name != "08_free_single_seg3.csv")
            .collect();
        assert_eq!(driven_alone(&session, &without_seg3), [0, 1]);
        assert!(driven_alone(&session, &[0, 1, 2, 3]).is_empty());
    }

    #[test]
    fn the_split_holds_out_only_drives_the_training_part_shows_before_and_after() {
        let session = example();
        let (train, hold) = split(&session);
        // Every third from the second, but not the last of the free drives
        // of all three segments (05: the one before, 04, in its place)
        // nor segment 3's lone run (08, whose neighbours are lone runs
        // too). Both blocked runs are their kind's ends: none is held out.
        assert_eq!(
            names(&session, &hold),
            ["02_free_step_2.5V.csv", "04_free_chirp.csv"]
        );
        assert_eq!(train.len() + hold.len(), session.recordings.len());
        let kind = |j: usize| {
            let r = &session.recordings[j];
            (r.rec.meta.fixture, r.driven())
        };
        for &i in &hold {
            // Its kind keeps a later run in training, and the free runs
            // an earlier one too.
            assert!(train.iter().any(|&j| j > i && kind(j) == kind(i)));
            if kind(i).0 == Fixture::Free {
                assert!(train.iter().any(|&j| j < i && kind(j) == kind(i)));
            }
        }
    }

    #[test]
    fn a_split_whose_every_third_run_is_a_lone_drive_holds_out_others() {
        // Keep segment 1 alone and segment 3 alone at the pattern's
        // positions (1 and 4): the pattern alone holds out nothing.
        let session = example_in_order(&[
            "01_free_step_1.0V.csv",
            "06_free_single_seg1.csv",
            "02_free_step_2.5V.csv",
            "03_free_step_4.0V.csv",
            "08_free_single_seg3.csv",
            "09_blocked_step_2.0V.csv",
            "10_blocked_step_4.0V.csv",
        ]);
        let (train, hold) = split(&session);
        assert_eq!(hold.len(), MIN_HELD_OUT, "{:?}", names(&session, &hold));
        for &i in &hold {
            assert!(!session.recordings[i].name.contains("single"));
            let kind = |j: usize| {
                let r = &session.recordings[j];
                (r.rec.meta.fixture, r.driven())
            };
            assert!(train.iter().any(|&j| kind(j) == kind(i)));
        }
    }

    #[test]
    fn a_split_short_of_inner_runs_holds_out_a_kinds_end_before_the_highest_drive() {
        // One kind of three free steps whose inner run is the 4 V one
        // (dev seed 50074's shape): no inner run may be held out, so the
        // ends are, and the 4 V step stays in training.
        let session = example_in_order(&[
            "01_free_step_1.0V.csv",
            "03_free_step_4.0V.csv",
            "08_free_single_seg3.csv",
            "09_blocked_step_2.0V.csv",
            "02_free_step_2.5V.csv",
            "07_free_single_seg2.csv",
        ]);
        let (train, hold) = split(&session);
        assert_eq!(
            names(&session, &hold),
            ["01_free_step_1.0V.csv", "02_free_step_2.5V.csv"]
        );
        assert!(train.contains(&1), "the 4 V step is trained on");
    }

    #[test]
    fn a_session_of_lone_drives_holds_out_nothing() {
        let mut session = example();
        // Segment 1, 2 and 3 alone, and one blocked step: one of each kind.
        session
            .recordings
            .retain(|r| r.name.contains("single") || r.name.starts_with("09"));
        assert_eq!(session.recordings.len(), 4);
        let (train, hold) = split(&session);
        assert!(hold.is_empty(), "{:?}", names(&session, &hold));
        assert_eq!(train, [0, 1, 2, 3]);
    }
}
