//! The fit itself: a session's targets, the least-squares problem the
//! optimiser sees, and its restarts.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use rayon::prelude::*;

use super::covariance::{self, Block};
use super::data::{Sensor, SessionTargets};
use super::drift::Drift;
use super::drift_set::DriftSet;
use super::effect::Effect;
use super::error::FitError;
use super::inflation::{profile_cost, Inflation};
use super::mode_start;
use super::race::{Lane, Progress};
use super::sampling::Sampling;
use super::space::{self, Knob, Space};
use super::stage::{descend, Problem, Stage, PATIENCE};
use super::start;
use super::stats::{self, ChannelFit, Estimate, Score};
use crate::model::params::{Beam, Electrical, ExtensionsFile, Mesh, ModelFile, Relaxation};
use crate::model::predict::{predict, predict_currents, ModelSpec, Traces};
use crate::recording::Channel;
use crate::session::Session;

/// Elements per segment the fit uses: four, not the seed's one (Appendix
/// B's `n = 3` for three segments). The undamped beam rings for seconds,
/// and one element a segment puts the blocked mode 0.2 Hz off (117.53
/// against 117.30 Hz), almost two cycles of phase in 8 s; four put the
/// first modes within 0.01 % of a finer mesh's, far below what the data
/// resolve. The static shape does not depend on it.
pub const FIT_ELEMENTS: usize = 4;

/// Descents of the beam's stage after its first, each with every sensor
/// weighed by the variance it showed at the end of the one before
/// (`inflation.rs`), at most; none once no sensor's variance moves by 10 %.
const INFLATION_ROUNDS: usize = 1;

/// The fit's worker threads: the model's work arrays for the largest
/// meshes take about 2 MiB of stack, rayon's default.
pub(super) fn pool() -> &'static rayon::ThreadPool {
    static POOL: std::sync::OnceLock<rayon::ThreadPool> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .stack_size(32 << 20)
            .build()
            .expect("threads can be started")
    })
}

/// A fitted model and how well it fits.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The effects on top of the baseline.
    pub effects: Vec<Effect>,
    /// The fitted model.
    pub spec: ModelSpec,
    /// Fitted parameters with 95 % confidence intervals.
    pub estimates: Vec<Estimate>,
    /// The covariance of the estimates' values, in `estimates`' order
    /// (see [`stats::value_covariance`]).
    pub value_covariance: nalgebra::DMatrix<f64>,
    /// How well it fits the recordings it was fitted on.
    pub score: Score,
    /// Parameters counted by AIC and BIC.
    pub parameters: usize,
    /// Akaike's information criterion, `m ln(RSS/m) + 2k`.
    pub aic: f64,
    /// Bayesian information criterion, `m ln(RSS/m) + k ln m`.
    pub bic: f64,
    /// Model evaluations the optimiser used.
    pub evaluations: usize,
    /// Why the optimiser stopped.
    pub termination: String,
    /// The same structure fitted with its damping law and with each
    /// mode's own ratio, whose intervals `estimates`' span
    /// ([`Fitter::fit_with_form_check`]); `None` where not checked.
    pub form: Option<FormCheck>,
}

/// A structure fitted with its damping law and with each mode's own
/// damping ratio in its place (`form.rs`): the two fits' own estimates,
/// each with its own 95 % interval, and their costs.
#[derive(Clone, Debug)]
pub struct FormCheck {
    /// The estimates with the law.
    pub law: Vec<Estimate>,
    /// The estimates with each mode's own ratio.
    pub each_mode: Vec<Estimate>,
    /// Whether the result is the fit with each mode's own ratio (else the
    /// law's).
    pub each_mode_final: bool,
    /// The cost both fits minimise ([`profile_cost`]) at the law's fit.
    pub cost_law: f64,
    /// The same at the fit with each mode's own ratio.
    pub cost_each_mode: f64,
}

impl FitResult {
    /// The fit with `est` beside its own estimates: a knob measured apart
    /// and held in this fit's model (the diagnosis's crosstalk on the lone
    /// drives). Counted by AIC and BIC as the parameter it is, its variance
    /// its interval's, uncorrelated with the others, which it was held
    /// apart from.
    pub fn with_held(mut self, est: Estimate) -> FitResult {
        let n = self.estimates.len();
        let se = 0.5 * (est.high - est.low) / super::stats::Z95;
        let mut cov = nalgebra::DMatrix::zeros(n + 1, n + 1);
        cov.view_mut((0, 0), (n, n))
            .copy_from(&self.value_covariance);
        cov[(n, n)] = se * se;
        self.value_covariance = cov;
        self.estimates.push(est);
        self.parameters += 1;
        self.aic += 2.0;
        self.bic += (self.score.m.max(1) as f64).ln();
        self
    }

