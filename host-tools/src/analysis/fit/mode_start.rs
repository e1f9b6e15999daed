//! Where a fit of the terms that move or damp the beam's first mode
//! starts: the model so far with the new terms off, except that those
//! terms start where the model rings as the data do (the blocked mode's
//! frequency and decay). The diagnosis starts each round's candidates
//! here; `finrs fit` tries it beside the data's own start
//! ([`Fitter::fit_from_either_start`](super::Fitter::fit_from_either_start)).

use super::modal::{self, Ringing};
use super::Effect;
use crate::model::predict::ModelSpec;
use crate::recording::Medium;
use crate::session::Session;

/// `(model, measured)` first blocked mode beside `current` on the
/// training recordings `train`, when some move of `moves` reads it.
pub fn modes(
    session: &Session,
    train: &[usize],
    current: &ModelSpec,
    moves: &[Vec<Effect>],
) -> Option<(Ringing, Ringing)> {
    if !moves.iter().flatten().any(|&e| reads_the_mode(e)) {
        return None;
    }
    let model = modal::model_blocked_ringing(current)?;
    let data =
        modal::measured_blocked_ringing(session, train, current, 0.2 * model.hz, 3.0 * model.hz)?;
    Some((model, data))
}

/// Whether a candidate moves or damps the beam's first mode.
fn reads_the_mode(e: Effect) -> bool {
    matches!(
        e,
        Effect::BeamStiffness | Effect::HydrodynamicLoading | Effect::Damping
    )
}

/// Where a candidate that moves or damps the beam's first mode starts:
/// where the model's mode rings at the measured frequency (`EI` for
/// beam-stiffness, added mass for hydrodynamic loading) and, for damping,
/// decays at the measured rate (the constant damping ratio takes all of
/// the missing ratio). Others, and the water's quadratic drag, start at
/// the current model, their own terms off.
pub fn start(e: Effect, current: &ModelSpec, modes: Option<(Ringing, Ringing)>) -> ModelSpec {
    let mut start = *current;
    if !reads_the_mode(e) {
        return start;
    }
    let Some((model, data)) = modes else {
        return start;
    };
    // f ∝ √(EI / mass per length).
    let ratio2 = (data.hz / model.hz).powi(2);
    match e {
        Effect::BeamStiffness => start.params.ei_nm2 *= ratio2,
        // The constant ratio is the measured ratio itself, at every mode.
        Effect::Damping => {
            start.ext.damping_ratio += (data.damping_ratio - model.damping_ratio).max(0.0)
        }
        _ => {
            let mass = start.params.mass_per_length_kg_per_m + start.ext.added_mass_kg_per_m;
            start.ext.added_mass_kg_per_m =
                (mass / ratio2 - start.params.mass_per_length_kg_per_m).max(0.0);
            // The quadratic drag starts off: the held ring moves
            // micrometres, where it does nothing, so the ring cannot set
            // it, and started at a plate's of this added mass (c₂ = ½ ρ
            // C_d b, b from m_a = ρ π b²/4) the fit of a development
            // session ended with no added mass at 8 times the cost.
        }
    }
    start
}

/// Where a move's terms (its effects together) start beside `current`:
/// each effect's own start ([`start`]) in turn, except where the move
/// brings the fluid and a stiffness together. One ring cannot set both
/// the added mass and `EI` (each alone would take the whole frequency
/// shift, and the two in turn take it twice), so the fluid starts at the
/// added mass of a plate of the strip's width in water (`ρ π b² / 4`, the
/// classical value for a strip moving across its plane; `width_m`, the
/// session's) and `EI` where the model, with that mass, rings at the
/// measured frequency.
pub fn start_move(
    m: &[Effect],
    current: &ModelSpec,
    modes: Option<(Ringing, Ringing)>,
    width_m: f64,
) -> ModelSpec {
    let both = [Effect::BeamStiffness, Effect::HydrodynamicLoading];
    if !both.iter().all(|e| m.contains(e)) {
        return m.iter().fold(*current, |spec, &e| start(e, &spec, modes));
    }
    let mut spec = m
        .iter()
        .filter(|e| !both.contains(e))
        .fold(*current, |spec, &e| start(e, &spec, modes));
    let Some((model, data)) = modes else {
        return spec;
    };
    let mass = |s: &ModelSpec| s.params.mass_per_length_kg_per_m + s.ext.added_mass_kg_per_m;
    let before = mass(&spec);
    let plate = Medium::Water.plate_added_mass_kg_per_m(width_m);
    spec.ext.added_mass_kg_per_m = spec.ext.added_mass_kg_per_m.max(plate);
    // f ∝ √(EI / mass per length).
    spec.params.ei_nm2 *= (data.hz / model.hz).powi(2) * mass(&spec) / before;
    spec
}

