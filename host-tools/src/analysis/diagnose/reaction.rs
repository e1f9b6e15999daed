//! The reaction's signature: how far the steady current the fit predicts
//! departs from linear between half the session's highest drive and the
//! whole of it, `D = I(v) / (2 I(v/2)) − 1`, with `I(v) = v/R2 + i(w)`,
//! the linear leak's current across the terminals and the reaction's
//! behind the double layer, whose voltage `w` solves `w + R1 i(w) = v`
//! ([`model_core::Reaction`]); and its standard error from the fit's
//! covariance of `R1`, `R2` and the reaction's two voltages (the delta
//! method).
//!
//! Not the reaction's own values, nor its share of the leak's current:
//! its voltage (where its current equals the linear leak's) and its Tafel
//! voltage trade against each other and against `R1` wherever the layer
//! never reaches that voltage, and a flat reaction trades with `R2`
//! (literature rig session 52002's first round: the reaction carried
//! 2.9 ± 1.0 linear leaks at 3.1 V, `R2`'s interval 870–2,400 Ω, while
//! `D` was 1.22 ± 0.12), so each can be wide while the curve the currents
//! trace over the drives is sure. Where a knob ran
//! to a bound its interval is none and it counts as known.

use crate::analysis::fit::{FitResult, Knob};

/// The departure `D` of a steady current or a charge from linear a strip
/// without electrolysis is seen to show, within its fit's error: the
/// effect is named only where the interval of some term's `D` lies beyond
/// it. (The electrochemical candidate's own probe, `identify.rs`, is a
/// tenth.)
pub const REACTION_ALIKE: f64 = 0.05;

/// The cubic `k` (per V²) that departs from linear by `d` between drives
/// `peak_v / 2` and `peak_v`: the leak's current `v/R2 (1 + k v²)` and the
/// charge's drive `v + k v³` both give `D = (1 + k v²)/(1 + k v²/4) − 1`,
/// so `k = 4D / (v² (3 − D))`. One margin for every term of the effect:
/// a cubic significant at a departure of a percent or two is a strip
/// drying while its drives rise, not electrolysis (development seed
/// 54028, drying alone: the leak's and the charge's cubics at 1.3e-3 and
/// 1.5e-3 /V², 1.5 % and 1.7 % at its 3.91 V, named the reaction).
pub fn cubic_at_departure(d: f64, peak_v: f64) -> f64 {
    4.0 * d / (peak_v * peak_v * (3.0 - d))
}

/// The departure `D` from linear of the steady current the fit's leak
/// and reaction draw between drives `peak_v / 2` and `peak_v`, and its
/// standard error; `None` when the fit has no reaction.
pub fn departure_at(fit: &FitResult, peak_v: f64) -> Option<(f64, f64)> {
    let at = |knob: Knob| fit.estimates.iter().position(|e| e.knob == knob);
    let idx = [
        at(Knob::R1)?,
        at(Knob::R2)?,
        at(Knob::ReactionRef)?,
        at(Knob::ReactionTafel)?,
    ];
    let x = idx.map(|i| fit.estimates[i].value);
    let d = departure(x, peak_v);
    // Central differences, relative: each value is positive.
    let grad = core::array::from_fn::<f64, 4, _>(|k| {
        let h = 1e-6 * x[k];
        let (mut up, mut down) = (x, x);
        up[k] += h;
        down[k] -= h;
        (departure(up, peak_v) - departure(down, peak_v)) / (2.0 * h)
    });
    let gradient: Vec<(usize, f64)> = idx.into_iter().zip(grad).collect();
    Some((d, fit.delta_method_se(&gradient)))
}

/// `D` of `[R1, R2, v_ref, b]` at drive `v`.
fn departure(x: [f64; 4], v: f64) -> f64 {
    let (whole, half) = (steady_a(x, v), steady_a(x, 0.5 * v));
    if half > 0.0 {
        whole / (2.0 * half) - 1.0
    } else {
        0.0
    }
}

/// The steady current at drive `v`, A: the linear leak's `v/R2` and the
/// reaction's, whose layer sits at `w + R1 i(w) = v` (the step's equation
/// with the whole drive taken: [`model_core::Reaction::drive_v`] returns
/// `w`).
fn steady_a([r1, r2, ref_v, tafel_v]: [f64; 4], v: f64) -> f64 {
    if !(v > 0.0 && r1 > 0.0 && r2 > 0.0 && ref_v > 0.0 && tafel_v > 0.0) {
        return 0.0;
    }
    let reaction = model_core::Reaction::new(1.0, ref_v, tafel_v, r2);
    let w = reaction.drive_v(v, v, r1, r1);
    v / r2 + reaction.current_a(w).0
}

#[cfg(test)]
mod tests {
    use super::{departure, steady_a};

    #[test]
    fn a_cubic_at_the_margin_departs_by_it() {
        for &(d, v) in &[(0.05, 3.9), (-0.05, 3.9), (0.2, 2.0)] {
            let k = super::cubic_at_departure(d, v);
            let departs = |v: f64| (1.0 + k * v * v) / (1.0 + k * v * v / 4.0) - 1.0;
            assert!((departs(v) - d).abs() < 1e-12, "{d} {v} {k}");
        }
    }

    #[test]
    fn the_layer_settles_where_r1_carries_the_reactions_current() {
        let (r1, r2, ref_v, b) = (160.0, 700.0, 1.6, 0.05);
        let x = [r1, r2, ref_v, b];
        let i = steady_a(x, 3.0) - 3.0 / r2;
        // The reaction's current through R1 leaves the layer at w, where
        // it draws i.
        let reaction = model_core::Reaction::new(1.0, ref_v, b, r2);
        let w = 3.0 - r1 * i;
        assert!((reaction.current_a(w).0 - i).abs() < 1e-12);
        assert!(i > 3.0 / r2 && w < 1.8, "{i} {w}");
        // The departure is the reaction's share of the linear leak's
        // current at the top, less its share at half the drive (the layer
        // held below its voltage there), over one plus the latter.
        let share = |v: f64| (steady_a(x, v) - v / r2) * r2 / v;
        let (q, q_half) = (share(3.0), share(1.5));
        let d = departure(x, 3.0);
        assert!((d - (q - q_half) / (1.0 + q_half)).abs() < 1e-12, "{d}");
        assert!(q_half < 0.1 && d > 1.5, "{q_half} {d}");
        // Out of the drive's reach, next to nothing; growing with the drive.
        assert!(departure([r1, r2, 6.0, b], 3.0) < 1e-9);
        assert!(departure(x, 2.0) < d);
        assert_eq!(departure(x, 0.0), 0.0);
    }
}
