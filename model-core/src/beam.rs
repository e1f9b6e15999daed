//! The finite-element Euler–Bernoulli cantilever (seed eq. 2.5–2.19, 2.26).
//!
//! Hermite-cubic elements with the consistent mass matrix (2.14) and the
//! stiffness matrix (2.17); a segment's moment `u` enters each of its
//! elements as the nodal load `[0, -1, 0, 1] u` (2.19). The clamp's node is
//! eliminated. Node `j` (1-based from the clamp) owns the degrees of freedom
//! `2(j-1)` (deflection `w`, m) and `2(j-1)+1` (slope scaled by the element
//! length, `ℓ θ`, m). The scaling puts both kinds of freedom in metres, which
//! keeps the mass and stiffness matrices balanced for the eigen solver.
//!
//! The modes are found in `f64`: Cholesky of the mass matrix, then cyclic
//! Jacobi on the symmetric `L⁻¹ K L⁻ᵀ`, which keeps small eigenvalues
//! accurate next to the large ones of this stiff beam.

// Index loops mirror the textbook formulas (Cholesky, Jacobi) one to one.
#![allow(clippy::needless_range_loop)]

use crate::matrix::{Mat, Square};
use crate::params::{ParamError, Params};

/// Element mass matrix of eq. 2.14 in units of `ρA ℓ / 420`, slopes scaled by `ℓ`.
const ELEMENT_MASS: [[f64; 4]; 4] = [
    [156.0, 22.0, 54.0, -13.0],
    [22.0, 4.0, 13.0, -3.0],
    [54.0, 13.0, 156.0, -22.0],
    [-13.0, -3.0, -22.0, 4.0],
];

/// Element stiffness matrix of eq. 2.17 in units of `EI / ℓ³`, slopes scaled by `ℓ`.
const ELEMENT_STIFFNESS: [[f64; 4]; 4] = [
    [12.0, 6.0, -12.0, 6.0],
    [6.0, 4.0, -6.0, 2.0],
    [-12.0, -6.0, 12.0, -6.0],
    [6.0, 2.0, -6.0, 4.0],
];

/// Global mass `M`, stiffness `K` and per-segment load `F` (unit moments),
/// assembled in the first `2NE` columns of `2NE`-row arrays.
pub(crate) struct Assembly<const N: usize, const E: usize, const S: usize> {
    pub m: Square<N, E>,
    pub k: Square<N, E>,
    pub f: Mat<S, N>,
    /// Element length `ℓ`, m.
    pub element_m: f64,
}

/// Assembles eq. 2.26 for `N` segments of `E` elements each.
pub(crate) fn assemble<const N: usize, const E: usize, const S: usize>(
    p: &Params,
) -> Assembly<N, E, S> {
    let l = p.length_m / (N * E) as f64;
    let m_scale = p.mass_per_length_kg_per_m * l / 420.0;
    let k_scale = p.ei_nm2 / (l * l * l);
    let load = [0.0, -1.0 / l, 0.0, 1.0 / l];
    let mut a = Assembly {
        m: Square::zeros(),
        k: Square::zeros(),
        f: [[0.0; N]; S],
        element_m: l,
    };
    for element in 0..N * E {
        let segment = element / E;
        // Local freedom r of this element is global 2(element-1)+r, or the
        // clamp (eliminated) for the first element's left node.
        let global = |r: usize| (2 * element + r).checked_sub(2);
        for r in 0..4 {
            let Some(gr) = global(r) else { continue };
            a.f[gr][segment] += load[r];
            for c in 0..4 {
                let Some(gc) = global(c) else { continue };
                a.m[(gr, gc)] += m_scale * ELEMENT_MASS[r][c];
                a.k[(gr, gc)] += k_scale * ELEMENT_STIFFNESS[r][c];
            }
        }
    }
    a
}

