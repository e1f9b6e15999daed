//! Drift: a bench term for the slow part of a mechanical channel that the
//! drive does not explain (docs/FORMAT.md, bench imperfections). A real
//! strip slowly curls by itself over minutes with no signal, by
//! millimetres, either way; a camera's, a laser's or a load cell's zero
//! wanders, and so does a current amplifier's. Left in the residuals, a
//! fit turns it into creep (a pole
//! near 0, an integrator) or into a softer beam, and every standard error
//! drowns in it.
//!
//! A drift is slow on the *session's* clock, not on a recording's: the
//! strip curls on between recordings. Every channel is taken relative to
//! its own opening rest (a camera's rest shape, which a brush can leave
//! off, a load cell's tare, a shunt amplifier's zero: `data.rs`), so a
//! drift is what moved since that rest. Over the recordings fitted
//! together, each camera and load-cell channel gets one polynomial in
//! session time
//! they share, at least a line, which can bend once per
//! [`DRIFT_SCALE_S`] (degree `1 + ⌊span/60 s⌋` over a span of the
//! session, at most [`DRIFT_MAX_DEGREE`]), each recording's part of it
//! taken from its mean over that recording's rest. Its shortest feature
//! is about a minute, far slower than the charging (`R1·C`, tens of
//! milliseconds) and the relaxation the session can show, whose pole the
//! fit keeps at or above `1/DRIFT_SCALE_S` (`space.rs`): what is slower
//! than a minute is drift. An offset free in each recording, in place
//! of its rest's, let a fit trade the offset against the slow part of
//! the response: a fit of the virtual bench's strip then held a 30 s step
//! 8.2 % off at its end, against 4.3 % with the rest as the reference
//! (`host-tools/tests/virtual_bench.rs`, `a_held_step_from_a_fit_...`).
//! A polynomial in each recording's own time would let a short
//! recording's slope take any slow response the drive gives (a
//! back-relaxation over a 3 s hold was absorbed whole): shared, a slope
//! must hold over every recording. Where the session does not give every
//! recording's `t_session_start_s`, or a recording is fitted alone, it
//! has its own polynomial, of degree `⌊T/60 s⌋` over its own `T` seconds
//! (an offset alone below a minute).
//!
//! Drift is fitted jointly with the model by variable projection: the
//! residuals, and so every Jacobian taken of them, are those left after
//! the least-squares drift is removed (Golub and Pereyra). A current's
//! zero wanders too (each recording's own offset alone left the currents
//! at 1.75 times their noise floor on the rig's lab bench), but is read
//! where no current flows, at rest, and joined straight between rests,
//! never fitted over a drive (`zero_drift.rs`): over holds of minutes a
//! polynomial that bends once a minute took the leak, the steady current
//! under a held voltage that the electrochemistry shows in (the lab
//! protocol's `sinh` leak went unnamed, docs/rig.md).
//!
//! ```
//! use finrs::analysis::fit::DriftBasis;
//! // Two recordings of 20 s at 10 rows/s, half a minute apart on the
//! // session's clock, each opening with 1 s at rest: a shared line, each
//! // recording's part taken from its rest's mean, removed exactly.
//! let a: Vec<f64> = (0..200).map(|i| i as f64 * 0.1).collect();
//! let b: Vec<f64> = a.iter().map(|t| t + 30.0).collect();
//! let basis = DriftBasis::new(&[&a, &b], &[10, 10], true);
//! assert_eq!(basis.degree(), 1);
//! let mut ra: Vec<f64> = a.iter().map(|t| -0.01 * (t - 0.45)).collect();
//! let mut rb: Vec<f64> = a.iter().map(|t| -0.01 * (t - 0.45)).collect();
//! basis.remove(&mut [&mut ra, &mut rb]);
//! assert!(ra.iter().chain(&rb).all(|x| x.abs() < 1e-9));
//! ```

/// The time over which a drift's polynomial may bend once, s.
pub const DRIFT_SCALE_S: f64 = 60.0;

