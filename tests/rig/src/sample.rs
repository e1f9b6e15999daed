//! What the rig's strip is: its true parameters, drawn at random around the
//! seed's, and the effects hidden in it, each in a form the fitted models
//! do not have.

use rand::Rng;

/// The true strip behind a session.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Series resistance `R1`, Ω.
    pub r1_ohm: f64,
    /// Leak resistance `R2`, Ω.
    pub r2_ohm: f64,
    /// Double-layer capacitance `C`, F.
    pub c_f: f64,
    /// Moment per charge `K`, N·m/C.
    pub k_nm_per_c: f64,
    /// Lead network zero `z`, 1/s.
    pub z_per_s: f64,
    /// Lead network pole `p`, 1/s.
    pub p_per_s: f64,
    /// Free length, m.
    pub length_m: f64,
    /// Width, m.
    pub width_m: f64,
    /// Nafion core thickness, m.
    pub core_m: f64,
    /// Platinum film thickness on each side, m.
    pub film_m: f64,
}

/// Young's modulus of the Nafion core and the platinum films, Pa, and their
/// densities, kg/m³ (the seed's Appendix B).
const CORE_PA: f64 = 5e7;
const FILM_PA: f64 = 144e9;
const CORE_KG_M3: f64 = 2600.0;
const FILM_KG_M3: f64 = 21500.0;

impl Sample {
    /// A strip like the seed's, every electrical and relaxation parameter
    /// drawn from a range wider than the seed's own scatter.
    pub fn draw(rng: &mut impl Rng) -> Sample {
        let p = rng.gen_range(0.07..0.15);
        Sample {
            r1_ohm: rng.gen_range(120.0..220.0),
            r2_ohm: rng.gen_range(500.0..900.0),
            c_f: rng.gen_range(0.7e-4..1.4e-4),
            k_nm_per_c: rng.gen_range(4.5..8.0),
            z_per_s: p * rng.gen_range(0.6..0.9),
            p_per_s: p,
            length_m: 0.05,
            width_m: 0.01,
            core_m: 2.818e-4,
            film_m: 2e-6,
        }
    }

    /// Thickness as the metadata gives it (core and both films), m.
    pub fn thickness_m(&self) -> f64 {
        self.core_m + 2.0 * self.film_m
    }

    /// Laminate bending stiffness (transformed section), N·m².
    pub fn laminate_ei_nm2(&self) -> f64 {
        let (b, hb, hp) = (self.width_m, self.core_m, self.film_m);
        let arm = 0.5 * (hb + hp);
        b * (CORE_PA * hb.powi(3) / 12.0 + 2.0 * FILM_PA * (hp.powi(3) / 12.0 + hp * arm * arm))
    }

    /// Mass per length, kg/m.
    pub fn mass_kg_per_m(&self) -> f64 {
        self.width_m * (CORE_KG_M3 * self.core_m + 2.0 * FILM_KG_M3 * self.film_m)
    }
}

/// Water around the strip.
#[derive(Clone, Copy, Debug)]
pub struct Water {
    /// Added mass as a fraction of the strip-theory value `ρ π b²/4`.
    pub added_mass_factor: f64,
    /// Drag coefficient of the quadratic (Morison) drag `½ ρ C_d b |v| v`.
    pub drag_coefficient: f64,
}

/// Density of water, kg/m³.
pub const WATER_KG_M3: f64 = 1000.0;

/// The effects hidden in a session, each in the rig's own form; the
/// default hides nothing.
#[derive(Clone, Debug, Default)]
pub struct Hidden {
    /// `large-deflection`: positions follow the arc of the slope field.
    pub arcs: bool,
    /// `beam-stiffness`: true `EI` over the laminate estimate (1: none).
    pub ei_factor: Option<f64>,
    /// `damping`: one modal damping ratio for every mode (not Rayleigh).
    pub damping_ratio: Option<f64>,
    /// `hydrodynamic-loading`: added mass and quadratic drag.
    pub water: Option<Water>,
    /// `electrochemical-nonlinearity`: the leak is `(V₀/R2) sinh(V/V₀)`
    /// with this `V₀`, V, and the double layer's capacitance grows as
    /// `C (1 + c₂ v²)` with `c₂` the second value, 1/V².
    pub electrochemistry: Option<(f64, f64)>,
    /// `back-relaxation`: a second, slower relaxation branch that takes
    /// back `β` times the steady moment, with time constant `τ`: `(β, τ_s)`.
    pub back_branch: Option<(f64, f64)>,
    /// `dehydration`: the moment falls as `1/(1 + t/τ)` over session time
    /// `t`, with this `τ`, s.
    pub drying_s: Option<f64>,
    /// `segment-crosstalk`: each neighbour's charge bends a segment with
    /// `κ K q`, without the relaxation its own moment has (the fitted term
    /// passes on a fraction of the whole relaxing moment).
    pub crosstalk: Option<f64>,
    /// Outside the catalogue: mains pickup at 50 Hz and its third harmonic
    /// on the DAQ's analogue channels (currents, load cell), with this
    /// amplitude in units of each channel's noise.
    pub mains_pickup: Option<f64>,
}

/// The names a rig can hide: FORMAT.md's catalogue and one outside it.
pub const CATALOGUE: [&str; 8] = [
    "large-deflection",
    "beam-stiffness",
    "damping",
    "hydrodynamic-loading",
    "electrochemical-nonlinearity",
    "back-relaxation",
    "dehydration",
    "segment-crosstalk",
];

/// The effect outside the catalogue.
pub const OUTSIDE: &str = "mains-pickup";

impl Hidden {
    /// Hides `names` (catalogue names or [`OUTSIDE`]), each with a strength
    /// drawn from `rng`; an unknown name is refused.
    pub fn draw(names: &[&str], rng: &mut impl Rng) -> Result<Hidden, String> {
        let mut h = Hidden::default();
        for &name in names {
            match name {
                "large-deflection" => h.arcs = true,
                "beam-stiffness" => {
                    // Stiffer (a solid film) or softer (a cracked one).
                    h.ei_factor = Some(if rng.gen_bool(0.5) {
                        rng.gen_range(1.5..2.2)
                    } else {
                        rng.gen_range(0.45..0.7)
                    })
                }
                "damping" => h.damping_ratio = Some(rng.gen_range(0.02..0.08)),
                "hydrodynamic-loading" => {
                    h.water = Some(Water {
                        added_mass_factor: rng.gen_range(0.7..1.2),
                        drag_coefficient: rng.gen_range(1.5..3.5),
                    })
                }
                "electrochemical-nonlinearity" => {
                    h.electrochemistry = Some((rng.gen_range(1.3..2.2), rng.gen_range(0.02..0.06)))
                }
                "back-relaxation" => {
                    h.back_branch = Some((rng.gen_range(1.3..2.0), rng.gen_range(2.0..5.0)))
                }
                "dehydration" => h.drying_s = Some(rng.gen_range(150.0..500.0)),
                // Not lagged: the beam is undamped, so a neighbour's moment
                // arriving even 20 ms late rings differently for ever, and
                // the instantaneous fitted term cannot follow it (measured:
                // κ fitted 0.01 for 0.16, RSS/m 6.4, at a 23 ms lag).
                "segment-crosstalk" => h.crosstalk = Some(rng.gen_range(0.15..0.35)),
                OUTSIDE => h.mains_pickup = Some(rng.gen_range(1.5..3.0)),
                other => {
                    return Err(format!(
                        "unknown effect `{other}`: the rig hides {CATALOGUE:?} and `{OUTSIDE}`"
                    ))
                }
            }
        }
        Ok(h)
    }
}
