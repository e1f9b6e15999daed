//! The dehydration's law: the moment gain of a strip that has dried for
//! `t` seconds of its session, `(1 + c r t)^(−1/c)`: `e^{−r t}` at
//! curvature `c = 0`, `1/(1 + r t)` at `c = 1` (a loss that slows as the
//! water goes). The fit finds `r` and `c` (`finrs fit --effects
//! dehydration`); [`crate::Strip::set_moment_gain`] takes the gain; the
//! board's shaper divides a motion's voltages by it.
//!
//! ```
//! use model_core::drying_gain;
//! assert_eq!(drying_gain(1e-3, 0.5, 0.0), 1.0);
//! assert!((drying_gain(1e-2, 1.0, 100.0) - 0.5).abs() < 1e-15);
//! assert!((drying_gain(1e-2, 0.0, 100.0) - (-1.0f64).exp()).abs() < 1e-15);
//! ```

/// The moment gain after drying for `t_s` at initial rate `rate_per_s`
/// with `curvature` (see the module's description).
pub fn drying_gain(rate_per_s: f64, curvature: f64, t_s: f64) -> f64 {
    let x = rate_per_s * t_s;
    // Below this the series of ln(1 + c x)/c is −x to rounding.
    if curvature * x < 1e-9 {
        libm::exp(-x)
    } else {
        libm::exp(-libm::log1p(curvature * x) / curvature)
    }
}
