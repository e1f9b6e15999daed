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

/// The chance, over a whole search, that any candidate's own term tests
/// significant by the noise alone (the family-wise error rate).
pub const FAMILY_ALPHA: f64 = 0.05;

/// Each test's two-sided tail when `tests` have been made in the search:
/// Bonferroni's `α / tests`. A search of four rounds tries some thirty
/// candidates, and each is a chance for a term to stand out by the noise:
/// at 95 % apiece, one in twenty would.
pub fn family_tail(tests: usize) -> f64 {
    FAMILY_ALPHA / tests.max(1) as f64
}

/// The normal deviate a term must clear among `tests`: `Φ⁻¹(1 − tail/2)`
/// (1.96 for one, 2.77 for the nine of a first round, 3.14 for thirty).
pub fn family_z(tests: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(1.0 - family_tail(tests) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::{family_tail, family_z};

    #[test]
    fn the_bar_is_95_percent_for_one_test_and_rises_with_their_count() {
        assert!((family_z(1) - 1.959_964).abs() < 1e-5);
        assert!((family_z(9) - 2.772_921).abs() < 1e-4, "{}", family_z(9));
        assert!((family_z(30) - 3.143_980).abs() < 1e-4, "{}", family_z(30));
        assert!((1..60).all(|m| family_z(m) < family_z(m + 1)));
        assert_eq!(family_tail(0), family_tail(1));
    }
}
