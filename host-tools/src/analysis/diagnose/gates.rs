//! The gates a candidate effect must pass, shared by the search that applies
//! them and by the identifiability analysis that predicts from which strength
//! an effect would pass them (its own module so neither imports the other).

/// BIC improvement an effect must reach on the training recordings.
pub const DELTA_BIC: f64 = -10.0;

/// Relative drop of held-out weighted RSS an effect must reach.
pub const HOLDOUT_RSS_GAIN: f64 = 0.01;

/// Whether a held-out RSS lower by the fraction `rss_gain` pays for what
/// was added: by more than [`HOLDOUT_RSS_GAIN`]. One rule for a candidate,
/// a pair over its member that passed alone, and the damping's form.
pub fn holdout_gain_passes(rss_gain: f64) -> bool {
    rss_gain > HOLDOUT_RSS_GAIN
}

/// Whether the final model takes each mode's own damping ratio in place
/// of the law: its held-out RSS lower by `gain_percent`
/// ([`holdout_gain_passes`]).
pub fn each_mode_damping_kept(gain_percent: f64) -> bool {
    holdout_gain_passes(gain_percent / 100.0)
}
