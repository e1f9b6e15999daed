//! `finrs diagnose`: what the baseline gets wrong in a session, which
//! effects of the catalogue explain it, and how much they gain on
//! recordings the fit did not see.
//!
//! The session is split: about a third of the recordings (every third,
//! from the second, keeping each kind's first and last run in the
//! training part) are held out. The baseline is fitted on the rest; then each effect of the
//! catalogue is added in turn and fitted. An effect is accepted only when
//! the evidence punishing its extra parameters favours it strongly
//! (`ΔBIC < −10` on the training part) *and* it lowers the held-out error
//! (weighted residual sum of squares by at least 1 %) *and* the term that
//! makes it that effect is significant (its interval excludes "off", at a
//! level that keeps the chance of any of the search's candidates passing
//! on noise alone at [`FAMILY_ALPHA`]:
//! hydrodynamic loading needs added mass, since its drag alone is
//! damping; back-relaxation needs the zero below zero). Of the effects
//! that pass, the one with the lowest held-out error joins the model, or
//! where the held-out part cannot tell passing effects apart, the one the
//! session's evidence calls for ([`choose`]). The model that joined is
//! fitted again from the data's own start, and the better of its two fits
//! is kept: a fit that starts from the model so far can stop in a corner
//! the earlier terms bent toward. The search repeats on top of it, so
//! several causes can be named, strongest first. The verdict:
//! - `none`: nothing accepted and the held-out residuals of every sensor
//!   (currents, load cell, camera: [`floors`]) are at its noise floor
//!   (weighted RSS per residual below [`NOISE_FLOOR_RATIO`]);
//! - `explained`: effects accepted and every sensor at its noise floor;
//! - `unexplained`: a sensor above its noise floor after the best model
//!   (the verdict names it and its worst channel), with the
//!   effects that did pass (possibly none); or the DAQ's channels already
//!   carry structure while the strip rests before its drive (most
//!   rests fail a Ljung–Box test) that no bench finding accounts for:
//!   every candidate is driven by the voltage, so nothing in the
//!   catalogue can account for that.
//!
//! Bench imperfections are not model effects: mains hum and coloured
//! sensor noise, seen in the opening rests ([`rests`]), and drift, the
//! strip's own curl or a sensor's wandering zero, fitted beside every
//! model on each measured channel ([`drift`]), are reported
//! as bench findings beside the verdict, never as a catalogue name; so
//! are the bench's faults found in the data when the session is read
//! (contact faults, out-of-range stretches, clipped sensors: [`faults`]),
//! whose samples no fit sees.

pub mod analyses;
pub mod choose;
pub mod drift;
mod drying;
pub mod faults;
pub mod floors;
mod gates;
pub mod identify;
mod reaction;
pub mod report;
pub mod rests;
mod search;
pub mod structure;
mod verdict;
pub mod whiteness;

pub use faults::FaultFinding;
pub use floors::{sensor_floors, SensorFloor, NOISE_FLOOR_RATIO};
pub use gates::{DELTA_BIC, FAMILY_ALPHA, HOLDOUT_RSS_GAIN};
pub use rests::{rest_structure, BenchFinding, RestStructure, REST_STRUCTURE_SHARE};
pub use search::{diagnose, split, tested_channels, untestable, MAX_CAUSES};
pub use verdict::{Candidate, Diagnosis, Evidence, ModelScore, ResidualTest, Untestable, Verdict};
pub use whiteness::INPUT_LAGS;
