//! The dehydration's signature: the moment gain the fitted drying takes
//! from the strip over the session, `L = 1 − g(r, c, T) s(r_c, T)` with
//! the moment's own law `g = (1 + c r T)^(−1/c)`
//! ([`model_core::drying_gain`]) and the circuit's `s = 1/(1 + r_c T)`
//! ([`crate::model::predict::circuit_gain`]: the charge falls with the
//! admittance), and its standard error from the fit's covariance of the
//! rates `r`, `r_c` and the curvature `c` (the delta method).
//!
//! Not the rate's own interval: where the fit bends the law (`c` of a few
//! or more, a loss front-loaded as a strip that dries then settles gives),
//! the loss hangs on `r` only as `r^(−1/c)`, so `r` and `c` trade against
//! each other and the rate's interval spans zero while the loss is sure.
//! On the literature strip drying alone (rig seed 50052, 3.3 times the
//! plausible loss), the drying gained 90 % of the held-out error with the
//! rate's interval from −0.67 to 1.1 /s.

use crate::analysis::fit::{FitResult, Knob};

/// How much moment gain a strip that does not dry seems to lose over a
/// session, the dehydration's margin: `dehydration` is named only where
/// the loss's interval lies beyond it, as the reaction's departure
/// ([`super::reaction::REACTION_ALIKE`]) and a segment's
/// ([`super::search::SEGMENT_ALIKE`]) lie beyond theirs; 5 %, the
/// strength the identifiability probe calls detectable. A strip changes
/// from run to run by a few percent as it settles, and a model that lacks
/// its form fits a misfit that varies over the session as a small
/// drying: on the literature strip's base (nothing departing, development
/// seed 61004) the fit took 6.4 ± 2.1 % over the session, its interval
/// just clear of zero.
pub const DRYING_ALIKE: f64 = 0.05;

/// Whether the loss `loss` with standard error `se` lies beyond
/// [`DRYING_ALIKE`] at `z` standard errors.
pub fn shows(loss: f64, se: f64, z: f64) -> bool {
    loss - z * se > DRYING_ALIKE
}

/// The fitted loss of moment gain by session time `span_s` and its
/// standard error; `None` when the fit has no drying rate.
pub fn loss_over(fit: &FitResult, span_s: f64) -> Option<(f64, f64)> {
    let at = |knob: Knob| fit.estimates.iter().position(|e| e.knob == knob);
    let ir = at(Knob::Dehydration)?;
    let ic = at(Knob::DryingCurvature);
    let is = at(Knob::CircuitDrying);
    let value = |i: Option<usize>| i.map_or(0.0, |i| fit.estimates[i].value);
    let (r, c, r_c) = (fit.estimates[ir].value, value(ic), value(is));
    let (loss, [d_r, d_c, d_rc]) = total_loss_and_gradient(r, c, r_c, span_s);
    let gradient: Vec<(usize, f64)> = std::iter::once((ir, d_r))
        .chain(ic.map(|i| (i, d_c)))
        .chain(is.map(|i| (i, d_rc)))
        .collect();
    Some((loss, fit.delta_method_se(&gradient)))
}

/// `L = 1 − g s` at time `t_s` and its derivatives in `r`, `c` and `r_c`:
/// the moment's each times `s`, and the circuit's `−g ds/dr_c = g t s²`.
fn total_loss_and_gradient(r: f64, c: f64, r_c: f64, t_s: f64) -> (f64, [f64; 3]) {
    let (moment_loss, d_r, d_c) = loss_and_gradient(r, c, t_s);
    let s = crate::model::predict::circuit_gain(r_c, t_s);
    let g = 1.0 - moment_loss;
    (1.0 - g * s, [d_r * s, d_c * s, g * t_s * s * s])
}

