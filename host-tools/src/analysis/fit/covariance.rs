//! The covariance of the fitted `θ` after the two stages (see
//! [`stage`](super::stage)): the circuit's from the currents, the beam's
//! from its own sensors, and what the circuit's uncertainty does to the
//! beam's values through the charge that drives it.
//!
//! The beam's values are fitted with the circuit held at its estimate, so
//! their conditional covariance alone would claim that the circuit is
//! known exactly: the moment is `C a`, and a `C` off by its error moves `a`
//! the other way. The two-step estimator's covariance (Murphy and Topel,
//! 1985) adds it: with `G = ∂θ̂_b/∂θ_c = −(J_bᵀJ_b)⁻¹ J_bᵀ J_bc`,
//! `cov θ_b = s_b² (J_bᵀJ_b)⁻¹ + G cov θ_c Gᵀ` and `cov(θ_b, θ_c) = G cov θ_c`.

use nalgebra::DMatrix;

/// A stage's Jacobian at the end of the fit.
pub struct Block {
    /// Indices in `θ` of the stage's knobs, in the Jacobian's column order.
    pub knobs: Vec<usize>,
    /// `∂r/∂θ` of the stage's weighted residuals over its own knobs.
    pub jacobian: DMatrix<f64>,
    /// The stage's residual sum of squares.
    pub rss: f64,
}

/// The covariance of all `k` knobs and the knobs it bounds: the circuit's
/// block, the beam's block with its `upstream` Jacobian (the beam's
/// residuals over the circuit's knobs, in the circuit block's order), and
/// their cross terms. A knob whose column is zero (held at a floor) or
/// whose stage's information does not invert is left out, with an
/// infinite variance.
pub fn two_stage(
    k: usize,
    circuit: Option<&Block>,
    beam: Option<(&Block, &DMatrix<f64>)>,
) -> (Vec<usize>, DMatrix<f64>) {
    let mut cov = DMatrix::from_element(k, k, 0.0);
    let mut active = Vec::new();
    // The circuit's active knobs: (local columns, global indices, covariance).
    let mut held = None;
    if let Some(c) = circuit {
        if let (on, Some(cc)) = conditional(c) {
            let global: Vec<usize> = on.iter().map(|&a| c.knobs[a]).collect();
            put(&mut cov, &global, &global, &cc);
            active.extend(&global);
            held = Some((on, global, cc));
        }
    }
    if let Some((b, upstream)) = beam {
        if let (on, Some(bb)) = conditional(b) {
            let global: Vec<usize> = on.iter().map(|&a| b.knobs[a]).collect();
            let mut total = bb.clone();
            if let Some((on_c, global_c, cc)) = &held {
                let jb = columns(&b.jacobian, &on);
                let jbc = columns(upstream, on_c);
                // (J_bᵀJ_b)⁻¹ is the conditional covariance over s_b².
                let g = -(&bb / variance(b, on.len())) * (jb.transpose() * jbc);
                let cross = &g * cc;
                total += &cross * g.transpose();
                put(&mut cov, &global, global_c, &cross);
                put(&mut cov, global_c, &global, &cross.transpose());
            }
            put(&mut cov, &global, &global, &total);
            active.extend(&global);
        }
    }
    for j in 0..k {
        if !active.contains(&j) {
            cov[(j, j)] = f64::INFINITY;
        }
    }
    (active, cov)
}

/// Writes `m` into `cov` at rows `rows` and columns `cols`.
fn put(cov: &mut DMatrix<f64>, rows: &[usize], cols: &[usize], m: &DMatrix<f64>) {
    for (a, &ja) in rows.iter().enumerate() {
        for (b, &jb) in cols.iter().enumerate() {
            cov[(ja, jb)] = m[(a, b)];
        }
    }
}

/// `s² = RSS/(m − k)` of a stage with `k` active knobs.
fn variance(b: &Block, k: usize) -> f64 {
    b.rss / (b.jacobian.nrows().saturating_sub(k).max(1)) as f64
}

/// The columns `on` of `jac`.
fn columns(jac: &DMatrix<f64>, on: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(jac.nrows(), on.len(), |i, a| jac[(i, on[a])])
}

/// Of a stage's knobs, those its residuals move (a knob held at its floor
/// of zero has a zero column: it is left out of the inverse, so the others
/// keep their variance), and their covariance `s² (JᵀJ)⁻¹` given the
/// stage's other inputs, if it inverts.
fn conditional(b: &Block) -> (Vec<usize>, Option<DMatrix<f64>>) {
    let jac = &b.jacobian;
    let norms: Vec<f64> = (0..jac.ncols()).map(|j| jac.column(j).norm()).collect();
    let top = norms.iter().fold(0.0f64, |m, &x| m.max(x));
    let on: Vec<usize> = (0..jac.ncols())
        .filter(|&j| norms[j] > 1e-12 * top)
        .collect();
    let sub = columns(jac, &on);
    let s2 = variance(b, on.len());
    let cov = (sub.transpose() * &sub).try_inverse().map(|c| c * s2);
    (on, cov)
}
