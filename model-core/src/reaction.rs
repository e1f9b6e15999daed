//! An electrochemical reaction behind each double layer: the
//! charge-transfer branch of Randles' cell, beside the double layer's
//! capacitance, with a Butler–Volmer current `i = i₀ sinh(v/b)` in the
//! layer's voltage `v` (symmetric transfer coefficients).
//!
//! Above about 1.2 V water is electrolysed: the current grows `e`-fold
//! every Tafel voltage `b` (tens of millivolts) and, flowing from the
//! layer's charge, holds the layer's voltage (and the charge, and the
//! moment) below a linear strip's at a high drive. The thesis's leak `R2`
//! sits across the terminals and cannot do that.
//!
//! Stepped implicitly over the zero-order hold: with `v_C ← a v_C + g₀ u`
//! the exact step of `v_C' = (u − v_C)/τ₁`, the drive the layer sees is
//! `u = v − R1 i(v_C⁺)`, `v_C⁺` the layer's voltage at the step's end,
//! found by Newton's method. Implicit, because the reaction's conductance
//! at a few hundred millivolts over its onset is many times `1/R1`: held
//! at the step's start instead, it would overshoot and ring.
//!
//! ```
//! use model_core::Reaction;
//!
//! // 50 % of a 700 Ω leak's current at 2 V on the layer, b = 60 mV.
//! let r = Reaction::new(0.5, 2.0, 0.06, 700.0);
//! let (i, _) = r.current_a(2.0);
//! assert!((i - 0.5 * 2.0 / 700.0).abs() < 1e-15);
//! // Odd in the voltage, and e-fold per b well above b.
//! assert_eq!(r.current_a(-2.0).0, -i);
//! assert!((r.current_a(2.06).0 / i - 1f64.exp()).abs() < 1e-6);
//! ```

/// Newton's iterations at most in a solve: a handful from a good start,
/// and a bisection's hundred halve any bracket past `f64`'s resolution.
const MAX_NEWTON: usize = 100;

/// The largest exponent evaluated: `e^200` stays finite in `f64`, and a
/// layer 200 Tafel voltages over its reference carries no meaning.
const MAX_EXPONENT: f64 = 200.0;

/// The exponent `2|v|/b` past which `1 ± e^{−2|v|/b}` rounds to 1
/// (`e^{−38} ≈ 3.1·10⁻¹⁷ < 2⁻⁵⁴`): a layer 19 Tafel voltages up.
const FALL_NEGLIGIBLE: f64 = 38.0;

/// The solve's tolerance on the layer's voltage, relative to `1 + |w|`.
const TOLERANCE: f64 = 1e-12;

/// A Butler–Volmer reaction behind one double layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reaction {
    /// The current at [`Self::ref_v`], A.
    ref_a: f64,
    /// The layer's voltage at which [`Self::ref_a`] flows, V.
    ref_v: f64,
    /// Tafel voltage `b`, V.
    tafel_v: f64,
    /// `1 − e^{−2 v_ref/b}`: `sinh(v_ref/b)` times `2 e^{−v_ref/b}`.
    ref_norm: f64,
}

impl Reaction {
    /// The reaction whose current at `ref_v` on the layer is `ratio` times
    /// a linear leak's there (`ref_v / r2_ohm`), with Tafel voltage
    /// `tafel_v`. The values are those [`crate::Extensions::validate`]
    /// checks.
    pub fn new(ratio: f64, ref_v: f64, tafel_v: f64, r2_ohm: f64) -> Self {
        Reaction {
            ref_a: ratio * ref_v / r2_ohm,
            ref_v,
            tafel_v,
            ref_norm: 1.0 - libm::exp(-2.0 * ref_v / tafel_v),
        }
    }