/// A second start for a move that brings the fluid (`hydrodynamic-loading`)
/// onto a model that has the damping or the beam's stiffness: the current
/// model with those terms back at the fixed model's (`EI` the laminate's,
/// `ζ₀` and `β` 0), from which [`start`] sets the added mass by the
/// measured ring. A stiffer beam with a heavy damping stands in for the
/// water's added mass and drag on the held ring, and the fluid's fit
/// started from them stayed there: on a development session in water
/// (the fluid alone hidden), beside the pair's `ζ₀` 0.45 it ended with no
/// added mass. `None` for any other move or model.
pub fn fluid_without_stand_ins(
    m: &[Effect],
    effects: &[Effect],
    current: &ModelSpec,
    fixed: &ModelSpec,
) -> Option<ModelSpec> {
    let stand_ins = [Effect::Damping, Effect::BeamStiffness];
    if !m.contains(&Effect::HydrodynamicLoading) || !effects.iter().any(|e| stand_ins.contains(e)) {
        return None;
    }
    let mut bare = *current;
    bare.params.ei_nm2 = fixed.params.ei_nm2;
    bare.ext.damping_ratio = 0.0;
    bare.ext.damping_stiffness_s = 0.0;
    Some(bare)
}

/// A second start for one member of the mode's pair (`damping` or
/// `beam-stiffness` alone), where the pair was fitted in the same round:
/// the pair's fit with the other member's terms back at `current`'s. Both
/// members' fits start their mode's terms from the same ring, and alone
/// a member's descent can end far from where the pair's took the same
/// term: on development sessions in water, `EI` alone stayed at its start
/// or ended at a third of the pair's, with training costs above the
/// model's without it, where the pair (its damping terms ending at zero
/// beside the fluid's drag) gained on held-out data. `None`
/// for any other move.
pub fn member_from_pair(m: &[Effect], pair: &ModelSpec, current: &ModelSpec) -> Option<ModelSpec> {
    let mut start = *pair;
    match m {
        [Effect::Damping] => start.params.ei_nm2 = current.params.ei_nm2,
        [Effect::BeamStiffness] => {
            start.ext.damping_ratio = current.ext.damping_ratio;
            start.ext.damping_stiffness_s = current.ext.damping_stiffness_s;
        }
        _ => return None,
    }
    Some(start)
}

#[cfg(test)]
mod tests {
    use super::*;
    use model_core::Params;

    #[test]
    fn the_fluid_gets_a_start_without_the_damped_stiff_beam_and_nothing_else_does() {
        let fixed = ModelSpec::baseline(Params::main_m_2006());
        let mut current = fixed;
        current.params.ei_nm2 *= 5.0;
        current.params.r1_ohm *= 2.0;
        current.ext.damping_ratio = 0.45;
        current.ext.damping_stiffness_s = 1e-4;
        let pair = [Effect::Damping, Effect::BeamStiffness];
        let fluid = [Effect::HydrodynamicLoading];
        let bare = fluid_without_stand_ins(&fluid, &pair, &current, &fixed).unwrap();
        assert_eq!(bare.params.ei_nm2, fixed.params.ei_nm2);
        assert_eq!(bare.ext.damping_ratio, 0.0);
        assert_eq!(bare.ext.damping_stiffness_s, 0.0);
        // What the stand-ins do not hold stays as fitted.
        assert_eq!(bare.params.r1_ohm, current.params.r1_ohm);
        assert!(
            fluid_without_stand_ins(&fluid, &[Effect::Dehydration], &current, &fixed).is_none()
        );
        assert!(fluid_without_stand_ins(&[Effect::Dehydration], &pair, &current, &fixed).is_none());
    }

