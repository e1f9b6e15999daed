//! The fit itself: a session's targets, the least-squares problem the
//! optimiser sees, and its restarts.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, MinimizationReport};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;

use super::data::SessionTargets;
use super::effect::Effect;
use super::error::FitError;
use super::space::Space;
use super::start;
use super::stats::{self, ChannelFit, Estimate, Score};
use crate::model::params::{Beam, Electrical, ExtensionsFile, ModelFile, Relaxation};
use crate::model::predict::{predict, ModelSpec};
use crate::session::Session;

/// Elements per segment the fit uses: four, not the seed's one (Appendix
/// B's `n = 3` for three segments). The undamped beam rings for seconds,
/// and one element a segment puts the blocked mode 0.2 Hz off (117.53
/// against 117.30 Hz), almost two cycles of phase in 8 s; four put the
/// first modes within 0.01 % of a finer mesh's, far below what the data
/// resolve. The static shape does not depend on it.
pub const FIT_ELEMENTS: usize = 4;
/// Restarts of the optimiser after its first stop, at most.
const MAX_RESTARTS: usize = 3;

/// The fit's worker threads: the model's work arrays for the largest
/// meshes take about 2 MiB of stack, rayon's default.
fn pool() -> &'static rayon::ThreadPool {
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
}

impl FitResult {
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
            ));
        }
        f
    }
}

/// A session prepared for fitting: its targets and noise levels.
pub struct Fitter<'a> {
    session: &'a Session,
    targets: SessionTargets,
}

