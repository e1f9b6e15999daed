//! `finrs fit`: estimates a model's free parameters over the recordings of
//! a session, by Levenberg–Marquardt on noise-weighted residuals, in two
//! stages as the model is built (the circuit from the currents, then the
//! relaxation and the beam from the camera and the load cell, see
//! `stage.rs`), and reports what a researcher needs to trust the result:
//! confidence intervals, fit per channel, AIC and BIC.
//!
//! Every channel is weighted by the noise of its sensor, measured on the
//! opening rest of each recording (FORMAT.md guarantees at least 1 s), so
//! the weighted residuals are in units of noise and their sum of squares is
//! `m` when the model explains the data to the noise floor. A sensor the
//! model leaves far above its noise is then weighed by the variance it
//! shows (`inflation.rs`), so that one sensor's misfit does not steer the
//! knobs another one determines.

mod carry;
mod covariance;
mod data;
pub mod drift;
mod drift_set;
mod effect;
mod error;
mod fitter;
pub mod form;
mod inflation;
pub mod modal;
pub mod mode_start;
pub mod normal;
mod race;
pub mod report;
pub mod sampling;
mod space;
mod stage;
mod start;
mod stats;
pub mod zero_drift;

pub use data::{Sensor, SessionTargets, Target};
pub use drift::{Drift, DriftBasis, DRIFT_MAX_DEGREE, DRIFT_SCALE_S};
pub use effect::Effect;
pub use error::FitError;
pub use fitter::{FitResult, Fitter, FormCheck, FIT_ELEMENTS};
pub use inflation::{profile_cost, Inflation};
pub use space::{difference_step, session_peak_v, with_session_peak, Knob, Space};
pub use stats::{
    above_at, below_at, beyond_at, excludes_at, nrmse, wilson_hilferty, ChannelFit, Estimate, Score,
};
