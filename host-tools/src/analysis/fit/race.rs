//! `finrs fit`'s two starts, side by side, and when the slower one is given
//! up.
//!
//! Either start can crawl: on the off-class rig's water sessions one start
//! ran to its evaluation limit (364 evaluations, 16.5 s of 10036's fit)
//! and ended eight times above the other's cost. A start is given up at
//! its first Jacobian past [`FACTOR`] times the evaluations the other took
//! in all, if its cost there is no lower than the other's at its end. The
//! rule reads the two starts' own paths alone, never which finished first
//! on the clock, so the fit is the same on any machine and under any load:
//! a start keeps the points where the rule may read it (cheap: no
//! simulation), and the one point the rule reads is scored when it is
//! read.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

use crate::model::predict::ModelSpec;

/// Evaluations a start may take, as a multiple of the other start's
/// evaluations in all, before its cost is compared with the other's end.
/// At 1, over the first 40 off-class seeds (a build printing both starts'
/// paths, 2026-11-27): the water fits' crawling starts given up at the
/// other's 30 (10002) and 171 (10036) evaluations, where they ran to 391
/// and 364; 1490 of the 6674 evaluations of both starts saved in all; no pick changed where
/// the two ends differ by more than a millionth of the cost; in 9 where
/// they do not, the start that got there in fewer evaluations is kept.
pub const FACTOR: f64 = 1.0;

// Below 1 both starts could be given up: each past the other's total.
const _: () = assert!(FACTOR >= 1.0);

/// One start's progress, as the other sees it.
#[derive(Debug, Default)]
pub struct Progress {
    /// Residual evaluations so far.
    evaluations: AtomicUsize,
    /// Its evaluations in all and its cost at the end, once finished.
    finished: Mutex<Option<(usize, f64)>>,
}

impl Progress {
    /// Its evaluations in all and its end's cost, once finished.
    fn finished(&self) -> Option<(usize, f64)> {
        *self.finished.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Evaluations so far: never more than in all.
    fn evaluations(&self) -> usize {
        self.evaluations.load(Ordering::SeqCst)
    }
}

/// A start's lane: its own progress, the other's, and the points at which
/// the rule may read it.
pub struct Lane<'a> {
    own: &'a Progress,
    other: &'a Progress,
    /// `(evaluations, model)` at each Jacobian at or past [`FACTOR`] times the
    /// other's evaluations at that moment (a lower bound of its total, so
    /// the first Jacobian past `FACTOR` times the total is always here).
    points: Mutex<Vec<(usize, ModelSpec)>>,
    /// The cost of a point of `points`, the profile cost of its model on
    /// the fitted recordings.
    cost: &'a (dyn Fn(&ModelSpec) -> Option<f64> + Sync),
    /// The rule's answer, once it has the point it reads (the other's end
    /// is then known and fixed).
    verdict: OnceLock<bool>,
}

impl<'a> Lane<'a> {
    /// The lane of the start whose progress is `own`, racing `other`;
    /// `cost` scores a point.
    pub fn new(
        own: &'a Progress,
        other: &'a Progress,
        cost: &'a (dyn Fn(&ModelSpec) -> Option<f64> + Sync),
    ) -> Self {
        Lane {
            own,
            other,
            points: Mutex::new(Vec::new()),
            cost,
            verdict: OnceLock::new(),
        }
    }

    /// Counts one residual evaluation.
    pub fn evaluated(&self) {
        self.own.evaluations.fetch_add(1, Ordering::SeqCst);
    }

    /// At a Jacobian, at the model `spec`: whether the start goes on (and
    /// it is marked given up if not).
    pub fn goes_on(&self, spec: &ModelSpec) -> bool {
        let n = self.own.evaluations();
        let other_so_far = self
            .other
            .finished()
            .map_or_else(|| self.other.evaluations(), |(e, _)| e);
        if n as f64 >= FACTOR * other_so_far as f64 {
            self.points().push((n, *spec));
        }
        !self.other.finished().is_some_and(|end| self.gives_up(end))
    }

    /// Whether the rule gives this start up against the other's `end`
    /// (evaluations in all, cost): its first kept point past [`FACTOR`]
    /// times those evaluations costs no less. `false` until it has such a
    /// point.
    pub fn gives_up(&self, end: (usize, f64)) -> bool {
        if let Some(&v) = self.verdict.get() {
            return v;
        }
        let first = self
            .points()
            .iter()
            .find(|(n, _)| *n as f64 >= FACTOR * end.0 as f64)
            .map(|(_, spec)| *spec);
        match first {
            // A point the model refuses costs more than any end.
            Some(spec) => *self
                .verdict
                .get_or_init(|| (self.cost)(&spec).is_none_or(|c| c >= end.1)),
            None => false,
        }
    }