/// Mass-normalised modes of the freedoms listed in `active`.
///
/// On return, column `k < active.len()` of `psi` is mode `k` in the global
/// numbering (rows not in `active` are zero), `ψₖᵀ M ψₖ = 1`, and
/// `omega2[k]` is its squared angular frequency, ascending. `m`, `k` and
/// `psi` are `2NE × 2NE`, as are the three work arrays, which are the whole
/// stack this takes beyond its small vectors. Not inlined, so that they are
/// freed on return.
#[inline(never)]
pub(crate) fn modes<const N: usize, const E: usize, const S: usize>(
    m: &Square<N, E>,
    k: &Square<N, E>,
    active: &[usize],
    psi: &mut Square<N, E>,
    omega2: &mut [f64; S],
) -> Result<(), ParamError> {
    let n = active.len();
    let mut l = Square::<N, E>::zeros();
    let mut y = Square::<N, E>::zeros();
    let mut a = Square::<N, E>::zeros();
    // Cholesky of the reduced mass matrix, in place: M_r = L Lᵀ.
    for i in 0..n {
        for j in 0..=i {
            let mut sum = m[(active[i], active[j])];
            for q in 0..j {
                sum -= l[(i, q)] * l[(j, q)];
            }
            if i == j {
                if sum.is_nan() || sum <= 0.0 {
                    return Err(ParamError::SingularMass);
                }
                l[(i, i)] = libm::sqrt(sum);
            } else {
                l[(i, j)] = sum / l[(j, j)];
            }
        }
    }
    // C = L⁻¹ K_r L⁻ᵀ: forward substitution on the columns of K_r, then on
    // the columns of the transpose (K_r is symmetric, so that is L⁻¹ K_r L⁻ᵀ).
    for c in 0..n {
        for i in 0..n {
            let mut sum = k[(active[i], active[c])];
            for q in 0..i {
                sum -= l[(i, q)] * y[(q, c)];
            }
            y[(i, c)] = sum / l[(i, i)];
        }
    }
    for c in 0..n {
        for i in 0..n {
            let mut sum = y[(c, i)];
            for q in 0..i {
                sum -= l[(i, q)] * a[(q, c)];
            }
            a[(i, c)] = sum / l[(i, i)];
        }
    }
    for i in 0..n {
        for j in 0..i {
            let s = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = s;
            a[(j, i)] = s;
        }
    }
    // Eigenvectors of C accumulate in `y` (reused).
    y.clear();
    for i in 0..n {
        y[(i, i)] = 1.0;
    }
    jacobi(&mut a, &mut y, n);

    // Ascending order, by selection (n is small; the order is for reports).
    let mut order = [0usize; S];
    for (i, o) in order.iter_mut().enumerate().take(n) {
        *o = i;
    }
    for i in 0..n {
        let mut best = i;
        for j in i + 1..n {
            if a[(order[j], order[j])] < a[(order[best], order[best])] {
                best = j;
            }
        }
        order.swap(i, best);
    }
    // ψ = L⁻ᵀ v by back substitution, scattered to global rows.
    psi.clear();
    for (col, &src) in order.iter().enumerate().take(n) {
        omega2[col] = a[(src, src)];
        let mut x = [0.0; S];
        for i in (0..n).rev() {
            let mut sum = y[(i, src)];
            for q in i + 1..n {
                sum -= l[(q, i)] * x[q];
            }
            x[i] = sum / l[(i, i)];
        }
        for i in 0..n {
            psi[(active[i], col)] = x[i];
        }
    }
    for w in omega2.iter_mut().skip(n) {
        *w = 0.0;
    }
    Ok(())
}

/// Cyclic Jacobi on the symmetric leading `n × n` block of `a`; rotations
/// accumulate into `v`. Ends when the off-diagonal part is negligible
/// against the diagonal, or after a bounded number of sweeps.
fn jacobi<const N: usize, const E: usize>(a: &mut Square<N, E>, v: &mut Square<N, E>, n: usize) {
    for _sweep in 0..64 {
        let mut off = 0.0;
        let mut diag = 0.0;
        for i in 0..n {
            diag += a[(i, i)] * a[(i, i)];
            for j in i + 1..n {
                off += a[(i, j)] * a[(i, j)];
            }
        }
        if off <= 1e-32 * diag {
            return;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[(p, q)];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = libm::copysign(1.0, theta)
                    / (libm::fabs(theta) + libm::sqrt(theta * theta + 1.0));
                let c = 1.0 / libm::sqrt(t * t + 1.0);
                let s = t * c;
                a[(p, p)] -= t * apq;
                a[(q, q)] += t * apq;
                a[(p, q)] = 0.0;
                a[(q, p)] = 0.0;
                for r in 0..n {
                    if r != p && r != q {
                        let arp = a[(r, p)];
                        let arq = a[(r, q)];
                        a[(r, p)] = c * arp - s * arq;
                        a[(p, r)] = a[(r, p)];
                        a[(r, q)] = s * arp + c * arq;
                        a[(q, r)] = a[(r, q)];
                    }
                    let vrp = v[(r, p)];
                    let vrq = v[(r, q)];
                    v[(r, p)] = c * vrp - s * vrq;
                    v[(r, q)] = s * vrp + c * vrq;
                }
            }
        }
    }
}