/// The highest degree of a drift's polynomial (a span of 24 minutes or
/// more).
pub const DRIFT_MAX_DEGREE: usize = 24;

/// An orthonormal basis, over the samples of one channel in several
/// recordings ("members"), of the polynomials of degree 1 to
/// [`DriftBasis::degree`] in time, each taken relative to its mean over
/// each member's opening rest: the data are taken relative to their own
/// rest (a camera's rest shape, a load cell's tare, a shunt's zero), so a
/// drift is what moved since. A member whose rest holds no sample has a
/// free offset instead. Its columns `q_j` satisfy `q_iᵀ q_j = δ_ij` on
/// those samples.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftBasis {
    /// Samples per member.
    lens: Vec<usize>,
    /// Members with a free offset (no sample in their rest).
    free: Vec<bool>,
    /// The polynomials' degree.
    degree: usize,
    /// The polynomial columns one after the other, each over every
    /// member's samples in turn, orthogonal to the free offsets (kept
    /// implicit: a member's mean).
    q: Vec<f64>,
}

impl DriftBasis {
    /// The basis over members sampled at `times` (each increasing, on
    /// one clock), whose first `rests[m]` samples are member `m`'s opening
    /// rest: with `shared`, one polynomial over all of them, of degree
    /// `1 + ⌊span/60 s⌋`; without, the members must be one, and the degree
    /// is `⌊span/60 s⌋`.
    ///
    /// # Panics
    /// If not `shared` and there is not exactly one member, or if `rests`
    /// is not one count per member.
    pub fn new(times: &[&[f64]], rests: &[usize], shared: bool) -> DriftBasis {
        assert!(shared || times.len() == 1, "one member unless shared");
        assert_eq!(times.len(), rests.len(), "one rest per member");
        let lens: Vec<usize> = times.iter().map(|t| t.len()).collect();
        let total: usize = lens.iter().sum();
        let free: Vec<bool> = rests.iter().map(|&r| r == 0).collect();
        let (lo, hi) = times
            .iter()
            .flat_map(|t| t.iter())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        let span_s = if hi > lo { hi - lo } else { 0.0 };
        // Never as many columns as samples: some residual must be left.
        let room = total.saturating_sub(lens.len()) / 2;
        let degree = ((span_s / DRIFT_SCALE_S).floor() as usize + usize::from(shared))
            .min(DRIFT_MAX_DEGREE)
            .min(room);
        let x: Vec<f64> = times
            .iter()
            .flat_map(|t| t.iter())
            .map(|&t| {
                if span_s > 0.0 {
                    2.0 * (t - lo) / span_s - 1.0
                } else {
                    0.0
                }
            })
            .collect();
        let mut basis = DriftBasis {
            lens,
            free,
            degree: 0,
            q: Vec::with_capacity(degree * total),
        };
        // Legendre polynomials on [-1, 1] (well conditioned on evenly
        // spread samples), each member's taken from its rest's mean, then
        // made orthogonal to the free offsets and to each other over the
        // samples themselves (twice: gaps and the pauses between
        // recordings leave them unevenly spread).
        let (mut p_prev, mut p) = (vec![0.0; total], vec![1.0; total]);
        for n in 0..degree {
            // (n + 1) P_{n+1} = (2n + 1) x P_n − n P_{n−1}.
            let next: Vec<f64> = x
                .iter()
                .zip(&p)
                .zip(&p_prev)
                .map(|((&x, &pn), &pm)| {
                    ((2 * n + 1) as f64 * x * pn - n as f64 * pm) / (n + 1) as f64
                })
                .collect();
            p_prev = std::mem::replace(&mut p, next);
            let mut col = p.clone();
            let mut at = 0;
            for (&len, &rest) in basis.lens.iter().zip(rests) {
                let part = &mut col[at..at + len];
                let rest = rest.min(len);
                if rest > 0 {
                    let mean = part[..rest].iter().sum::<f64>() / rest as f64;
                    part.iter_mut().for_each(|v| *v -= mean);
                }
                at += len;
            }
            for _ in 0..2 {
                basis.remove_columns(&mut col);
            }
            let norm = col.iter().map(|c| c * c).sum::<f64>().sqrt();
            if norm <= 1e-9 * (total as f64).sqrt() {
                // The samples cannot tell this degree from the lower ones.
                break;
            }
            basis.q.extend(col.iter().map(|c| c / norm));
            basis.degree += 1;
        }
        basis
    }

