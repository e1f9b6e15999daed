//! The carry-over of recordings that open while the strip still moves:
//! the relaxation the recording before left, `e^{−p t}` from each such
//! member's first row under the model's pole, an amplitude per member,
//! fitted beside the drift (`drift_set.rs`).
//!
//! A carry-over column lives on its own member's samples only, while the
//! drift's columns span every member of the group (a 20-minute session
//! holds over a hundred thousand samples per channel). Made orthogonal to
//! the drift, the column would span them all too, and doing so inside
//! every residual evaluation of a fit was a third of a diagnosis's time.
//! So the columns are kept as they are, with their coordinates on the
//! drift's columns, `c̃ = c − Q a` with `a = Qᵀ c` (only the member's own
//! samples enter `a`), and made orthonormal among themselves through the
//! Cholesky factor of their small Gram matrix `c̃ᵢᵀ c̃ⱼ = cᵢᵀ cⱼ − aᵢᵀ aⱼ`:
//! the same columns as a Gram–Schmidt in member order over every sample,
//! at the cost of the members' own samples and one pass of the drift's
//! columns.

use super::drift::DriftBasis;

/// Pivots below this share of a column's own squared norm are dropped:
/// what is left of the column beyond the drift is too small to tell from
/// rounding in `cᵀc − aᵀa`.
const RELATIVE_PIVOT: f64 = 1e-12;

/// The carry-over columns of one group under one pole.
#[derive(Debug)]
pub(super) struct CarryColumns {
    /// Per kept column: its member, its values over that member's samples
    /// (`c`), its coordinates on the drift's polynomial columns (`a`).
    columns: Vec<(usize, Vec<f64>, Vec<f64>)>,
    /// The lower Cholesky factor `L` of the kept columns' Gram matrix,
    /// row by row: the orthonormal columns are `C̃ L⁻ᵀ`.
    l: Vec<Vec<f64>>,
}

impl CarryColumns {
    /// The columns of the members that carry one: `carry[m]` holds member
    /// `m`'s samples' times from its recording's first row, s, and how
    /// many lie in its opening rest (its column is taken from its rest's
    /// mean, or from its own mean where `basis` gives it a free offset).
    pub(super) fn new(
        basis: &DriftBasis,
        carry: &[Option<(Vec<f64>, usize)>],
        p_per_s: f64,
    ) -> CarryColumns {
        let total = basis.lens().iter().sum::<usize>();
        let mut out = CarryColumns {
            columns: Vec::new(),
            l: Vec::new(),
        };
        for (m, carry) in carry.iter().enumerate() {
            let Some((tau_s, rest)) = carry else {
                continue;
            };
            let mut c: Vec<f64> = tau_s.iter().map(|&t| (-p_per_s * t).exp()).collect();
            let from = if basis.is_free(m) {
                c.len()
            } else {
                (*rest).min(c.len())
            };
            if from > 0 {
                let mean = c[..from].iter().sum::<f64>() / from as f64;
                c.iter_mut().for_each(|v| *v -= mean);
            }
            // A free offset is the member's mean, taken out above; the
            // other members' offsets do not reach this one's samples.
            let a = basis.coordinates(m, &c);
            let own: f64 = c.iter().map(|v| v * v).sum();
            // Row of L: the Gram entries with the kept columns before,
            // forward-substituted (columns of other members share no
            // sample: their product is that of their coordinates alone).
            let mut row: Vec<f64> = out.columns.iter().map(|(_, _, ak)| -dot(ak, &a)).collect();
            for k in 0..row.len() {
                let s: f64 = (0..k).map(|j| out.l[k][j] * row[j]).sum();
                row[k] = (row[k] - s) / out.l[k][k];
            }
            let pivot = own - dot(&a, &a) - dot(&row, &row);
            if pivot > 1e-18 * total as f64 && pivot > RELATIVE_PIVOT * own {
                row.push(pivot.sqrt());
                out.l.push(row);
                out.columns.push((m, c, a));
            }
        }
        out
    }

    /// Whether no column is kept.
    pub(super) fn is_empty(&self) -> bool {
        self.columns.is_empty()
    }

    /// The coefficients of `parts` (one residual per sample of each
    /// member, already orthogonal to the drift) on the orthonormal
    /// columns: `L⁻¹ C̃ᵀ r`, where `C̃ᵀ r = Cᵀ r` as `r` is orthogonal to
    /// the drift.
    fn on_orthonormal(&self, parts: &[Vec<f64>]) -> Vec<f64> {
        let mut z: Vec<f64> = self
            .columns
            .iter()
            .map(|(m, c, _)| dot(c, &parts[*m]))
            .collect();
        for k in 0..z.len() {
            let s: f64 = (0..k).map(|j| self.l[k][j] * z[j]).sum();
            z[k] = (z[k] - s) / self.l[k][k];
        }
        z
    }

