//! The deflected shape between nodes: the Hermite shape functions of
//! eq. 2.8, so that a point anywhere along the strip (a tracked dot) is read
//! with the same cubic the element matrices assume.
//!
//! [`Shape`] reads every node once for a state, so a camera's several dots
//! cost one pass over the state (and, with `large_deflection`, one
//! integration of the arc) instead of one each.

use crate::real::Real;
use crate::strip::Strip;

/// The strip's shape at one state: each node's deflection and slope, and
/// with `large_deflection` the arc integrated from the clamp to each node.
///
/// Node arrays are `S` long (the state's length, always more than the
/// `N E + 1` nodes) because a const generic cannot be `N E + 1` on stable
/// Rust; entries past the tip stay zero.
///
/// ```
/// use model_core::{Extensions, Fixture, Params, Strip};
/// let ext = Extensions { large_deflection: true, ..Extensions::NONE };
/// let s = Strip::<f64, 3, 1, 18>::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3).unwrap();
/// let mut x = s.rest();
/// for _ in 0..200 {
///     s.step(&mut x, &[2.5; 3]);
/// }
/// let shape = s.shape(&x);
/// // The same numbers as reading each point alone, bit for bit.
/// for s_m in [0.01, 0.025, 0.05] {
///     assert_eq!(shape.position_at_m(s_m), s.position_at_m(&x, s_m));
/// }
/// assert_eq!(shape.position_at_m(0.06), None);
/// ```
#[derive(Clone, Debug)]
pub struct Shape<T, const S: usize> {
    /// Node deflections `w`, m, the clamp's first.
    w: [T; S],
    /// Node slopes `θ = w'`, rad.
    theta: [T; S],
    /// `∫₀ˢ (cos θ − 1)` from the clamp to each node, m (large deflection).
    along: [f64; S],
    /// `∫₀ˢ sin θ` from the clamp to each node, m (large deflection).
    across: [f64; S],
    /// Elements along the strip, `N E`.
    elements: usize,
    /// Strip length `L`, m.
    length_m: f64,
    /// Whether points move on the arc (`large_deflection`) or straight across.
    large: bool,
}

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// The shape at state `x`, for reading many points along the strip.
    pub fn shape(&self, x: &[T; S]) -> Shape<T, S> {
        let elements = N * E;
        let mut shape = Shape {
            w: [T::ZERO; S],
            theta: [T::ZERO; S],
            along: [0.0; S],
            across: [0.0; S],
            elements,
            length_m: self.params().length_m,
            large: self.extensions().large_deflection,
        };
        // Node 0 is the clamp: zero deflection and slope.
        for node in 1..=elements {
            shape.w[node] = self.node_deflection_m(x, node).unwrap_or(T::ZERO);
            shape.theta[node] = self.node_slope_rad(x, node).unwrap_or(T::ZERO);
        }
        if shape.large {
            // One running sum over the whole strip, as a single point's
            // reading accumulates it: node j's entry is that sum's value
            // after element j − 1, so a point's reading continues from it.
            let (mut along, mut across) = (0.0, 0.0);
            for j in 0..elements {
                shape.arc(j, 1.0, &mut along, &mut across);
                shape.along[j + 1] = along;
                shape.across[j + 1] = across;
            }
        }
        shape
    }

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
        // Two nodes of the state, not the whole shape: the board reads its
        // dots this way each sample.
        let (j, xi, l) = element_of(s_m, self.params().length_m, N * E)?;
        let w0 = self.node_deflection_m(x, j)?;
        let t0 = self.node_slope_rad(x, j)?;
        let w1 = self.node_deflection_m(x, j + 1)?;
        let t1 = self.node_slope_rad(x, j + 1)?;
        Some(hermite(w0, t0, w1, t1, xi, l))
    }

    /// Position of the point at arc length `s_m` from the clamp, relative to
    /// its rest position, m: `(along, across)`. `None` outside `0..=L`.
    ///
    /// Small-deflection kinematics (the seed's) give `(0, w(s))`. With the
    /// `large_deflection` extension the strip is an inextensible arc whose
    /// tangent angle is the slope field `θ(s) = w'(s)`:
    /// `along = ∫₀ˢ (cos θ − 1)`, `across = ∫₀ˢ sin θ`, so the tip moves
    /// toward the clamp and falls short of `w` across (seed 4.1.1: 13 mm
    /// across, about 2 mm along). Reading several points of one state,
    /// [`Strip::shape`] does it in one pass.
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
        self.shape(x).position_at_m(s_m)
    }
}

