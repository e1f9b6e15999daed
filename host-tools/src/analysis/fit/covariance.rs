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
//! `cov θ_b = V_b + G cov θ_c Gᵀ` and `cov(θ_b, θ_c) = G cov θ_c`.
//!
//! Each stage's own `V` is a cluster-robust sandwich, `(JᵀJ)⁻¹ B (JᵀJ)⁻¹`
//! with `B = Σ_c g_c g_cᵀ` and `g_c = J_cᵀ r_c` summed over a cluster `c`
//! of residuals (a window of [`CLUSTER_S`] of one recording, all its
//! channels), and never narrower than the white-noise `s² (JᵀJ)⁻¹`. A
//! misfit leaves residuals that run together for many samples; counted as
//! independent they made every term of a wrong model "significant" (#12):
//! the sandwich counts each window once. On a right model the residuals
//! are the sensors' white noise, and the two agree.

use nalgebra::DMatrix;

/// Length of a recording's window whose residuals form one cluster, s:
/// long against the sensors' noise correlation and a mode's ringing, short
/// enough that a session gives many more windows than knobs.
pub const CLUSTER_S: f64 = 1.0;

/// A stage's Jacobian at the end of the fit.
pub struct Block {
    /// Indices in `θ` of the stage's knobs, in the Jacobian's column order.
    pub knobs: Vec<usize>,
    /// `∂r/∂θ` of the stage's weighted residuals over its own knobs.
    pub jacobian: DMatrix<f64>,
    /// The stage's weighted residuals, in the Jacobian's row order.
    pub residuals: Vec<f64>,
    /// Each row's cluster: dense labels, rows of one window of one
    /// recording alike (see [`CLUSTER_S`]).
    pub clusters: Vec<usize>,
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
            let cc = cc.cov;
            let global: Vec<usize> = on.iter().map(|&a| c.knobs[a]).collect();
            put(&mut cov, &global, &global, &cc);
            active.extend(&global);
            held = Some((on, global, cc));
        }
    }
    if let Some((b, upstream)) = beam {
        if let (on, Some(bb)) = conditional(b) {
            let global: Vec<usize> = on.iter().map(|&a| b.knobs[a]).collect();
            let mut total = bb.cov.clone();
            if let Some((on_c, global_c, cc)) = &held {
                let jb = columns(&b.jacobian, &on);
                let jbc = columns(upstream, on_c);
                let g = -(bb.inverse_information) * (jb.transpose() * jbc);
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

/// `s² = RSS/(m − k)` of a stage's `m` residuals with `k` active knobs.
fn variance(rss: f64, m: usize, k: usize) -> f64 {
    rss / (m.saturating_sub(k).max(1)) as f64
}

/// The columns `on` of `jac`.
fn columns(jac: &DMatrix<f64>, on: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(jac.nrows(), on.len(), |i, a| jac[(i, on[a])])
}

/// A stage's covariance given its other inputs.
struct Conditional {
    /// `(JᵀJ)⁻¹`.
    inverse_information: DMatrix<f64>,
    /// The cluster-robust covariance, its variances at least `s² (JᵀJ)⁻¹`'s.
    cov: DMatrix<f64>,
}

/// Standard error, in a knob's own units of `θ` (its term's typical size,
/// or a factor `e` for a positive value), past which a stage's residuals
/// do not resolve the knob: moved over a thousand of its typical sizes,
/// the fit would change by less than the noise.
const UNRESOLVED_SE: f64 = 1e3;

/// Of a stage's knobs, those its residuals resolve, and their covariance
/// given the stage's other inputs, if it inverts. A knob held at its floor
/// of zero has a zero column, and one the residuals barely move (its
/// standard error past [`UNRESOLVED_SE`]) a column at the forward
/// difference's rounding: each is left out of the inverse, so that the
/// others keep their variance. Kept, four held modes' own damping ratios
/// at their floor, whose columns were one rounding pattern 1e-10 of the
/// largest, made the beam's information singular and every beam knob's
/// interval infinite (literature development seed 50065), so that no
/// beam term could show.
fn conditional(b: &Block) -> (Vec<usize>, Option<Conditional>) {
    let jac = &b.jacobian;
    let norms: Vec<f64> = (0..jac.ncols()).map(|j| jac.column(j).norm()).collect();
    let top = norms.iter().fold(0.0f64, |m, &x| m.max(x));
    let moved: Vec<usize> = (0..jac.ncols())
        .filter(|&j| norms[j] > 1e-12 * top)
        .collect();
    // One pass over the residuals for both degrees of freedom.
    let rss: f64 = b.residuals.iter().map(|r| r * r).sum();
    let s = variance(rss, jac.nrows(), moved.len()).sqrt();
    let on: Vec<usize> = moved
        .into_iter()
        .filter(|&j| s < UNRESOLVED_SE * norms[j])
        .collect();
    let sub = columns(jac, &on);
    let s2 = variance(rss, jac.nrows(), on.len());
    let Some(inv) = (sub.transpose() * &sub).try_inverse() else {
        return (on, None);
    };
    let cov = robust(&inv, &meat(&sub, &b.residuals, &b.clusters), s2);
    (
        on,
        Some(Conditional {
            inverse_information: inv,
            cov,
        }),
    )
}

/// `B = Σ_c g_c g_cᵀ`, `g_c = Σ_{rows of c} Jᵢᵀ rᵢ`.
fn meat(jac: &DMatrix<f64>, r: &[f64], clusters: &[usize]) -> DMatrix<f64> {
    let k = jac.ncols();
    let n = clusters.iter().max().map_or(0, |m| m + 1);
    let mut g = DMatrix::from_element(n, k, 0.0);
    for (i, (&c, &ri)) in clusters.iter().zip(r).enumerate() {
        for j in 0..k {
            g[(c, j)] += jac[(i, j)] * ri;
        }
    }
    g.transpose() * g
}

/// `A B A` with `A = (JᵀJ)⁻¹`, each knob's row and column scaled up where
/// its variance falls below the white-noise `s² A`'s (a scaling `D V D`
/// keeps it a covariance): few clusters can understate a spread, and noise
/// is never less than the sensors'.
fn robust(inv: &DMatrix<f64>, meat: &DMatrix<f64>, s2: f64) -> DMatrix<f64> {
    let mut v = inv * meat * inv;
    let k = v.nrows();
    let white: Vec<f64> = (0..k).map(|i| s2 * inv[(i, i)]).collect();
    // A knob no cluster moves (no variance) cannot be scaled up: its row
    // and column are cleared below and it keeps the white-noise variance.
    let scale: Vec<f64> = (0..k)
        .map(|i| {
            let vi = v[(i, i)];
            if vi > 0.0 {
                (white[i] / vi).sqrt().max(1.0)
            } else {
                0.0
            }
        })
        .collect();
    for i in 0..k {
        for j in 0..k {
            v[(i, j)] *= scale[i] * scale[j];
        }
    }
    for i in (0..k).filter(|&i| scale[i] == 0.0) {
        v.row_mut(i).fill(0.0);
        v.column_mut(i).fill(0.0);
        v[(i, i)] = white[i];
    }
    v
}

#[cfg(test)]
mod tests {
    use super::{conditional, Block};
    use nalgebra::DMatrix;

    /// A constant fitted to `r`: its variance from [`conditional`] with
    /// clusters of `window` residuals.
    fn variance_of_mean(r: &[f64], window: usize) -> f64 {
        let b = Block {
            knobs: vec![0],
            jacobian: DMatrix::from_element(r.len(), 1, 1.0),
            residuals: r.to_vec(),
            clusters: (0..r.len()).map(|i| i / window).collect(),
        };
        conditional(&b).1.unwrap().cov[(0, 0)]
    }

    #[test]
    fn residuals_that_run_together_widen_the_interval_white_ones_do_not() {
        let n = 4000;
        // White: ±1 from a xorshift generator.
        let mut x = 0x2545_f491_u32;
        let white: Vec<f64> = (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                if x & 1 == 0 {
                    1.0
                } else {
                    -1.0
                }
            })
            .collect();
        let white_var = variance_of_mean(&white, 100);
        let s2 = white.iter().map(|r| r * r).sum::<f64>() / (n - 1) as f64;
        assert!(
            (white_var / (s2 / n as f64) - 1.0).abs() < 0.5,
            "{white_var}"
        );
        // A misfit: the same ±1 in runs of 200 samples. The white-noise
        // formula says s²/n; the runs make it 200 times that.
        let runs: Vec<f64> = (0..n)
            .map(|i| if (i / 200) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let run_var = variance_of_mean(&runs, 100);
        assert!(run_var > 50.0 * s2 / n as f64, "{run_var}");
    }

    /// Two knobs the residuals resolve beside two whose columns are one
    /// rounding pattern, equal, far below the noise: the two keep their
    /// variance (left out, the pair would make the information singular);
    /// a column the noise does resolve stays in, and two equal ones of
    /// that size leave nothing to invert.
    #[test]
    fn unresolved_columns_are_left_out_and_the_others_keep_their_variance() {
        let n = 400;
        let r: Vec<f64> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let block = |tiny: f64| {
            let jacobian = DMatrix::from_fn(n, 4, |i, j| match j {
                0 => 1.0,
                1 => i as f64 / n as f64,
                _ => tiny * ((i % 7) as f64 - 3.0),
            });
            Block {
                knobs: vec![0, 1, 2, 3],
                jacobian,
                residuals: r.clone(),
                clusters: (0..n).collect(),
            }
        };
        let (on, cov) = conditional(&block(1e-9));
        assert_eq!(on, vec![0, 1]);
        let cov = cov.unwrap().cov;
        assert!(cov[(0, 0)].is_finite() && cov[(1, 1)] > 0.0, "{cov}");
        // Resolved (a standard error of a few units), the equal pair is
        // kept: the information then does not invert.
        let (on, cov) = conditional(&block(1.0));
        assert_eq!(on, vec![0, 1, 2, 3]);
        assert!(cov.is_none());
    }
}
