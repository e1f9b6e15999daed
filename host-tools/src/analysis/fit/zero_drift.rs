//! A current channel's wandering zero, read where no current flows.
//!
//! A shunt amplifier's zero wanders as a camera's does, but a current
//! has one thing a position lacks: at rest, once the charge has settled,
//! it is zero, whatever the strip's state. So the zero is read at each
//! rest (its residual's mean over the stretch) and followed between rests
//! by straight lines (before the first and after the last, held), never
//! fitted over the drive: a drift free to bend over a held voltage took
//! the leak, the steady current that the electrochemical nonlinearity
//! shows in (the rig's lab protocol, a `sinh` leak over holds of minutes:
//! missed with a polynomial fitted over every sample). The estimate is
//! linear in the residuals, so a fit's Jacobian sees it as it sees the
//! polynomial drift (`drift.rs`).
//!
//! ```
//! use finrs::analysis::fit::zero_drift::ZeroDrift;
//! // A rest (samples 0-9), a drive (10-29) and a rest (30-39).
//! let z = ZeroDrift::new(&(0..40).map(|i| i as f64).collect::<Vec<_>>(), &[(0, 10), (30, 40)]);
//! // The zero moved by 2 between the rests; the drive keeps its own 5.
//! let mut r: Vec<f64> = (0..40).map(|i| 2.0 * i as f64 / 30.0 + if (10..30).contains(&i) { 5.0 } else { 0.0 }).collect();
//! z.remove(&mut r);
//! assert!((r[20] - 5.0).abs() < 0.2 && r[35].abs() < 0.2);
//! ```

use super::drift::{chi2_999, share_of_excess, DriftMeasure};

/// Time after the last driven row before a current at rest reads its
/// zero, s: fifty charging time constants `R1·C` of the seed's strip
/// (16 ms), ten of a strip with a tenfold `C`.
pub const QUIET_SETTLE_S: f64 = 0.8;

/// One recording's current zero, anchored at its quiet stretches.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeroDrift {
    /// Per quiet stretch: its samples `from..to` and its centre, s.
    stretches: Vec<(usize, usize, f64)>,
    /// Times of the samples, s.
    t_s: Vec<f64>,
}

impl ZeroDrift {
    /// The zero of samples at `t_s`, quiet over the stretches `from..to`
    /// (sample indices, in order, not overlapping).
    pub fn new(t_s: &[f64], stretches: &[(usize, usize)]) -> ZeroDrift {
        ZeroDrift {
            stretches: stretches
                .iter()
                .filter(|(from, to)| to > from && *to <= t_s.len())
                .map(|&(from, to)| (from, to, 0.5 * (t_s[from] + t_s[to - 1])))
                .collect(),
            t_s: t_s.to_vec(),
        }
    }

    /// Each stretch's centre, s, and the mean of `r` over it.
    fn levels(&self, r: &[f64]) -> Vec<(f64, f64)> {
        self.stretches
            .iter()
            .map(|&(from, to, centre)| {
                (centre, r[from..to].iter().sum::<f64>() / (to - from) as f64)
            })
            .collect()
    }

    /// The zero in `r` at every sample: each stretch's mean, joined by
    /// straight lines, held before the first and after the last.
    pub fn zero(&self, r: &[f64]) -> Vec<f64> {
        let levels = self.levels(r);
        let Some(&(_, first)) = levels.first() else {
            return vec![0.0; r.len()];
        };
        let mut next = 0;
        self.t_s
            .iter()
            .map(|&t| {
                while next < levels.len() && levels[next].0 <= t {
                    next += 1;
                }
                // `next` counts the stretches centred at or before `t`.
                match next {
                    0 => first,
                    n if n >= levels.len() => levels[levels.len() - 1].1,
                    n => {
                        let ((t0, a), (t1, b)) = (levels[n - 1], levels[n]);
                        a + (b - a) * (t - t0) / (t1 - t0)
                    }
                }
            })
            .collect()
    }

    /// Removes the zero from `r`.
    pub fn remove(&self, r: &mut [f64]) {
        let zero = self.zero(r);
        for (x, z) in r.iter_mut().zip(zero) {
            *x -= z;
        }
    }

    /// What the zero is in `r` (in units of its noise): its range over
    /// the samples; whether it stands out of unit-variance noise (the
    /// stretches' means' sum of squares, each weighted by its samples,
    /// beyond the 99.9 % point of `χ²` with a degree of freedom per
    /// stretch after the first); the share of what `r` holds beyond the
    /// noise that it takes; and what is left once it is removed.
    pub fn measure(&self, r: &[f64]) -> DriftMeasure {
        let zero = self.zero(r);
        let (lo, hi) = zero
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        let range = if hi >= lo { hi - lo } else { 0.0 };
        // Only the wander: each stretch's level from the first's.
        let levels = self.levels(r);
        let first = levels.first().map_or(0.0, |&(_, level)| level);
        let explained: f64 = self
            .stretches
            .iter()
            .zip(&levels)
            .skip(1)
            .map(|(&(from, to, _), &(_, level))| (to - from) as f64 * (level - first).powi(2))
            .sum();
        let dof = levels.len().saturating_sub(1);
        let significant = dof > 0 && explained > chi2_999(dof);
        // What the zero takes out of every sample, against what the
        // model leaves beyond the noise.
        let taken: f64 = zero.iter().map(|z| z * z).sum();
        let left: f64 = r.iter().zip(&zero).map(|(x, z)| (x - z) * (x - z)).sum();
        DriftMeasure {
            ranges: vec![range],
            significant,
            share: share_of_excess(taken, r.iter()),
            left_per_residual: left / r.len().max(1) as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_zero_is_read_at_rests_and_joined_straight() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let z = ZeroDrift::new(&t, &[(0, 10), (40, 50), (90, 100)]);
        // A zero that wanders 0 -> 5 -> 2.5 noise levels, a drive of 7
        // between rests.
        let wander = |t: f64| {
            5.0 * if t < 4.5 {
                t / 4.5
            } else {
                1.0 - 0.5 * (t - 4.5) / 5.0
            }
        };
        let mut r: Vec<f64> = t
            .iter()
            .map(|&t| {
                wander(t)
                    + if (1.0..4.0).contains(&t) || (5.0..9.0).contains(&t) {
                        7.0
                    } else {
                        0.0
                    }
            })
            .collect();
        let m = z.measure(&r);
        let (range, significant) = (m.ranges[0], m.significant);
        // Each stretch's mean: 0.5 over the first, 4.76 over the second.
        assert!(significant && (range - 4.26).abs() < 0.1, "{range}");
        z.remove(&mut r);
        // The drive is left whole where the zero was joined straight.
        for (i, &x) in r.iter().enumerate() {
            let t = t[i];
            let want = if (1.0..4.0).contains(&t) || (5.0..9.0).contains(&t) {
                7.0
            } else {
                0.0
            };
            assert!((x - want).abs() < 0.75, "{t}: {x}");
        }
    }

    #[test]
    fn one_rest_holds_its_level_and_none_removes_nothing() {
        let t: Vec<f64> = (0..20).map(f64::from).collect();
        let mut r = vec![3.0; 20];
        ZeroDrift::new(&t, &[(0, 5)]).remove(&mut r);
        assert!(r.iter().all(|&x| x.abs() < 1e-12));
        let mut r = vec![3.0; 20];
        ZeroDrift::new(&t, &[]).remove(&mut r);
        assert!(r.iter().all(|&x| x == 3.0));
        assert!(!ZeroDrift::new(&t, &[(0, 5)]).measure(&r).significant);
    }
}
