//! The gates a candidate effect must pass, shared by the search that applies
//! them and by the identifiability analysis that predicts from which strength
//! an effect would pass them (its own module so neither imports the other).

/// BIC improvement an effect must reach on the training recordings.
pub const DELTA_BIC: f64 = -10.0;

/// Relative drop of held-out weighted RSS an effect must reach.
pub const HOLDOUT_RSS_GAIN: f64 = 0.01;
