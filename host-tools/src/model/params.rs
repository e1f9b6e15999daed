//! Model parameters as a TOML file: what `finrs fit` writes and
//! `finrs simulate --params` reads.
//!
//! The file holds the sample's material and the fitted electrical and
//! relaxation parameters; the geometry (length, width, thickness) comes from
//! each recording's metadata, so one file serves a whole session. The beam's
//! `EI` and `ρA` follow from geometry and material by the seed's laminate
//! formula unless the optional `[beam]` section overrides them.

use std::path::Path;

use model_core::{
    Laminate, ModalDamping, ParamError, Params, SegmentVariation, DAMPED_MODES, MAX_SEGMENTS,
};

use crate::model::predict::{ModelSpec, ELEMENTS};
use crate::recording::Geometry;
use serde::{Deserialize, Serialize};

/// The contents of a parameter file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// RC circuit, eq. 2.1–2.2.
    pub electrical: Electrical,
    /// Relaxation network, eq. 2.3.
    pub relaxation: Relaxation,
    /// Laminate materials, Appendix B.
    pub material: Material,
    /// Optional override of the laminate formula.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beam: Option<Beam>,
    /// Optional model terms beyond the seed's (all off when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extensions: Option<ExtensionsFile>,
    /// The mesh the parameters were fitted on (absent: none stated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<Mesh>,
}

/// The `[mesh]` section: the finite elements per segment a fit simulated
/// with. A fitted file predicts what the fit saw only on the same mesh (a
/// held strip's ringing moves with it: the blocked force of a soft strip
/// fitted on four elements, simulated on one, is off by several times the
/// load cell's noise), so `finrs simulate` uses it unless told otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    /// Elements per segment, one of [`ELEMENTS`].
    pub elements_per_segment: usize,
}

/// The `[extensions]` section: the terms of [`model_core::Extensions`] and
/// the dehydration rate, each off when omitted.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExtensionsFile {
    /// Rayleigh mass-proportional damping `α`, 1/s.
    pub damping_mass_per_s: f64,
    /// Rayleigh stiffness-proportional damping `β`, s.
    pub damping_stiffness_s: f64,
    /// Constant modal damping ratio `ζ₀` (`0 ≤ ζ₀ < 1`).
    pub damping_ratio: f64,
    /// Each of the free strip's first modes' own damping ratio, ascending
    /// in frequency, added to the law above; the modes above the list take
    /// its last ([`model_core::ModalDamping`]). None listed: off.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub modal_damping_free: Vec<f64>,
    /// As `modal_damping_free`, for the strip held by the load cell.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub modal_damping_blocked: Vec<f64>,
    /// Added fluid mass per length, kg/m.
    pub added_mass_kg_per_m: f64,
    /// Linear fluid drag per length, N·s/m².
    pub drag_n_s_per_m2: f64,
    /// Quadratic fluid drag per length, `c₂` in `c₂ |v| v`, N·s²/m³.
    pub drag_quadratic_n_s2_per_m3: f64,
    /// `a` of the double layer's `v (1 + a v²)`, 1/V².
    pub charge_cubic_per_v2: f64,
    /// `b` of the leak's `v/R2 (1 + b v²)`, 1/V².
    pub leak_cubic_per_v2: f64,
    /// A reaction behind the double layer: its current at
    /// `reaction_ref_v` over the linear leak's there (0, omitted: off;
    /// [`model_core::Extensions::reaction_ratio`]).
    #[serde(skip_serializing_if = "is_zero")]
    pub reaction_ratio: f64,
    /// The double layer's voltage at which `reaction_ratio` is stated, V.
    #[serde(skip_serializing_if = "is_zero")]
    pub reaction_ref_v: f64,
    /// The reaction's Tafel voltage `b` in `sinh(v/b)`, V.
    #[serde(skip_serializing_if = "is_zero")]
    pub reaction_tafel_v: f64,
    /// Fraction of a segment's moment on each neighbour.
    pub crosstalk: f64,
    /// Lets the relaxation's `b = K z` lie at or below 0 (`z ≤ 0`).
    pub back_relaxation: bool,
    /// Arc kinematics for positions along the strip.
    pub large_deflection: bool,
    /// Initial drying rate `r` of the moment gain over session time, 1/s.
    pub dehydration_per_s: f64,
    /// Drying curvature `c` (`≥ 0`): the gain is `(1 + c r t)^(−1/c)`,
    /// `e^{−r t}` at 0.
    pub dehydration_curvature: f64,
    /// Drying rate `r_c` of the circuit's admittance, 1/s: `C`, `1/R1`
    /// and `1/R2` times `1/(1 + r_c t)` over session time `t`.
    #[serde(skip_serializing_if = "is_zero")]
    pub circuit_drying_per_s: f64,
    /// `segment-variation`: each segment's `R1` relative to segment 1's,
    /// minus one, from segment 1 on (segment 1, the reference, is 0);
    /// segments not listed are alike.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub segment_r1_deviation: Vec<f64>,
    /// As `segment_r1_deviation`, for `C`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub segment_c_deviation: Vec<f64>,
    /// As `segment_r1_deviation`, for the moment gain `K`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub segment_k_deviation: Vec<f64>,
}

