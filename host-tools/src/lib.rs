//! `finrs`: host tools for segmented IPMC fins.
//!
//! The command line in `main.rs` is a thin layer over this library: every
//! command is a function here, so that tests call the same code users run.
//!
//! The modules are layered; each imports only from layers below it
//! (`scripts/module-graph` checks this, and `cargo test` runs it):
//! - [`recording`] (the `ipmc-bench/1` format) and [`wave`] (the `--wave`
//!   syntax on the firmware's generator), at the bottom;
//! - [`session`] (the recordings of one sample), [`camera`] (a
//!   tracker's dots merged into a free recording) and [`import`] (a
//!   lab's own exports made recordings);
//! - [`model`] (parameters, prediction, simulation, drives from waves),
//!   [`link`] (probe, force stream, commands to the firmware), [`plot`]
//!   and [`protocol`] (the recordings a session is to hold);
//! - [`analysis`] (fit, diagnosis, the seed's check and the plan of
//!   further recordings) and [`bench`] (a
//!   session's protocol run against the board), on top.
#![deny(missing_docs)]

pub mod analysis;
pub mod bench;
pub mod camera;
pub mod import;
pub mod link;
pub mod model;
pub mod plot;
pub mod protocol;
pub mod recording;
pub mod session;
pub mod wave;
