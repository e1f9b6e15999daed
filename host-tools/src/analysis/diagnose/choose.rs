//! Which of the candidates that pass a round joins the model.
//!
//! The held-out error ranks them: the training BIC gates, but over some
//! 10⁵ correlated residuals it cannot rank two strong candidates (on the
//! rig a six-knob segment variation out-scored, on BIC, the dehydration and
//! the crosstalk it was soaking up, with a twentieth of their held-out
//! gain). The held-out part is a few recordings, though, and two
//! candidates whose held-out errors differ by less than its channels
//! disagree cannot be told apart there. Then the session's own evidence
//! decides where it can: in water, the fluid's drag is mass-proportional
//! damping, so `damping` and `hydrodynamic-loading` differ only by the
//! added mass, and the fluid the session names (`medium`, which the
//! contract makes evidence) is the expected cause of both.

use crate::analysis::fit::{FitResult, Score};

/// Standard errors by which a candidate's held-out error must exceed the
/// best's for the two to be told apart.
pub const TOLD_APART_SE: f64 = 2.0;

/// A candidate that passed: its effect, its fit and its held-out score.
pub type Passed<E> = (E, FitResult, Score);

/// The candidate that joins: of the lowest held-out error and those whose
/// held-out error is within [`TOLD_APART_SE`] standard errors of it (the
/// log ratio paired over the held-out recordings' channels), the first
/// that `expected` accepts; if none, the lowest held-out error.
pub fn choose<E>(passed: Vec<Passed<E>>, expected: impl Fn(&E) -> bool) -> Option<Passed<E>> {
    let best = passed
        .iter()
        .enumerate()
        .min_by(|(_, a), (_, b)| a.2.rss.total_cmp(&b.2.rss))?
        .0;
    let best_rss = per_channel(&passed[best].2);
    let tied = |s: &Score| {
        // On a log scale: each channel's ratio counts alike, so one
        // channel's large RSS does not stand for all of them.
        let d: Vec<f64> = per_channel(s)
            .iter()
            .zip(&best_rss)
            .map(|(a, b)| (a / b).ln())
            .collect();
        indistinguishable(&d)
    };
    let pick = passed
        .iter()
        .enumerate()
        .filter(|(i, p)| *i == best || tied(&p.2))
        .filter(|(_, p)| expected(&p.0))
        .min_by(|(_, a), (_, b)| a.2.rss.total_cmp(&b.2.rss))
        .map_or(best, |(i, _)| i);
    passed.into_iter().nth(pick)
}

/// The held-out RSS of each channel of each recording, in the score's
/// order (the same for every candidate: the same recordings and targets).
fn per_channel(s: &Score) -> Vec<f64> {
    s.channels
        .iter()
        .map(|c| {
            c.residuals
                .iter()
                .map(|r| r * r)
                .sum::<f64>()
                .max(f64::MIN_POSITIVE)
        })
        .collect()
}

/// Whether paired log ratios `d` (candidate over best) are within
/// [`TOLD_APART_SE`] standard errors of zero; a single channel cannot tell.
fn indistinguishable(d: &[f64]) -> bool {
    let n = d.len();
    if n < 2 {
        return true;
    }
    let mean = d.iter().sum::<f64>() / n as f64;
    let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    mean <= TOLD_APART_SE * (var / n as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::indistinguishable;

    #[test]
    fn a_consistent_difference_is_told_apart_a_noisy_one_is_not() {
        // Worse on every recording by about the same: told apart.
        assert!(!indistinguishable(&[10.0, 12.0, 11.0]));
        // Worse on one, better on another: not.
        assert!(indistinguishable(&[30.0, -20.0, 5.0]));
        // One recording says nothing about the spread.
        assert!(indistinguishable(&[100.0]));
    }
}