impl ExtensionsFile {
    /// The core's terms (the dehydration rate is the caller's); refuses a
    /// deviation list longer than a strip can be.
    pub fn core(&self) -> Result<model_core::Extensions, ParamError> {
        let mut var = SegmentVariation::NONE;
        for (field, list, out) in [
            (
                "segment_r1_deviation",
                &self.segment_r1_deviation,
                &mut var.r1_deviation,
            ),
            (
                "segment_c_deviation",
                &self.segment_c_deviation,
                &mut var.c_deviation,
            ),
            (
                "segment_k_deviation",
                &self.segment_k_deviation,
                &mut var.k_deviation,
            ),
        ] {
            if list.len() > MAX_SEGMENTS {
                return Err(ParamError::SegmentDeviation {
                    field,
                    segment: list.len(),
                    value: list[list.len() - 1],
                    rule: "a strip has at most 8 segments",
                });
            }
            out[..list.len()].copy_from_slice(list);
        }
        let mut modal = ModalDamping::NONE;
        for (field, list, out) in [
            (
                "modal_damping_free",
                &self.modal_damping_free,
                &mut modal.free,
            ),
            (
                "modal_damping_blocked",
                &self.modal_damping_blocked,
                &mut modal.blocked,
            ),
        ] {
            if list.len() > DAMPED_MODES {
                return Err(ParamError::TooMany {
                    field,
                    count: list.len(),
                    max: DAMPED_MODES,
                });
            }
            out[..list.len()].copy_from_slice(list);
            // Unlisted modes take the last listed ratio, as the core's
            // modes above its last do.
            if let Some(&last) = list.last() {
                out[list.len()..].fill(last);
            }
        }
        Ok(model_core::Extensions {
            damping_mass_per_s: self.damping_mass_per_s,
            damping_stiffness_s: self.damping_stiffness_s,
            damping_ratio: self.damping_ratio,
            modal_damping: modal,
            added_mass_kg_per_m: self.added_mass_kg_per_m,
            drag_n_s_per_m2: self.drag_n_s_per_m2,
            drag_quadratic_n_s2_per_m3: self.drag_quadratic_n_s2_per_m3,
            charge_cubic_per_v2: self.charge_cubic_per_v2,
            leak_cubic_per_v2: self.leak_cubic_per_v2,
            reaction_ratio: self.reaction_ratio,
            reaction_ref_v: self.reaction_ref_v,
            reaction_tafel_v: self.reaction_tafel_v,
            crosstalk: self.crosstalk,
            back_relaxation: self.back_relaxation,
            large_deflection: self.large_deflection,
            segment_variation: var,
        })
    }

