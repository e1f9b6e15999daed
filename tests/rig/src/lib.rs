//! `finrs-rig`: a synthetic bench for testing `finrs diagnose`.
//!
//! The rig is not the model the fit uses. Its free strip has a finer mesh
//! ([`strip::MESH`]; the blocked one pins the tip and keeps the fitted
//! mesh, [`strip::BLOCKED_MESH`], whose undamped force would not converge),
//! its own integrator (Runge–Kutta electrics, exact modal beam with
//! first-order hold), and its effects come in forms the fitted extensions
//! only approximate: constant modal damping, quadratic drag, a `sinh` leak
//! and voltage-dependent capacitance, a second relaxation branch,
//! hyperbolic drying, crosstalk from the neighbours' charge (instantaneous,
//! without their relaxation); and mains pickup, outside the catalogue. Its
//! sensors are the example session's: noise, 30 frames/s in whole pixels of
//! 0.109 mm against a 1 kHz DAQ, rest offsets.
//!
//! ```no_run
//! use rand::SeedableRng;
//! let mut rng = rand::rngs::StdRng::seed_from_u64(7);
//! let sample = finrs_rig::Sample::draw(&mut rng);
//! let hidden = finrs_rig::Hidden::draw(&["damping"], &mut rng).unwrap();
//! let sensors = finrs_rig::Sensors::draw(&mut rng);
//! finrs_rig::write_session(
//!     std::path::Path::new("out/rig"), &sample, &hidden, &sensors,
//!     &finrs_rig::protocol(), "RIG-7", &mut rng,
//! ).unwrap();
//! ```
#![deny(missing_docs)]

pub mod beam;
pub mod sample;
pub mod session;
pub mod strip;

pub use sample::{Hidden, Sample, Water, CATALOGUE, OUTSIDE};
pub use session::{protocol, short_protocol, write as write_session, Run, Sensors};