    /// Whether the knobs in `off` differ from their "off" values jointly
    /// at the level `1 − tail` (see [`stats::wald_excludes`]): those of
    /// them the fit had and bounded (a knob with an unbounded interval says
    /// nothing either way); false when there are none.
    pub fn jointly_excludes(&self, off: &[(Knob, f64)], tail: f64) -> bool {
        let (at, d): (Vec<usize>, Vec<f64>) = off
            .iter()
            .filter_map(|(knob, o)| {
                let i = self.estimates.iter().position(|e| e.knob == *knob)?;
                self.value_covariance[(i, i)]
                    .is_finite()
                    .then(|| (i, self.estimates[i].value - o))
            })
            .unzip();
        let sigma = nalgebra::DMatrix::from_fn(at.len(), at.len(), |a, b| {
            self.value_covariance[(at[a], at[b])]
        });
        stats::wald_excludes(&d, &sigma, tail)
    }

    /// The standard error of a function of the estimates whose gradient
    /// is `gradient` (each estimate's index and the derivative there), by
    /// the delta method over their covariance. A knob the fit held (an
    /// infinite variance) counts as known, as [`Self::jointly_excludes`]
    /// counts it.
    pub fn delta_method_se(&self, gradient: &[(usize, f64)]) -> f64 {
        let known: Vec<(usize, f64)> = gradient
            .iter()
            .copied()
            .filter(|&(i, _)| self.value_covariance[(i, i)].is_finite())
            .collect();
        let var: f64 = known
            .iter()
            .flat_map(|&(a, ga)| {
                known
                    .iter()
                    .map(move |&(b, gb)| ga * gb * self.value_covariance[(a, b)])
            })
            .sum();
        var.max(0.0).sqrt()
    }

    /// The parameter file for this fit: the seed's material; `[beam]` when
    /// the fit freed `EI` (its `ρA` from the laminate of the fitted
    /// strip); `[extensions]` when any effect is on.
    pub fn model_file(&self) -> ModelFile {
        let mut f = ModelFile::main_m_2006();
        let p = &self.spec.params;
        f.electrical = Electrical {
            r1_ohm: p.r1_ohm,
            r2_ohm: p.r2_ohm,
            c_f: p.c_f,
        };
        f.relaxation = Relaxation {
            a_nm_per_c: p.a_nm_per_c,
            b_nm_per_c_s: p.b_nm_per_c_s,
            p_per_s: p.p_per_s,
        };
        if self.effects.contains(&Effect::BeamStiffness) {
            f.beam = Some(Beam {
                ei_nm2: p.ei_nm2,
                mass_per_length_kg_per_m: p.mass_per_length_kg_per_m,
            });
        }
        if !self.effects.is_empty() {
            f.extensions = Some(ExtensionsFile::from_spec(
                &self.spec.ext,
                self.spec.dehydration_per_s,
                self.spec.dehydration_curvature,
                self.spec.circuit_drying_per_s,
            ));
        }
        f.mesh = Some(Mesh {
            elements_per_segment: FIT_ELEMENTS,
        });
        f
    }
}

/// A session prepared for fitting: its targets and noise levels.
pub struct Fitter<'a> {
    pub(super) session: &'a Session,
    targets: SessionTargets,
    /// Whether measured channels have drift terms.
    drift: bool,
    /// The drift terms of each set of recordings fitted or scored
    /// together, built once per set.
    drift_sets: Mutex<HashMap<Vec<usize>, Arc<DriftSet>>>,
    /// The highest drive any recording applies, V: where a reaction
    /// starts and is judged ([`space::with_session_peak`]), read once.
    peak_drive_v: f64,
}

