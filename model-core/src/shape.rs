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
    /// let s = Strip::<f64, 3, 1, 18>::new(&Params::thesis_2006(), Fixture::Free, 1e-3).unwrap();
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
