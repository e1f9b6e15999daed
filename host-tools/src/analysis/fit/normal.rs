//! Least squares from its normal equations `AᵀA x = Aᵀb` by a
//! pseudo-inverse: a few knobs, many rows, and knobs the rows may not tell
//! apart (or not see at all), which an inverse would send anywhere.

use nalgebra::{DMatrix, DVector};

/// Iterations the eigen-decomposition of a few knobs' normal matrix may
/// take.
const EIGEN_ITERATIONS: usize = 1000;

/// Eigenvalues below this fraction of the largest (of the unit-diagonal
/// matrix) are cut: directions the rows do not determine get no step.
const CUT: f64 = 1e-10;

/// The minimum-norm `x` (in the columns' own scale) of the normal
/// equations `ata x = atb`. A column the rows do not see (a zero diagonal)
/// gets 0; anything not finite gives all zeros (a model that overflowed
/// somewhere has nothing to say).
pub fn solve(ata: &DMatrix<f64>, atb: &DVector<f64>) -> Vec<f64> {
    let n = atb.len();
    if n == 0 {
        return Vec::new();
    }
    if ata.iter().chain(atb.iter()).any(|x| !x.is_finite()) {
        return vec![0.0; n];
    }
    // In the columns' own scale the matrix has a unit diagonal and entries
    // within ±1, so one relative cut-off serves every unit.
    let seen: Vec<bool> = (0..n).map(|a| ata[(a, a)] > 0.0).collect();
    let scale: Vec<f64> = (0..n)
        .map(|a| if seen[a] { ata[(a, a)].sqrt() } else { 1.0 })
        .collect();
    let scaled = DMatrix::from_fn(n, n, |a, b| {
        if seen[a] && seen[b] {
            ata[(a, b)] / (scale[a] * scale[b])
        } else {
            0.0
        }
    });
    let rhs = DVector::from_fn(n, |a, _| if seen[a] { atb[a] / scale[a] } else { 0.0 });
    if scaled.iter().chain(rhs.iter()).any(|x| !x.is_finite()) {
        return vec![0.0; n];
    }
    // The symmetric eigen-decomposition, not nalgebra's SVD: the SVD
    // panicked sorting a NaN singular value on a session of the CLI sweep.
    let Some(eig) = nalgebra::SymmetricEigen::try_new(scaled, f64::EPSILON, EIGEN_ITERATIONS)
    else {
        return vec![0.0; n];
    };
    let top = eig.eigenvalues.iter().fold(0.0_f64, |m, &l| m.max(l.abs()));
    let mut x = DVector::<f64>::zeros(n);
    for (k, &l) in eig.eigenvalues.iter().enumerate() {
        if l.is_finite() && l > CUT * top {
            let v = eig.eigenvectors.column(k);
            x += v * (v.dot(&rhs) / l);
        }
    }
    if x.iter().any(|v| !v.is_finite()) {
        return vec![0.0; n];
    }
    (0..n).map(|a| x[a] / scale[a]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_well_posed_system_and_leaves_an_unseen_column_at_zero() {
        // Rows of A: x0 + 2 x1, 3 x0 − x1, x0; column 2 never seen.
        let a = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 3.0, -1.0, 0.0, 1.0, 0.0, 0.0]);
        let x_true = DVector::from_vec(vec![0.5, -2.0, 7.0]);
        let b = &a * &x_true;
        let x = solve(&(a.transpose() * &a), &(a.transpose() * b));
        assert!(
            (x[0] - 0.5).abs() < 1e-12 && (x[1] + 2.0).abs() < 1e-12,
            "{x:?}"
        );
        assert_eq!(x[2], 0.0);
    }

    #[test]
    fn two_columns_alike_share_the_fit() {
        // The same column twice: any split fits; the minimum norm splits
        // it evenly.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]);
        let b = DVector::from_vec(vec![2.0, 4.0]);
        let x = solve(&(a.transpose() * &a), &(a.transpose() * b));
        assert!(
            (x[0] - 1.0).abs() < 1e-9 && (x[1] - 1.0).abs() < 1e-9,
            "{x:?}"
        );
    }

    #[test]
    fn anything_not_finite_gives_zeros() {
        let ata = DMatrix::from_row_slice(2, 2, &[1.0, f64::NAN, f64::NAN, 1.0]);
        let atb = DVector::from_vec(vec![1.0, 1.0]);
        assert_eq!(solve(&ata, &atb), vec![0.0, 0.0]);
    }
}