    /// The current at the layer's voltage `v`, A, and its slope `di/dv`,
    /// S: `i_ref sinh(v/b) / sinh(v_ref/b)`, written so that neither
    /// `sinh` overflows.
    pub fn current_a(&self, v: f64) -> (f64, f64) {
        let (a, b) = (libm::fabs(v), self.tafel_v);
        let grow = libm::exp(((a - self.ref_v) / b).min(MAX_EXPONENT)) / self.ref_norm;
        // Past FALL_NEGLIGIBLE, 1 ± e^{−2a/b} rounds to 1: the second
        // exponential would change no bit.
        let fall = if 2.0 * a / b > FALL_NEGLIGIBLE {
            0.0
        } else {
            libm::exp(-2.0 * a / b)
        };
        let i = self.ref_a * grow * (1.0 - fall);
        let slope = self.ref_a * grow * (1.0 + fall) / b;
        (if v < 0.0 { -i } else { i }, slope)
    }

    /// The drive `u` the layer sees over a step whose linear part ends at
    /// `v_lin = a v_C + g₀ v`, with `k = g₀ R1` and `R1` in ohms: the
    /// `v_C⁺` that solves `v_C⁺ + k i(v_C⁺) = v_lin`, and `u = v − R1
    /// i(v_C⁺)`. With `k = R1` and `v_lin = v` it is the layer's steady
    /// voltage under `v`.
    pub fn drive_v(&self, v: f64, v_lin: f64, k: f64, r1_ohm: f64) -> f64 {
        let w = self.layer_v(v_lin, k);
        // At the root `k i(w) = v_lin − w`: the current without another
        // pair of exponentials, and the step then lands on the root.
        let i = if k > 0.0 {
            (v_lin - w) / k
        } else {
            self.current_a(w).0
        };
        v - r1_ohm * i
    }