impl<T: Real, const S: usize> Shape<T, S> {
    /// Deflection across the strip at arc length `s_m` from the clamp, m;
    /// `None` outside `0..=L` (or for NaN).
    pub fn deflection_at_m(&self, s_m: f64) -> Option<T> {
        let (j, xi, l) = element_of(s_m, self.length_m, self.elements)?;
        Some(hermite(
            self.w[j],
            self.theta[j],
            self.w[j + 1],
            self.theta[j + 1],
            xi,
            l,
        ))
    }

    /// Position of the point at arc length `s_m`, relative to its rest
    /// position, m: `(along, across)`, as [`Strip::position_at_m`] reads it.
    /// `None` outside `0..=L`.
    pub fn position_at_m(&self, s_m: f64) -> Option<(T, T)> {
        let w = self.deflection_at_m(s_m)?;
        if !self.large {
            return Some((T::ZERO, w));
        }
        let l = self.length_m / self.elements as f64;
        let (mut along, mut across) = (0.0, 0.0);
        // While every element so far was whole, the sum is a node's stored
        // one; the first part-element continues it term by term, so the
        // reading is the one-point integration's to the last bit.
        let mut on_node = true;
        for j in 0..self.elements {
            let start = j as f64 * l;
            if start >= s_m {
                break;
            }
            // The part of element j below s, in its own coordinate ξ.
            let xi_end = ((s_m - start) / l).min(1.0);
            if on_node && xi_end == 1.0 {
                along = self.along[j + 1];
                across = self.across[j + 1];
            } else {
                on_node = false;
                self.arc(j, xi_end, &mut along, &mut across);
            }
        }
        Some((T::from_f64(along), T::from_f64(across)))
    }

    /// Adds element `j`'s arc from its start to `ξ = xi_end` to the running
    /// sums: five Gauss points of `cos θ − 1` and `sin θ`.
    fn arc(&self, j: usize, xi_end: f64, along: &mut f64, across: &mut f64) {
        let l = self.length_m / self.elements as f64;
        let (w0, t0) = (self.w[j].to_f64(), self.theta[j].to_f64());
        let (w1, t1) = (self.w[j + 1].to_f64(), self.theta[j + 1].to_f64());
        for (node, weight) in GAUSS5 {
            let xi = node * xi_end;
            // θ = dw/ds from the derivatives of the Hermite functions.
            let theta = ((-6.0 * xi + 6.0 * xi * xi) * (w0 - w1)) / l
                + (1.0 - 4.0 * xi + 3.0 * xi * xi) * t0
                + (3.0 * xi * xi - 2.0 * xi) * t1;
            let ds = weight * xi_end * l;
            let (sin, cos_m1) = sin_cos_m1(theta);
            *along += cos_m1 * ds;
            *across += sin * ds;
        }
    }
}

/// `sin θ` and `cos θ − 1`. Up to `π/4` (a slope of 45°, beyond any IPMC
/// strip's) their Taylor series, whose first terms left out are below
/// 10⁻¹⁷ of the sums there: no branches and no argument reduction, where
/// libm's `sincos` was a sixth of a large-deflection fit (perf, rig seed
/// 10099, 2026-11-27), and `cos θ − 1` without `cos θ`'s cancellation
/// against 1. Beyond, libm's.
fn sin_cos_m1(theta: f64) -> (f64, f64) {
    if theta.abs() > core::f64::consts::FRAC_PI_4 {
        let (sin, cos) = libm::sincos(theta);
        return (sin, cos - 1.0);
    }
    let t2 = theta * theta;
    // Horner in θ², the highest power first: θ¹⁷/17! and θ¹⁸/18! last.
    let sin = SIN_TAYLOR.iter().rev().fold(0.0, |acc, &c| acc * t2 + c) * theta;
    let cos_m1 = COS_M1_TAYLOR.iter().rev().fold(0.0, |acc, &c| acc * t2 + c) * t2;
    (sin, cos_m1)
}

/// `(−1)ᵏ/(2k + 1)!`, k = 0..=8: `sin θ = θ Σ cₖ θ²ᵏ`.
const SIN_TAYLOR: [f64; 9] = taylor(1);

