//! The fitted strip model as the board holds it: what `finrs tune` sends in
//! a SetModel command, what the board stores in flash and names (by its
//! CRC) in the Info frame, and from which it shapes motion waves.
//!
//! On the wire every value is an `f32` (the board's model runs in `f32`,
//! and 7 digits are finer than any fit's interval); the host shapes its
//! own twin from the same rounded values ([`ModelRecord::decode`] of the
//! record it sends), so that host and board invert the same numbers.
//!
//! ```
//! use finrs_frames::{ModelRecord, StripModel};
//! use model_core::{Extensions, Params};
//!
//! let m = StripModel {
//!     params: Params::main_m_2006(),
//!     extensions: Extensions { damping_ratio: 0.05, ..Extensions::NONE },
//!     dehydration_per_s: 1e-4,
//!     dehydration_curvature: 0.0,
//! };
//! let record = ModelRecord::encode(&m);
//! let back = record.decode().unwrap();
//! // Each value as its nearest f32.
//! assert_eq!(back.params.r1_ohm, 160.0);
//! assert_eq!(back.extensions.damping_ratio, f64::from(0.05f32));
//! assert_eq!(ModelRecord::encode(&back), record);
//! ```

use core::fmt;

use model_core::{Extensions, ModalDamping, Params, SegmentVariation};

use crate::crc16;

/// The record's layout version, its first byte: 3 since the reaction's
/// three values were appended (2 added the quadratic drag; a record of an
/// older layout, stored by an older firmware, is refused by its version,
/// not read with values missing).
pub const MODEL_FORMAT: u8 = 3;

/// Values in a record (each an `f32`): the strip's 9 parameters, the
/// extensions' 48, the drying's 2, the quadratic drag and the reaction's
/// 3, in [`MODEL_FIELD_NAMES`]' order.
pub const MODEL_FIELDS: usize = 63;

/// Bytes of a [`ModelRecord`]: the layout version u8, the flags u8
/// (bit 0 back-relaxation, bit 1 large deflection), then
/// [`MODEL_FIELDS`] little-endian `f32`.
pub const MODEL_RECORD_LEN: usize = 2 + 4 * MODEL_FIELDS;

const FLAG_BACK_RELAXATION: u8 = 1 << 0;
const FLAG_LARGE_DEFLECTION: u8 = 1 << 1;
const KNOWN_FLAGS: u8 = FLAG_BACK_RELAXATION | FLAG_LARGE_DEFLECTION;

/// Each value's name, in the record's order (as a fit file names them).
pub const MODEL_FIELD_NAMES: [&str; MODEL_FIELDS] = [
    "r1_ohm",
    "r2_ohm",
    "c_f",
    "a_nm_per_c",
    "b_nm_per_c_s",
    "p_per_s",
    "length_m",
    "ei_nm2",
    "mass_per_length_kg_per_m",
    "damping_mass_per_s",
    "damping_stiffness_s",
    "damping_ratio",
    "modal_damping.free[0]",
    "modal_damping.free[1]",
    "modal_damping.free[2]",
    "modal_damping.free[3]",
    "modal_damping.free[4]",
    "modal_damping.free[5]",
    "modal_damping.free[6]",
    "modal_damping.free[7]",
    "modal_damping.blocked[0]",
    "modal_damping.blocked[1]",
    "modal_damping.blocked[2]",
    "modal_damping.blocked[3]",
    "modal_damping.blocked[4]",
    "modal_damping.blocked[5]",
    "modal_damping.blocked[6]",
    "modal_damping.blocked[7]",
    "added_mass_kg_per_m",
    "drag_n_s_per_m2",
    "charge_cubic_per_v2",
    "leak_cubic_per_v2",
    "crosstalk",
    "segment_variation.r1_deviation[0]",
    "segment_variation.r1_deviation[1]",
    "segment_variation.r1_deviation[2]",
    "segment_variation.r1_deviation[3]",
    "segment_variation.r1_deviation[4]",
    "segment_variation.r1_deviation[5]",
    "segment_variation.r1_deviation[6]",
    "segment_variation.r1_deviation[7]",
    "segment_variation.c_deviation[0]",
    "segment_variation.c_deviation[1]",
    "segment_variation.c_deviation[2]",
    "segment_variation.c_deviation[3]",
    "segment_variation.c_deviation[4]",
    "segment_variation.c_deviation[5]",
    "segment_variation.c_deviation[6]",
    "segment_variation.c_deviation[7]",
    "segment_variation.k_deviation[0]",
    "segment_variation.k_deviation[1]",
    "segment_variation.k_deviation[2]",
    "segment_variation.k_deviation[3]",
    "segment_variation.k_deviation[4]",
    "segment_variation.k_deviation[5]",
    "segment_variation.k_deviation[6]",
    "segment_variation.k_deviation[7]",
    "dehydration_per_s",
    "dehydration_curvature",
    "drag_quadratic_n_s2_per_m3",
    "reaction_ratio",
    "reaction_ref_v",
    "reaction_tafel_v",
];