    /// The section for a model's terms and dehydration rates.
    pub fn from_spec(
        ext: &model_core::Extensions,
        dehydration_per_s: f64,
        dehydration_curvature: f64,
        circuit_drying_per_s: f64,
    ) -> ExtensionsFile {
        ExtensionsFile {
            damping_mass_per_s: ext.damping_mass_per_s,
            damping_stiffness_s: ext.damping_stiffness_s,
            damping_ratio: ext.damping_ratio,
            modal_damping_free: modal_listed(&ext.modal_damping.free),
            modal_damping_blocked: modal_listed(&ext.modal_damping.blocked),
            added_mass_kg_per_m: ext.added_mass_kg_per_m,
            drag_n_s_per_m2: ext.drag_n_s_per_m2,
            drag_quadratic_n_s2_per_m3: ext.drag_quadratic_n_s2_per_m3,
            charge_cubic_per_v2: ext.charge_cubic_per_v2,
            leak_cubic_per_v2: ext.leak_cubic_per_v2,
            reaction_ratio: ext.reaction_ratio,
            reaction_ref_v: ext.reaction_ref_v,
            reaction_tafel_v: ext.reaction_tafel_v,
            crosstalk: ext.crosstalk,
            back_relaxation: ext.back_relaxation,
            large_deflection: ext.large_deflection,
            dehydration_per_s,
            dehydration_curvature,
            circuit_drying_per_s,
            segment_r1_deviation: listed(&ext.segment_variation.r1_deviation),
            segment_c_deviation: listed(&ext.segment_variation.c_deviation),
            segment_k_deviation: listed(&ext.segment_variation.k_deviation),
        }
    }
}

/// A deviation per segment up to the last that is not 0 (none when all are).
fn listed(deviations: &[f64; MAX_SEGMENTS]) -> Vec<f64> {
    let len = deviations
        .iter()
        .rposition(|&d| d != 0.0)
        .map_or(0, |last| last + 1);
    deviations[..len].to_vec()
}

/// Modal ratios up to the last that differs from the one after it (the
/// modes above take the last listed); none when all are 0.
fn modal_listed(ratios: &[f64; DAMPED_MODES]) -> Vec<f64> {
    if ratios.iter().all(|&z| z == 0.0) {
        return Vec::new();
    }
    let last = ratios[DAMPED_MODES - 1];
    let len = ratios
        .iter()
        .rposition(|&z| z != last)
        .map_or(1, |differs| differs + 2);
    ratios[..len].to_vec()
}

/// `R1`, `R2`, `C`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Electrical {
    /// Series resistance, Ω.
    pub r1_ohm: f64,
    /// Parallel resistance, Ω.
    pub r2_ohm: f64,
    /// Double-layer capacitance, F.
    pub c_f: f64,
}

/// `a`, `b`, `p` of `u/Q = (a s + b)/(s + p)`, the seed's
/// `K (s+z)/(s+p)` with `a = K`, `b = K z` (see [`model_core::Params`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Relaxation {
    /// `a`: instant moment per charge, N·m/C (`≥ 0`; 0 is the pure lag).
    pub a_nm_per_c: f64,
    /// `b = K z`, N·m/(C·s) (`> 0`; `b/p` is the DC moment per charge).
    pub b_nm_per_c_s: f64,
    /// `p`: pole, 1/s.
    pub p_per_s: f64,
}

/// The seed's parameter sets, by the name `finrs params --preset` takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Appendix B `main.m` ([`Params::main_m_2006`]): the 13 mm calibration.
    MainM2006,
    /// Table 4-2 ([`Params::table_4_2_2006`]).
    Table4_2_2006,
}

impl Preset {
    /// Every preset, the default first.
    pub const ALL: [Preset; 2] = [Preset::MainM2006, Preset::Table4_2_2006];

    /// Its name.
    pub fn name(&self) -> &'static str {
        match self {
            Preset::MainM2006 => "main_m_2006",
            Preset::Table4_2_2006 => "table_4_2_2006",
        }
    }

    /// The preset of that name, if any.
    pub fn parse(name: &str) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The core's parameters.
    pub fn params(&self) -> Params {
        match self {
            Preset::MainM2006 => Params::main_m_2006(),
            Preset::Table4_2_2006 => Params::table_4_2_2006(),
        }
    }
}

/// Core and film materials; the film's thickness is a material property of
/// the plating, the core's follows from the recording's total thickness.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Core (Nafion) Young's modulus, Pa.
    pub core_modulus_pa: f64,
    /// Film (platinum) Young's modulus, Pa.
    pub film_modulus_pa: f64,
    /// Core density, kg/m³.
    pub core_density_kg_per_m3: f64,
    /// Film density, kg/m³.
    pub film_density_kg_per_m3: f64,
    /// Thickness of each film, m.
    pub film_thickness_m: f64,
}

