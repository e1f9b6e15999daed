//! `model-core`: the segmented IPMC strip of the seed thesis (chapter 2),
//! `no_std`, allocation-free and fixed-size.
//!
//! Per segment an RC circuit (eq. 2.1–2.2) charges the double layer; a
//! relaxation lead network (eq. 2.3) turns charge into a bending moment; the
//! moments drive a Hermite-cubic finite-element Euler–Bernoulli cantilever
//! (eq. 2.14–2.19). [`Strip`] assembles the whole (eq. 2.28) and discretises it
//! exactly for a fixed sample time, so the same code steps the model on a PC,
//! in QEMU and on the Cortex-M4F board.
//!
//! ```
//! use model_core::{Fixture, Params, Strip};
//! let p = Params::main_m_2006();
//! let blocked = Strip::<f32, 3, 1, 18>::new(&p, Fixture::Blocked, 1e-3).unwrap();
//! let mut x = blocked.rest();
//! for _ in 0..100 {
//!     blocked.step(&mut x, &[2.5; 3]);
//! }
//! assert!(blocked.blocking_force_n(&x) > 0.0);
//! ```
#![no_std]
#![deny(missing_docs, unsafe_code)]

mod beam;
mod beam_modes;
mod circuit;
mod drying;
mod extensions;
pub mod matrix;
mod params;
mod phasor;
mod reaction;
mod real;
mod rounding;
mod shape;
mod strip;
pub mod zoh;

pub use beam_modes::BeamModes;
pub use circuit::Circuit;
pub use drying::drying_gain;
pub use extensions::{Extensions, ModalDamping, SegmentVariation, DAMPED_MODES, MAX_SEGMENTS};
pub use params::{Laminate, ParamError, Params};
pub use phasor::Phasor;
pub use reaction::Reaction;
pub use real::Real;
pub use shape::Shape;
pub use strip::{
    state_len, Fixture, Harmonic, HarmonicError, StepError, Strip, TipStep, DRAGGED_MODES,
};