    /// The root `w` of `w + k i(w) = v_lin`: the current is odd, so the
    /// root has `v_lin`'s sign and lies between 0 and `v_lin`. Newton's
    /// method kept inside that bracket (a step that leaves it bisects),
    /// so that it converges from any start; it starts at `v_lin` (a step's
    /// root lies within a few Tafel voltages of it) or, where the reaction
    /// there would take more than the whole drive, where it would take all
    /// of it (a steady state far up the exponential, where each of
    /// Newton's steps from `v_lin` would gain only `b`).
    fn layer_v(&self, v_lin: f64, k: f64) -> f64 {
        let t = libm::fabs(v_lin);
        let h = |w: f64| {
            let (i, slope) = self.current_a(w);
            (w + k * i - t, 1.0 + k * slope)
        };
        let (mut lo, mut hi) = (0.0, t);
        let mut w = t;
        // The current at the start serves the test below and the first
        // step (h(t), as h computes it): a layer far below the reaction's
        // voltage, as most steps are, then costs one evaluation of it.
        let (i_t, slope_t) = self.current_a(t);
        let mut at_w = (t + k * i_t - t, 1.0 + k * slope_t);
        if k * i_t > t && self.ref_a > 0.0 && k > 0.0 {
            // i ≈ i_ref e^{(w − v_ref)/b} / norm there.
            let at = self.ref_v + self.tafel_v * libm::log(t * self.ref_norm / (k * self.ref_a));
            w = at.clamp(0.0, t);
            at_w = h(w);
        }
        for _ in 0..MAX_NEWTON {
            let (f, df) = at_w;
            if f > 0.0 {
                hi = w;
            } else {
                lo = w;
            }
            let newton = w - f / df;
            let bisects = !(newton > lo && newton < hi);
            let next = if bisects { 0.5 * (lo + hi) } else { newton };
            let step = libm::fabs(next - w);
            let newton_down = !bisects && f > 0.0;
            w = next;
            let tol = TOLERANCE * (1.0 + w);
            // From above the root, h convex, Newton's step leaves an
            // error below step²·h''/(2h') ≤ step²/(2b) (i'' ≤ i'/b for
            // a sinh): under the tolerance, no further evaluation is owed.
            if step <= tol || hi - lo <= tol || (newton_down && step * step <= self.tafel_v * tol) {
                break;
            }
            at_w = h(w);
        }
        if v_lin < 0.0 {
            -w
        } else {
            w
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Reaction;

    #[test]
    fn the_step_ends_where_the_layer_balances_the_reaction() {
        // k = g₀ R1 of a step 1/16 of τ1; the drive's u then makes the
        // linear step land on the root.
        let r = Reaction::new(2.0, 2.0, 0.05, 700.0);
        let (r1, g0, a) = (160.0, 1.0 - (-1.0f64 / 16.0).exp(), (-1.0f64 / 16.0).exp());
        for (vc, v) in [(2.1, 3.0), (0.0, 3.0), (-1.9, -2.5), (1.0, 1.0)] {
            let v_lin = a * vc + g0 * v;
            let u = r.drive_v(v, v_lin, g0 * r1, r1);
            let w = a * vc + g0 * u;
            let back = w + g0 * r1 * r.current_a(w).0;
            assert!((back - v_lin).abs() < 1e-9, "{vc} {v}: {back} {v_lin}");
        }
    }

    #[test]
    fn held_the_layer_settles_where_r1_and_the_reaction_share_the_drive() {
        let r = Reaction::new(1.0, 2.0, 0.06, 700.0);
        let (r1, h) = (160.0, 1.0f64 / 16.0);
        let (a, g0) = ((-h).exp(), 1.0 - (-h).exp());
        let mut vc = 0.0;
        for _ in 0..2_000 {
            let u = r.drive_v(3.0, a * vc + g0 * 3.0, g0 * r1, r1);
            vc = a * vc + g0 * u;
        }
        // Steady: (3 − v_C)/R1 = i(v_C), and well below 3 V.
        assert!(((3.0 - vc) / r1 - r.current_a(vc).0).abs() < 1e-9);
        assert!(vc < 2.3, "{vc}");
    }

    #[test]
    fn a_steady_layer_far_up_the_exponential_is_found() {
        // Whole drive taken (k = R1, v_lin = v): 3.1 V against a reaction
        // at 1.6 V and 26 mV, some 57 Tafel voltages away.
        let r = Reaction::new(1.0, 1.595, 0.0257, 937.0);
        let r1 = 237.0;
        for v in [3.1, -3.1, 1.0, 0.0] {
            let w = v - r1 * r.current_a(r.layer_v(v, r1)).0;
            let back = w + r1 * r.current_a(w).0;
            assert!((back - v).abs() < 1e-8 * (1.0 + v.abs()), "{v}: {w} {back}");
            assert!(w.abs() <= v.abs() && w * v >= 0.0, "{v}: {w}");
            // The drive takes the current off the root's balance: the
            // same to the solve's tolerance.
            assert!((r.drive_v(v, v, r1, r1) - w).abs() < 1e-11, "{v}");
        }
    }

    #[test]
    fn far_up_the_second_exponential_changes_no_bit() {
        let r = Reaction::new(0.3, 1.5, 0.08, 500.0);
        // Just past the cut (2v/b = 38 at 1.52 V) and far beyond it.
        for v in [1.5201f64, 1.6, 3.0, -2.5] {
            let (a, b) = (v.abs(), 0.08);
            let fall = (-2.0 * a / b).exp();
            assert_eq!(1.0 - fall, 1.0, "{v}");
            assert_eq!(1.0 + fall, 1.0, "{v}");
            let grow = ((a - 1.5) / b).exp() / (1.0 - (-2.0 * 1.5 / b).exp());
            let i = 0.3 * 1.5 / 500.0 * grow;
            let (got, slope) = r.current_a(v);
            assert!((got - i.copysign(v)).abs() <= 1e-14 * i, "{v}");
            assert!((slope - i / b).abs() <= 1e-14 * i / b, "{v}");
        }
    }

    #[test]
    fn the_slope_is_the_currents_derivative() {
        let r = Reaction::new(0.3, 1.5, 0.08, 500.0);
        for v in [-2.0, -0.1, 0.0, 0.4, 1.5, 2.2] {
            let e = 1e-6;
            let numeric = (r.current_a(v + e).0 - r.current_a(v - e).0) / (2.0 * e);
            let (_, slope) = r.current_a(v);
            assert!(
                (numeric - slope).abs() <= 1e-6 * slope.abs().max(1e-9),
                "{v}"
            );
        }
    }
}
