//! Terms beyond the seed's baseline model, for the effects that measured
//! data show and the baseline lacks (`docs/FORMAT.md`'s catalogue).
//!
//! Every term is off at its zero value, so [`Extensions::NONE`] is the
//! seed's model exactly. Each keeps the model fixed-size and, except the
//! input nonlinearity, the moment gain and the quadratic drag, linear, so
//! the exact block-wise discretisation still applies:
//!
//! | effect | term | how it enters |
//! |---|---|---|
//! | `damping` | Rayleigh `C = α M + β K`, a constant ratio `ζ₀`, and each of the first modes' own ratio `ζ'ₖ` ([`ModalDamping`]) | each mode's 2×2 block gets `−2ζₖωₖ`, `2ζₖωₖ = α + 2(ζ₀ + ζ'ₖ)ωₖ + β ωₖ²` |
//! | `hydrodynamic-loading` | added mass `m_a` per length, linear drag `c_d` and quadratic drag `c₂` per length | `ρA + m_a` in the mass matrix; drag `c_d/(ρA + m_a)` like `α`; `c₂ |v| v` at the nodes, after each exact step (the one term that is not linear in the state) |
//! | `beam-stiffness` | `EI` differs from the laminate's | a parameter ([`crate::Params::ei_nm2`]), no term |
//! | `back-relaxation` | the relaxation network's `b = K z` may be `≤ 0` (`z ≤ 0`) | the moment relaxes past zero under a held voltage |
//! | `segment-crosstalk` | a segment's moment spreads to its neighbours by `κ` | `uᵢ ← uᵢ + κ (uᵢ₋₁ + uᵢ₊₁)` in the modal couplings |
//! | `electrochemical-nonlinearity` | the double layer sees `v (1 + a v²)`; the leak passes `v/R2 (1 + b v²)` | static input nonlinearity, exact under zero-order hold |
//! | `dehydration` | the moment weakens over minutes | [`crate::Strip::set_moment_gain`], set by the caller from session time |
//! | `large-deflection` | arc kinematics of the slope field | [`crate::Strip::position_at_m`]: the tip moves toward the clamp |
//! | `segment-variation` | segment `i`'s `R1`, `C`, `K` times `1 + δ`, segment 1 the reference | per segment its own electrical block and coupling, each exact |
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

use crate::params::{non_negative, ParamError};

