//! `finrs`: host tools for segmented IPMC fins.
//!
//! The command line in `main.rs` is a thin layer over this library: every
//! command is a function here, so that tests call the same code users run.
#![deny(missing_docs)]

pub mod capture;
pub mod command;
pub mod diagnose;
pub mod fit;
pub mod params;
pub mod plot;
pub mod predict;
pub mod probe;
pub mod recording;
pub mod seed_check;
pub mod session;
pub mod simulate;
pub mod stream;
pub mod synth;
pub mod wave;