    #[test]
    fn the_fluid_and_the_stiffness_together_share_the_rings_shift_once() {
        let current = ModelSpec::baseline(Params::main_m_2006());
        let model = Ringing {
            hz: 40.0,
            damping_ratio: 0.01,
        };
        let data = Ringing {
            hz: 20.0,
            damping_ratio: 0.06,
        };
        let modes = Some((model, data));
        let width_m = 0.005;
        let hz2 = |s: &ModelSpec| {
            s.params.ei_nm2 / (s.params.mass_per_length_kg_per_m + s.ext.added_mass_kg_per_m)
        };
        let shift2 = (data.hz / model.hz).powi(2);
        // Each alone takes the whole shift.
        for e in [Effect::BeamStiffness, Effect::HydrodynamicLoading] {
            let alone = start_move(&[e], &current, modes, width_m);
            assert!((hz2(&alone) / hz2(&current) - shift2).abs() < 1e-12);
        }
        let all = [
            Effect::Damping,
            Effect::BeamStiffness,
            Effect::HydrodynamicLoading,
        ];
        let together = start_move(&all, &current, modes, width_m);
        // A plate's added mass, and the ring at the measured frequency
        // once, not twice.
        let plate = 1000.0 * std::f64::consts::PI * width_m * width_m / 4.0;
        assert!((together.ext.added_mass_kg_per_m - plate).abs() < 1e-15);
        assert!((hz2(&together) / hz2(&current) - shift2).abs() < 1e-12);
        // The damping as it starts alone.
        assert_eq!(
            together.ext.damping_ratio,
            start(Effect::Damping, &current, modes).ext.damping_ratio
        );
        // Without a measured ring, every term starts off.
        let off = start_move(&all, &current, None, width_m);
        assert_eq!(off.params.ei_nm2, current.params.ei_nm2);
        assert_eq!(off.ext.added_mass_kg_per_m, 0.0);
    }

    #[test]
    fn a_member_of_the_pair_starts_from_the_pair_without_the_other() {
        let current = ModelSpec::baseline(Params::main_m_2006());
        let mut pair = current;
        pair.params.ei_nm2 *= 0.6;
        pair.params.r1_ohm *= 1.3;
        pair.ext.damping_ratio = 0.002;
        pair.ext.damping_stiffness_s = 1e-5;
        pair.ext.drag_quadratic_n_s2_per_m3 = 300.0;
        let stiff = member_from_pair(&[Effect::BeamStiffness], &pair, &current).unwrap();
        assert_eq!(stiff.params.ei_nm2, pair.params.ei_nm2);
        assert_eq!(stiff.ext.damping_ratio, current.ext.damping_ratio);
        assert_eq!(
            stiff.ext.damping_stiffness_s,
            current.ext.damping_stiffness_s
        );
        let damped = member_from_pair(&[Effect::Damping], &pair, &current).unwrap();
        assert_eq!(damped.params.ei_nm2, current.params.ei_nm2);
        assert_eq!(damped.ext.damping_ratio, pair.ext.damping_ratio);
        assert_eq!(damped.ext.damping_stiffness_s, pair.ext.damping_stiffness_s);
        // The knobs the pair shares with the model stay as the pair left them.
        for start in [stiff, damped] {
            assert_eq!(start.params.r1_ohm, pair.params.r1_ohm);
            assert_eq!(start.ext.drag_quadratic_n_s2_per_m3, 300.0);
        }
        let pair_move = [Effect::Damping, Effect::BeamStiffness];
        assert!(member_from_pair(&pair_move, &pair, &current).is_none());
        assert!(member_from_pair(&[Effect::Dehydration], &pair, &current).is_none());
    }
}