/// A fitted strip: the seed's parameters, the extensions the diagnosis
/// added, and how fast the moment dries (the gain tracker's prior).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StripModel {
    /// The seed's parameters, SI.
    pub params: Params,
    /// The terms beyond the baseline (all off: the seed's model).
    pub extensions: Extensions,
    /// Dehydration: the rate `r` at which the moment gain falls, 1/s.
    pub dehydration_per_s: f64,
    /// How drying slows as the strip loses its water, `c ≥ 0`.
    pub dehydration_curvature: f64,
}

/// A [`StripModel`] in its wire and flash form: [`MODEL_RECORD_LEN`]
/// bytes. Carried as is by the SetModel command; [`decode`](Self::decode)
/// checks the layout, the model's own rules are the model's to check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ModelRecord(pub [u8; MODEL_RECORD_LEN]);

/// Why a record is not a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormatError {
    /// The layout version is not [`MODEL_FORMAT`].
    Version(u8),
    /// Flag bits this layout does not define are set.
    Flags(u8),
    /// A value is NaN or infinite (its name).
    NotFinite(&'static str),
}

impl fmt::Display for ModelFormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Version(v) => write!(
                f,
                "model record layout {v}, this firmware reads {MODEL_FORMAT}"
            ),
            Self::Flags(b) => write!(
                f,
                "model record flags {b:#04x}: only bits 0 and 1 are defined"
            ),
            Self::NotFinite(name) => write!(f, "model record: `{name}` is not a finite number"),
        }
    }
}

impl core::error::Error for ModelFormatError {}

impl ModelRecord {
    /// The record of `m`, each value rounded to the nearest `f32`.
    pub fn encode(m: &StripModel) -> ModelRecord {
        let mut b = [0u8; MODEL_RECORD_LEN];
        let e = &m.extensions;
        b[0] = MODEL_FORMAT;
        b[1] = if e.back_relaxation {
            FLAG_BACK_RELAXATION
        } else {
            0
        } | if e.large_deflection {
            FLAG_LARGE_DEFLECTION
        } else {
            0
        };
        for (k, v) in values(m).iter().enumerate() {
            b[2 + 4 * k..6 + 4 * k].copy_from_slice(&(*v as f32).to_le_bytes());
        }
        ModelRecord(b)
    }

    /// The model the record holds.
    pub fn decode(&self) -> Result<StripModel, ModelFormatError> {
        let b = &self.0;
        if b[0] != MODEL_FORMAT {
            return Err(ModelFormatError::Version(b[0]));
        }
        if b[1] & !KNOWN_FLAGS != 0 {
            return Err(ModelFormatError::Flags(b[1]));
        }
        let mut v = [0.0f64; MODEL_FIELDS];
        for (k, x) in v.iter_mut().enumerate() {
            let f = f32::from_le_bytes([b[2 + 4 * k], b[3 + 4 * k], b[4 + 4 * k], b[5 + 4 * k]]);
            if !f.is_finite() {
                return Err(ModelFormatError::NotFinite(MODEL_FIELD_NAMES[k]));
            }
            *x = f64::from(f);
        }
        Ok(from_values(
            &v,
            b[1] & FLAG_BACK_RELAXATION != 0,
            b[1] & FLAG_LARGE_DEFLECTION != 0,
        ))
    }

    /// CRC-16 of the record: the Info frame names the model in force by it.
    pub fn crc(&self) -> u16 {
        crc16(&self.0)
    }
}

