//! The fit in two stages, as the model is built: the circuit from the
//! currents, then the relaxation and the beam from the camera and the load
//! cell with the circuit held.
//!
//! The circuit is upstream of the beam: the currents depend on `R1`, `R2`,
//! `C` and the electrochemical terms alone. Fitted jointly, a misfit of the
//! beam (damping the model lacks, a creeping strip) pulls the circuit's
//! values wherever they lower the beam's residuals, and the currents'
//! sharp intervals then claim a precision the values do not have. In
//! stages, each sensor moves only what it determines; the circuit's stage
//! runs the circuit alone (no modes, no beam), and the beam's Jacobian has
//! only the beam's columns.

use levenberg_marquardt::{
    LeastSquaresProblem, LevenbergMarquardt, MinimizationReport, TerminationReason,
};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;
use std::sync::Mutex;

use super::error::FitError;
use super::race::Lane;
use super::space::{difference_step, Knob, Space};
use crate::model::predict::ModelSpec;
use crate::recording::Channel;

/// Restarts of the optimiser after its first stop, at most.
const MAX_RESTARTS: usize = 3;

/// Where a descent stops: the cost's predicted and actual relative
/// decrease (`ftol`), or the cosine between the residuals and every
/// Jacobian column (`gtol`), below a millionth. The crate's default, 30
/// machine epsilons, asks more than a forward-difference Jacobian (steps
/// of a millionth) can answer, so descents crawled to their evaluation
/// limit: on off-class rig seed 10072 a diagnosis took 110 s at the
/// default and 25 s at a millionth, with the same verdict and held-out
/// gain to six digits. A millionth of the cost is far below anything the
/// selection reads (a ΔBIC of 10, a held-out gain of 1 %).
const TOLERANCE: f64 = 1e-6;

/// Accepted points in a row at which a knob whose model is even in `θ`
/// flipped its sign before it is held at its bound (`θ = 0`): see
/// [`descend`].
const FLIPS_TO_HOLD: usize = 4;

/// A stage of the fit: which knobs it moves and which residuals it sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The electrics, from the currents.
    Circuit,
    /// The relaxation network and the beam, from the camera and the load
    /// cell, with the circuit held.
    Beam,
}

impl Stage {
    /// Both, in the order they run.
    pub const ALL: [Stage; 2] = [Stage::Circuit, Stage::Beam];

    /// Whether the stage's residuals include channel `ch`.
    pub fn sees(self, ch: Channel) -> bool {
        matches!(ch, Channel::Current(_)) == (self == Stage::Circuit)
    }

    /// Whether the stage fits `knob`.
    pub fn moves(self, knob: Knob) -> bool {
        knob.is_circuit() == (self == Stage::Circuit)
    }

    /// The indices in `space`'s `θ` that the stage fits.
    pub fn knobs(self, space: &Space) -> Vec<usize> {
        (0..space.knobs.len())
            .filter(|&j| self.moves(space.knobs[j]))
            .collect()
    }

    /// Its name in the fit's report.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Circuit => "circuit",
            Stage::Beam => "beam",
        }
    }
}

/// Runs a model and returns the weighted residuals a stage sees.
pub type Residuals<'a> = dyn Fn(&ModelSpec) -> Result<Vec<f64>, FitError> + Sync + 'a;

/// The least-squares problem of one stage, as the optimiser sees it: the
/// stage's knobs free, every other part of `θ` held.
pub struct Problem<'b> {
    /// The stage's residuals of a model.
    run: &'b Residuals<'b>,
    space: &'b Space,
    /// Indices in `θ` of the free knobs.
    free: Vec<usize>,
    /// The whole `θ`, its free entries the optimiser's current point.
    pub(super) theta: Vec<f64>,
    /// Residuals at `theta`; `None` where the model refused it.
    residuals: Option<DVector<f64>>,
    /// Residual count.
    m: usize,
    /// The start's lane when two starts race (`race.rs`).
    lane: Option<&'b Lane<'b>>,
    /// The signs of the knobs even in `θ` at the accepted points.
    flips: Mutex<Flips>,
}

/// What [`Problem`] has seen of its knobs' signs.
#[derive(Debug, Default)]
struct Flips {
    /// Per free knob, the sign of its `θ` at the last accepted point and
    /// how many accepted points in a row flipped it.
    signs: Vec<(f64, usize)>,
    /// The free knob found flipping ([`FLIPS_TO_HOLD`]), where the
    /// descent stopped.
    flipping: Option<usize>,
}