    /// `L⁻ᵀ z`: coefficients on the kept columns `c̃` of `Σ zₖ qₖ`.
    fn on_columns(&self, z: &[f64]) -> Vec<f64> {
        let mut beta = z.to_vec();
        for k in (0..beta.len()).rev() {
            let s: f64 = (k + 1..beta.len()).map(|j| self.l[j][k] * beta[j]).sum();
            beta[k] = (beta[k] - s) / self.l[k][k];
        }
        beta
    }

    /// Removes the columns' least-squares part from `parts` (already
    /// orthogonal to the drift): `r ← r − Σ βₖ cₖ + Q Σ βₖ aₖ`.
    /// Returns, per kept column, `(member, the sum of squares its
    /// orthonormal column took, the range of what it took over its
    /// member)`, in member order.
    pub(super) fn remove(
        &self,
        basis: &DriftBasis,
        parts: &mut [Vec<f64>],
    ) -> Vec<(usize, f64, f64)> {
        let z = self.on_orthonormal(parts);
        let beta = self.on_columns(&z);
        let mut back = vec![0.0; basis.degree()];
        for ((m, c, a), &b) in self.columns.iter().zip(&beta) {
            parts[*m].iter_mut().zip(c).for_each(|(v, c)| *v -= b * c);
            back.iter_mut().zip(a).for_each(|(s, a)| *s += b * a);
        }
        basis.add_columns(parts, &back);
        self.columns
            .iter()
            .enumerate()
            .map(|(k, (m, _, _))| (*m, z[k] * z[k], self.range(basis, k) * z[k].abs()))
            .collect()
    }

