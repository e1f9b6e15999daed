//! The beam's modes, kept: the eigen-analysis a [`Strip`](crate::Strip) is built on is
//! the costly part of building one (on the host, a fifth of a fit's time
//! went to solving the same beam again for each recording and for each
//! electrical, relaxation or damping trial), and it depends on the beam
//! and the fixture alone.

use crate::beam::{assemble, modes};
use crate::extensions::Extensions;
use crate::matrix::Square;
use crate::params::{ParamError, Params};
use crate::strip::Fixture;

/// The undamped, mass-normalised modes `Ψ` and their `ω²` of one beam in
/// one fixture. [`Strip::with_modes`](crate::Strip::with_modes) builds a strip on them under any
/// electrics, relaxation, damping or sample time, bit for bit the strip
/// [`Strip::with_extensions`](crate::Strip::with_extensions) builds.
///
/// ```
/// use model_core::{BeamModes, Extensions, Fixture, Params, Strip};
/// let p = Params::main_m_2006();
/// let modes = BeamModes::<3, 1, 18>::new(&p, &Extensions::NONE, Fixture::Free).unwrap();
/// // Another circuit on the same beam: the modes still serve.
/// let q = Params { r1_ohm: 2.0 * p.r1_ohm, ..p };
/// assert!(modes.is_for(&q, &Extensions::NONE));
/// let kept = Strip::<f64, 3, 1, 18>::with_modes(&modes, &q, &Extensions::NONE, 1e-3).unwrap();
/// let fresh = Strip::<f64, 3, 1, 18>::with_extensions(&q, &Extensions::NONE, Fixture::Free, 1e-3).unwrap();
/// let (mut a, mut b) = (kept.rest(), fresh.rest());
/// for _ in 0..100 {
///     kept.step(&mut a, &[2.5; 3]);
///     fresh.step(&mut b, &[2.5; 3]);
/// }
/// assert_eq!(a, b);
/// // A stiffer beam is another beam.
/// assert!(!modes.is_for(&Params { ei_nm2: 2.0 * p.ei_nm2, ..p }, &Extensions::NONE));
/// ```
#[derive(Clone)]
pub struct BeamModes<const N: usize, const E: usize, const S: usize> {
    /// What the modes depend on.
    beam: Beam,
    /// Mass-normalised modes `Ψ` as columns (rows: freedoms), ascending.
    pub(crate) psi: Square<N, E>,
    /// `ω²` of each mode, rad²/s²; zero past the last.
    pub(crate) omega2: [f64; S],
    /// Modes: the freedoms the fixture leaves free.
    pub(crate) count: usize,
}

/// The beam's values the modes depend on: `assemble` reads these alone.
#[derive(Clone, Copy, PartialEq)]
struct Beam {
    length_m: f64,
    /// Mass per length with the fluid's added mass, kg/m.
    loaded_kg_per_m: f64,
    ei_nm2: f64,
    fixture: Fixture,
}

impl Beam {
    fn of(params: &Params, ext: &Extensions, fixture: Fixture) -> Beam {
        Beam {
            length_m: params.length_m,
            loaded_kg_per_m: loaded(params, ext).mass_per_length_kg_per_m,
            ei_nm2: params.ei_nm2,
            fixture,
        }
    }
}

/// `params` as the beam is assembled from them: the fluid's added mass
/// (`ext`) moves with the strip.
pub(crate) fn loaded(params: &Params, ext: &Extensions) -> Params {
    Params {
        mass_per_length_kg_per_m: params.mass_per_length_kg_per_m + ext.added_mass_kg_per_m,
        ..*params
    }
}

impl<const N: usize, const E: usize, const S: usize> BeamModes<N, E, S> {
    /// Assembles the beam of `params` (with `ext`'s added mass) in
    /// `fixture` and finds its modes.
    ///
    /// Not inlined (nor is `modes`): each frame's arrays are then freed on
    /// return instead of piling up in the caller's frame, which keeps
    /// [`Strip::new`](crate::Strip::new) within a Cortex-M4's RAM for N = 8.
    #[inline(never)]
    pub fn new(params: &Params, ext: &Extensions, fixture: Fixture) -> Result<Self, ParamError> {
        let assembly = assemble::<N, E, S>(&loaded(params, ext));
        // Every freedom but the tip's deflection where the load cell holds it.
        let dof = 2 * N * E;
        let mut active = [0usize; S];
        let mut count = 0;
        for d in 0..dof {
            if !(fixture == Fixture::Blocked && d == dof - 2) {
                active[count] = d;
                count += 1;
            }
        }
        let mut psi = Square::zeros();
        let mut omega2 = [0.0; S];
        modes(
            &assembly.m,
            &assembly.k,
            &active[..count],
            &mut psi,
            &mut omega2,
        )?;
        Ok(BeamModes {
            beam: Beam::of(params, ext, fixture),
            psi,
            omega2,
            count,
        })
    }

    /// Whether these are the modes of the beam of `params` with `ext`'s
    /// added mass: its length, mass per length and `EI` the same, to the
    /// bit.
    pub fn is_for(&self, params: &Params, ext: &Extensions) -> bool {
        self.beam == Beam::of(params, ext, self.beam.fixture)
    }

    /// The fixture they are the modes in.
    pub fn fixture(&self) -> Fixture {
        self.beam.fixture
    }
}