    /// Marks the start finished, its end costing `cost`.
    pub fn finish(&self, cost: f64) {
        let total = self.own.evaluations();
        *self.own.finished.lock().unwrap_or_else(|e| e.into_inner()) = Some((total, cost));
    }

    /// Whether the rule has given the start up.
    pub fn dropped(&self) -> bool {
        self.verdict.get() == Some(&true)
    }

    /// The start's evaluations and its end's cost, once finished.
    pub fn end(&self) -> Option<(usize, f64)> {
        self.own.finished()
    }

    fn points(&self) -> std::sync::MutexGuard<'_, Vec<(usize, ModelSpec)>> {
        self.points.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::Params;

    /// A model whose cost (below) is `c`.
    fn costing(c: f64) -> ModelSpec {
        let mut p = Params::main_m_2006();
        p.r1_ohm = c;
        ModelSpec::baseline(p)
    }

    fn cost(spec: &ModelSpec) -> Option<f64> {
        Some(spec.params.r1_ohm)
    }

    /// The first count at or past [`FACTOR`] times `e`.
    fn past(e: usize) -> usize {
        (FACTOR * e as f64).ceil() as usize
    }

    /// This start's lane and the other's, racing.
    fn lanes<'a>(
        own: &'a Progress,
        other: &'a Progress,
        cost: &'a (dyn Fn(&ModelSpec) -> Option<f64> + Sync),
    ) -> (Lane<'a>, Lane<'a>) {
        (Lane::new(own, other, cost), Lane::new(other, own, cost))
    }

    fn evaluate(lane: &Lane<'_>, n: usize) {
        for _ in 0..n {
            lane.evaluated();
        }
    }

    #[test]
    fn a_start_past_the_factor_and_no_lower_than_the_others_end_is_given_up() {
        let (own, other) = (Progress::default(), Progress::default());
        let (lane, rival) = lanes(&own, &other, &cost);
        evaluate(&rival, 10);
        rival.finish(5.0);
        evaluate(&lane, past(10) - 1);
        // Not yet FACTOR times the other's 10: it goes on however it costs.
        assert!(lane.goes_on(&costing(9.0)));
        evaluate(&lane, 1);
        assert!(!lane.goes_on(&costing(9.0)));
        assert!(lane.dropped());
        assert_eq!(lane.end(), None, "a start given up has no end");
    }

    #[test]
    fn a_start_lower_than_the_others_end_at_the_point_read_goes_on_to_its_end() {
        let (own, other) = (Progress::default(), Progress::default());
        let (lane, rival) = lanes(&own, &other, &cost);
        evaluate(&rival, 10);
        rival.finish(5.0);
        evaluate(&lane, past(10));
        assert!(lane.goes_on(&costing(4.0)));
        // The rule reads one point: a later one does not undo its answer.
        evaluate(&lane, 5);
        assert!(lane.goes_on(&costing(6.0)));
        assert!(!lane.dropped());
    }

    #[test]
    fn the_answer_does_not_depend_on_when_the_other_finished_on_the_clock() {
        // The same two paths, the other finishing before and after this
        // start's points: the rule reads the same point, its first past
        // FACTOR times the other's 12 evaluations.
        let answer = |other_finishes_first: bool| {
            let (own, other) = (Progress::default(), Progress::default());
            let (lane, rival) = lanes(&own, &other, &cost);
            if other_finishes_first {
                evaluate(&rival, 12);
                rival.finish(5.0);
            } else {
                evaluate(&rival, 4);
            }
            evaluate(&lane, past(12));
            let went_on = lane.goes_on(&costing(9.0));
            evaluate(&lane, 10);
            let went_on_later = lane.goes_on(&costing(3.0));
            if !other_finishes_first {
                evaluate(&rival, 8);
                rival.finish(5.0);
            }
            (
                went_on && went_on_later,
                lane.gives_up(rival.end().expect("finished")),
            )
        };
        // Given up at once when the other's end was known, after the fact
        // (the pick after both ends) when it was not: the same answer.
        assert_eq!(answer(true), (false, true));
        assert_eq!(answer(false), (true, true));
    }

    #[test]
    fn a_point_the_model_refuses_is_given_up() {
        let refused = |_: &ModelSpec| None;
        let (own, other) = (Progress::default(), Progress::default());
        let (lane, rival) = lanes(&own, &other, &refused);
        evaluate(&rival, 2);
        rival.finish(1.0);
        evaluate(&lane, 3);
        assert!(!lane.goes_on(&costing(0.5)));
    }
}