/// Optional model terms; all off in [`Extensions::NONE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extensions {
    /// Rayleigh mass-proportional damping `α`, 1/s (`≥ 0`).
    pub damping_mass_per_s: f64,
    /// Rayleigh stiffness-proportional damping `β`, s (`≥ 0`).
    pub damping_stiffness_s: f64,
    /// Constant modal damping ratio `ζ₀` (`0 ≤ ζ₀ < 1`): every mode loses
    /// the same fraction of critical damping, as a polymer's frequency-
    /// independent loss factor `η = 2ζ₀` gives (structural or hysteretic
    /// damping), where Rayleigh's ratio falls and rises with frequency.
    pub damping_ratio: f64,
    /// Each of the first modes' own damping ratio, in each fixture, added
    /// to the law above (all 0: off).
    pub modal_damping: ModalDamping,
    /// Added mass of the surrounding fluid per length `m_a`, kg/m (`≥ 0`).
    pub added_mass_kg_per_m: f64,
    /// Linear drag of the surrounding fluid per length `c_d`, N·s/m² (`≥ 0`).
    pub drag_n_s_per_m2: f64,
    /// Quadratic (Morison) drag of the surrounding fluid per length `c₂`
    /// in `c₂ |v| v`, N·s²/m³ (`≥ 0`; `½ ρ C_d b` for a strip of width
    /// `b` in a fluid of density `ρ`). A strip that swings tenths of a
    /// metre a second in water loses its energy to the wake it sheds, in
    /// proportion to the speed squared, where a held tip's micrometres
    /// shed next to none: one linear `c_d` cannot be both. Stepped after
    /// the exact linear step, linearly implicit in the speed (see
    /// [`crate::Strip::step`]).
    pub drag_quadratic_n_s2_per_m3: f64,
    /// Cubic term of the voltage the double layer sees, `a` in
    /// `v (1 + a v²)`, 1/V² (`> −1/48`, so it rises monotonically to 4 V).
    pub charge_cubic_per_v2: f64,
    /// Cubic term of the leakage, `b` in `v/R2 (1 + b v²)`, 1/V² (`> −1/48`).
    pub leak_cubic_per_v2: f64,
    /// An electrochemical reaction behind each double layer (Randles'
    /// charge-transfer branch, beside the capacitance): its current at
    /// the double layer's voltage [`reaction_ref_v`](Self::reaction_ref_v)
    /// as a fraction of the linear leak's there (`v_ref / R2`), `≥ 0`,
    /// 0 off. Unlike the leak's cubic, which the thesis's `R2` puts across
    /// the terminals, it drains the double layer: a strong reaction holds
    /// the layer's voltage, and with it the charge and the moment, below
    /// what a linear strip reaches at a high drive.
    pub reaction_ratio: f64,
    /// The double layer's voltage at which
    /// [`reaction_ratio`](Self::reaction_ratio) is stated, V (`> 0` where
    /// the reaction is on).
    pub reaction_ref_v: f64,
    /// The reaction's Tafel voltage `b` in `i ∝ sinh(v/b)` (Butler–Volmer,
    /// symmetric), V (`0.005–10` where the reaction is on): the current
    /// grows `e`-fold every `b` of the double layer's voltage.
    pub reaction_tafel_v: f64,
    /// Fraction `κ` of a segment's moment that acts on each neighbour
    /// (`|κ| < 1`).
    pub crosstalk: f64,
    /// Allows `b ≤ 0` in the relaxation network (the zero `z ≤ 0`): the
    /// moment relaxes back past zero under a held voltage.
    pub back_relaxation: bool,
    /// Positions along the strip follow the arc of the slope field instead
    /// of the small-deflection line.
    pub large_deflection: bool,
    /// Segments that differ in `R1`, `C` and `K` (`segment-variation`).
    pub segment_variation: SegmentVariation,
}

/// Most segments a strip has (as [`crate::Strip`] accepts).
pub const MAX_SEGMENTS: usize = 8;

/// Modes whose damping ratio [`ModalDamping`] sets one by one.
pub const DAMPED_MODES: usize = 8;

/// Each of the first [`DAMPED_MODES`] modes' own damping ratio `ζ'ₖ`, for
/// the free strip and for the strip held by the load cell, added to the
/// law's (`α`, `ζ₀`, `β`); the modes above take the last one's. A strip's
/// loss changes with frequency in ways no two-term law follows (a
/// polymer's loss peak, the clamp's friction), and a held tip's force
/// rings in several modes at once. The two fixtures have different modes
/// (the held tip's first rings about four times higher than the free
/// one's), so each has its own ratios. All 0 is off.
///
/// ```
/// use model_core::{Extensions, Fixture, ModalDamping, Params, Strip};
/// let p = Params::main_m_2006();
/// let mut modal = ModalDamping::NONE;
/// modal.free[1] = 0.05; // the second free mode at 5 % of critical
/// let ext = Extensions { modal_damping: modal, ..Extensions::NONE };
/// let s = Strip::<f64, 3, 1, 18>::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
/// modal.free[1] = -0.05; // a mode that gains energy
/// let ext = Extensions { modal_damping: modal, ..Extensions::NONE };
/// assert!(Strip::<f64, 3, 1, 18>::with_extensions(&p, &ext, Fixture::Free, 1e-3).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModalDamping {
    /// `ζ'ₖ` of the free strip's modes, ascending in frequency.
    pub free: [f64; DAMPED_MODES],
    /// `ζ'ₖ` of the held strip's modes, ascending in frequency.
    pub blocked: [f64; DAMPED_MODES],
}

impl ModalDamping {
    /// No mode damped on its own.
    pub const NONE: ModalDamping = ModalDamping {
        free: [0.0; DAMPED_MODES],
        blocked: [0.0; DAMPED_MODES],
    };

