//! Beams solved lately, shared by every run in this process.
//!
//! A fit runs the same beam again and again: each recording of a fixture,
//! and each trial of the electrics, relaxation or damping. Solving its
//! modes every time was a fifth of a diagnosis (a perf profile of rig seed
//! 10035, 2026-11-26). A strip built on kept modes is bit for bit the one
//! built afresh ([`model_core::BeamModes`]), so keeping them changes no
//! number.

use std::any::Any;
use std::sync::Arc;

use model_core::{BeamModes, Extensions, Fixture, ParamError, Params};

use super::recent::Recent;

/// Beams kept at most, the newest first: a fit's trials move the beam
/// (`EI`, mass) a few values at a time.
const KEPT: usize = 16;

/// One kept beam, of whichever mesh (`BeamModes<N, E, S>`).
type Kept = Arc<dyn Any + Send + Sync>;

static KEPT_MODES: Recent<Kept> = Recent::new(KEPT);

/// The modes of the beam of `params` (with `ext`'s added mass) in
/// `fixture`: kept ones if there are, else solved and kept.
pub(super) fn modes_for<const N: usize, const E: usize, const S: usize>(
    params: &Params,
    ext: &Extensions,
    fixture: Fixture,
) -> Result<Arc<BeamModes<N, E, S>>, ParamError> {
    let found = KEPT_MODES.find_map(|k| {
        Arc::clone(k)
            .downcast::<BeamModes<N, E, S>>()
            .ok()
            .filter(|m| m.fixture() == fixture && m.is_for(params, ext))
    });
    if let Some(modes) = found {
        return Ok(modes);
    }
    let modes = Arc::new(BeamModes::<N, E, S>::new(params, ext, fixture)?);
    KEPT_MODES.keep(Arc::clone(&modes) as Kept);
    Ok(modes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_beam_is_solved_once_and_another_beam_anew() {
        // A length no other test uses: the store is shared by the process.
        let p = Params {
            length_m: 0.0437,
            ..Params::main_m_2006()
        };
        let ext = Extensions::NONE;
        let first = modes_for::<3, 1, 18>(&p, &ext, Fixture::Free).unwrap();
        // Other electrics: the same beam, the same solve.
        let q = Params {
            r1_ohm: 3.0 * p.r1_ohm,
            ..p
        };
        let again = modes_for::<3, 1, 18>(&q, &ext, Fixture::Free).unwrap();
        assert!(Arc::ptr_eq(&first, &again));
        // Another fixture, stiffness, added mass or mesh: another beam.
        let blocked = modes_for::<3, 1, 18>(&p, &ext, Fixture::Blocked).unwrap();
        assert!(!Arc::ptr_eq(&first, &blocked));
        assert_eq!(blocked.fixture(), Fixture::Blocked);
        let stiffer = Params {
            ei_nm2: 1.5 * p.ei_nm2,
            ..p
        };
        let other = modes_for::<3, 1, 18>(&stiffer, &ext, Fixture::Free).unwrap();
        assert!(!Arc::ptr_eq(&first, &other));
        assert!(other.is_for(&stiffer, &ext) && !other.is_for(&p, &ext));
        let wet = Extensions {
            added_mass_kg_per_m: 0.01,
            ..Extensions::NONE
        };
        assert!(!modes_for::<3, 1, 18>(&p, &wet, Fixture::Free)
            .unwrap()
            .is_for(&p, &ext));
        let finer = modes_for::<3, 2, 30>(&p, &ext, Fixture::Free).unwrap();
        assert!(finer.is_for(&p, &ext));
    }

    #[test]
    fn a_beam_the_core_refuses_is_refused_and_not_kept() {
        let p = Params {
            length_m: 0.0438,
            mass_per_length_kg_per_m: -1.0,
            ..Params::main_m_2006()
        };
        for _ in 0..2 {
            assert!(modes_for::<3, 1, 18>(&p, &Extensions::NONE, Fixture::Free).is_err());
        }
    }
}