/// Beam properties that replace the laminate formula.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Beam {
    /// Bending stiffness, N·m².
    pub ei_nm2: f64,
    /// Mass per length, kg/m.
    pub mass_per_length_kg_per_m: f64,
}

/// Why a parameter file or its combination with a geometry was refused.
#[derive(Debug, thiserror::Error)]
pub enum ParamsError {
    /// The file could not be read.
    #[error("reading {path}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid TOML or misses or misnames a field.
    #[error("{path}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// The mesh is not one the model has.
    #[error("{path}: [mesh] elements_per_segment must be one of {ELEMENTS:?}, got {value}")]
    Mesh {
        /// The file.
        path: String,
        /// The value given.
        value: usize,
    },
    /// A value is not physical.
    #[error("{context}")]
    Invalid {
        /// Where the values came from.
        context: String,
        /// The rule broken.
        #[source]
        source: model_core::ParamError,
    },
}

impl ModelFile {
    /// `main.m`'s preset ([`Params::main_m_2006`]), the default of every
    /// command.
    pub fn main_m_2006() -> ModelFile {
        ModelFile::preset(Preset::MainM2006)
    }

    /// A preset of the seed. Both share the sample's materials; Table 4-2's
    /// thinner core (0.28 mm) is geometry, which recordings state.
    pub fn preset(preset: Preset) -> ModelFile {
        let p = preset.params();
        let lam = Laminate::THESIS_2006;
        ModelFile {
            electrical: Electrical {
                r1_ohm: p.r1_ohm,
                r2_ohm: p.r2_ohm,
                c_f: p.c_f,
            },
            relaxation: Relaxation {
                a_nm_per_c: p.a_nm_per_c,
                b_nm_per_c_s: p.b_nm_per_c_s,
                p_per_s: p.p_per_s,
            },
            material: Material {
                core_modulus_pa: lam.core_modulus_pa,
                film_modulus_pa: lam.film_modulus_pa,
                core_density_kg_per_m3: lam.core_density_kg_per_m3,
                film_density_kg_per_m3: lam.film_density_kg_per_m3,
                film_thickness_m: lam.film_thickness_m,
            },
            beam: None,
            extensions: None,
            mesh: None,
        }
    }

