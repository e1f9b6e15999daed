//! Why a fit failed.

use crate::model::predict::PredictError;

/// Why a fit failed.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The model refused a parameter set the optimiser reached.
    #[error("{recording}")]
    Model {
        /// The recording.
        recording: String,
        /// Why.
        #[source]
        source: PredictError,
    },
    /// Nothing to fit.
    #[error("the fit needs at least one recording with a measured channel")]
    NoData,
    /// No recording drives a segment: the data say nothing of the model.
    #[error("no recording of the fit drives a segment (every voltage is 0 V): the data say nothing of the model's parameters")]
    NoDrive,
    /// Too few recordings to hold some out.
    #[error("a diagnosis holds recordings out to test on: it needs at least two, and a second of each fixture it holds out; this session has {0}")]
    TooFewToHoldOut(usize),
}