    /// The shared polynomial's degree (0: no drift but free offsets).
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The degrees of freedom the drift takes: the free offsets and the
    /// polynomial's columns.
    pub fn columns(&self) -> usize {
        self.free.iter().filter(|&&f| f).count() + self.degree
    }

    /// The samples of all members, end to end.
    fn total(&self) -> usize {
        self.lens.iter().sum()
    }

    /// Whether member `m` has a free offset (no sample in its rest).
    pub fn is_free(&self, m: usize) -> bool {
        self.free[m]
    }

    /// Samples per member.
    pub(super) fn lens(&self) -> &[usize] {
        &self.lens
    }

    /// Where member `m`'s samples start among every member's.
    fn start(&self, m: usize) -> usize {
        self.lens[..m].iter().sum()
    }

    /// The polynomial columns, each over every member's samples.
    fn polynomial_columns(&self) -> std::slice::ChunksExact<'_, f64> {
        self.q.chunks_exact(self.total().max(1))
    }

    /// `Qᵀ x` for `x` nonzero on member `m`'s samples only (given there):
    /// its coordinates on the polynomial columns.
    pub(super) fn coordinates(&self, m: usize, x: &[f64]) -> Vec<f64> {
        let at = self.start(m);
        self.polynomial_columns()
            .map(|q| q[at..at + x.len()].iter().zip(x).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// `Q c` on member `m`'s samples.
    pub(super) fn member_part(&self, m: usize, coeffs: &[f64]) -> Vec<f64> {
        let (at, len) = (self.start(m), self.lens[m]);
        let mut out = vec![0.0; len];
        for (q, &c) in self.polynomial_columns().zip(coeffs) {
            out.iter_mut()
                .zip(&q[at..at + len])
                .for_each(|(v, a)| *v += c * a);
        }
        out
    }

    /// `r ← r + Q c` over the members' `parts`.
    pub(super) fn add_columns(&self, parts: &mut [Vec<f64>], coeffs: &[f64]) {
        for (q, &c) in self.polynomial_columns().zip(coeffs) {
            let mut at = 0;
            for p in parts.iter_mut() {
                let len = p.len();
                p.iter_mut()
                    .zip(&q[at..at + len])
                    .for_each(|(v, a)| *v += c * a);
                at += len;
            }
        }
    }

    /// Removes the free offsets and the polynomial columns (those built so
    /// far, while building) from `x`, one value per sample of every member
    /// end to end.
    pub fn remove_columns(&self, x: &mut [f64]) {
        let mut at = 0;
        for (&len, &free) in self.lens.iter().zip(&self.free) {
            if free {
                let part = &mut x[at..at + len];
                let mean = part.iter().sum::<f64>() / len.max(1) as f64;
                part.iter_mut().for_each(|v| *v -= mean);
            }
            at += len;
        }
        let total = self.total();
        for qj in self.q.chunks_exact(total.max(1)) {
            let dot: f64 = qj.iter().zip(x.iter()).map(|(a, b)| a * b).sum();
            for (v, a) in x.iter_mut().zip(qj) {
                *v -= dot * a;
            }
        }
    }

    /// Removes from the members' residuals `parts` (one value per sample,
    /// member by member) their least-squares drift: `r ← r − Q Qᵀ r`.
    /// Returns the polynomial's share of `‖r‖²` (free offsets not
    /// counted), what tells a drift from noise.
    ///
    /// # Panics
    /// If `parts` does not hold one value per sample of each member.
    pub fn remove(&self, parts: &mut [&mut Vec<f64>]) -> f64 {
        assert_eq!(parts.len(), self.lens.len(), "one part per member");
        for (p, &len) in parts.iter().zip(&self.lens) {
            assert_eq!(p.len(), len, "one residual per sample");
        }
        for (p, &free) in parts.iter_mut().zip(&self.free) {
            if free {
                let mean = p.iter().sum::<f64>() / p.len().max(1) as f64;
                p.iter_mut().for_each(|v| *v -= mean);
            }
        }
        let total = self.total();
        let mut explained = 0.0;
        for qj in self.q.chunks_exact(total.max(1)) {
            let mut dot = 0.0;
            let mut at = 0;
            for p in parts.iter() {
                dot += qj[at..at + p.len()]
                    .iter()
                    .zip(p.iter())
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
                at += p.len();
            }
            explained += dot * dot;
            let mut at = 0;
            for p in parts.iter_mut() {
                let len = p.len();
                for (v, a) in p.iter_mut().zip(&qj[at..at + len]) {
                    *v -= dot * a;
                }
                at += len;
            }
        }
        explained
    }

    /// The drift on the members' residuals `r = (ŷ − y)/σ` before its
    /// removal, in `σ` units of `y − ŷ`: per member, the range of the
    /// fitted drift over its samples; whether the polynomial stands out of
    /// the noise (the sum of squares it takes beyond the 99.9 % point of
    /// `χ²` with as many degrees of freedom as it has columns: what white
    /// noise alone would give it); its share of what the residuals hold
    /// beyond the noise; and what is left once it is removed.
    pub fn measure(&self, parts: &[&[f64]]) -> DriftMeasure {
        let mut left: Vec<Vec<f64>> = parts.iter().map(|p| p.to_vec()).collect();
        let mut refs: Vec<&mut Vec<f64>> = left.iter_mut().collect();
        let explained = self.remove(&mut refs);
        let share = share_of_excess(explained, parts.iter().flat_map(|p| p.iter()));
        let (left_sum, n) = left
            .iter()
            .flatten()
            .fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
        // A free offset is constant over its member: no part of a range.
        let ranges = parts
            .iter()
            .zip(&left)
            .map(|(p, l)| {
                let (lo, hi) = p
                    .iter()
                    .zip(l)
                    .map(|(a, b)| a - b)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                        (lo.min(x), hi.max(x))
                    });
                if hi >= lo {
                    hi - lo
                } else {
                    0.0
                }
            })
            .collect();
        DriftMeasure {
            ranges,
            significant: self.degree > 0 && explained > chi2_999(self.degree),
            share,
            left_per_residual: left_sum / n.max(1) as f64,
        }
    }
}