/// `m`'s values in the record's order.
fn values(m: &StripModel) -> [f64; MODEL_FIELDS] {
    let (p, e) = (&m.params, &m.extensions);
    let mut v = [0.0; MODEL_FIELDS];
    let head = [
        p.r1_ohm,
        p.r2_ohm,
        p.c_f,
        p.a_nm_per_c,
        p.b_nm_per_c_s,
        p.p_per_s,
        p.length_m,
        p.ei_nm2,
        p.mass_per_length_kg_per_m,
        e.damping_mass_per_s,
        e.damping_stiffness_s,
        e.damping_ratio,
    ];
    v[..12].copy_from_slice(&head);
    v[12..20].copy_from_slice(&e.modal_damping.free);
    v[20..28].copy_from_slice(&e.modal_damping.blocked);
    v[28..33].copy_from_slice(&[
        e.added_mass_kg_per_m,
        e.drag_n_s_per_m2,
        e.charge_cubic_per_v2,
        e.leak_cubic_per_v2,
        e.crosstalk,
    ]);
    let sv = &e.segment_variation;
    v[33..41].copy_from_slice(&sv.r1_deviation);
    v[41..49].copy_from_slice(&sv.c_deviation);
    v[49..57].copy_from_slice(&sv.k_deviation);
    v[57] = m.dehydration_per_s;
    v[58] = m.dehydration_curvature;
    v[59] = e.drag_quadratic_n_s2_per_m3;
    v[60..63].copy_from_slice(&[e.reaction_ratio, e.reaction_ref_v, e.reaction_tafel_v]);
    v
}

/// The model of [`values`]' order.
fn from_values(
    v: &[f64; MODEL_FIELDS],
    back_relaxation: bool,
    large_deflection: bool,
) -> StripModel {
    let eight = |at: usize| -> [f64; 8] { core::array::from_fn(|k| v[at + k]) };
    StripModel {
        params: Params {
            r1_ohm: v[0],
            r2_ohm: v[1],
            c_f: v[2],
            a_nm_per_c: v[3],
            b_nm_per_c_s: v[4],
            p_per_s: v[5],
            length_m: v[6],
            ei_nm2: v[7],
            mass_per_length_kg_per_m: v[8],
        },
        extensions: Extensions {
            damping_mass_per_s: v[9],
            damping_stiffness_s: v[10],
            damping_ratio: v[11],
            modal_damping: ModalDamping {
                free: eight(12),
                blocked: eight(20),
            },
            added_mass_kg_per_m: v[28],
            drag_n_s_per_m2: v[29],
            drag_quadratic_n_s2_per_m3: v[59],
            charge_cubic_per_v2: v[30],
            leak_cubic_per_v2: v[31],
            reaction_ratio: v[60],
            reaction_ref_v: v[61],
            reaction_tafel_v: v[62],
            crosstalk: v[32],
            back_relaxation,
            large_deflection,
            segment_variation: SegmentVariation {
                r1_deviation: eight(33),
                c_deviation: eight(41),
                k_deviation: eight(49),
            },
        },
        dehydration_per_s: v[57],
        dehydration_curvature: v[58],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every_field_distinct() -> StripModel {
        // Each value its own index + 1: a field written to the wrong place
        // comes back as another's number.
        let v: [f64; MODEL_FIELDS] = core::array::from_fn(|k| (k + 1) as f64);
        from_values(&v, true, false)
    }

    #[test]
    fn each_value_keeps_its_place() {
        let m = every_field_distinct();
        let back = ModelRecord::encode(&m).decode().unwrap();
        assert_eq!(back, m);
        assert_eq!(values(&back), core::array::from_fn(|k| (k + 1) as f64));
        assert!(back.extensions.back_relaxation && !back.extensions.large_deflection);
    }

    #[test]
    fn a_bad_record_names_what_is_wrong() {
        let mut r = ModelRecord::encode(&every_field_distinct());
        r.0[0] = 9;
        assert_eq!(r.decode(), Err(ModelFormatError::Version(9)));
        r.0[0] = MODEL_FORMAT;
        r.0[1] = 0x84;
        assert_eq!(r.decode(), Err(ModelFormatError::Flags(0x84)));
        r.0[1] = 0;
        // The value of field 32, crosstalk.
        r.0[2 + 4 * 32..6 + 4 * 32].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(r.decode(), Err(ModelFormatError::NotFinite("crosstalk")));
    }

    #[test]
    fn the_crc_tells_records_apart() {
        let a = ModelRecord::encode(&every_field_distinct());
        let mut b = a;
        b.0[100] ^= 1;
        assert_ne!(a.crc(), b.crc());
    }
}