    /// Reads and checks a parameter file.
    pub fn read(path: &Path) -> Result<ModelFile, ParamsError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ParamsError::Io {
            path: name.clone(),
            source,
        })?;
        Self::parse(&name, &text)
    }

    /// Parses and checks the text of a parameter file.
    pub fn parse(name: &str, text: &str) -> Result<ModelFile, ParamsError> {
        let file: ModelFile = toml::from_str(text).map_err(|e| ParamsError::Syntax {
            path: name.to_string(),
            message: e.to_string().trim_end().to_string(),
        })?;
        // Check against the preset's geometry so that a bad value is named
        // now, not at the first recording.
        file.params_for(&Geometry::THESIS_2006)
            .map_err(|e| match e {
                ParamsError::Invalid { source, .. } => ParamsError::Invalid {
                    context: name.to_string(),
                    source,
                },
                other => other,
            })?;
        if let Some(m) = file.mesh {
            if !ELEMENTS.contains(&m.elements_per_segment) {
                return Err(ParamsError::Mesh {
                    path: name.to_string(),
                    value: m.elements_per_segment,
                });
            }
        }
        Ok(file)
    }

    /// The file's TOML text.
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).expect("plain numbers always serialise");
        format!("# finrs model parameters, SI units\n{body}")
    }

    /// The laminate of this material with a recording's geometry.
    pub fn laminate(&self, g: &Geometry) -> Laminate {
        Laminate {
            width_m: g.width_m,
            core_thickness_m: g.thickness_m - 2.0 * self.material.film_thickness_m,
            film_thickness_m: self.material.film_thickness_m,
            core_modulus_pa: self.material.core_modulus_pa,
            film_modulus_pa: self.material.film_modulus_pa,
            core_density_kg_per_m3: self.material.core_density_kg_per_m3,
            film_density_kg_per_m3: self.material.film_density_kg_per_m3,
        }
    }

    /// The model's parameters for a strip of geometry `g`, validated.
    pub fn params_for(&self, g: &Geometry) -> Result<Params, ParamsError> {
        let invalid = |source| ParamsError::Invalid {
            context: format!(
                "strip of length {} m, width {} m, thickness {} m",
                g.length_m, g.width_m, g.thickness_m
            ),
            source,
        };
        let lam = self.laminate(g);
        lam.validate().map_err(invalid)?;
        let (ei_nm2, mass_per_length_kg_per_m) = match self.beam {
            Some(b) => (b.ei_nm2, b.mass_per_length_kg_per_m),
            None => (lam.ei_nm2(), lam.mass_per_length_kg_per_m()),
        };
        let p = Params {
            r1_ohm: self.electrical.r1_ohm,
            r2_ohm: self.electrical.r2_ohm,
            c_f: self.electrical.c_f,
            a_nm_per_c: self.relaxation.a_nm_per_c,
            b_nm_per_c_s: self.relaxation.b_nm_per_c_s,
            p_per_s: self.relaxation.p_per_s,
            length_m: g.length_m,
            ei_nm2,
            mass_per_length_kg_per_m,
        };
        let ext = self.extensions.clone().unwrap_or_default();
        p.validate_relaxation(ext.back_relaxation)
            .map_err(invalid)?;
        ext.core().and_then(|c| c.validate()).map_err(invalid)?;
        for (field, value) in [
            ("dehydration_per_s", ext.dehydration_per_s),
            ("dehydration_curvature", ext.dehydration_curvature),
            ("circuit_drying_per_s", ext.circuit_drying_per_s),
        ] {
            if !value.is_finite() {
                return Err(invalid(model_core::ParamError::NotFinite { field, value }));
            }
            if value < 0.0 {
                return Err(invalid(model_core::ParamError::OutOfRange {
                    field,
                    value,
                    min: 0.0,
                    max: f64::INFINITY,
                }));
            }
        }
        Ok(p)
    }

    /// The whole model for a strip of geometry `g`: parameters, optional
    /// terms and dehydration rate, validated.
    pub fn spec_for(&self, g: &Geometry) -> Result<ModelSpec, ParamsError> {
        let params = self.params_for(g)?;
        let ext = self.extensions.clone().unwrap_or_default();
        let core = ext.core().map_err(|source| ParamsError::Invalid {
            context: "[extensions]".to_string(),
            source,
        })?;
        Ok(ModelSpec {
            params,
            ext: core,
            dehydration_per_s: ext.dehydration_per_s,
            dehydration_curvature: ext.dehydration_curvature,
            circuit_drying_per_s: ext.circuit_drying_per_s,
            // A bench's, not a parameter file's: the fit finds it.
            sensors_before_update: false,
        })
    }
}