/// What [`DriftBasis::measure`] finds of a drift.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftMeasure {
    /// Per member, the range of the fitted drift over its samples, in
    /// units of the noise.
    pub ranges: Vec<f64>,
    /// Whether the polynomial stands out of the noise.
    pub significant: bool,
    /// The share of what the residuals hold beyond the noise that it
    /// takes ([`share_of_excess`]).
    pub share: f64,
    /// The residuals' sum of squares per residual once it is removed
    /// (1: the noise alone is left).
    pub left_per_residual: f64,
}

/// The share of what residuals `r` (in units of their noise) hold beyond
/// the noise (`Σr² − n`) that a drift taking `explained` of their sum of
/// squares accounts for, at most 1: near 1 where the drift is what the
/// model leaves, small where a model's misfit leaves slow structure too.
pub fn share_of_excess<'a>(explained: f64, r: impl Iterator<Item = &'a f64>) -> f64 {
    let (sum, n) = r.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
    let excess = sum - n as f64;
    if excess <= 0.0 {
        return 0.0;
    }
    (explained / excess).min(1.0)
}

/// The 99.9 % point of `χ²` with `dof` degrees of freedom.
pub(super) fn chi2_999(dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(dof as f64).map_or(f64::INFINITY, |d| d.inverse_cdf(0.999))
}

