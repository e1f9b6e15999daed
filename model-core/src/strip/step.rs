//! The held step of the tip (#16's `motion-step:`): the voltages that move
//! the free tip to a deflection and hold it there while the strip's
//! relaxation would make it creep on or fall back.
//!
//! Each segment's own moment per volt is `H(s) = K (s + z)/((s + p)(1 +
//! s τ1))` (its electrics `1/(1 + s τ1)`, `τ1 = R1 C`, then the relaxation
//! network, `z = b/a`). A voltage `v(t) = V · y(t)` with `y` the inverse of
//! the relaxation applied to a rise `ρ(t)` from 0 to 1,
//!
//! `y = ρ + (z − p)/p · (e^{−z t} ∗ ρ′)`, Laplace `(s + p) z/((s + z) p) ρ`,
//!
//! gives the moment `V · H(0) · ρ` seen through the electrics alone: the
//! relaxation is undone, the charging is not (inverting it too would need
//! the voltage's derivative). `y` is stable for `z > 0` and ends at 1, so
//! `V` is the voltage that holds the step for good: this module gives those
//! levels ([`TipStep::levels_v`]) and the network's `p` and `z`; the board's
//! generator (`finrs_drive::Program::HeldStep`) evaluates `y` for a raised-
//! cosine rise.
//!
//! The levels are the exact steady state of the discretised model (its
//! response to held voltages, `z = 1` in the sampled system), so every
//! stored block enters: each segment's own electrics and moment per charge
//! (`segment-variation`), the crosstalk (every segment's moment on the beam
//! one and the same, as [`Strip::tip_wave`] asks), the moment gain, and the
//! beam's static deflection from its modes. The beam's gain is static: a
//! rise much slower than the first mode's period moves the tip
//! quasi-statically; a faster one leaves the first mode ringing (see
//! docs/model.md for how much).
//!
//! ```
//! use model_core::{Fixture, Params, Strip};
//! // Table 4-2's strip creeps: its moment grows to z/p = 2.4 times the
//! // instant one under a held voltage.
//! let strip = Strip::<f64, 3, 1, 18>::new(&Params::table_4_2_2006(), Fixture::Free, 1e-3).unwrap();
//! let step = strip.tip_step(5e-3).unwrap();
//! assert!(step.pole_per_s == 0.1 && (step.zero_per_s - 0.24).abs() < 1e-12);
//! // y(t) for an instant rise: z/p at once, then down to 1.
//! let y = |t: f64| 1.0 + (step.zero_per_s / step.pole_per_s - 1.0) * (-step.zero_per_s * t).exp();
//! let mut x = strip.rest();
//! for k in 0..60_000 {
//!     let t = k as f64 * 1e-3;
//!     if k == 12_000 || k == 59_999 {
//!         // From 12 s (past the 1.6 s charging) the tip holds its 5 mm.
//!         assert!((strip.tip_deflection_m(&x) / 5e-3 - 1.0).abs() < 3e-3);
//!     }
//!     strip.step(&mut x, &step.levels_v.map(|l| l * y(t)));
//! }
//! ```

use super::harmonic::tridiagonal_solve;
use super::Strip;
use crate::phasor::Phasor;
use crate::real::Real;

/// A held tip step: each segment's level and the relaxation it undoes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipStep<const N: usize> {
    /// `V`: each segment's voltage once the step has settled, V.
    pub levels_v: [f64; N],
    /// `p`: the relaxation network's pole, 1/s.
    pub pole_per_s: f64,
    /// `z = b/a`: its zero, 1/s; `+∞` for a pure lag (`a = 0`, no instant
    /// moment), whose inverse needs a rise of some length.
    pub zero_per_s: f64,
}

