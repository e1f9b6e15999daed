//! Physical parameters of a strip, their validation, and the seed's preset.

use core::fmt;

/// The model's parameters, SI units throughout.
///
/// Per segment (all segments alike): the RC circuit of eq. 2.1–2.2 (`R1` in
/// series with the double-layer capacitance `C`, the pair in parallel with
/// the leakage `R2`), and the relaxation lead network of eq. 2.3,
/// `u/Q = K (s + z)/(s + p)`. The beam: free length, bending stiffness `EI`
/// and mass per length `ρA`, uniform along the strip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// `R1`: series (electrolyte) resistance, Ω.
    pub r1_ohm: f64,
    /// `R2`: parallel (leakage) resistance, Ω.
    pub r2_ohm: f64,
    /// `C`: double-layer capacitance, F.
    pub c_f: f64,
    /// `K`: moment per charge of the lead network, N·m/C.
    pub k_nm_per_c: f64,
    /// `z`: zero of the lead network, 1/s.
    pub z_per_s: f64,
    /// `p`: pole of the lead network, 1/s (`1/p` is the relaxation time).
    pub p_per_s: f64,
    /// `L`: free length of the strip from the clamp, m.
    pub length_m: f64,
    /// `EI`: bending stiffness, N·m².
    pub ei_nm2: f64,
    /// `ρA`: mass per unit length, kg/m.
    pub mass_per_length_kg_per_m: f64,
}

/// A Nafion core with a platinum film on each face: the seed's laminate
/// (Appendix B, `main.m`), reduced to one beam by the transformed section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Laminate {
    /// Strip width `b`, m (core and films alike).
    pub width_m: f64,
    /// Core (Nafion) thickness `h_b`, m.
    pub core_thickness_m: f64,
    /// Thickness of each electrode film `h_p`, m.
    pub film_thickness_m: f64,
    /// Core Young's modulus `E_b`, Pa.
    pub core_modulus_pa: f64,
    /// Film Young's modulus `E_p`, Pa.
    pub film_modulus_pa: f64,
    /// Core density `ρ_b`, kg/m³.
    pub core_density_kg_per_m3: f64,
    /// Film density `ρ_p`, kg/m³.
    pub film_density_kg_per_m3: f64,
}

impl Laminate {
    /// The seed's sample (Appendix B `main.m`; Table 4-2 rounds `h_b`).
    pub const THESIS_2006: Laminate = Laminate {
        width_m: 0.01,
        core_thickness_m: 0.000_281_8,
        film_thickness_m: 0.000_002,
        core_modulus_pa: 5e7,
        film_modulus_pa: 144e9,
        core_density_kg_per_m3: 2600.0,
        film_density_kg_per_m3: 21500.0,
    };

    /// `EI` of the transformed section: each film becomes core material of
    /// width `b E_p/E_b`, with its own inertia plus the parallel-axis term
    /// about the (symmetric) neutral axis.
    pub fn ei_nm2(&self) -> f64 {
        let b = self.width_m;
        let hb = self.core_thickness_m;
        let hp = self.film_thickness_m;
        let b_eq = b * self.film_modulus_pa / self.core_modulus_pa;
        let arm = 0.5 * (hb + hp);
        let i =
            b * hb * hb * hb / 12.0 + 2.0 * (b_eq * hp * hp * hp / 12.0 + b_eq * hp * arm * arm);
        self.core_modulus_pa * i
    }

    /// Mass per unit length: core plus both films.
    pub fn mass_per_length_kg_per_m(&self) -> f64 {
        self.width_m
            * (self.core_density_kg_per_m3 * self.core_thickness_m
                + 2.0 * self.film_density_kg_per_m3 * self.film_thickness_m)
    }

    /// Total thickness `h_b + 2 h_p`, as recordings state it.
    pub fn thickness_m(&self) -> f64 {
        self.core_thickness_m + 2.0 * self.film_thickness_m
    }

    /// Refuses non-physical values.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("width_m", self.width_m)?;
        positive("core_thickness_m", self.core_thickness_m)?;
        positive("film_thickness_m", self.film_thickness_m)?;
        positive("core_modulus_pa", self.core_modulus_pa)?;
        positive("film_modulus_pa", self.film_modulus_pa)?;
        positive("core_density_kg_per_m3", self.core_density_kg_per_m3)?;
        positive("film_density_kg_per_m3", self.film_density_kg_per_m3)
    }
}

