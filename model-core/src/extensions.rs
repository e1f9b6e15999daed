//! Terms beyond the seed's baseline model, for the effects that measured
//! data show and the baseline lacks (`docs/FORMAT.md`'s catalogue).
//!
//! Every term is off at its zero value, so [`Extensions::NONE`] is the
//! seed's model exactly. Each keeps the model fixed-size and, except the
//! input nonlinearity and the moment gain, linear, so the exact block-wise
//! discretisation still applies:
//!
//! | effect | term | how it enters |
//! |---|---|---|
//! | `damping` | Rayleigh `C = α M + β K` | each mode's 2×2 block gets `−2ζₖωₖ`, `2ζₖωₖ = α + β ωₖ²` |
//! | `hydrodynamic-loading` | added mass `m_a` per length, linear drag `c_d` per length | `ρA + m_a` in the mass matrix; drag `c_d/(ρA + m_a)` like `α` |
//! | `beam-stiffness` | `EI` differs from the laminate's | a parameter ([`crate::Params::ei_nm2`]), no term |
//! | `back-relaxation` | the relaxation network's `b = K z` may be `≤ 0` (`z ≤ 0`) | the moment relaxes past zero under a held voltage |
//! | `segment-crosstalk` | a segment's moment spreads to its neighbours by `κ` | `uᵢ ← uᵢ + κ (uᵢ₋₁ + uᵢ₊₁)` in the modal couplings |
//! | `electrochemical-nonlinearity` | the double layer sees `v (1 + a v²)`; the leak passes `v/R2 (1 + b v²)` | static input nonlinearity, exact under zero-order hold |
//! | `dehydration` | the moment weakens over minutes | [`crate::Strip::set_moment_gain`], set by the caller from session time |
//! | `large-deflection` | arc kinematics of the slope field | [`crate::Strip::position_at_m`]: the tip moves toward the clamp |
//!
//! ```
//! use model_core::{Extensions, Fixture, Params, Strip};
//! let p = Params::main_m_2006();
//! let damped = Extensions { damping_mass_per_s: 20.0, ..Extensions::NONE };
//! let s = Strip::<f64, 3, 1, 18>::with_extensions(&p, &damped, Fixture::Free, 1e-3).unwrap();
//! let mut x = s.rest();
//! for _ in 0..20_000 {
//!     s.step(&mut x, &[2.5; 3]);
//! }
//! // Damped, the ringing has died out: the tip sits on the relaxing mean.
//! let a = s.tip_deflection_m(&x);
//! s.step(&mut x, &[2.5; 3]);
//! assert!((s.tip_deflection_m(&x) - a).abs() < 1e-6);
//! ```

use crate::params::ParamError;

/// Optional model terms; all off in [`Extensions::NONE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extensions {
    /// Rayleigh mass-proportional damping `α`, 1/s (`≥ 0`).
    pub damping_mass_per_s: f64,
    /// Rayleigh stiffness-proportional damping `β`, s (`≥ 0`).
    pub damping_stiffness_s: f64,
    /// Added mass of the surrounding fluid per length `m_a`, kg/m (`≥ 0`).
    pub added_mass_kg_per_m: f64,
    /// Linear drag of the surrounding fluid per length `c_d`, N·s/m² (`≥ 0`).
    pub drag_n_s_per_m2: f64,
    /// Cubic term of the voltage the double layer sees, `a` in
    /// `v (1 + a v²)`, 1/V² (`> −1/48`, so it rises monotonically to 4 V).
    pub charge_cubic_per_v2: f64,
    /// Cubic term of the leakage, `b` in `v/R2 (1 + b v²)`, 1/V² (`> −1/48`).
    pub leak_cubic_per_v2: f64,
    /// Fraction `κ` of a segment's moment that acts on each neighbour
    /// (`|κ| < 1`).
    pub crosstalk: f64,
    /// Allows `b ≤ 0` in the relaxation network (the zero `z ≤ 0`): the
    /// moment relaxes back past zero under a held voltage.
    pub back_relaxation: bool,
    /// Positions along the strip follow the arc of the slope field instead
    /// of the small-deflection line.
    pub large_deflection: bool,
}

impl Extensions {
    /// The seed's baseline: no term on.
    pub const NONE: Extensions = Extensions {
        damping_mass_per_s: 0.0,
        damping_stiffness_s: 0.0,
        added_mass_kg_per_m: 0.0,
        drag_n_s_per_m2: 0.0,
        charge_cubic_per_v2: 0.0,
        leak_cubic_per_v2: 0.0,
        crosstalk: 0.0,
        back_relaxation: false,
        large_deflection: false,
    };

    /// Refuses values outside each term's documented range.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("damping_mass_per_s", self.damping_mass_per_s)?;
        non_negative("damping_stiffness_s", self.damping_stiffness_s)?;
        non_negative("added_mass_kg_per_m", self.added_mass_kg_per_m)?;
        non_negative("drag_n_s_per_m2", self.drag_n_s_per_m2)?;
        within(
            "charge_cubic_per_v2",
            self.charge_cubic_per_v2,
            -1.0 / 48.0,
            f64::INFINITY,
        )?;
        within(
            "leak_cubic_per_v2",
            self.leak_cubic_per_v2,
            -1.0 / 48.0,
            f64::INFINITY,
        )?;
        within("crosstalk", self.crosstalk, -1.0, 1.0)
    }

    /// Modal damping `2ζω` of a mode at `omega_rad_s`, with `rho_a` the
    /// strip's own mass per length, 1/s.
    pub(crate) fn two_zeta_omega(&self, omega_rad_s: f64, rho_a: f64) -> f64 {
        self.damping_mass_per_s
            + self.damping_stiffness_s * omega_rad_s * omega_rad_s
            + self.drag_n_s_per_m2 / (rho_a + self.added_mass_kg_per_m)
    }
}

impl Default for Extensions {
    fn default() -> Self {
        Extensions::NONE
    }
}

fn non_negative(field: &'static str, value: f64) -> Result<(), ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite { field, value })
    } else if value < 0.0 {
        Err(ParamError::OutOfRange {
            field,
            value,
            min: 0.0,
            max: f64::INFINITY,
        })
    } else {
        Ok(())
    }
}

/// `min < value < max`.
fn within(field: &'static str, value: f64, min: f64, max: f64) -> Result<(), ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite { field, value })
    } else if value <= min || value >= max {
        Err(ParamError::OutOfRange {
            field,
            value,
            min,
            max,
        })
    } else {
        Ok(())
    }
}