    /// The range of orthonormal column `k` over its own member's samples.
    fn range(&self, basis: &DriftBasis, k: usize) -> f64 {
        // q_k = Σ_{i ≤ k} W_ik c̃_i with W = L⁻ᵀ; on member m_k only c_k
        // of the raw columns is nonzero.
        let unit: Vec<f64> = (0..self.columns.len())
            .map(|i| if i == k { 1.0 } else { 0.0 })
            .collect();
        let w = self.on_columns(&unit);
        let (m, c, _) = &self.columns[k];
        let mut coeffs = vec![0.0; basis.degree()];
        for ((_, _, a), &wi) in self.columns.iter().zip(&w) {
            coeffs.iter_mut().zip(a).for_each(|(s, a)| *s -= wi * a);
        }
        let mut own = basis.member_part(*m, &coeffs);
        own.iter_mut().zip(c).for_each(|(v, c)| *v += w[k] * c);
        let (lo, hi) = own
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
        if hi >= lo {
            hi - lo
        } else {
            0.0
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The drift's polynomial columns over every sample.
    fn whole_polynomials(basis: &DriftBasis) -> Vec<Vec<f64>> {
        let members = basis.lens().len();
        (0..basis.degree())
            .map(|j| {
                let mut e = vec![0.0; basis.degree()];
                e[j] = 1.0;
                (0..members)
                    .flat_map(|m| basis.member_part(m, &e))
                    .collect()
            })
            .collect()
    }

    /// Member `m`'s raw carry-over column over every sample (its own
    /// start at `at`), taken from its rest's mean or its own.
    fn whole_carry(
        basis: &DriftBasis,
        m: usize,
        at: usize,
        carry: &(Vec<f64>, usize),
        p: f64,
    ) -> Vec<f64> {
        let (tau, rest) = carry;
        let (len, total) = (basis.lens()[m], basis.lens().iter().sum::<usize>());
        let mut c = vec![0.0; total];
        for (v, t) in c[at..at + len].iter_mut().zip(tau) {
            *v = (-p * t).exp();
        }
        let from = if basis.is_free(m) { len } else { *rest };
        let mean = c[at..at + from].iter().sum::<f64>() / from as f64;
        c[at..at + len].iter_mut().for_each(|v| *v -= mean);
        c
    }

    /// The projection onto the drift and the carry-over columns by a dense
    /// least-squares solve over every sample: what `remove` must match.
    fn dense(
        basis: &DriftBasis,
        carry: &[Option<(Vec<f64>, usize)>],
        p: f64,
        r: &[f64],
    ) -> Vec<f64> {
        use nalgebra::{DMatrix, DVector};
        let lens = basis.lens().to_vec();
        let total: usize = lens.iter().sum();
        let mut cols = whole_polynomials(basis);
        let mut at = 0;
        for (m, (cm, &len)) in carry.iter().zip(&lens).enumerate() {
            if basis.is_free(m) {
                let mut col = vec![0.0; total];
                col[at..at + len].iter_mut().for_each(|v| *v = 1.0);
                cols.push(col);
            }
            if let Some(cm) = cm {
                cols.push(whole_carry(basis, m, at, cm, p));
            }
            at += len;
        }
        let x = DMatrix::from_fn(total, cols.len(), |i, j| cols[j][i]);
        let y = DVector::from_column_slice(r);
        let beta = x.clone().svd(true, true).solve(&y, 1e-12).expect("solved");
        (y - x * beta).iter().copied().collect()
    }

    /// The carry-over columns made orthogonal to the drift and to each
    /// other over every sample, and what each takes of `r` (after the
    /// drift): `(member, sum of squares, range over its member)`.
    fn gram_schmidt(
        basis: &DriftBasis,
        carry: &[Option<(Vec<f64>, usize)>],
        p: f64,
        r: &[f64],
    ) -> Vec<(usize, f64, f64)> {
        let lens = basis.lens().to_vec();
        let poly = whole_polynomials(basis);
        let project_out = |x: &mut Vec<f64>, q: &[f64]| {
            let d = dot(q, x);
            x.iter_mut().zip(q).for_each(|(v, a)| *v -= d * a);
        };
        let mut r = r.to_vec();
        let mut at = 0;
        for (m, &len) in lens.iter().enumerate() {
            if basis.is_free(m) {
                let mean = r[at..at + len].iter().sum::<f64>() / len as f64;
                r[at..at + len].iter_mut().for_each(|v| *v -= mean);
            }
            at += len;
        }
        poly.iter().for_each(|q| project_out(&mut r, q));
        let mut done: Vec<Vec<f64>> = Vec::new();
        let mut out = Vec::new();
        let mut at = 0;
        for (m, (cm, &len)) in carry.iter().zip(&lens).enumerate() {
            if let Some(cm) = cm {
                let mut c = whole_carry(basis, m, at, cm, p);
                for _ in 0..2 {
                    poly.iter()
                        .chain(&done)
                        .for_each(|q| project_out(&mut c, q));
                }
                let norm = dot(&c, &c).sqrt();
                c.iter_mut().for_each(|v| *v /= norm);
                let z = dot(&c, &r);
                let own = &c[at..at + len];
                let hi = own.iter().copied().fold(f64::MIN, f64::max);
                let lo = own.iter().copied().fold(f64::MAX, f64::min);
                out.push((m, z * z, (hi - lo) * z.abs()));
                done.push(c);
            }
            at += len;
        }
        out
    }

    #[test]
    fn the_sparse_columns_remove_what_a_dense_solve_removes() {
        // Three recordings on one clock, the second's rest missed by the
        // camera (a free offset); the first and third open moving.
        let times =
            |n: usize, from: f64| -> Vec<f64> { (0..n).map(|i| from + 0.05 * i as f64).collect() };
        let (a, b, c) = (times(1500, 0.0), times(900, 100.0), times(1300, 170.0));
        let basis = DriftBasis::new(&[&a, &b, &c], &[20, 0, 20], true);
        assert!(basis.degree() >= 3);
        let own = |t: &[f64]| -> Vec<f64> { t.iter().map(|x| x - t[0]).collect() };
        let carry = vec![Some((own(&a), 20)), None, Some((own(&c), 20))];
        let p = 0.2;
        let mut x = 99u64;
        let mut noise = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        // A slow drift, two carry-overs and noise.
        let mut parts: Vec<Vec<f64>> = [&a, &b, &c]
            .iter()
            .enumerate()
            .map(|(m, t)| {
                t.iter()
                    .map(|&s| {
                        let k = if m == 1 { 0.0 } else { 3.0 - m as f64 };
                        1e-3 * s + k * (-p * (s - t[0])).exp() + noise()
                    })
                    .collect()
            })
            .collect();
        let whole: Vec<f64> = parts.iter().flatten().copied().collect();
        let want = dense(&basis, &carry, p, &whole);
        let mut refs: Vec<&mut Vec<f64>> = parts.iter_mut().collect();
        basis.remove(&mut refs);
        let columns = CarryColumns::new(&basis, &carry, p);
        let taken = columns.remove(&basis, &mut parts);
        let got: Vec<f64> = parts.iter().flatten().copied().collect();
        let worst = got
            .iter()
            .zip(&want)
            .map(|(g, w)| (g - w).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{worst}");
        // Each carried member's orthonormal column took what a Gram-Schmidt
        // over every sample, in member order, gives it.
        let want = gram_schmidt(&basis, &carry, p, &whole);
        assert_eq!(taken.len(), want.len());
        for (got, want) in taken.iter().zip(&want) {
            assert_eq!(got.0, want.0);
            assert!((got.1 - want.1).abs() < 1e-8 * want.1, "{got:?} {want:?}");
            assert!((got.2 - want.2).abs() < 1e-8 * want.2, "{got:?} {want:?}");
        }
        // A column the drift holds whole (no decay at p = 0) is dropped.
        assert!(CarryColumns::new(&basis, &carry, 0.0).is_empty());
    }
}