/// A term left out of a written file where it is off (files written before
/// it existed read the same).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error;

    #[test]
    fn presets_round_trip_and_match_the_core() {
        for preset in Preset::ALL {
            assert_eq!(Preset::parse(preset.name()), Some(preset));
            let f = ModelFile::preset(preset);
            let back = ModelFile::parse("preset.toml", &f.to_toml()).unwrap();
            assert_eq!(back, f);
            let p = back.params_for(&Geometry::THESIS_2006).unwrap();
            let core = preset.params();
            assert_eq!(
                (p.r1_ohm, p.r2_ohm, p.c_f),
                (core.r1_ohm, core.r2_ohm, core.c_f)
            );
            assert_eq!(
                (p.a_nm_per_c, p.b_nm_per_c_s, p.p_per_s),
                (core.a_nm_per_c, core.b_nm_per_c_s, core.p_per_s)
            );
        }
        // main.m's sample is the recordings' geometry: the same beam.
        let p = ModelFile::main_m_2006()
            .params_for(&Geometry::THESIS_2006)
            .unwrap();
        let core = Params::main_m_2006();
        assert!((p.ei_nm2 / core.ei_nm2 - 1.0).abs() < 1e-12);
        assert!((p.mass_per_length_kg_per_m / core.mass_per_length_kg_per_m - 1.0).abs() < 1e-12);
        assert_eq!(Preset::parse("thesis_2006"), None);
    }

    #[test]
    fn old_relaxation_keys_are_named() {
        let text = ModelFile::main_m_2006()
            .to_toml()
            .replace("a_nm_per_c = 0.0", "k_nm_per_c = 4.87");
        let err = ModelFile::parse("old.toml", &text).unwrap_err().to_string();
        assert!(
            err.starts_with("old.toml:") && err.contains("k_nm_per_c"),
            "{err}"
        );
    }

    #[test]
    fn unknown_and_missing_fields_are_named() {
        let text = ModelFile::main_m_2006()
            .to_toml()
            .replace("r1_ohm", "r1_ohms");
        let err = ModelFile::parse("p.toml", &text).unwrap_err().to_string();
        assert!(
            err.starts_with("p.toml:") && err.contains("r1_ohms"),
            "{err}"
        );
        let text = ModelFile::main_m_2006()
            .to_toml()
            .replace("c_f = 0.0001\n", "");
        let err = ModelFile::parse("p.toml", &text).unwrap_err().to_string();
        assert!(err.contains("c_f"), "{err}");
    }

    #[test]
    fn non_physical_values_are_refused_by_name() {
        let text = ModelFile::main_m_2006()
            .to_toml()
            .replace("b_nm_per_c_s = 0.487", "b_nm_per_c_s = -0.5");
        let err = ModelFile::parse("p.toml", &text).unwrap_err();
        // The file is the message, the rule its source: each said once.
        assert_eq!(err.to_string(), "p.toml");
        let rule = err.source().unwrap().to_string();
        assert!(
            rule.starts_with("b_nm_per_c_s must be positive") && rule.contains("back-relaxation"),
            "{rule}"
        );
        let f = ModelFile::main_m_2006();
        let thin = Geometry {
            thickness_m: 3e-6,
            ..Geometry::THESIS_2006
        };
        let err = f.params_for(&thin).unwrap_err();
        assert!(err.to_string().starts_with("strip of length"), "{err}");
        let rule = err.source().unwrap().to_string();
        assert!(rule.contains("core_thickness_m must be positive"), "{rule}");
    }

    /// The message and its causes, as the binary prints them.
    fn said(e: &dyn Error) -> String {
        let mut s = e.to_string();
        let mut cause = e.source();
        while let Some(c) = cause {
            s = format!("{s}: {c}");
            cause = c.source();
        }
        s
    }

    #[test]
    fn segment_deviations_round_trip_and_are_refused_by_segment() {
        let mut ext = model_core::Extensions::NONE;
        ext.segment_variation.k_deviation[2] = -0.1;
        ext.segment_variation.r1_deviation[1] = 0.05;
        let mut f = ModelFile::main_m_2006();
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 0.0, 0.0, 0.0));
        let text = f.to_toml();
        assert!(
            text.contains("segment_k_deviation = [0.0, 0.0, -0.1]")
                && !text.contains("segment_c_deviation"),
            "{text}"
        );
        let back = ModelFile::parse("p.toml", &text).unwrap();
        let spec = back.spec_for(&Geometry::THESIS_2006).unwrap();
        assert_eq!(spec.ext, ext);
        let err = ModelFile::parse(
            "p.toml",
            &text.replace("[0.0, 0.0, -0.1]", "[0.1, 0.0, -0.1]"),
        )
        .unwrap_err();
        let err = said(&err);
        assert!(
            err.starts_with("p.toml: k_deviation of segment 1 is 0.1: segment 1 is the reference"),
            "{err}"
        );
        let err = ModelFile::parse(
            "p.toml",
            &text.replace("[0.0, 0.0, -0.1]", &format!("{:?}", [0.0; 9])),
        )
        .unwrap_err();
        let err = said(&err);
        assert!(
            err.contains("segment_k_deviation of segment 9") && err.contains("at most 8"),
            "{err}"
        );
    }

    #[test]
    fn modal_damping_round_trips_and_a_long_list_is_refused() {
        let mut ext = model_core::Extensions::NONE;
        // The held strip's first mode undamped, the second and every one
        // above it at 5 %; the free strip undamped.
        ext.modal_damping.blocked[1..].fill(0.05);
        let mut f = ModelFile::main_m_2006();
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 0.0, 0.0, 0.0));
        let text = f.to_toml();
        assert!(
            text.contains("modal_damping_blocked = [0.0, 0.05]")
                && !text.contains("modal_damping_free"),
            "{text}"
        );
        let back = ModelFile::parse("p.toml", &text).unwrap();
        assert_eq!(back.spec_for(&Geometry::THESIS_2006).unwrap().ext, ext);
        let long = format!("{:?}", [0.0; model_core::DAMPED_MODES + 1]);
        let err = ModelFile::parse("p.toml", &text.replace("[0.0, 0.05]", &long)).unwrap_err();
        let err = said(&err);
        assert!(
            err.contains("modal_damping_blocked lists 9 values, the model has 8"),
            "{err}"
        );
        let err = ModelFile::parse("p.toml", &text.replace("0.05]", "-0.05]")).unwrap_err();
        let err = said(&err);
        assert!(err.contains("modal_damping.blocked"), "{err}");
    }

    #[test]
    fn the_reaction_round_trips_and_an_out_of_range_tafel_voltage_is_refused() {
        let mut ext = model_core::Extensions::NONE;
        // Off, a written file says nothing of it.
        let mut f = ModelFile::main_m_2006();
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 0.0, 0.0, 0.0));
        assert!(!f.to_toml().contains("reaction"), "{}", f.to_toml());
        ext.reaction_ratio = 0.5;
        ext.reaction_ref_v = 1.6;
        ext.reaction_tafel_v = 0.05;
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 0.0, 0.0, 0.0));
        let text = f.to_toml();
        let back = ModelFile::parse("p.toml", &text).unwrap();
        assert_eq!(back.spec_for(&Geometry::THESIS_2006).unwrap().ext, ext);
        let steep = text.replace("reaction_tafel_v = 0.05", "reaction_tafel_v = 0.001");
        let err = ModelFile::parse("p.toml", &steep)
            .and_then(|f| f.spec_for(&Geometry::THESIS_2006).map(|_| ()));
        let err = said(&err.unwrap_err());
        assert!(err.contains("reaction_tafel_v"), "{err}");
    }

    #[test]
    fn the_circuits_drying_round_trips_and_a_negative_rate_is_refused() {
        let ext = model_core::Extensions::NONE;
        let mut f = ModelFile::main_m_2006();
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 1e-3, 0.5, 0.0));
        assert!(!f.to_toml().contains("circuit_drying"), "{}", f.to_toml());
        f.extensions = Some(ExtensionsFile::from_spec(&ext, 1e-3, 0.5, 2e-3));
        let text = f.to_toml();
        let spec = ModelFile::parse("p.toml", &text)
            .and_then(|f| f.spec_for(&Geometry::THESIS_2006))
            .unwrap();
        assert_eq!(
            (spec.dehydration_per_s, spec.circuit_drying_per_s),
            (1e-3, 2e-3)
        );
        let wetter = text.replace(
            "circuit_drying_per_s = 0.002",
            "circuit_drying_per_s = -0.002",
        );
        let err = ModelFile::parse("p.toml", &wetter)
            .and_then(|f| f.spec_for(&Geometry::THESIS_2006).map(|_| ()));
        let err = said(&err.unwrap_err());
        assert!(err.contains("circuit_drying_per_s"), "{err}");
    }

    #[test]
    fn the_mesh_round_trips_and_one_the_model_lacks_is_refused() {
        let mut f = ModelFile::main_m_2006();
        assert!(!f.to_toml().contains("[mesh]"));
        f.mesh = Some(Mesh {
            elements_per_segment: 4,
        });
        let text = f.to_toml();
        assert!(text.contains("[mesh]\nelements_per_segment = 4"), "{text}");
        assert_eq!(ModelFile::parse("p.toml", &text).unwrap(), f);
        let err = ModelFile::parse("p.toml", &text.replace("= 4", "= 3")).unwrap_err();
        assert_eq!(
            said(&err),
            "p.toml: [mesh] elements_per_segment must be one of [1, 2, 4], got 3"
        );
    }
}