impl Flips {
    fn new(free: usize) -> Mutex<Flips> {
        Mutex::new(Flips {
            signs: vec![(0.0, 0); free],
            flipping: None,
        })
    }
}

impl<'b> Problem<'b> {
    /// The problem of the stage whose residuals `run` gives, `m` of them,
    /// over the knobs `free` of `space`, at `theta`, not yet evaluated.
    pub fn new(
        run: &'b Residuals<'b>,
        space: &'b Space,
        free: &'b [usize],
        theta: Vec<f64>,
        m: usize,
    ) -> Self {
        Problem {
            run,
            space,
            free: free.to_vec(),
            theta,
            residuals: None,
            m,
            lane: None,
            flips: Flips::new(free.len()),
        }
    }

    /// The problem with free knob `k` (its position among the free ones)
    /// held at its bound `θ = 0`, or where it is if the bound costs more,
    /// evaluated.
    fn holding(mut self, k: usize) -> Self {
        let j = self.free.remove(k);
        let (here, cost_here) = (self.theta[j], self.cost());
        // Kept, so that going back costs no second simulation.
        let residuals_here = self.residuals.clone();
        self.theta[j] = 0.0;
        let x = self.params();
        self.set_params(&x);
        if self.cost() > cost_here {
            self.theta[j] = here;
            self.residuals = residuals_here;
        }
        self.flips = Flips::new(self.free.len());
        self
    }

    /// The sum of squares at the last point evaluated (infinite where the
    /// model refused it).
    fn cost(&self) -> f64 {
        self.residuals
            .as_ref()
            .map_or(f64::INFINITY, |r| r.norm_squared())
    }

    /// The free knob (its position among the free ones) whose sign
    /// flipped at [`FLIPS_TO_HOLD`] accepted points in a row, if the
    /// descent stopped for one.
    fn flipping(&self) -> Option<usize> {
        self.flips
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .flipping
    }

    /// Notes the signs of the knobs even in `θ` at an accepted point;
    /// true when one has flipped [`FLIPS_TO_HOLD`] times in a row.
    fn note_signs(&self) -> bool {
        let mut flips = self.flips.lock().unwrap_or_else(|e| e.into_inner());
        for (k, &j) in self.free.iter().enumerate() {
            if !self.space.even(j) {
                continue;
            }
            let sign = if self.theta[j] > 0.0 {
                1.0
            } else if self.theta[j] < 0.0 {
                -1.0
            } else {
                0.0
            };
            let (last, row) = flips.signs[k];
            let row = if sign != 0.0 && last == -sign {
                row + 1
            } else {
                0
            };
            flips.signs[k] = (sign, row);
            if row >= FLIPS_TO_HOLD {
                flips.flipping = Some(k);
                return true;
            }
        }
        false
    }

    /// The problem in a start's `lane`: its evaluations counted, and given
    /// up at a Jacobian where the race's rule says so.
    pub fn racing(self, lane: Option<&'b Lane<'b>>) -> Self {
        Problem { lane, ..self }
    }

    /// Whether the race gave this start up.
    pub fn given_up(&self) -> bool {
        self.lane.is_some_and(Lane::dropped)
    }

    /// `θ` with the free entries `x`.
    fn with_free(&self, x: &[f64]) -> Vec<f64> {
        let mut t = self.theta.clone();
        for (&j, &v) in self.free.iter().zip(x) {
            t[j] = v;
        }
        t
    }

    /// The stage's weighted residuals at the whole `theta`.
    fn residuals_at(&self, theta: &[f64]) -> Result<Vec<f64>, FitError> {
        (self.run)(&self.space.spec(theta))
    }

    /// Forward-difference Jacobian of the stage's residuals at the whole
    /// `theta`, whose residuals are `base`: one column per free knob, the
    /// columns in parallel (each is a whole session's simulation).
    pub fn jacobian_at(&self, theta: &[f64], base: &[f64]) -> Result<DMatrix<f64>, FitError> {
        let columns: Result<Vec<Vec<f64>>, FitError> = self
            .free
            .par_iter()
            .map(|&j| {
                let h = difference_step(theta[j]);
                let mut t = theta.to_vec();
                t[j] += h;
                let r = self.residuals_at(&t)?;
                Ok(r.iter().zip(base).map(|(a, b)| (a - b) / h).collect())
            })
            .collect();
        let columns = columns?;
        Ok(DMatrix::from_fn(base.len(), self.free.len(), |i, j| {
            columns[j][i]
        }))
    }