/// `L = 1 − (1 + c r T)^(−1/c)` and its derivatives in `r` and `c`.
fn loss_and_gradient(r: f64, c: f64, t_s: f64) -> (f64, f64, f64) {
    let x = r * t_s;
    let g = model_core::drying_gain(r, c, t_s);
    let cx = c * x;
    let d_g_d_r = -g * t_s / (1.0 + cx);
    // d/dc of −ln(1 + c x)/c; near c x = 0 its series (the closed form
    // cancels there).
    let d_exp_d_c = if cx.abs() < 1e-4 {
        x * x / 2.0 - 2.0 * c * x * x * x / 3.0
    } else {
        cx.ln_1p() / (c * c) - x / (c * (1.0 + cx))
    };
    (1.0 - g, -d_g_d_r, -g * d_exp_d_c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loss_is_shown_only_beyond_the_margin_at_its_interval() {
        // Sure of 6.4 % to within 2.1 %: clear of zero at three standard
        // errors, not of the margin.
        let (loss, se) = (0.064, 0.021);
        assert!(loss - 3.0 * se > 0.0);
        assert!(!shows(loss, se, 3.0));
        // A plausible loss (10 %), fitted tightly, is shown.
        assert!(shows(0.10, 0.01, 3.0));
        // The margin itself, however sure, is not.
        assert!(!shows(DRYING_ALIKE, 0.0, 3.0));
    }

    #[test]
    fn the_gradient_is_the_losss_own() {
        for &(r, c, t) in &[
            (2e-3, 0.0, 140.0),
            (2e-3, 1e-7, 140.0),
            (2e-3, 1.0, 140.0),
            (0.06, 6.0, 140.0),
            (5.7, 24.0, 300.0),
        ] {
            let (l, d_r, d_c) = loss_and_gradient(r, c, t);
            let f = |r: f64, c: f64| 1.0 - model_core::drying_gain(r, c, t);
            assert!((l - f(r, c)).abs() < 1e-15);
            let hr = 1e-6 * r;
            let num_r = (f(r + hr, c) - f(r - hr, c)) / (2.0 * hr);
            // Central where the curvature allows, forward from 0; a step
            // of 1e-4 at least, above the law's own switch to `e^{-x}`.
            let hc = (1e-6 * c).max(1e-4);
            let num_c = if c >= hc {
                (f(r, c + hc) - f(r, c - hc)) / (2.0 * hc)
            } else {
                (f(r, c + hc) - f(r, c)) / hc
            };
            assert!(
                (d_r - num_r).abs() <= 1e-5 * num_r.abs().max(1e-9),
                "{r} {c}: {d_r} {num_r}"
            );
            assert!(
                (d_c - num_c).abs() <= 1e-4 * num_c.abs().max(1e-9),
                "{r} {c}: {d_c} {num_c}"
            );
        }
    }

    #[test]
    fn the_circuits_drying_adds_to_the_moments_loss_with_its_own_gradient() {
        let t = 140.0;
        for &(r, c, r_c) in &[(2e-3, 1.0, 0.0), (2e-3, 0.5, 1e-3), (0.0, 0.0, 3e-3)] {
            let (l, grad) = total_loss_and_gradient(r, c, r_c, t);
            let f = |x: [f64; 3]| total_loss_and_gradient(x[0], x[1], x[2], t).0;
            // The loss is the product's: the moment's gain times the circuit's.
            let product = model_core::drying_gain(r, c, t) / (1.0 + r_c * t);
            assert!((l - (1.0 - product)).abs() < 1e-15, "{l} {product}");
            for k in 0..3 {
                let x = [r, c, r_c];
                let h = (1e-6 * x[k]).max(1e-7);
                let (mut up, mut down) = (x, x);
                up[k] += h;
                down[k] = (down[k] - h).max(0.0);
                let num = (f(up) - f(down)) / (up[k] - down[k]);
                assert!(
                    (grad[k] - num).abs() <= 1e-4 * num.abs().max(1e-6),
                    "{k}: {} {num}",
                    grad[k]
                );
            }
        }
    }

    #[test]
    fn no_rate_loses_nothing_whatever_the_curvature() {
        for c in [0.0, 1.0, 100.0] {
            let (l, _, d_c) = loss_and_gradient(0.0, c, 140.0);
            assert_eq!(l, 0.0);
            assert_eq!(d_c, 0.0);
        }
    }
}
