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
//! That is the *ideal* rig, the baseline's own class. The *off-class* rig
//! ([`Sample::draw_off_class`], [`Hidden::draw_off_class`]) is what real
//! strips are: always damped, softer than the laminate, relaxing or
//! creeping, with segments that may differ and crosstalk through a lag; and
//! a [`Bench`] adds what real benches have: hum, 1/f noise, a load cell
//! that gives, camera exposure. [`expect`] says, for each, what a right
//! diagnosis names, written from the contract before any tuning.
//!
//! The *lab-like* bench ([`lab`], [`write_lab`]) is what real labs add
//! besides: the strip's own curl and the sensors' wandering zeros (drift),
//! dropouts and out-of-range stretches, quantised channels, the voltage
//! as a DAQ reads it back, contact faults, recordings that carry the last
//! one's state over, a moment that differs by sign; and the lab's own
//! protocol (one segment, steps held for minutes, 100 rows/s, a laser).
//!
//! The *literature* strip ([`literature`]) is the one the fit does not
//! share: electrodes as resistive lines, electrolysis above its onset, a
//! viscoelastic relaxation spectrum, drying by water content, a free strip
//! of large rotation ([`rotation`]), metadata measured a few percent off;
//! with a protocol drawn per session ([`protocols`]) and each departure
//! over a range of strengths.
//!
//! ```no_run
//! use rand::SeedableRng;
//! let mut rng = rand::rngs::StdRng::seed_from_u64(7);
//! let sample = finrs_rig::Sample::draw(&mut rng);
//! let hidden = finrs_rig::Hidden::draw(&["damping"], &mut rng).unwrap();
//! let sensors = finrs_rig::Sensors::draw(&mut rng);
//! finrs_rig::write_session(
//!     std::path::Path::new("out/rig"), &sample, &hidden, &sensors,
//!     &finrs_rig::Bench::default(), &finrs_rig::protocol(), "RIG-7", &mut rng,
//! ).unwrap();
//! ```
#![deny(missing_docs)]

pub mod beam;
pub mod bench;
pub mod coverage;
pub mod expect;
pub mod heatmap;
pub mod lab;
pub mod lab_session;
pub mod literature;
pub mod protocols;
pub mod rotation;
pub mod runner;
pub mod sample;
pub mod session;
pub mod strip;
pub mod sweep;
pub mod trivial;

pub use beam::Tip;
pub use bench::{Bench, IMPERFECTIONS};
pub use expect::{expected, score, Expected, Protocol, Score};
pub use lab::{LabBench, LabProtocol, DRIFT, LAB_ARTEFACTS};
pub use lab_session::{write_lab, Layout, Tracker};
pub use sample::{
    Hidden, Sample, SegmentFactors, Water, CATALOGUE, OFF_CLASS_DEPARTURES, OUTSIDE,
    SEGMENT_VARIATION,
};
pub use session::{board_protocol, protocol, short_protocol, write as write_session, Run, Sensors};