    /// The ratios of `fixture`'s modes.
    pub fn of(&self, fixture: crate::Fixture) -> &[f64; DAMPED_MODES] {
        match fixture {
            crate::Fixture::Free => &self.free,
            crate::Fixture::Blocked => &self.blocked,
        }
    }

    /// `ζ'` of mode `k` (from 0) of `fixture`: the last one's for the modes
    /// above.
    pub fn ratio(&self, fixture: crate::Fixture, k: usize) -> f64 {
        self.of(fixture)[k.min(DAMPED_MODES - 1)]
    }

    /// Refuses a ratio outside `[0, 1)`.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (field, ratios) in [
            ("modal_damping.free", &self.free),
            ("modal_damping.blocked", &self.blocked),
        ] {
            for &value in ratios {
                damping_ratio(field, value)?;
            }
        }
        Ok(())
    }
}

impl Default for ModalDamping {
    fn default() -> Self {
        ModalDamping::NONE
    }
}

/// `segment-variation`: segment `i` (index 0 at the clamp) has
/// `R1 (1 + δᵢ)`, `C (1 + δᵢ)` and `K (1 + δᵢ)`, each with its own
/// deviation `δᵢ > −1`.
///
/// Segment 1 (index 0) is the reference, with all its deviations 0: the
/// shared [`crate::Params`] are its values, which is what keeps the
/// parameters identifiable (scaling every segment alike is a change of
/// `R1`, `C` or `K`). Entries past the strip's segments must be 0 too, so a
/// deviation meant for a longer strip is refused rather than dropped.
///
/// ```
/// use model_core::{Extensions, Fixture, Params, SegmentVariation, Strip};
/// let mut var = SegmentVariation::NONE;
/// var.k_deviation[2] = -0.1; // the third segment bends 10 % less
/// let ext = Extensions { segment_variation: var, ..Extensions::NONE };
/// let s = Strip::<f64, 3, 1, 18>::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3);
/// assert!(s.is_ok());
/// var.k_deviation[3] = 0.1; // a fourth segment the strip does not have
/// let ext = Extensions { segment_variation: var, ..Extensions::NONE };
/// let s = Strip::<f64, 3, 1, 18>::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3);
/// assert!(s.is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentVariation {
    /// Relative departure of each segment's `R1` from the reference's.
    pub r1_deviation: [f64; MAX_SEGMENTS],
    /// Relative departure of each segment's `C` from the reference's.
    pub c_deviation: [f64; MAX_SEGMENTS],
    /// Relative departure of each segment's moment gain `K` from the
    /// reference's.
    pub k_deviation: [f64; MAX_SEGMENTS],
}

impl SegmentVariation {
    /// Every segment alike.
    pub const NONE: SegmentVariation = SegmentVariation {
        r1_deviation: [0.0; MAX_SEGMENTS],
        c_deviation: [0.0; MAX_SEGMENTS],
        k_deviation: [0.0; MAX_SEGMENTS],
    };

    /// The deviations by field name, in a fixed order.
    pub fn fields(&self) -> [(&'static str, &[f64; MAX_SEGMENTS]); 3] {
        [
            ("r1_deviation", &self.r1_deviation),
            ("c_deviation", &self.c_deviation),
            ("k_deviation", &self.k_deviation),
        ]
    }

    /// Whether every segment is alike.
    pub fn is_none(&self) -> bool {
        *self == SegmentVariation::NONE
    }

    /// Refuses a varied reference segment, a deviation at or below −1 (a
    /// factor that is not positive), or one that is not finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.validate_for(MAX_SEGMENTS)
    }

    /// As [`SegmentVariation::validate`], and refuses a deviation on a
    /// segment past the first `segments`.
    pub fn validate_for(&self, segments: usize) -> Result<(), ParamError> {
        for (field, values) in self.fields() {
            for (i, &value) in values.iter().enumerate() {
                let refuse = |rule| {
                    Err(ParamError::SegmentDeviation {
                        field,
                        segment: i + 1,
                        value,
                        rule,
                    })
                };
                if !value.is_finite() {
                    return refuse("must be finite");
                }
                if i == 0 && value != 0.0 {
                    return refuse("segment 1 is the reference, its deviations must be 0");
                }
                if i >= segments && value != 0.0 {
                    return refuse("the strip has fewer segments, the deviation must be 0");
                }
                if value <= -1.0 {
                    return refuse("must be above -1 (a positive factor)");
                }
            }
        }
        Ok(())
    }

