//! Exact zero-order-hold discretisation.
//!
//! For `ẋ = A x + B v` with `v` held constant over a step `h`,
//!
//! ```text
//! x[k+1] = Φ x[k] + Γ v[k],   Φ = e^{A h},   Γ = ∫₀ʰ e^{A s} ds · B
//! ```
//!
//! which is the top-right block of the exponential of the augmented matrix
//! `[[A, B], [0, 0]] h`. We never form the augmented matrix: `Γ = φ₁(A h) h B`
//! with `φ₁(X) = Σ Xᵏ/(k+1)!`, and both `Φ` and `Γ` double together
//! (`e^{2X} = e^X e^X`, `Γ(2h) = (I + Φ(h)) Γ(h)`), so scaling and squaring
//! works on `S × S` and `S × M` arrays only.
//!
//! Error: the truncated Taylor series of degree [`TAYLOR_DEGREE`] on
//! `‖X‖₁ ≤ ½` leaves a relative remainder below `½¹⁵/15! ≈ 2·10⁻¹⁷`, under
//! `f64` rounding; what remains is rounding, which the squarings amplify by
//! about their count. The test `zoh_matches_independent_expm` bounds the
//! total against nalgebra's Padé exponential.

use crate::matrix::{mul, norm1, Mat};

/// Degree of the Taylor polynomial for `φ₁` after scaling.
pub const TAYLOR_DEGREE: usize = 14;

/// Largest `‖A h‖₁` left after scaling, before the series is summed.
const SCALED_NORM: f64 = 0.5;

/// Computes `Φ = e^{A h}` and `Γ = ∫₀ʰ e^{A s} ds B` in place.
///
/// `a` is overwritten (it becomes the scaled `A h`), so the caller's buffer
/// is reused instead of another `S × S` array on the stack.
pub fn discretise<const S: usize, const M: usize>(
    a: &mut Mat<S, S>,
    b: &Mat<S, M>,
    h: f64,
    phi: &mut Mat<S, S>,
    gamma: &mut Mat<S, M>,
) {
    // Scale: X = A h / 2^s with ‖X‖₁ ≤ ½.
    let norm = norm1(a) * h;
    let mut squarings = 0u32;
    let mut scale = 1.0;
    while norm * scale > SCALED_NORM && squarings < 64 {
        scale *= 0.5;
        squarings += 1;
    }
    let hs = h * scale;
    for row in a.iter_mut() {
        for x in row.iter_mut() {
            *x *= hs;
        }
    }

    // φ₁(X) by Horner: P ← I/(k+1)! + X P, from the highest degree down.
    // `phi` holds P; one temporary holds the product.
    let mut tmp = [[0.0; S]; S];
    let mut coeff = [0.0; TAYLOR_DEGREE + 1];
    let mut f = 1.0;
    for (k, c) in coeff.iter_mut().enumerate() {
        f *= (k + 1) as f64;
        *c = 1.0 / f;
    }
    *phi = [[0.0; S]; S];
    for (i, row) in phi.iter_mut().enumerate() {
        row[i] = coeff[TAYLOR_DEGREE];
    }
    for k in (0..TAYLOR_DEGREE).rev() {
        mul(a, phi, &mut tmp);
        for (i, row) in tmp.iter_mut().enumerate() {
            row[i] += coeff[k];
        }
        core::mem::swap(phi, &mut tmp);
    }

    // Γ(h_s) = φ₁(X) h_s B, then e^X = I + X φ₁(X).
    mul(phi, b, gamma);
    for row in gamma.iter_mut() {
        for g in row.iter_mut() {
            *g *= hs;
        }
    }
    mul(a, phi, &mut tmp);
    core::mem::swap(phi, &mut tmp);
    for (i, row) in phi.iter_mut().enumerate() {
        row[i] += 1.0;
    }

    // Undo the scaling: Γ ← (I + Φ) Γ, then Φ ← Φ².
    let mut g_tmp = [[0.0; M]; S];
    for _ in 0..squarings {
        mul(phi, gamma, &mut g_tmp);
        for (g, t) in gamma.iter_mut().zip(g_tmp.iter()) {
            for (gi, ti) in g.iter_mut().zip(t.iter()) {
                *gi += *ti;
            }
        }
        mul(phi, phi, &mut tmp);
        core::mem::swap(phi, &mut tmp);
    }
}