impl Params {
    /// The seed's model (Appendix B `main.m`) on its 50 mm sample.
    ///
    /// The seed contradicts itself (see `DESIGN.md` of this crate); we keep
    /// `main.m`'s numbers, which give the 13.0 mm of section 4.1.1:
    /// `R1 = 160 Ω`, `R2 = 700 Ω`, `C = 1e-4 F` (`τ1 = 16 ms`), and a lead
    /// network with `p = 0.1/s` (`τ2 = 10 s`), `z/p = 0.77` and `K` chosen so
    /// that the DC moment gain `K C z/p` is `main.m`'s 4.87e-4 N·m/V.
    pub fn thesis_2006() -> Params {
        let lam = Laminate::THESIS_2006;
        let c_f = 1e-4;
        let p_per_s = 0.1;
        let z_per_s = 0.077;
        Params {
            r1_ohm: 160.0,
            r2_ohm: 700.0,
            c_f,
            k_nm_per_c: 4.87e-4 / c_f * p_per_s / z_per_s,
            z_per_s,
            p_per_s,
            length_m: 0.05,
            ei_nm2: lam.ei_nm2(),
            mass_per_length_kg_per_m: lam.mass_per_length_kg_per_m(),
        }
    }

    /// `τ1 = R1 C`, the charging time constant, s.
    pub fn tau1_s(&self) -> f64 {
        self.r1_ohm * self.c_f
    }

    /// DC moment per volt `u/V = K C z/p`, N·m/V.
    pub fn dc_moment_per_volt(&self) -> f64 {
        self.k_nm_per_c * self.c_f * self.z_per_s / self.p_per_s
    }

    /// Refuses non-physical values with the offending field named.
    ///
    /// The relaxation network must be the seed's lead network,
    /// `0 < z < p` (eq. 2.3): the moment overshoots and relaxes toward its
    /// DC value, never past zero.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.validate_relaxation(false)
    }

    /// As [`Params::validate`]; with `back_relaxation`, the zero may also
    /// be at or below zero (`z < p` still), the back-relaxation extension.
    pub fn validate_relaxation(&self, back_relaxation: bool) -> Result<(), ParamError> {
        positive("r1_ohm", self.r1_ohm)?;
        positive("r2_ohm", self.r2_ohm)?;
        positive("c_f", self.c_f)?;
        positive("k_nm_per_c", self.k_nm_per_c)?;
        if back_relaxation {
            if !self.z_per_s.is_finite() {
                return Err(ParamError::NotFinite {
                    field: "z_per_s",
                    value: self.z_per_s,
                });
            }
        } else {
            positive("z_per_s", self.z_per_s)?;
        }
        positive("p_per_s", self.p_per_s)?;
        positive("length_m", self.length_m)?;
        positive("ei_nm2", self.ei_nm2)?;
        positive("mass_per_length_kg_per_m", self.mass_per_length_kg_per_m)?;
        if self.z_per_s >= self.p_per_s {
            return Err(ParamError::RelaxationOrder {
                z_per_s: self.z_per_s,
                p_per_s: self.p_per_s,
            });
        }
        Ok(())
    }
}

fn positive(field: &'static str, value: f64) -> Result<(), ParamError> {
    if !value.is_finite() {
        Err(ParamError::NotFinite { field, value })
    } else if value <= 0.0 {
        Err(ParamError::NotPositive { field, value })
    } else {
        Ok(())
    }
}

/// Why parameters or a model request were refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// A quantity that must be finite is NaN or infinite.
    NotFinite {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A quantity that must be positive is zero or negative.
    NotPositive {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The relaxation network is not a lead network (`0 < z < p`).
    RelaxationOrder {
        /// The zero `z`, 1/s.
        z_per_s: f64,
        /// The pole `p`, 1/s.
        p_per_s: f64,
    },
    /// A quantity outside its allowed open interval.
    OutOfRange {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Lower end (excluded, or included for a lower end of 0).
        min: f64,
        /// Upper end (excluded).
        max: f64,
    },
    /// The beam's mass matrix is not positive definite (numerically
    /// degenerate geometry).
    SingularMass,
    /// A `segment-variation` deviation is refused.
    SegmentDeviation {
        /// The deviation's field.
        field: &'static str,
        /// The segment, counted from 1 at the clamp.
        segment: usize,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamError::NotFinite { field, value } => {
                write!(f, "{field} must be finite, got {value}")
            }
            ParamError::NotPositive { field, value } => {
                write!(f, "{field} must be positive, got {value}")
            }
            ParamError::RelaxationOrder { z_per_s, p_per_s } => write!(
                f,
                "relaxation needs its zero below its pole, z < p (eq. 2.3), got z_per_s = {z_per_s}, p_per_s = {p_per_s}"
            ),
            ParamError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(f, "{field} must lie between {min} and {max}, got {value}"),
            ParamError::SingularMass => write!(f, "beam mass matrix is not positive definite"),
            ParamError::SegmentDeviation {
                field,
                segment,
                value,
                rule,
            } => write!(f, "{field} of segment {segment} is {value}: {rule}"),
        }
    }
}

impl core::error::Error for ParamError {}