/// The drift fitted on one channel of one recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Drift {
    /// The recording's file name.
    pub recording: String,
    /// The channel.
    pub channel: crate::recording::Channel,
    /// The drift's range over the recording (highest minus lowest), in
    /// the channel's SI unit.
    pub peak_to_peak: f64,
    /// The same in units of the channel's noise.
    pub peak_to_peak_in_noise: f64,
    /// The time it spans, s.
    pub span_s: f64,
    /// Whether the channel's drift, over the recordings fitted together,
    /// stands out of the noise ([`DriftBasis::measure`]).
    pub significant: bool,
    /// The share of what the model leaves beyond the noise on the channel,
    /// over the recordings fitted together, that the drift takes
    /// ([`share_of_excess`]).
    pub share: f64,
    /// What the model and the drift leave on the channel, over the
    /// recordings fitted together: the sum of squares per residual in
    /// units of its noise (1: the noise alone).
    pub left_per_residual: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(n: usize, dt_s: f64, from_s: f64) -> Vec<f64> {
        (0..n).map(|i| from_s + i as f64 * dt_s).collect()
    }

    #[test]
    fn the_degree_follows_the_span() {
        let one = |n, dt| DriftBasis::new(&[&times(n, dt, 0.0)], &[1], false).degree();
        assert_eq!(one(5000, 0.01), 0);
        assert_eq!(one(6001, 0.01), 1);
        assert_eq!(one(30_001, 0.01), 5);
        assert_eq!(one(200_000, 0.01), 24);
        // Too few samples: some residual is left.
        assert_eq!(one(5, 100.0), 2);
        assert_eq!(DriftBasis::new(&[&[]], &[0], false).columns(), 1);
        // Two short recordings four minutes apart share a quintic; a
        // minute apart, a quadratic.
        let (a, b) = (times(800, 0.01, 0.0), times(800, 0.01, 240.0));
        assert_eq!(DriftBasis::new(&[&a, &b], &[100, 100], true).degree(), 5);
        let b = times(800, 0.01, 60.0);
        assert_eq!(DriftBasis::new(&[&a, &b], &[100, 100], true).degree(), 2);
    }

    #[test]
    fn columns_are_orthonormal_and_free_offsets_orthogonal_to_them() {
        // Five minutes at 100 rows/s with a minute out of range, and a
        // second recording after a pause, whose rest the camera missed.
        let a: Vec<f64> = times(30_000, 0.01, 0.0)
            .into_iter()
            .filter(|&t| !(100.0..160.0).contains(&t))
            .collect();
        let b = times(9000, 0.01, 330.0);
        let basis = DriftBasis::new(&[&a, &b], &[100, 0], true);
        assert_eq!(basis.degree(), 7);
        assert_eq!(basis.columns(), 8);
        let total = basis.total();
        let cols: Vec<&[f64]> = basis.q.chunks_exact(total).collect();
        for (i, ci) in cols.iter().enumerate() {
            for (j, cj) in cols.iter().enumerate() {
                let dot: f64 = ci.iter().zip(*cj).map(|(a, c)| a * c).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-10, "{i} {j}: {dot}");
            }
            let on_b: f64 = ci[a.len()..].iter().sum();
            assert!(on_b.abs() < 1e-10, "{i}: {on_b}");
        }
    }

    #[test]
    fn a_drift_since_each_rest_is_removed_and_measured_and_a_fast_step_kept() {
        let (a, b) = (times(12_001, 0.01, 0.0), times(6000, 0.01, 150.0));
        let rest = 100;
        let basis = DriftBasis::new(&[&a, &b], &[rest, rest], true);
        assert_eq!(basis.degree(), 4);
        let drift = |t: f64| 2e-3 - 3e-5 * t + 4e-7 * t * t - 1e-9 * t * t * t;
        // The residuals of a model that misses the drift since each
        // recording's rest, in units of a 0.05 mm noise (r = −drift/σ).
        let sigma = 5e-5;
        let since_rest = |ts: &[f64]| -> Vec<f64> {
            let mean = ts[..rest].iter().map(|&t| drift(t)).sum::<f64>() / rest as f64;
            ts.iter().map(|&t| -(drift(t) - mean) / sigma).collect()
        };
        let (ra, rb) = (since_rest(&a), since_rest(&b));
        let m = basis.measure(&[&ra, &rb]);
        assert!(m.share > 0.999 && m.left_per_residual < 1e-12, "{m:?}");
        let (ranges, significant) = (m.ranges, m.significant);
        assert!(significant);
        let range = |ts: &[f64]| {
            let d: Vec<f64> = ts.iter().map(|&t| drift(t)).collect();
            d.iter().cloned().fold(f64::MIN, f64::max) - d.iter().cloned().fold(f64::MAX, f64::min)
        };
        assert!((ranges[0] * sigma - range(&a)).abs() < 1e-9, "{ranges:?}");
        assert!((ranges[1] * sigma - range(&b)).abs() < 1e-9, "{ranges:?}");
        let (mut ra, mut rb) = (ra, rb);
        basis.remove(&mut [&mut ra, &mut rb]);
        assert!(ra.iter().chain(&rb).all(|x| x.abs() < 1e-9));
        // A jump at the rest's end is no drift: its edge is left (a
        // polynomial that bends once a minute can follow an offset held
        // for minutes, not the jump into it).
        let mut shifted: Vec<f64> = (0..a.len())
            .map(|i| if i < rest { 0.0 } else { 1.0 })
            .collect();
        basis.remove(&mut [&mut shifted, &mut vec![0.0; b.len()]]);
        let edge = shifted[rest..2 * rest].iter().sum::<f64>() / rest as f64
            - shifted[..rest].iter().sum::<f64>() / rest as f64;
        assert!(edge > 0.9, "{edge}");
        // A step held from 10 s to 70 s keeps its edges: the polynomial
        // cannot bend fast enough to follow them (its plateau, a minute
        // long, it can: what a drift of minutes hides).
        let mut step: Vec<f64> = a
            .iter()
            .map(|&t| if (10.0..70.0).contains(&t) { 1.0 } else { 0.0 })
            .collect();
        basis.remove(&mut [&mut step, &mut vec![0.0; b.len()]]);
        let mean = |from_s: f64, to_s: f64| {
            let (i, j) = ((from_s * 100.0) as usize, (to_s * 100.0) as usize);
            step[i..j].iter().sum::<f64>() / (j - i) as f64
        };
        let rise = mean(10.0, 11.0) - mean(9.0, 10.0);
        let fall = mean(69.0, 70.0) - mean(70.0, 71.0);
        assert!(rise > 0.9 && fall > 0.9, "{rise} {fall}");
    }

    #[test]
    fn noise_alone_is_no_drift() {
        let a = times(6000, 0.01, 0.0);
        let b = times(6000, 0.01, 100.0);
        let basis = DriftBasis::new(&[&a, &b], &[100, 100], true);
        let mut x = 12345u64;
        let mut unit = || {
            // Sums of twelve uniforms: near-Gaussian, unit variance.
            (0..12)
                .map(|_| {
                    x = x
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (x >> 11) as f64 / (1u64 << 53) as f64
                })
                .sum::<f64>()
                - 6.0
        };
        let na: Vec<f64> = (0..6000).map(|_| unit()).collect();
        let nb: Vec<f64> = (0..6000).map(|_| unit()).collect();
        assert!(!basis.measure(&[&na, &nb]).significant);
        // A drift beside a larger misfit that is no drift: a small share.
        let misfit: Vec<f64> = (0..6000)
            .map(|i| 20.0 * ((i as f64) * 0.7).sin() + 0.5 * i as f64 / 6000.0)
            .collect();
        let zeros = vec![0.0; 6000];
        let m = basis.measure(&[&misfit, &zeros]);
        assert!(m.share < 0.01 && m.left_per_residual > 100.0, "{m:?}");
    }
}