    /// The free entries of the point on the edge of any floor a term sank
    /// below (where the optimiser sees its gradient again).
    fn edge(&self) -> DVector<f64> {
        let back = self.space.theta(&self.space.spec(&self.theta));
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&j| back[j]))
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        if let Some(lane) = self.lane {
            lane.evaluated();
        }
        self.theta = self.with_free(x.as_slice());
        self.residuals = self
            .residuals_at(&self.theta)
            .ok()
            .filter(|r| r.iter().all(|v| v.is_finite()))
            .map(DVector::from_vec);
    }

    fn params(&self) -> DVector<f64> {
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&j| self.theta[j]))
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
        // Given up, or a knob found flipping, the optimiser stops here
        // (`User("jacobian")`).
        if self.note_signs() {
            return None;
        }
        if let Some(lane) = self.lane {
            if !lane.goes_on(&self.space.spec(&self.theta)) {
                return None;
            }
        }
        // The cached residuals are the base: no second simulation here.
        let base = self.residuals.as_ref()?;
        self.jacobian_at(&self.theta, base.as_slice()).ok()
    }
}

/// Levenberg–Marquardt from `problem`'s point, restarted: it stops on a
/// small step as readily as on a minimum, so it restarts from where it
/// stopped, with a fresh trust region, until a restart no longer lowers the
/// cost by a millionth. Without this, a later model with one more term
/// "gains" only by finishing this one's descent. A descent that ran out of
/// evaluations (`LostPatience`) is not restarted: it was crawling along a
/// valley, and three more crawls cost four times the evaluations for
/// little (on an off-class session every candidate on top of dehydration
/// ran 1454 evaluations so, and the session took 490 s). Returns the
/// problem at the end, the last report and the evaluations in all. Each
/// descent takes at most `patience` evaluations per free knob and one
/// ([`PATIENCE`] for a fit).
///
/// A knob whose model is even in `θ` (`a` and `b/p` of the model without
/// back-relaxation: [`Space::even`]) has its bound at `θ = 0`. Where the
/// data want it past the bound (`b < 0`), each step's linear model
/// promises a fall through it that the model cannot give, the trust
/// region shrinks to a flip of the knob's sign, and every other knob
/// crawls beside it: on the lab protocol's back-relaxing strip (rig seed
/// 20024), the damping's candidate flipped `b`'s sign at each of 240
/// evaluations and ran out of them, a third of the diagnosis. A knob
/// that flips at [`FLIPS_TO_HOLD`] accepted points in a row is held at
/// its bound, and the others descend again (not counted as a restart).
pub fn descend(
    mut problem: Problem<'_>,
    patience: usize,
) -> (Problem<'_>, MinimizationReport<f64>, usize) {
    let start = problem.params();
    problem.set_params(&start);
    let (mut problem, mut report) = optimiser(patience).minimize(problem);
    let mut evaluations = report.number_of_evaluations;
    let mut restarts = 0;
    loop {
        if let Some(k) = problem.flipping() {
            problem = problem.holding(k);
            let (p, r) = optimiser(patience).minimize(problem);
            evaluations += r.number_of_evaluations;
            (problem, report) = (p, r);
            continue;
        }
        if restarts == MAX_RESTARTS
            || matches!(report.termination, TerminationReason::LostPatience)
            || problem.given_up()
        {
            break;
        }
        restarts += 1;
        let before = report.objective_function;
        let edge = problem.edge();
        problem.set_params(&edge);
        let (p, r) = optimiser(patience).minimize(problem);
        evaluations += r.number_of_evaluations;
        problem = p;
        let gained = before - r.objective_function;
        report = r;
        if problem.flipping().is_none() && (gained.is_nan() || gained <= TOLERANCE * before.abs()) {
            break;
        }
    }
    (problem, report, evaluations)
}

/// Evaluations a fit's descent may take per free knob and one.
pub const PATIENCE: usize = 40;

/// One descent's optimiser: [`TOLERANCE`] on the cost and the gradient,
/// the crate's own on the step, and at most `patience` evaluations per
/// free knob and one. Not the step at a millionth: in a stiff valley the
/// steps are small while the cost still falls, and a descent so stopped
/// left the virtual bench's soft beam (`tests/diagnose.rs`) at 1.04 times
/// the noise held out, `unexplained`.
fn optimiser(patience: usize) -> LevenbergMarquardt<f64> {
    LevenbergMarquardt::new()
        .with_patience(patience)
        .with_ftol(TOLERANCE)
        .with_gtol(TOLERANCE)
}