/// `(−1)ᵏ⁺¹/(2k + 2)!`, k = 0..=8: `cos θ − 1 = θ² Σ cₖ θ²ᵏ`.
const COS_M1_TAYLOR: [f64; 9] = taylor(2);

/// `±1/n!` for `n = first, first + 2, …`, alternating from `+` for `sin`
/// (`first` = 1) and from `−` for `cos − 1` (`first` = 2). Every factorial
/// up to 18! is exact in `f64`, so each coefficient is one rounding.
const fn taylor(first: u32) -> [f64; 9] {
    let mut out = [0.0; 9];
    let mut k = 0;
    while k < 9 {
        let n = first + 2 * k as u32;
        let mut factorial = 1.0;
        let mut i = 2;
        while i <= n {
            factorial *= i as f64;
            i += 1;
        }
        let sign = if (k % 2 == 0) == (first == 1) {
            1.0
        } else {
            -1.0
        };
        out[k] = sign / factorial;
        k += 1;
    }
    out
}

/// The element holding arc length `s_m` on a strip of `length_m` in
/// `elements` elements, `s`'s coordinate `ξ` in it and the element's
/// length; the tip belongs to the last one. `None` outside `0..=L`.
fn element_of(s_m: f64, length_m: f64, elements: usize) -> Option<(usize, f64, f64)> {
    if !(0.0..=length_m).contains(&s_m) {
        return None;
    }
    let l = length_m / elements as f64;
    let j = ((s_m / l) as usize).min(elements - 1);
    Some((j, (s_m - j as f64 * l) / l, l))
}

/// The cubic of eq. 2.8 between nodes `(w0, t0)` and `(w1, t1)` of an
/// element of length `l`, at `ξ`.
fn hermite<T: Real>(w0: T, t0: T, w1: T, t1: T, xi: f64, l: f64) -> T {
    let (xi2, xi3) = (xi * xi, xi * xi * xi);
    let n1 = 1.0 - 3.0 * xi2 + 2.0 * xi3;
    let n2 = (xi - 2.0 * xi2 + xi3) * l;
    let n3 = 3.0 * xi2 - 2.0 * xi3;
    let n4 = (xi3 - xi2) * l;
    w0 * T::from_f64(n1) + t0 * T::from_f64(n2) + w1 * T::from_f64(n3) + t1 * T::from_f64(n4)
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

#[cfg(test)]
mod tests {
    use super::sin_cos_m1;

    /// `θ`'s sine and `cos θ − 1` within a few units in the last place of
    /// references free of cancellation (libm's `sin`, and `−2 sin²(θ/2)`),
    /// on both sides of the series' limit `π/4` and far past it.
    #[test]
    fn the_arcs_sine_and_cosine_are_libms_to_rounding() {
        let ulp = |x: f64| f64::EPSILON * x.abs().max(f64::MIN_POSITIVE);
        let check = |theta: f64| {
            let (sin, cos_m1) = sin_cos_m1(theta);
            let half = libm::sin(theta / 2.0);
            let (sin_ref, cos_m1_ref) = (libm::sin(theta), -2.0 * half * half);
            assert!(
                (sin - sin_ref).abs() <= 2.0 * ulp(sin_ref),
                "sin {theta:e}: {sin:e} against {sin_ref:e}"
            );
            // Past π/4 libm's cos − 1 carries cos's rounding: one unit of 1.
            let tol = if theta.abs() <= core::f64::consts::FRAC_PI_4 {
                4.0 * ulp(cos_m1_ref)
            } else {
                2.0 * f64::EPSILON
            };
            assert!(
                (cos_m1 - cos_m1_ref).abs() <= tol,
                "cos - 1 {theta:e}: {cos_m1:e} against {cos_m1_ref:e}"
            );
        };
        // A 64-bit LCG (Knuth's MMIX constants): reproducible, no crate.
        let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..200_000 {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = 2.0 * ((seed >> 11) as f64 / (1u64 << 53) as f64) - 1.0;
            check(u * core::f64::consts::FRAC_PI_4);
            check(u * 0.05);
            check(u * 1e-6);
            check(u * 3.0);
        }
        let edge = core::f64::consts::FRAC_PI_4;
        for theta in [0.0, -0.0, edge, -edge, edge.next_up(), 1e-300] {
            check(theta);
        }
        assert_eq!(sin_cos_m1(0.0), (0.0, 0.0));
        let (s, c) = sin_cos_m1(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
    }
}
