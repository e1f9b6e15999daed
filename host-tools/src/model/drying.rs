//! The dehydration's moment gain over a recording's rows, kept: a fit
//! runs each recording again and again with the same drying (every
//! Jacobian column but the drying's own), and the gain's `ln_1p` and `exp`
//! on every row were a tenth of a fit with dehydration (perf of rig seed
//! 10013, 2026-11-27). Kept gains are the very numbers computed afresh,
//! so keeping them changes no number.

use std::sync::Arc;

use super::recent::Recent;

/// Gain vectors kept at most, the newest first: a session's recordings
/// under the drying of the current point and of a trial or two.
const KEPT: usize = 32;

/// What a gain vector depends on: the rate, the curvature, the session
/// time of the recording's start, and the recording's own times (kept
/// and compared bit for bit: a comparison is a fraction of hashing them,
/// which was 3 % of a fit with dehydration).
struct Kept {
    rate: u64,
    curvature: u64,
    t_start: u64,
    times_s: Arc<[f64]>,
    gains: Arc<[f64]>,
}

impl Kept {
    fn is_for(&self, rate: u64, curvature: u64, t_start: u64, times_s: &[f64]) -> bool {
        (self.rate, self.curvature, self.t_start) == (rate, curvature, t_start)
            && self.times_s.len() == times_s.len()
            && self
                .times_s
                .iter()
                .zip(times_s)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

static KEPT_GAINS: Recent<Kept> = Recent::new(KEPT);

/// The moment gain after drying for `t_s` at initial rate `r` with
/// curvature `c`: `(1 + c r t)^(−1/c)`, which is `e^{−r t}` at `c = 0` and
/// `1/(1 + r t)` at `c = 1` (a loss that slows as the water goes).
pub fn drying_gain(rate_per_s: f64, curvature: f64, t_s: f64) -> f64 {
    let x = rate_per_s * t_s;
    if curvature * x < 1e-9 {
        (-x).exp()
    } else {
        (-(curvature * x).ln_1p() / curvature).exp()
    }
}

/// The curvature of the circuit's drying law: `1/(1 + r t)`, a loss that
/// slows as the water goes. Fixed, not fitted: the circuit's stage runs
/// before the beam's, which fits the moment's own curvature, and one rate
/// is what the currents of a session of minutes pin.
pub const CIRCUIT_CURVATURE: f64 = 1.0;

/// The circuit's admittance gain after drying for `t_s` at rate `r`,
/// `1/(1 + r t)`: `C` times it, `R1` and `R2` over it. `R1 C` stays, so
/// the layer's voltage does too, and the currents and the charge are the
/// wet strip's times the gain.
pub fn circuit_gain(rate_per_s: f64, t_s: f64) -> f64 {
    drying_gain(rate_per_s, CIRCUIT_CURVATURE, t_s)
}

/// [`drying_gain`] at session time `t_start_s + t` for every `t` of
/// `times_s`: kept ones if there are, else computed and kept.
pub(super) fn gains(
    rate_per_s: f64,
    curvature: f64,
    t_start_s: f64,
    times_s: &[f64],
) -> Arc<[f64]> {
    let (rate, curv, start) = (
        rate_per_s.to_bits(),
        curvature.to_bits(),
        t_start_s.to_bits(),
    );
    let found = KEPT_GAINS.find_map(|k| {
        k.is_for(rate, curv, start, times_s)
            .then(|| Arc::clone(&k.gains))
    });
    if let Some(gains) = found {
        return gains;
    }
    let gains: Arc<[f64]> = times_s
        .iter()
        .map(|&t| drying_gain(rate_per_s, curvature, t_start_s + t))
        .collect();
    KEPT_GAINS.keep(Kept {
        rate,
        curvature: curv,
        t_start: start,
        times_s: times_s.into(),
        gains: Arc::clone(&gains),
    });
    gains
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kept_gains_are_the_gains_computed_afresh_and_another_drying_is_computed_anew() {
        let times: Vec<f64> = (0..500).map(|i| i as f64 * 1e-3).collect();
        let first = gains(2e-3, 0.5, 40.0, &times);
        for (g, &t) in first.iter().zip(&times) {
            assert_eq!(g.to_bits(), drying_gain(2e-3, 0.5, 40.0 + t).to_bits());
        }
        let again = gains(2e-3, 0.5, 40.0, &times);
        assert!(Arc::ptr_eq(&first, &again), "the same drying is kept");
        // Another rate, start or set of times is another vector.
        let faster = gains(3e-3, 0.5, 40.0, &times);
        assert!(!Arc::ptr_eq(&first, &faster));
        assert!(faster[499] < first[499]);
        let later = gains(2e-3, 0.5, 41.0, &times);
        assert!(later[0] < first[0]);
        let mut shifted = times.clone();
        shifted[250] += 1e-4;
        let other = gains(2e-3, 0.5, 40.0, &shifted);
        assert!(!Arc::ptr_eq(&first, &other));
    }

    #[test]
    fn the_boards_drying_law_is_the_hosts() {
        // The board's (model_core, libm) and the fit's (std) agree to
        // rounding, over the curvatures and times a fit meets.
        for c in [0.0, 1e-6, 0.3, 1.0, 2.5] {
            for t in [0.0, 1.0, 60.0, 600.0, 3600.0] {
                let (host, board) = (drying_gain(2e-3, c, t), model_core::drying_gain(2e-3, c, t));
                assert!((host - board).abs() <= 4.0 * f64::EPSILON * host, "{c} {t}");
            }
        }
    }

    #[test]
    fn the_drying_gain_is_exponential_at_zero_curvature_and_hyperbolic_at_one() {
        let (r, t) = (1e-2, 30.0);
        assert!((drying_gain(r, 0.0, t) - (-r * t).exp()).abs() < 1e-15);
        assert!((drying_gain(r, 1.0, t) - 1.0 / (1.0 + r * t)).abs() < 1e-15);
    }
}