impl<'a> Fitter<'a> {
    /// Prepares `session`.
    pub fn new(session: &'a Session) -> Fitter<'a> {
        Fitter {
            session,
            targets: SessionTargets::new(session),
        }
    }

    /// The session's targets and noise levels.
    pub fn targets(&self) -> &SessionTargets {
        &self.targets
    }

    /// Runs the model on recording `index` and returns its weighted
    /// residuals, target by target.
    fn residuals_of(&self, index: usize, spec: &ModelSpec) -> Result<Vec<Vec<f64>>, FitError> {
        let r = &self.session.recordings[index];
        let rt = &self.targets.recordings[index];
        let t0 = r.t_start_s.unwrap_or(0.0);
        let traces = predict(
            &r.rec,
            spec,
            FIT_ELEMENTS,
            r.dt_s,
            t0,
            Some(&rt.camera_rows),
            &mut |_| {},
        )
        .map_err(|source| FitError::Model {
            recording: r.name.clone(),
            source,
        })?;
        Ok(rt
            .targets
            .iter()
            .map(|t| {
                t.model(&traces)
                    .zip(&t.values)
                    .map(|(m, y)| (m - y) / t.sigma)
                    .collect()
            })
            .collect())
    }

    /// Weighted residuals of `spec` over `recordings`, concatenated.
    fn residuals(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Vec<f64>, FitError> {
        let parts: Result<Vec<Vec<Vec<f64>>>, FitError> = recordings
            .par_iter()
            .map(|&i| self.residuals_of(i, spec))
            .collect();
        Ok(parts?.into_iter().flatten().flatten().collect())
    }

    /// Scores `spec` on `recordings`: per-channel fit and the pooled error.
    pub fn score(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Score, FitError> {
        pool().install(|| self.score_here(recordings, spec))
    }

    fn score_here(&self, recordings: &[usize], spec: &ModelSpec) -> Result<Score, FitError> {
        let mut channels = Vec::new();
        for &i in recordings {
            let res = self.residuals_of(i, spec)?;
            for (t, r) in self.targets.recordings[i].targets.iter().zip(res) {
                let rec = &self.session.recordings[i];
                channels.push(ChannelFit::new(&rec.name, t, &r, &rec.rec.v_v));
            }
        }
        Ok(Score::new(channels))
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
        pool().install(|| self.fit_here(recordings, effects, start, fixed))
    }

    fn fit_here(
        &self,
        recordings: &[usize],
        effects: &[Effect],
        start: Option<&ModelSpec>,
        fixed: ModelSpec,
    ) -> Result<FitResult, FitError> {
        let n_data = self.data_to_fit(recordings)?;
        let segments = self.session.recordings[0].rec.meta.segments;
        let space = Space::new(effects, segments, fixed);
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
        let theta0 = DVector::from_vec(space.theta(&start));
        let mut problem = Problem {
            fitter: self,
            recordings,
            space: &space,
            theta: theta0.clone(),
            residuals: None,
            m: n_data,
        };
        problem.set_params(&theta0);
        let (problem, report, evaluations) = descend(problem, &space);
        // One simulation at the optimiser's final point serves the score,
        // the information criteria and the Jacobian's base.
        let theta = problem.theta.clone();
        let spec = space.spec(theta.as_slice());
        let score = self.score_here(recordings, &spec)?;
        let (rss, m) = (score.rss, score.m);
        let base: Vec<f64> = score
            .channels
            .iter()
            .flat_map(|c| c.residuals.iter().copied())
            .collect();
        let jac = problem.jacobian_at(&theta, &base)?;
        let estimates = stats::estimates(&space, theta.as_slice(), &jac, rss, m);
        let k = space.counted_parameters();
        let (aic, bic) = stats::information(rss, m, k);
        Ok(FitResult {
            effects: space.effects.clone(),
            spec,
            estimates,
            score,
            parameters: k,
            aic,
            bic,
            evaluations,
            termination: format!("{:?}", report.termination),
        })
    }

    /// The residual count of `recordings`, refused when it is 0 or when
    /// no recording drives a segment (the data then say nothing).
    fn data_to_fit(&self, recordings: &[usize]) -> Result<usize, FitError> {
        let n_data: usize = recordings
            .iter()
            .map(|&i| {
                self.targets.recordings[i]
                    .targets
                    .iter()
                    .map(|t| t.rows.len())
                    .sum::<usize>()
            })
            .sum();
        if n_data == 0 {
            return Err(FitError::NoData);
        }
        let driven = recordings.iter().any(|&i| {
            let v_v = &self.session.recordings[i].rec.v_v;
            v_v.as_flat().iter().any(|&v| v != 0.0)
        });
        if !driven {
            return Err(FitError::NoDrive);
        }
        Ok(n_data)
    }
}

/// Levenberg–Marquardt from `problem`'s point, restarted: it stops on a
/// small step as readily as on a minimum, so it restarts from where it
/// stopped, with a fresh trust region, until a restart no longer lowers the
/// cost by a millionth. Without this, a later model with one more term
/// "gains" only by finishing this one's descent. Returns the problem at the
/// end, the last report and the evaluations in all.
fn descend<'a, 'b>(
    problem: Problem<'a, 'b>,
    space: &Space,
) -> (Problem<'a, 'b>, MinimizationReport<f64>, usize) {
    let (mut problem, mut report) = LevenbergMarquardt::new()
        .with_patience(40)
        .minimize(problem);
    let mut evaluations = report.number_of_evaluations;
    for _ in 0..MAX_RESTARTS {
        let before = report.objective_function;
        // Back onto the edge of any floor a term sank below: there the
        // optimiser sees its gradient again.
        let edge = DVector::from_vec(space.theta(&space.spec(problem.theta.as_slice())));
        problem.set_params(&edge);
        let (p, r) = LevenbergMarquardt::new()
            .with_patience(40)
            .minimize(problem);
        evaluations += r.number_of_evaluations;
        problem = p;
        let gained = before - r.objective_function;
        report = r;
        if gained.is_nan() || gained <= 1e-6 * before.abs() {
            break;
        }
    }
    (problem, report, evaluations)
}

/// The least-squares problem the optimiser sees.
struct Problem<'a, 'b> {
    fitter: &'b Fitter<'a>,
    recordings: &'b [usize],
    space: &'b Space,
    theta: DVector<f64>,
    /// Residuals at `theta`; `None` where the model refused it.
    residuals: Option<DVector<f64>>,
    /// Residual count.
    m: usize,
}

impl Problem<'_, '_> {
    /// Forward-difference Jacobian at `theta`, whose residuals are `base`,
    /// one column per knob, the columns in parallel (each is a whole
    /// session's simulation).
    fn jacobian_at(&self, theta: &DVector<f64>, base: &[f64]) -> Result<DMatrix<f64>, FitError> {
        let columns: Result<Vec<Vec<f64>>, FitError> = (0..theta.len())
            .into_par_iter()
            .map(|j| {
                // θ is a logarithm or similar: a fixed step is a relative one.
                let h = 1e-6 * theta[j].abs().max(1.0);
                let mut t = theta.clone();
                t[j] += h;
                let r = self
                    .fitter
                    .residuals(self.recordings, &self.space.spec(t.as_slice()))?;
                Ok(r.iter().zip(base).map(|(a, b)| (a - b) / h).collect())
            })
            .collect();
        let columns = columns?;
        Ok(DMatrix::from_fn(base.len(), theta.len(), |i, j| {
            columns[j][i]
        }))
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_, '_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.theta.copy_from(x);
        self.residuals = self
            .fitter
            .residuals(self.recordings, &self.space.spec(x.as_slice()))
            .ok()
            .filter(|r| r.iter().all(|v| v.is_finite()))
            .map(DVector::from_vec);
    }

    fn params(&self) -> DVector<f64> {
        self.theta.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        // Where the model refuses a trial point (or it overflows), a huge
        // residual makes the optimiser step back instead of stopping.
        Some(
            self.residuals
                .clone()
                .unwrap_or_else(|| DVector::from_element(self.m, 1e6)),
        )
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        // The cached residuals are the base: no second simulation here.
        let base = self.residuals.as_ref()?;
        self.jacobian_at(&self.theta, base.as_slice()).ok()
    }
}
