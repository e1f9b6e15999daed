//! The deflected shape between nodes: the Hermite shape functions of
//! eq. 2.8, so that a point anywhere along the strip (a tracked dot) is read
//! with the same cubic the element matrices assume.

use crate::real::Real;
use crate::strip::Strip;

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// Deflection across the strip at arc length `s_m` from the clamp, m;
    /// `None` outside `0..=L` (or for NaN).
    ///
    /// ```
    /// use model_core::{Fixture, Params, Strip};
    /// let s = Strip::<f64, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3).unwrap();
    /// let mut x = s.rest();
    /// s.step(&mut x, &[1.0; 3]);
    /// let tip = s.tip_deflection_m(&x);
    /// assert!((s.deflection_at_m(&x, 0.05).unwrap() - tip).abs() < 1e-12 * tip.abs());
    /// assert_eq!(s.deflection_at_m(&x, 0.06), None);
    /// ```
    pub fn deflection_at_m(&self, x: &[T; S], s_m: f64) -> Option<T> {
        let length = self.params().length_m;
        if !(0.0..=length).contains(&s_m) {
            return None;
        }
        let elements = N * E;
        let l = length / elements as f64;
        // The element holding s; the tip itself belongs to the last one.
        let j = ((s_m / l) as usize).min(elements - 1);
        let xi = (s_m - j as f64 * l) / l;
        let (xi2, xi3) = (xi * xi, xi * xi * xi);
        let n1 = 1.0 - 3.0 * xi2 + 2.0 * xi3;
        let n2 = (xi - 2.0 * xi2 + xi3) * l;
        let n3 = 3.0 * xi2 - 2.0 * xi3;
        let n4 = (xi3 - xi2) * l;
        let w0 = self.node_deflection_m(x, j)?;
        let t0 = self.node_slope_rad(x, j)?;
        let w1 = self.node_deflection_m(x, j + 1)?;
        let t1 = self.node_slope_rad(x, j + 1)?;
        Some(
            w0 * T::from_f64(n1)
                + t0 * T::from_f64(n2)
                + w1 * T::from_f64(n3)
                + t1 * T::from_f64(n4),
        )
    }
}

/// Gauss–Legendre nodes and weights on `[0, 1]`, five points: exact for
/// polynomials of degree 9, far below rounding for `sin` and `cos` of the
/// quadratic slope of one element at the slopes an IPMC strip reaches.
const GAUSS5: [(f64, f64); 5] = [
    (0.046_910_077_030_668, 0.118_463_442_528_094_5),
    (0.230_765_344_947_158_5, 0.239_314_335_249_683_2),
    (0.5, 0.284_444_444_444_444_4),
    (0.769_234_655_052_841_5, 0.239_314_335_249_683_2),
    (0.953_089_922_969_332, 0.118_463_442_528_094_5),
];

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// Position of the point at arc length `s_m` from the clamp, relative to
    /// its rest position, m: `(along, across)`. `None` outside `0..=L`.
    ///
    /// Small-deflection kinematics (the seed's) give `(0, w(s))`. With the
    /// `large_deflection` extension the strip is an inextensible arc whose
    /// tangent angle is the slope field `θ(s) = w'(s)`:
    /// `along = ∫₀ˢ (cos θ − 1)`, `across = ∫₀ˢ sin θ`, so the tip moves
    /// toward the clamp and falls short of `w` across (seed 4.1.1: 13 mm
    /// across, about 2 mm along).
    ///
    /// ```
    /// use model_core::{Extensions, Fixture, Params, Strip};
    /// let ext = Extensions { large_deflection: true, ..Extensions::NONE };
    /// let s = Strip::<f64, 3, 1, 18>::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3).unwrap();
    /// let mut x = s.rest();
    /// for _ in 0..200 {
    ///     s.step(&mut x, &[2.5; 3]);
    /// }
    /// let (along, across) = s.position_at_m(&x, 0.05).unwrap();
    /// let w = s.tip_deflection_m(&x);
    /// assert!(along < 0.0 && across < w);
    /// ```
    pub fn position_at_m(&self, x: &[T; S], s_m: f64) -> Option<(T, T)> {
        let w = self.deflection_at_m(x, s_m)?;
        if !self.extensions().large_deflection {
            return Some((T::ZERO, w));
        }
        let elements = N * E;
        let l = self.params().length_m / elements as f64;
        let (mut along, mut across) = (0.0, 0.0);
        for j in 0..elements {
            let start = j as f64 * l;
            if start >= s_m {
                break;
            }
            // The part of element j below s, in its own coordinate ξ.
            let xi_end = ((s_m - start) / l).min(1.0);
            let (w0, t0) = (self.node_deflection_m(x, j)?, self.node_slope_rad(x, j)?);
            let (w1, t1) = (
                self.node_deflection_m(x, j + 1)?,
                self.node_slope_rad(x, j + 1)?,
            );
            let (w0, t0, w1, t1) = (w0.to_f64(), t0.to_f64(), w1.to_f64(), t1.to_f64());
            for (node, weight) in GAUSS5 {
                let xi = node * xi_end;
                // θ = dw/ds from the derivatives of the Hermite functions.
                let theta = ((-6.0 * xi + 6.0 * xi * xi) * (w0 - w1)) / l
                    + (1.0 - 4.0 * xi + 3.0 * xi * xi) * t0
                    + (3.0 * xi * xi - 2.0 * xi) * t1;
                let ds = weight * xi_end * l;
                along += (libm::cos(theta) - 1.0) * ds;
                across += libm::sin(theta) * ds;
            }
        }
        Some((T::from_f64(along), T::from_f64(across)))
    }
}
