//! The board's model runs in `f32` for as long as the board is on. An
//! undamped mode is a rotation whose `f32` entries, rounded, need not keep
//! the circle: `c² + s²` off one by an ulp grows or shrinks the ringing by
//! that much every step. Over 10⁶ steps (17 minutes at 1 kHz) the ringing
//! must keep its amplitude.

use model_core::{Fixture, Params, Strip};

const S: usize = 18;
/// Modes of the free beam of 3 segments, 1 element each.
const MODES: usize = 6;

/// Each mode's amplitude `√(η² + ζ²)` (`ζ = η̇/ω`: constant while undamped).
fn amplitudes<T: Copy + Into<f64>>(x: &[T; S]) -> [f64; MODES] {
    core::array::from_fn(|k| {
        let (eta, zeta): (f64, f64) = (x[k].into(), x[MODES + k].into());
        (eta * eta + zeta * zeta).sqrt()
    })
}

#[test]
fn an_undamped_f32_mode_keeps_its_amplitude_over_a_million_steps() {
    let p = Params::main_m_2006();
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let s = Strip::<f32, 3, 1, S>::new(&p, fixture, 1e-3).unwrap();
        let mut x = s.rest();
        // Every mode rings (η = 1e-3, ζ = 0); the electrics rest.
        x[..MODES].fill(1e-3);
        let start = amplitudes(&x);
        for _ in 0..1_000_000 {
            s.step(&mut x, &[0.0; 3]);
        }
        let end = amplitudes(&x);
        let steps = 1e6;
        for (k, hz) in s.natural_frequencies_hz().enumerate() {
            let ratio = end[k] / start[k];
            // The decay as a damping ratio: ratio = exp(−ζ ω dt · steps).
            let zeta = -ratio.ln() / (2.0 * std::f64::consts::PI * hz * 1e-3 * steps);
            eprintln!("{fixture:?} mode {k} ({hz:.0} Hz): amplitude x{ratio:.6}, as a damping ratio {zeta:.1e}");
            // Rounded entry by entry, modes grew by up to 2.4 %.
            assert!(ratio < 1.0 + 1e-4, "{fixture:?} mode {k} grew: x{ratio}");
            // A real strip's damping ratio is 10⁻² or more.
            assert!(zeta < 1e-6, "{fixture:?} mode {k}: damping ratio {zeta:e}");
        }
    }
}