    /// Segment `i`'s `(R1, C, K)` from the shared ones: each times
    /// `1 + δ`, which is exact (the shared value itself) at `δ = 0`.
    pub(crate) fn segment(&self, i: usize, r1: f64, c: f64, k: f64) -> (f64, f64, f64) {
        (
            r1 * (1.0 + self.r1_deviation[i]),
            c * (1.0 + self.c_deviation[i]),
            k * (1.0 + self.k_deviation[i]),
        )
    }
}

impl Default for SegmentVariation {
    fn default() -> Self {
        SegmentVariation::NONE
    }
}

impl Extensions {
    /// The seed's baseline: no term on.
    pub const NONE: Extensions = Extensions {
        damping_mass_per_s: 0.0,
        damping_stiffness_s: 0.0,
        damping_ratio: 0.0,
        modal_damping: ModalDamping::NONE,
        added_mass_kg_per_m: 0.0,
        drag_n_s_per_m2: 0.0,
        drag_quadratic_n_s2_per_m3: 0.0,
        charge_cubic_per_v2: 0.0,
        leak_cubic_per_v2: 0.0,
        reaction_ratio: 0.0,
        reaction_ref_v: 0.0,
        reaction_tafel_v: 0.0,
        crosstalk: 0.0,
        back_relaxation: false,
        large_deflection: false,
        segment_variation: SegmentVariation::NONE,
    };

    /// Refuses values outside each term's documented range.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("damping_mass_per_s", self.damping_mass_per_s)?;
        non_negative("damping_stiffness_s", self.damping_stiffness_s)?;
        damping_ratio("damping_ratio", self.damping_ratio)?;
        self.modal_damping.validate()?;
        non_negative("added_mass_kg_per_m", self.added_mass_kg_per_m)?;
        non_negative("drag_n_s_per_m2", self.drag_n_s_per_m2)?;
        non_negative(
            "drag_quadratic_n_s2_per_m3",
            self.drag_quadratic_n_s2_per_m3,
        )?;
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
        non_negative("reaction_ratio", self.reaction_ratio)?;
        if self.reaction_ratio > 0.0 {
            within("reaction_ref_v", self.reaction_ref_v, 1e-3, 10.0)?;
            within("reaction_tafel_v", self.reaction_tafel_v, 5e-3, 10.0)?;
        }
        within("crosstalk", self.crosstalk, -1.0, 1.0)?;
        self.segment_variation.validate()
    }

    /// Modal damping `2ζω` of mode `k` (from 0) of `fixture`, at
    /// `omega_rad_s`, with `rho_a` the strip's own mass per length, 1/s
    /// (the fit reads `ζ` off it to start a damping term where the
    /// measured ringing decays).
    pub fn two_zeta_omega(
        &self,
        fixture: crate::Fixture,
        k: usize,
        omega_rad_s: f64,
        rho_a: f64,
    ) -> f64 {
        self.damping_mass_per_s
            + 2.0 * (self.damping_ratio + self.modal_damping.ratio(fixture, k)) * omega_rad_s
            + self.damping_stiffness_s * omega_rad_s * omega_rad_s
            + self.drag_n_s_per_m2 / (rho_a + self.added_mass_kg_per_m)
    }
}

impl Default for Extensions {
    fn default() -> Self {
        Extensions::NONE
    }
}

/// Refuses a damping ratio outside `[0, 1)`: a mode that gains energy, or
/// one past critical, which the terms are not for.
fn damping_ratio(field: &'static str, value: f64) -> Result<(), ParamError> {
    non_negative(field, value)?;
    if value >= 1.0 {
        return Err(ParamError::OutOfRange {
            field,
            value,
            min: 0.0,
            max: 1.0,
        });
    }
    Ok(())
}

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