impl<'a> Fitter<'a> {
    /// Prepares `session`, with the bench's drift on every camera and
    /// load-cell channel and current fitted jointly (`drift.rs`).
    pub fn new(session: &'a Session) -> Fitter<'a> {
        Self::with_drift(session, true)
    }

    /// Prepares `session`, with drift terms or without (to measure what
    /// they change).
    pub fn with_drift(session: &'a Session, drift: bool) -> Fitter<'a> {
        Fitter {
            session,
            targets: SessionTargets::new(session),
            drift,
            drift_sets: Mutex::new(HashMap::new()),
            peak_drive_v: session
                .recordings
                .iter()
                .flat_map(|r| r.drive().v_v.as_flat())
                .fold(0.0f64, |m, &v| m.max(v.abs())),
        }
    }

    /// The highest drive any recording of the session applies, V.
    pub fn peak_drive_v(&self) -> f64 {
        self.peak_drive_v
    }

    /// The drift terms of `recordings` fitted or scored together (none
    /// without drift).
    fn drift_set(&self, recordings: &[usize]) -> Arc<DriftSet> {
        if !self.drift {
            return Arc::new(DriftSet::default());
        }
        let mut sets = self.drift_sets.lock().unwrap_or_else(|e| e.into_inner());
        sets.entry(recordings.to_vec())
            .or_insert_with(|| Arc::new(DriftSet::new(self.session, &self.targets, recordings)))
            .clone()
    }

    /// When the session's bench read its currents (found in the data);
    /// every prediction of the fit follows it.
    pub fn sampling(&self) -> Sampling {
        self.targets.sampling
    }

    /// `spec` as this session's bench samples it.
    fn as_sampled(&self, spec: &ModelSpec) -> ModelSpec {
        ModelSpec {
            sensors_before_update: self.targets.sampling.before_update,
            ..*spec
        }
    }

    /// The session's targets and noise levels.
    pub fn targets(&self) -> &SessionTargets {
        &self.targets
    }

    /// Runs the model on recording `index` and returns its weighted
    /// residuals, target by target.
    fn residuals_of(&self, index: usize, spec: &ModelSpec) -> Result<Vec<Vec<f64>>, FitError> {
        let mut res =
            vec![self.weighted(index, &self.traces(index, spec)?, |_| true, &Inflation::ONE)];
        self.drift_set(&[index])
            .remove(&mut res, spec.params.p_per_s);
        Ok(res.remove(0).into_iter().flatten().collect())
    }

    /// The model's outputs on recording `index` (the camera only where it
    /// looked), driven by what the strip saw (a contact fault from the
    /// rest left it at rest: `SessionRecording::drive`).
    fn traces(&self, index: usize, spec: &ModelSpec) -> Result<Traces, FitError> {
        let r = &self.session.recordings[index];
        let rt = &self.targets.recordings[index];
        predict(
            r.drive(),
            &self.as_sampled(spec),
            FIT_ELEMENTS,
            r.dt_s,
            r.t_start_s.unwrap_or(0.0),
            Some(&rt.camera_rows),
            &mut |_| {},
        )
        .map_err(|source| FitError::Model {
            recording: r.name.clone(),
            source,
        })
    }

    /// Weighted residuals `(ŷ − y)/σ` of the targets of recording `index`,
    /// target by target (`None` for those `keep` refuses), each sensor's
    /// `σ` its rests' noise times `inflation`'s factor; drift not removed
    /// (it is fitted over every recording fitted together: [`DriftSet`]).
    fn weighted(
        &self,
        index: usize,
        traces: &Traces,
        keep: impl Fn(&super::data::Target) -> bool,
        inflation: &Inflation,
    ) -> Vec<Option<Vec<f64>>> {
        self.targets.recordings[index]
            .targets
            .iter()
            .map(|t| {
                keep(t).then(|| {
                    let sigma = t.sigma * inflation.sigma_factor(Sensor::of(t.channel));
                    t.model(traces)
                        .zip(&t.values)
                        .map(|(m, y)| (m - y) / sigma)
                        .collect()
                })
            })
            .collect()
    }

    /// The weighted residuals that `stage` sees over `recordings`,
    /// concatenated, each sensor's noise inflated by `inflation`; the
    /// circuit's stage runs the circuit alone.
    fn stage_residuals(
        &self,
        stage: Stage,
        recordings: &[usize],
        spec: &ModelSpec,
        inflation: &Inflation,
    ) -> Result<Vec<f64>, FitError> {
        let parts: Result<Vec<Vec<Option<Vec<f64>>>>, FitError> = recordings
            .par_iter()
            .map(|&i| {
                let traces = match stage {
                    Stage::Circuit => {
                        let r = &self.session.recordings[i];
                        Traces {
                            currents_a: predict_currents(
                                r.drive(),
                                &self.as_sampled(spec),
                                r.dt_s,
                                r.t_start_s.unwrap_or(0.0),
                            )
                            .map_err(|source| FitError::Model {
                                recording: r.name.clone(),
                                source,
                            })?,
                            ..Traces::default()
                        }
                    }
                    Stage::Beam => self.traces(i, spec)?,
                };
                Ok(self.weighted(i, &traces, |t| stage.sees(t.channel), inflation))
            })
            .collect();
        let mut parts = parts?;
        self.drift_set(recordings)
            .remove(&mut parts, spec.params.p_per_s);
        Ok(parts.into_iter().flatten().flatten().flatten().collect())
    }

    /// The drift fitted on every measured channel of
    /// `recordings` under `spec` (`drift.rs`), channel by channel of each
    /// recording.
    pub fn drifts(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Vec<Drift>, FitError> {
        let raw = self.raw_weighted(recordings, spec)?;
        Ok(self
            .drift_set(recordings)
            .measure(&raw)
            .into_iter()
            .map(|(k, j, range, m)| {
                let r = &self.session.recordings[recordings[k]];
                let t = &self.targets.recordings[recordings[k]].targets[j];
                let at = |row: Option<&usize>| row.map_or(0.0, |&row| r.rec.t_s[row]);
                Drift {
                    recording: r.name.clone(),
                    channel: t.channel,
                    peak_to_peak: range * t.sigma,
                    peak_to_peak_in_noise: range,
                    span_s: at(t.rows.last()) - at(t.rows.first()),
                    significant: m.significant,
                    share: m.share,
                    left_per_residual: m.left_per_residual,
                }
            })
            .collect())
    }

    /// The carry-over fitted on each camera and load-cell channel of the
    /// recordings of `recordings` that open while the strip still moves
    /// (a line through a rest beyond [`MOVING_REST_Z`] standard errors),
    /// under `spec`: `(recording, channel, the sum of squares its column
    /// takes beyond the drift, the range of what it takes in units of the
    /// channel's noise)`.
    ///
    /// [`MOVING_REST_Z`]: super::drift_set::MOVING_REST_Z
    pub fn carry_overs(
        &self,
        recordings: &[usize],
        spec: &ModelSpec,
    ) -> Result<Vec<(String, Channel, f64, f64)>, FitError> {
        let set = self.drift_set(recordings);
        if set.moving().is_empty() {
            return Ok(Vec::new());
        }
        let raw = self.raw_weighted(recordings, spec)?;
        Ok(set
            .carried(&raw, spec.params.p_per_s)
            .into_iter()
            .map(|(k, j, explained, range)| {
                let i = recordings[k];
                let channel = self.targets.recordings[i].targets[j].channel;
                (
                    self.session.recordings[i].name.clone(),
                    channel,
                    explained,
                    range,
                )
            })
            .collect())
    }

    /// The weighted residuals, drift not removed, of every target of
    /// `recordings` that has some under `spec`, computed in the pool: what
    /// [`DriftSet`](super::drift_set::DriftSet) measures.
    fn raw_weighted(
        &self,
        recordings: &[usize],
        spec: &ModelSpec,
    ) -> Result<Vec<Vec<Vec<f64>>>, FitError> {
        let raw = pool().install(|| self.raw_residuals(recordings, spec))?;
        Ok(raw
            .into_iter()
            .map(|r| r.into_iter().flatten().collect())
            .collect())
    }

    /// Every target's weighted residuals on `recordings` under `spec`,
    /// drift not removed, in the pool.
    fn raw_residuals(
        &self,
        recordings: &[usize],
        spec: &ModelSpec,
    ) -> Result<Vec<Vec<Option<Vec<f64>>>>, FitError> {
        recordings
            .par_iter()
            .map(|&i| Ok(self.weighted(i, &self.traces(i, spec)?, |_| true, &Inflation::ONE)))
            .collect()
    }

    /// Scores `spec` on `recordings`: per-channel fit and the pooled error.
    pub fn score(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Score, FitError> {
        pool().install(|| self.score_here(recordings, spec))
    }

    fn score_here(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Score, FitError> {
        let raw = self.raw_residuals(recordings, spec)?;
        let mut res = raw.clone();
        self.drift_set(recordings)
            .remove(&mut res, spec.params.p_per_s);
        let mut channels = Vec::new();
        for ((&i, res), raw) in recordings.iter().zip(res).zip(raw) {
            let rec = &self.session.recordings[i];
            let targets = &self.targets.recordings[i].targets;
            let both = res.into_iter().flatten().zip(raw.into_iter().flatten());
            for (t, (r, raw)) in targets.iter().zip(both) {
                channels.push(ChannelFit::new(
                    &rec.name,
                    t,
                    &r,
                    &raw,
                    &rec.drive().v_v,
                    rec.dt_s,
                ));
            }
        }
        Ok(Score::new(channels))
    }

    /// `fixed` carrying the session's highest drive, over all its
    /// recordings ([`space::with_session_peak`]).
    fn with_reaction_ref(&self, fixed: ModelSpec) -> ModelSpec {
        space::with_session_peak(fixed, self.peak_drive_v)
    }

    /// Fits the baseline plus `effects` on `recordings`, from `start` (or
    /// from estimates read off the data when `None`).
    pub fn fit(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        start: Option<&ModelSpec>,
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        pool().install(|| {
            let d = self.descend_here(recordings, effects, start, fixed, None)?;
            self.finish(recordings, d)
        })
    }

    /// `effects` fitted on `recordings` from two starts, the lower cost
    /// kept: the data's own ([`Self::fit`] without a start), and the
    /// baseline's fit on the same recordings with the effects added as the
    /// diagnosis adds them ([`mode_start`]: the terms that move or damp the
    /// first mode start where the measured mode rings). Either start alone
    /// can stop in a corner: from the data's own, the off-class rig's large
    /// deflections ended with `EI` at a tenth of the truth. The two run
    /// side by side, and one that falls behind the other's end is given up
    /// (`race.rs`): then the other is kept whatever the lower cost would
    /// have been, which over the first 40 rig seeds changed no pick where
    /// the two ends differ by more than a millionth.
    pub fn fit_from_either_start(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        pool().install(|| {
            let kept = self.race_starts(recordings, effects, fixed)?;
            self.finish(recordings, kept)
        })
    }

    /// The descents of [`Self::fit_from_either_start`]: the start kept,
    /// its intervals not yet computed. In the pool.
    pub(super) fn race_starts(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        fixed: ModelSpec,
    ) -> Result<Descended, FitError> {
        if effects.is_empty() {
            return self.descend_here(recordings, effects, None, fixed, None);
        }
        let (data_progress, modes_progress) = (Progress::default(), Progress::default());
        let cost = |spec: &ModelSpec| {
            self.score_here(recordings, spec)
                .ok()
                .map(|s| profile_cost(&s))
        };
        let data_lane = Lane::new(&data_progress, &modes_progress, &cost);
        let modes_lane = Lane::new(&modes_progress, &data_progress, &cost);
        let from_data = || {
            let d = self.descend_here(recordings, effects, None, fixed, Some(&data_lane))?;
            if !d.given_up {
                data_lane.finish(profile_cost(&d.score));
            }
            Ok::<_, FitError>(d)
        };
        let from_modes = || {
            // The baseline's point alone: its intervals are not needed.
            let baseline = self.descend_here(recordings, &[], None, fixed, Some(&modes_lane))?;
            if baseline.given_up {
                return Ok(baseline);
            }
            let baseline = baseline.space.spec(&baseline.theta);
            let modes = mode_start::modes(self.session, recordings, &baseline, &[effects.to_vec()]);
            let start =
                mode_start::start_move(effects, &baseline, modes, self.session.geometry().width_m);
            let d =
                self.descend_here(recordings, effects, Some(&start), fixed, Some(&modes_lane))?;
            if !d.given_up {
                modes_lane.finish(profile_cost(&d.score));
            }
            Ok(d)
        };
        // The two starts side by side: a descent's serial part (the
        // optimiser's factorisation of the tall Jacobian, its copies)
        // leaves a core that the other's simulations fill. 10036's water
        // fit: 16.6 s against 19.5 s, every estimate as before. A start
        // that falls behind is given up by `race.rs`'s rule, and only the
        // kept one's intervals are computed.
        let (from_data, from_modes) = rayon::join(from_data, from_modes);
        let (from_data, from_modes) = (from_data?, from_modes?);
        let lower = match (data_lane.end(), modes_lane.end()) {
            (None, _) => from_modes,
            (_, None) => from_data,
            (Some(data_end), Some(modes_end)) => {
                if data_lane.gives_up(modes_end) {
                    from_modes
                } else if modes_lane.gives_up(data_end) {
                    from_data
                } else if modes_end.1 < data_end.1 {
                    from_modes
                } else {
                    from_data
                }
            }
        };
        Ok(lower)
    }

    /// The descents of `effects` on `recordings` from `start` (or from
    /// estimates read off the data), in the pool.
    fn descend_here(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        start: Option<&ModelSpec>,
        fixed: ModelSpec,
        lane: Option<&Lane<'_>>,
    ) -> Result<Descended, FitError> {
        self.data_to_fit(recordings)?;
        let segments = self.session.recordings[0].rec.meta.segments;
        let space = Space::new(effects, segments, self.with_reaction_ref(fixed));
        let start = match start {
            Some(s) => *s,
            None => start::from_data(
                self.session,
                &self.targets,
                recordings,
                &space,
                &|i, spec| self.residuals_of(i, spec),
            )?,
        };
        // Already in the pool, and the data checked.
        self.descend_space_here(recordings, space, &start, PATIENCE, lane)
    }

    /// Fits `space` on `recordings` from `start`: the descents stage by
    /// stage (each at most `patience` evaluations per free knob and one),
    /// then the intervals and the criteria at the end.
    pub(super) fn fit_space(
        &self,
        recordings: &[usize],
        space: Space,
        start: &ModelSpec,
        patience: usize,
    ) -> Result<FitResult, FitError> {
        self.data_to_fit(recordings)?;
        let mut space = space;
        space.fixed = self.with_reaction_ref(space.fixed);
        pool().install(|| {
            let d = self.descend_space_here(recordings, space, start, patience, None)?;
            self.finish(recordings, d)
        })
    }

    /// The descents of `space` on `recordings` from `start`, in the pool,
    /// and the score at their end. The charge's cubic is fitted in the
    /// circuit's stage, on the currents alone, and shapes the moment the
    /// beam's stage must then follow: where it leaves the fit worse than
    /// its start ([`profile_cost`]), or at its floor
    /// ([`Space::charge_cubic_at_floor`]), the stages run again with it
    /// held at its start, and the lower cost is kept. On the literature
    /// rig's electrolysis (a Tafel current behind `R1`) the floor's moment
    /// fitted the camera and the load cell worse than the model without
    /// the effect (`finrs fit` on development seed 52127's training
    /// recordings: BIC +22,000, the leak alone −54,000), and on others far
    /// better (52086: the reaction's ΔBIC in the search −143,000, −4,000
    /// held). Off its floor too: on development seed 50043's eight
    /// training recordings, started at the damped, stiffer model as the
    /// diagnosis starts it, the cubic at −0.0076/V² left the BIC 61,000
    /// above that model's, the load cell's misfit fourfold
    /// (`tests/rig/tests/electrolysis_fit.rs`).
    fn descend_space_here(
        &self,
        recordings: &[usize],
        space: Space,
        start: &ModelSpec,
        patience: usize,
        lane: Option<&Lane<'_>>,
    ) -> Result<Descended, FitError> {
        let free = self.descend_stages(recordings, space.clone(), start, patience, lane, false)?;
        if free.given_up || !space.knobs.contains(&Knob::ChargeCubic) {
            return Ok(free);
        }
        // One simulation at the start, where the floor does not already
        // say to try; a start the model refuses is not a cost to beat.
        let worse_than_start = || {
            self.score_here(recordings, &space.spec(&space.start_theta(start)))
                .is_ok_and(|begun| profile_cost(&free.score) > profile_cost(&begun))
        };
        if !space.charge_cubic_at_floor(&free.circuit_theta) && !worse_than_start() {
            return Ok(free);
        }
        let held = self.descend_stages(recordings, space, start, patience, lane, true)?;
        if held.given_up || profile_cost(&held.score) >= profile_cost(&free.score) {
            return Ok(free);
        }
        Ok(Descended {
            evaluations: held.evaluations + free.evaluations,
            ..held
        })
    }

    /// [`Self::descend_space_here`]'s stages, once: with the charge's
    /// cubic free, or (`hold_charge`) held at its start in the circuit's
    /// stage.
    fn descend_stages(
        &self,
        recordings: &[usize],
        space: Space,
        start: &ModelSpec,
        patience: usize,
        lane: Option<&Lane<'_>>,
        hold_charge: bool,
    ) -> Result<Descended, FitError> {
        let mut theta = space.start_theta(start);
        let mut circuit_theta = theta.clone();
        let (mut evaluations, mut termination) = (0, Vec::new());
        let stages: Vec<(Stage, Vec<usize>, usize)> = Stage::ALL
            .iter()
            .map(|&stage| {
                let m = self.stage_count(stage, recordings);
                (stage, stage.knobs(&space), m)
            })
            .collect();
        let mut inflation = Inflation::ONE;
        let mut given_up = false;
        'stages: for (stage, free, m) in &stages {
            if free.is_empty() || *m == 0 {
                continue;
            }
            // The beam's sensors weighed by the variance each shows (the
            // circuit's one sensor needs no weight of its own): first as
            // at the start, then as at the end of the descent, once more
            // if that moved any by 10 %. A start from a fitted model is
            // near its end, so one descent mostly does.
            let beam = *stage == Stage::Beam;
            if beam {
                inflation = self.inflation(*stage, recordings, &space.spec(&theta))?;
            }
            // The charge's cubic held at its start where asked.
            let free: Vec<usize> = free
                .iter()
                .copied()
                .filter(|&j| !(hold_charge && space.knobs[j] == Knob::ChargeCubic))
                .collect();
            let free = &free;
            if !beam {
                theta = self.best_reaction_start(recordings, &space, theta, &inflation);
            }
            for round in 0..=INFLATION_ROUNDS {
                let run =
                    |spec: &ModelSpec| self.stage_residuals(*stage, recordings, spec, &inflation);
                let problem = Problem::new(&run, &space, free, theta.clone(), *m).racing(lane);
                let (problem, report, n) = descend(problem, patience);
                evaluations += n;
                given_up = problem.given_up();
                theta = problem.theta;
                if given_up {
                    break 'stages;
                }
                termination.push(format!("{}: {:?}", stage.name(), report.termination));
                if !beam {
                    circuit_theta = theta.clone();
                }
                if !beam || round == INFLATION_ROUNDS {
                    break;
                }
                let next = self.inflation(*stage, recordings, &space.spec(&theta))?;
                if !next.moved(&inflation, 0.1) {
                    break;
                }
                inflation = next;
            }
        }
        // One simulation at the final point serves the score, the
        // information criteria and the beam stage's Jacobian base; none
        // for a start given up.
        let score = if given_up {
            Score::new(Vec::new())
        } else {
            self.score_here(recordings, &space.spec(&theta))?
        };
        Ok(Descended {
            space,
            theta,
            circuit_theta,
            stages,
            inflation,
            score,
            evaluations,
            termination,
            given_up,
        })
    }

    /// Of `theta` and the reaction's grid of starts around it
    /// ([`Space::reaction_starts`]), the one whose currents fit best:
    /// sixteen runs of the circuit alone, against a Jacobian's one per
    /// knob at every step of the descent. A start the model refuses is
    /// passed over (the descent from `theta` reports its own errors).
    fn best_reaction_start(
        &self,
        recordings: &[usize],
        space: &Space,
        theta: Vec<f64>,
        inflation: &Inflation,
    ) -> Vec<f64> {
        let cost = |t: &[f64]| {
            self.stage_residuals(Stage::Circuit, recordings, &space.spec(t), inflation)
                .map(|r| r.iter().map(|x| x * x).sum::<f64>())
                .ok()
                .filter(|c| c.is_finite())
        };
        let starts = space.reaction_starts(&theta);
        if starts.is_empty() {
            return theta;
        }
        let mut best = (cost(&theta).unwrap_or(f64::INFINITY), theta);
        for t in starts {
            if let Some(c) = cost(&t).filter(|&c| c < best.0) {
                best = (c, t);
            }
        }
        best.1
    }

    /// The intervals and the criteria at the end of descents `d`, in the
    /// pool.
    pub(super) fn finish(&self, recordings: &[usize], d: Descended) -> Result<FitResult, FitError> {
        let Descended {
            space,
            theta,
            circuit_theta: _,
            stages,
            inflation,
            score,
            evaluations,
            termination,
            given_up: _,
        } = d;
        let spec = space.spec(&theta);
        let (active, cov) =
            self.covariance(recordings, &space, &theta, &score, &stages, &inflation)?;
        let grads = stats::value_gradients(&space, &theta, &active);
        let value_covariance = stats::value_covariance(&cov, &active, &grads);
        let estimates = stats::estimates(&space, &theta, &value_covariance, &active);
        let (rss, m) = (score.rss, score.m);
        let k = space.counted_parameters();
        let (aic, bic) = stats::information(rss, m, k);
        Ok(FitResult {
            effects: space.effects.clone(),
            spec,
            estimates,
            value_covariance,
            score,
            parameters: k,
            aic,
            bic,
            evaluations,
            termination: termination.join(", "),
            form: None,
        })
    }

    /// Each sensor's variance over its rests' that `stage` sees over
    /// `recordings` under `spec`.
    fn inflation(
        &self,
        stage: Stage,
        recordings: &[usize],
        spec: &ModelSpec,
    ) -> Result<Inflation, FitError> {
        let seen = self.score_here(recordings, spec)?;
        Ok(Inflation::of(
            seen.channels.iter().filter(|c| stage.sees(c.channel)),
        ))
    }

    /// The covariance of `θ` at the end of a fit whose stages were
    /// `stages` and whose score is `score` (see [`covariance::two_stage`]):
    /// the circuit's Jacobian over the currents, the beam's over its own
    /// sensors and the circuit's knobs.
    fn covariance(
        &self,
        recordings: &[usize],
        space: &Space,
        theta: &[f64],
        score: &Score,
        stages: &[(Stage, Vec<usize>, usize)],
        inflation: &Inflation,
    ) -> Result<(Vec<usize>, nalgebra::DMatrix<f64>), FitError> {
        let mut circuit = None;
        let mut beam = None;
        for (stage, free, m) in stages {
            if *m == 0 {
                continue;
            }
            // The residuals as the stage weighed them at its end.
            let base: Vec<f64> = score
                .channels
                .iter()
                .filter(|c| stage.sees(c.channel))
                .flat_map(|c| {
                    let f = inflation.sigma_factor(Sensor::of(c.channel));
                    c.residuals.iter().map(move |r| r / f)
                })
                .collect();
            let clusters = self.clusters(*stage, recordings);
            let run = |spec: &ModelSpec| self.stage_residuals(*stage, recordings, spec, inflation);
            match stage {
                Stage::Circuit => {
                    let p = Problem::new(&run, space, free, theta.to_vec(), *m);
                    circuit = Some(Block {
                        knobs: free.clone(),
                        jacobian: p.jacobian_at(theta, &base)?,
                        residuals: base,
                        clusters,
                    });
                }
                Stage::Beam => {
                    // One pass for the beam's columns and the circuit's
                    // upstream ones.
                    let upstream = Stage::Circuit.knobs(space);
                    let all: Vec<usize> = free.iter().chain(&upstream).copied().collect();
                    let p = Problem::new(&run, space, &all, theta.to_vec(), *m);
                    let jac = p.jacobian_at(theta, &base)?;
                    let own = jac.columns(0, free.len()).into_owned();
                    let up = jac.columns(free.len(), upstream.len()).into_owned();
                    beam = Some((
                        Block {
                            knobs: free.clone(),
                            jacobian: own,
                            residuals: base,
                            clusters,
                        },
                        up,
                    ));
                }
            }
        }
        let beam = beam.as_ref().map(|(b, up)| (b, up));
        Ok(covariance::two_stage(theta.len(), circuit.as_ref(), beam))
    }

    /// The cluster of each residual `stage` sees over `recordings`, in
    /// [`Self::stage_residuals`]' order: a window of
    /// [`covariance::CLUSTER_S`] of one recording, every channel in it.
    fn clusters(&self, stage: Stage, recordings: &[usize]) -> Vec<usize> {
        let mut labels = Vec::new();
        let mut first = 0;
        for &i in recordings {
            let window = (covariance::CLUSTER_S / self.session.recordings[i].dt_s)
                .round()
                .max(1.0) as usize;
            let mut last = 0;
            for t in self.targets.recordings[i]
                .targets
                .iter()
                .filter(|t| stage.sees(t.channel))
            {
                for &row in &t.rows {
                    labels.push(first + row / window);
                    last = last.max(row / window);
                }
            }
            first += last + 1;
        }
        labels
    }

    /// The residual count `stage` sees over `recordings`.
    fn stage_count(&self, stage: Stage, recordings: &[usize]) -> usize {
        recordings
            .iter()
            .flat_map(|&i| &self.targets.recordings[i].targets)
            .filter(|t| stage.sees(t.channel))
            .map(|t| t.rows.len())
            .sum()
    }

    /// Refuses `recordings` when they hold no residual or when no
    /// recording drives a segment (the data then say nothing).
    fn data_to_fit(&self, recordings: &[usize]) -> Result<(), FitError> {
        let n_data: usize = Stage::ALL
            .iter()
            .map(|&stage| self.stage_count(stage, recordings))
            .sum();
        if n_data == 0 {
            return Err(FitError::NoData);
        }
        let driven = recordings
            .iter()
            .any(|&i| !self.session.recordings[i].driven().is_empty());
        if !driven {
            return Err(FitError::NoDrive);
        }
        Ok(())
    }
}

/// A fit's descents done, its intervals not yet computed: what picks the
/// lower of two starts before either's intervals are paid for.
pub(super) struct Descended {
    /// The structure fitted and its knobs.
    pub(super) space: Space,
    /// The point the descents ended at.
    pub(super) theta: Vec<f64>,
    /// The point at the end of the circuit's stage.
    circuit_theta: Vec<f64>,
    /// Each stage, its free knobs and its residual count.
    stages: Vec<(Stage, Vec<usize>, usize)>,
    /// The sensors' weights at the end of the beam's descents.
    inflation: Inflation,
    /// The score at `theta` on the fitted recordings.
    score: Score,
    evaluations: usize,
    /// How each descent stopped.
    termination: Vec<String>,
    /// Whether a race gave this start up (`race.rs`): then `score` is
    /// empty and nothing else is to be read.
    given_up: bool,
}
