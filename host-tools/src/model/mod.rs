//! What the model predicts: its parameter file ([`params`]), the engine's
//! traces for a recording's drive ([`predict`]), those traces as a
//! recording ([`simulate`]) and drives made from waves ([`synth`]).

mod drying;
mod kept_modes;
pub mod motion;
pub mod params;
pub mod predict;
mod recent;
pub mod simulate;
pub mod synth;