/// Why a strip's tip cannot be stepped and held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepError {
    /// An electrochemical cubic is on (its field named): the voltage for a
    /// moment is then not one level times a shape.
    Nonlinear {
        /// The extension's field.
        field: &'static str,
    },
    /// The moment relaxes back past zero under a held voltage (`z ≤ 0`):
    /// the inverse that would hold it grows without bound.
    BackRelaxation {
        /// The zero `b/a`, 1/s.
        zero_per_s: f64,
    },
    /// No held voltage moves the tip (a moment gain of 0, or segments whose
    /// moments cancel at the tip).
    NoResponse,
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Nonlinear { field } => write!(
                f,
                "{field} is on: the voltage for a moment is not a level times a shape"
            ),
            Self::BackRelaxation { zero_per_s } => write!(
                f,
                "the moment relaxes back (z = {zero_per_s} 1/s ≤ 0): a held tip needs a voltage that grows without bound"
            ),
            Self::NoResponse => write!(f, "no held voltage moves the tip"),
        }
    }
}

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// The levels that hold the free tip at `tip_m` once settled, and the
    /// relaxation they undo on the way: see the module's description.
    /// Nothing here limits the voltage: the caller's limiter decides.
    pub fn tip_step(&self, tip_m: f64) -> Result<TipStep<N>, StepError> {
        if let Some(field) = self.nonlinear_field() {
            return Err(StepError::Nonlinear { field });
        }
        let p = &self.params;
        if p.b_nm_per_c_s <= 0.0 {
            return Err(StepError::BackRelaxation {
                zero_per_s: p.b_nm_per_c_s / p.a_nm_per_c,
            });
        }
        let zero_per_s = p.zero_per_s().unwrap_or(f64::INFINITY);
        // Each segment's own moment per held volt, in the sampled model.
        let held = Phasor::real(1.0);
        let gain = self.moment_gain.to_f64();
        let own = tridiagonal_solve(self.crosstalk.to_f64(), &[held; N]);
        let mut v = [Phasor::ZERO; N];
        for i in 0..N {
            let h = self.own_moment(i, self.electrics(held, i)).re * gain;
            if h == 0.0 || !h.is_finite() {
                return Err(StepError::NoResponse);
            }
            v[i] = own[i].scale(1.0 / h);
        }
        let got = self
            .response(held, &v)
            .map_err(|_| StepError::NoResponse)?
            .tip_m
            .re;
        let scale = tip_m / got;
        if got == 0.0 || !scale.is_finite() {
            return Err(StepError::NoResponse);
        }
        Ok(TipStep {
            levels_v: v.map(|vi| vi.re * scale),
            pole_per_s: p.p_per_s,
            zero_per_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::StepError;
    use crate::{Extensions, Fixture, Params, Strip};

    type Strip3 = Strip<f64, 3, 1, 18>;

    /// The tip under `levels · y(t)` for an instant rise, sampled at `at`
    /// (seconds, ascending), over 1 ms steps.
    fn tips(s: &Strip3, levels: [f64; 3], y: impl Fn(f64) -> f64, at: &[f64; 4]) -> [f64; 4] {
        let mut x = s.rest();
        let mut out = [f64::NAN; 4];
        let mut next = at.iter().enumerate().peekable();
        for k in 0..=((at[at.len() - 1] * 1e3).round() as u64) {
            let t = k as f64 * 1e-3;
            if let Some(&(j, _)) = next.peek().filter(|(_, &a)| (a - t).abs() < 5e-4) {
                out[j] = s.tip_deflection_m(&x);
                next.next();
            }
            s.step(&mut x, &levels.map(|l| l * y(t)));
        }
        out
    }

    /// A creeping strip and a relaxing one, with every linear term that
    /// changes a level (unequal segments, crosstalk, a moment gain,
    /// damping so the first mode's ringing dies): the inverse holds the
    /// tip within 0.2 % from 15 s to 120 s; the levels alone are 5 % off or
    /// more at 15 s (6.7 and 13 %).
    #[test]
    fn the_inverse_holds_the_tip_where_a_held_voltage_drifts() {
        let mut ext = Extensions {
            damping_ratio: 0.05,
            crosstalk: 0.1,
            ..Extensions::NONE
        };
        ext.segment_variation.r1_deviation[1] = 0.2;
        ext.segment_variation.k_deviation[2] = -0.15;
        let at = [15.0, 30.0, 60.0, 120.0];
        for params in [Params::table_4_2_2006(), Params::baseline_air_example()] {
            let mut s = Strip3::with_extensions(&params, &ext, Fixture::Free, 1e-3).unwrap();
            s.set_moment_gain(0.8);
            let step = s.tip_step(4e-3).unwrap();
            let (p, z) = (step.pole_per_s, step.zero_per_s);
            assert_eq!((p, z), (params.p_per_s, params.zero_per_s().unwrap()));
            let held = tips(
                &s,
                step.levels_v,
                |t| 1.0 + (z / p - 1.0) * (-z * t).exp(),
                &at,
            );
            for (t, tip) in at.iter().zip(&held) {
                assert!((tip / 4e-3 - 1.0).abs() < 2e-3, "{t} s: {held:?}");
            }
            let plain = tips(&s, step.levels_v, |_| 1.0, &at);
            assert!((plain[0] / 4e-3 - 1.0).abs() > 0.05, "{plain:?}");
            // The levels are the plain step's end: it gets there at last.
            assert!((plain[3] / 4e-3 - 1.0).abs() < 0.01, "{plain:?}");
        }
    }

    /// The pure lag (`main.m`, `a = 0`) has no zero: `+∞`. Its levels are
    /// the static inverse: 13.0 mm at 2.5 V on every segment.
    #[test]
    fn a_pure_lag_has_its_zero_at_infinity_and_the_static_levels() {
        let s = Strip3::new(&Params::main_m_2006(), Fixture::Free, 1e-3).unwrap();
        let step = s.tip_step(13.0e-3).unwrap();
        assert_eq!(step.zero_per_s, f64::INFINITY);
        for l in step.levels_v {
            assert!((l / 2.5 - 1.0).abs() < 0.01, "{l}");
        }
    }

    #[test]
    fn a_nonlinear_a_back_relaxing_or_an_unmoved_strip_is_refused() {
        let p = Params::table_4_2_2006();
        let cubic = Extensions {
            leak_cubic_per_v2: 0.01,
            ..Extensions::NONE
        };
        let s = Strip3::with_extensions(&p, &cubic, Fixture::Free, 1e-3).unwrap();
        assert_eq!(
            s.tip_step(1e-3),
            Err(StepError::Nonlinear {
                field: "leak_cubic_per_v2"
            })
        );
        let back = Extensions {
            back_relaxation: true,
            ..Extensions::NONE
        };
        let q = Params {
            b_nm_per_c_s: -0.5 * p.b_nm_per_c_s,
            ..p
        };
        let s = Strip3::with_extensions(&q, &back, Fixture::Free, 1e-3).unwrap();
        assert!(matches!(
            s.tip_step(1e-3),
            Err(StepError::BackRelaxation { zero_per_s }) if zero_per_s < 0.0
        ));
        let mut s = Strip3::new(&p, Fixture::Free, 1e-3).unwrap();
        s.set_moment_gain(0.0);
        assert_eq!(s.tip_step(1e-3), Err(StepError::NoResponse));
    }
}
