//! The strip's exact steady-state response to sinusoidal drives: what a
//! wave generator's sampled sine settles to, sample for sample, with no
//! simulation (the forward half of shaping waves by the model, #16).
//!
//! Every segment driven by `v_k = Re(Vᵢ e^{jθk})`, `θ = 2π f Δt`, held over
//! each step, the state settles to `x_k = Re(X e^{jθk})` with
//! `(e^{jθ} I − Φ) X = Γ V`. The stored blocks solve that in `O(S)`: each
//! segment's electrics (two states, lower triangular) from its voltage,
//! then each mode's pair (a 2 × 2 system) from every segment's electrics.
//! Exact for the discretised model, including the zero-order hold's
//! delay, so a simulation of the same sine agrees to rounding once its
//! transients (the relaxation's `e^{−p t}`, each mode's ringing) are gone.
//!
//! Only the linear model has one: the electrochemical cubics make the
//! response hold harmonics, so they are refused.
//!
//! ```
//! use model_core::{Fixture, Params, Phasor, Strip};
//! let p = Params::main_m_2006();
//! let strip = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, 1e-3).unwrap();
//! let one_volt = [Phasor::from_sine(1.0, 0.0); 3];
//! // Slow, the tip follows the static 5.2 mm per volt (13 mm at 2.5 V) ...
//! let slow = strip.harmonic(1e-3, &one_volt).unwrap().tip_m;
//! assert!((slow.amplitude() / 5.2e-3 - 1.0).abs() < 0.01);
//! // ... at 1 Hz, far above the relaxation's pole (p = 0.1/s), only
//! // p/ω of it, a quarter period behind: the network integrates.
//! let fast = strip.harmonic(1.0, &one_volt).unwrap().tip_m;
//! let omega = 2.0 * core::f64::consts::PI;
//! assert!((fast.amplitude() / (5.2e-3 * 0.1 / omega) - 1.0).abs() < 0.01);
//! assert!((fast.sine_phase_rad().to_degrees() + 95.0).abs() < 1.0);
//! // The voltages of a travelling wave of 5 mm at the tip, 60° a segment.
//! let v = strip.tip_wave(1.0, 5e-3, 60f64.to_radians()).unwrap();
//! assert!(v.iter().all(|vi| vi.amplitude() > 4.0)); // more than the 4 V limit
//! ```

use super::{Fixture, Strip};
use crate::phasor::Phasor;
use crate::real::Real;

/// The steady-state outputs of a sinusoidal drive, each `Re(Y e^{jθk})`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Harmonic<const N: usize> {
    /// Tip deflection across the strip, m (zero for the blocked fixture).
    pub tip_m: Phasor,
    /// Force on the load cell, N (zero for the free fixture).
    pub force_n: Phasor,
    /// Each segment's current, A.
    pub currents_a: [Phasor; N],
    /// Each segment's bending moment on the beam, N·m (crosstalk and the
    /// moment gain included).
    pub moments_nm: [Phasor; N],
}

/// Why a strip has no steady-state sinusoidal response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HarmonicError {
    /// The frequency is not finite, not above 0, or not below Nyquist's
    /// (half the sample rate), Hz.
    Frequency {
        /// The frequency asked for, Hz.
        hz: f64,
        /// Nyquist's frequency of the strip's sample time, Hz.
        nyquist_hz: f64,
    },
    /// A nonlinear term is on (its field named): the response holds
    /// harmonics, not one sinusoid.
    Nonlinear {
        /// The extension's field.
        field: &'static str,
    },
    /// The drive sits on an undamped mode's own frequency: the response
    /// grows without bound.
    Resonant {
        /// The mode, counted from 0.
        mode: usize,
    },
    /// No voltage moves what was asked for at this frequency (a moment
    /// gain of 0, or a wave whose moments cancel at the output).
    NoResponse,
}

impl core::fmt::Display for HarmonicError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Frequency { hz, nyquist_hz } => {
                write!(f, "frequency {hz} Hz is not within (0, {nyquist_hz}) Hz")
            }
            Self::Nonlinear { field } => write!(
                f,
                "{field} is on: the response holds harmonics, not one sine"
            ),
            Self::Resonant { mode } => {
                write!(f, "the drive sits on undamped mode {mode}'s own frequency")
            }
            Self::NoResponse => write!(f, "no voltage moves the output at this frequency"),
        }
    }
}

/// Which output a wave's amplitude is asked of.
#[derive(Clone, Copy)]
enum Output {
    Tip,
    Force,
}

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// The steady state the phasors `v` (V, one per segment, `Re(Vᵢ
    /// e^{jθk})` at step `k`) settle to at `hz`, Hz: see the module's
    /// description. Computed in `f64` from the stored blocks (of `T`).
    pub fn harmonic(&self, hz: f64, v: &[Phasor; N]) -> Result<Harmonic<N>, HarmonicError> {
        self.has_sine_response(hz)?;
        self.response(
            Phasor::unit(2.0 * core::f64::consts::PI * hz * self.dt_s),
            v,
        )
    }

    /// The steady response to `v` of a drive whose step turns it by `z`
    /// (`z = 1`: held voltages, the steady state of a step).
    pub(super) fn response(
        &self,
        z: Phasor,
        v: &[Phasor; N],
    ) -> Result<Harmonic<N>, HarmonicError> {
        let f = |x: T| x.to_f64();
        let gain = f(self.moment_gain);

        let elec: [[Phasor; 2]; N] =
            core::array::from_fn(|i| self.electrics(z, i).map(|e| e * v[i]));

        // Each mode's pair from its own rotation and every segment's drive.
        let dof = Self::DOF;
        let mut eta = [Phasor::ZERO; S];
        for k in 0..dof {
            let (mut f_eta, mut f_zeta) = (Phasor::ZERO, Phasor::ZERO);
            for (i, cols) in self.drive.iter().enumerate() {
                let [vc, r] = elec[i];
                let drive = |row: usize| {
                    vc.scale(f(cols[0][row]))
                        + r.scale(f(cols[1][row]))
                        + v[i].scale(f(cols[2][row]))
                };
                f_eta += drive(k).scale(gain);
                f_zeta += drive(dof + k).scale(gain);
            }
            let [r0, r1, r2, r3] = [0, 1, 2, 3].map(|j| f(self.rot[j][k]));
            // [[z − r0, −r1], [−r2, z − r3]] [η; ζ] = [F_η; F_ζ], by Cramer.
            let (a, d) = (z - Phasor::real(r0), z - Phasor::real(r3));
            let det = a * d - Phasor::real(r1 * r2);
            if det.norm_sqr() < 1e-30 {
                return Err(HarmonicError::Resonant { mode: k });
            }
            eta[k] = (f_eta * d + f_zeta.scale(r1)) / det;
            eta[dof + k] = (a * f_zeta + f_eta.scale(r2)) / det;
        }

        let tip_m = match self.fixture {
            Fixture::Free => {
                let row = &crate::matrix::rows(&self.dof_from_modal)[Self::TIP];
                let mut y = Phasor::ZERO;
                for k in 0..self.modes {
                    y += eta[k].scale(f(row[k]));
                }
                y
            }
            Fixture::Blocked => Phasor::ZERO,
        };
        let mut force_n = Phasor::ZERO;
        for (k, &e) in eta[..Self::ELEC].iter().enumerate() {
            force_n += e.scale(f(self.force_row[k]));
        }
        for (i, [vc, r]) in elec.iter().enumerate() {
            let at = Self::ELEC + 2 * i;
            force_n +=
                (vc.scale(f(self.force_row[at])) + r.scale(f(self.force_row[at + 1]))).scale(gain);
        }
        // The current is linear in (v, v_C) once the cubics are off.
        let currents_a = core::array::from_fn(|i| {
            let per_v = f(self.circuit.current(i, T::from_f64(1.0), T::ZERO));
            let per_vc = f(self.circuit.current(i, T::ZERO, T::from_f64(1.0)));
            v[i].scale(per_v) + elec[i][0].scale(per_vc)
        });
        let own: [Phasor; N] = core::array::from_fn(|i| self.own_moment(i, elec[i]));
        let kappa = f(self.crosstalk);
        let moments_nm = core::array::from_fn(|i| {
            let mut u = own[i];
            if i > 0 {
                u += own[i - 1].scale(kappa);
            }
            if i + 1 < N {
                u += own[i + 1].scale(kappa);
            }
            u.scale(gain)
        });
        Ok(Harmonic {
            tip_m,
            force_n,
            currents_a,
            moments_nm,
        })
    }

    /// Each segment's admittance at `hz` as a board's shunt samples it,
    /// A/V: the current read at the end of a sample period (with the
    /// capacitor's voltage then) over the voltage held through that period.
    /// [`Strip::harmonic`]'s current is the one at a period's start, with
    /// its new voltage; the two differ by a period's turn of the
    /// capacitor's part, a third of a degree at 1 Hz and 1 kHz, but that
    /// part nearly cancels the instant one (`(v − v_C)/R1`), so a gain
    /// tracker comparing them would be off by percent. Refused as
    /// [`Strip::harmonic`] refuses.
    ///
    /// ```
    /// use model_core::{Fixture, Params, Strip};
    /// let p = Params::main_m_2006();
    /// let strip = Strip::<f64, 1, 1, 6>::new(&p, Fixture::Free, 1e-3).unwrap();
    /// // Slow, the double layer is charged: only the leak, 1/R2.
    /// let y = strip.sampled_admittance(1e-3).unwrap()[0];
    /// assert!((y.re * p.r2_ohm - 1.0).abs() < 1e-3 && y.im.abs() < 1e-6);
    /// ```
    pub fn sampled_admittance(&self, hz: f64) -> Result<[Phasor; N], HarmonicError> {
        self.has_sine_response(hz)?;
        let z = Phasor::unit(2.0 * core::f64::consts::PI * hz * self.dt_s);
        Ok(core::array::from_fn(|i| {
            let f = |v: f64, v_c: f64| {
                self.circuit
                    .current(i, T::from_f64(v), T::from_f64(v_c))
                    .to_f64()
            };
            let vc = self.electrics(z, i)[0];
            Phasor::real(f(1.0, 0.0)) + (vc * z).scale(f(0.0, 1.0))
        }))
    }

    /// Each segment's force on the load cell per volt at `hz` as the board
    /// samples it, N/V: the force read at the end of a sample period (the
    /// state after it) over the voltage held through it, the others at 0
    /// V; [`Strip::harmonic`]'s force is the one at the period's start.
    /// Zero on a free strip. Refused as [`Strip::harmonic`] refuses.
    ///
    /// ```
    /// use model_core::{Fixture, Params, Phasor, Strip};
    /// let p = Params::main_m_2006();
    /// let held = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Blocked, 1e-3).unwrap();
    /// let per_volt = held.sampled_force_per_volt(1.0).unwrap();
    /// // Linear: the force of any voltages is their sum.
    /// let v = [Phasor::from_sine(1.0, 0.0), Phasor::from_sine(0.5, -1.0), Phasor::ZERO];
    /// let f = held.harmonic(1.0, &v).unwrap().force_n * Phasor::unit(2.0 * core::f64::consts::PI * 1e-3);
    /// let sum = per_volt[0] * v[0] + per_volt[1] * v[1];
    /// assert!((f - sum).norm_sqr().sqrt() < 1e-12 * f.amplitude());
    /// ```
    pub fn sampled_force_per_volt(&self, hz: f64) -> Result<[Phasor; N], HarmonicError> {
        self.has_sine_response(hz)?;
        let z = Phasor::unit(2.0 * core::f64::consts::PI * hz * self.dt_s);
        let mut out = [Phasor::ZERO; N];
        for (k, f) in out.iter_mut().enumerate() {
            let mut v = [Phasor::ZERO; N];
            v[k] = Phasor::real(1.0);
            // The period's end: the state one step on.
            *f = self.response(z, &v)?.force_n * z;
        }
        Ok(out)
    }

    /// The voltages (phasors, V) of a travelling bending wave at `hz`:
    /// every segment's moment of one amplitude, each `lag_rad` behind the
    /// one before it (from the clamp), scaled so that the free tip moves
    /// as `tip_amp_m · sin(θk)`. The exact inverse of each segment's
    /// electrics and relaxation and of the crosstalk at this frequency,
    /// and of the beam's response at the tip (its modes included, not a
    /// quasi-static gain). Nothing here limits the voltage: the caller's
    /// limiter decides whether the wave can be driven.
    pub fn tip_wave(
        &self,
        hz: f64,
        tip_amp_m: f64,
        lag_rad: f64,
    ) -> Result<[Phasor; N], HarmonicError> {
        self.wave(hz, lag_rad, Output::Tip, tip_amp_m)
    }

    /// [`Strip::tip_wave`] for the held strip: scaled so that the force on
    /// the load cell is `force_amp_n · sin(θk)`.
    pub fn force_wave(
        &self,
        hz: f64,
        force_amp_n: f64,
        lag_rad: f64,
    ) -> Result<[Phasor; N], HarmonicError> {
        self.wave(hz, lag_rad, Output::Force, force_amp_n)
    }

    fn wave(
        &self,
        hz: f64,
        lag_rad: f64,
        output: Output,
        amplitude: f64,
    ) -> Result<[Phasor; N], HarmonicError> {
        // Each segment's own moment per volt at this frequency (its own
        // moment does not depend on the others').
        let z = Phasor::unit(2.0 * core::f64::consts::PI * hz * self.dt_s);
        let per_volt: [Phasor; N] =
            core::array::from_fn(|i| self.own_moment(i, self.electrics(z, i)));
        // Wanted moments on the beam, then the segments' own moments
        // through the crosstalk's tridiagonal (I + κT) (Thomas' sweep),
        // then the voltages.
        let gain = self.moment_gain.to_f64();
        let kappa = self.crosstalk.to_f64();
        let wanted: [Phasor; N] = core::array::from_fn(|i| Phasor::unit(-lag_rad * i as f64));
        let own = tridiagonal_solve(kappa, &wanted);
        let mut v = [Phasor::ZERO; N];
        for i in 0..N {
            let h = per_volt[i].scale(gain);
            if h.norm_sqr() == 0.0 || !h.norm_sqr().is_finite() {
                return Err(HarmonicError::NoResponse);
            }
            v[i] = own[i] / h;
        }
        let y = self.harmonic(hz, &v)?;
        let got = match output {
            Output::Tip => y.tip_m,
            Output::Force => y.force_n,
        };
        if got.norm_sqr() == 0.0 || !got.norm_sqr().is_finite() {
            return Err(HarmonicError::NoResponse);
        }
        // Linear: scale every voltage by what turns `got` into the sine asked.
        let c = Phasor::from_sine(amplitude, 0.0) / got;
        Ok(v.map(|vi| vi * c))
    }

    /// Whether the strip has one steady sine at `hz`: a frequency inside
    /// `(0, Nyquist)`, no electrochemical cubic and no quadratic drag.
    pub(super) fn has_sine_response(&self, hz: f64) -> Result<(), HarmonicError> {
        let nyquist_hz = 0.5 / self.dt_s;
        if !(hz.is_finite() && hz > 0.0 && hz < nyquist_hz) {
            return Err(HarmonicError::Frequency { hz, nyquist_hz });
        }
        // The quadratic drag damps a large sine more than a small one: no
        // one transfer function (the held step's static inverse does not
        // see it).
        let drag =
            (self.ext.drag_quadratic_n_s2_per_m3 != 0.0).then_some("drag_quadratic_n_s2_per_m3");
        match self.nonlinear_field().or(drag) {
            Some(field) => Err(HarmonicError::Nonlinear { field }),
            None => Ok(()),
        }
    }

    /// The electrochemical term that is on, if one is: the response to a
    /// voltage then is not linear in it.
    pub(super) fn nonlinear_field(&self) -> Option<&'static str> {
        if self.ext.charge_cubic_per_v2 != 0.0 {
            Some("charge_cubic_per_v2")
        } else if self.ext.leak_cubic_per_v2 != 0.0 {
            Some("leak_cubic_per_v2")
        } else if self.ext.reaction_ratio != 0.0 {
            Some("reaction_ratio")
        } else {
            None
        }
    }

    /// Segment `i`'s own moment (before crosstalk and the moment gain)
    /// from its electrics `e = [v_C, r]`: `C a v_C + C (b − a p) r`.
    pub(super) fn own_moment(&self, i: usize, e: [Phasor; 2]) -> Phasor {
        e[0].scale(self.instant[i].to_f64()) + e[1].scale(self.lag[i].to_f64())
    }

    /// Segment `i`'s electrics `[v_C, r]` per volt of a sine whose step
    /// turns it by `z = e^{jθ}`: `v_C ← a v_C + g₀ v` and
    /// `r ← b v_C + c r + g₁ v` settled.
    pub(super) fn electrics(&self, z: Phasor, i: usize) -> [Phasor; 2] {
        let [a, b, c, g0, g1] = self.circuit.elec[i].map(|x| x.to_f64());
        let vc = Phasor::real(g0) / (z - Phasor::real(a));
        let r = (vc.scale(b) + Phasor::real(g1)) / (z - Phasor::real(c));
        [vc, r]
    }
}

/// `x` with `(I + κT) x = d`, `T` ones on the first off-diagonals: Thomas'
/// sweep (diagonally dominant for `|κ| < 1/2`; the model allows `|κ| < 1`,
/// where a pivot can vanish, so every pivot is checked by the caller's
/// result being finite).
pub(super) fn tridiagonal_solve<const N: usize>(kappa: f64, d: &[Phasor; N]) -> [Phasor; N] {
    let mut c = [0.0; N];
    let mut x = *d;
    let mut pivot = 1.0;
    for i in 0..N {
        if i > 0 {
            pivot = 1.0 - kappa * c[i - 1];
            x[i] = (x[i] - x[i - 1].scale(kappa)).scale(1.0 / pivot);
        }
        c[i] = kappa / pivot;
    }
    for i in (0..N.saturating_sub(1)).rev() {
        x[i] = x[i] - x[i + 1].scale(c[i]);
    }
    x
}

#[cfg(test)]
mod tests {
    use super::HarmonicError;
    use crate::{Extensions, Fixture, Params, Phasor, Strip};

    type Strip3 = Strip<f64, 3, 2, 30>;

    /// A damped strip with every effect that keeps it linear, so that the
    /// response depends on every stored block.
    fn strip(fixture: Fixture) -> Strip3 {
        let mut ext = Extensions {
            damping_ratio: 0.05,
            damping_stiffness_s: 2e-5,
            crosstalk: 0.1,
            added_mass_kg_per_m: 1e-3,
            drag_n_s_per_m2: 0.02,
            ..Extensions::NONE
        };
        ext.segment_variation.r1_deviation[1] = 0.2;
        ext.segment_variation.k_deviation[2] = -0.15;
        let mut s =
            Strip3::with_extensions(&Params::table_4_2_2006(), &ext, fixture, 1e-3).unwrap();
        s.set_moment_gain(0.8);
        s
    }

    /// The simulated outputs' phasors at `hz` (its period a whole number
    /// of steps), by lock-in over the last `periods` periods of `steps`.
    fn simulated(s: &Strip3, hz: f64, v: &[Phasor; 3], steps: u64, periods: u64) -> [Phasor; 5] {
        let theta = 2.0 * core::f64::consts::PI * hz * s.dt_s();
        let per = (1.0 / (hz * s.dt_s())).round() as u64;
        let mut x = s.rest();
        let mut sums = [Phasor::ZERO; 5];
        for k in 0..steps {
            let vk: [f64; 3] = core::array::from_fn(|i| v[i].at(theta, k));
            if k >= steps - periods * per {
                let i = s.currents_a(&x, &vk);
                let y = [
                    s.tip_deflection_m(&x),
                    s.blocking_force_n(&x),
                    i[0],
                    i[1],
                    i[2],
                ];
                // Y = (2/M) Σ y_k e^{−jθk}.
                let w = Phasor::unit(-theta * k as f64).scale(2.0 / (periods * per) as f64);
                for (sum, &yk) in sums.iter_mut().zip(&y) {
                    *sum += w.scale(yk);
                }
            }
            s.step(&mut x, &vk);
        }
        sums
    }

    #[test]
    fn a_simulated_sine_settles_to_the_harmonic_response() {
        // A travelling wave, unequal amplitudes, at a slow and a fast
        // frequency (the second past the free strip's first mode).
        let v: [Phasor; 3] =
            core::array::from_fn(|i| Phasor::from_sine(1.0 + 0.5 * i as f64, -1.1 * i as f64));
        for fixture in [Fixture::Free, Fixture::Blocked] {
            let s = strip(fixture);
            for hz in [0.5, 20.0] {
                let y = s.harmonic(hz, &v).unwrap();
                // The relaxation (p = 0.1/s) settles in some 200 s.
                let sim = simulated(&s, hz, &v, 250_000, 10);
                let want = [
                    y.tip_m,
                    y.force_n,
                    y.currents_a[0],
                    y.currents_a[1],
                    y.currents_a[2],
                ];
                for (j, (w, got)) in want.iter().zip(&sim).enumerate() {
                    let scale = w.amplitude().max(1e-300);
                    let err = (*w - *got).amplitude() / scale;
                    let zero = (fixture == Fixture::Free && j == 1)
                        || (fixture == Fixture::Blocked && j == 0);
                    if zero {
                        assert!(
                            w.amplitude() == 0.0 && got.amplitude() == 0.0,
                            "{fixture:?} {j}"
                        );
                    } else {
                        assert!(
                            err < 1e-6,
                            "{fixture:?} {hz} Hz output {j}: {w:?} against {got:?}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_moments_are_the_ones_the_simulation_applies() {
        let s = strip(Fixture::Free);
        let v: [Phasor; 3] = core::array::from_fn(|i| Phasor::from_sine(2.0, 0.3 * i as f64));
        let y = s.harmonic(2.0, &v).unwrap();
        let theta = 2.0 * core::f64::consts::PI * 2.0 * s.dt_s();
        let mut x = s.rest();
        let mut worst: f64 = 0.0;
        for k in 0..250_000u64 {
            let vk: [f64; 3] = core::array::from_fn(|i| v[i].at(theta, k));
            if k > 240_000 {
                let m = s.moments_nm(&x);
                for i in 0..3 {
                    worst = worst.max(
                        (m[i] - y.moments_nm[i].at(theta, k)).abs() / y.moments_nm[i].amplitude(),
                    );
                }
            }
            s.step(&mut x, &vk);
        }
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn a_travelling_wave_s_voltages_give_the_motion_asked_for() {
        let lag = core::f64::consts::FRAC_PI_3;
        for (fixture, amp) in [(Fixture::Free, 5e-3), (Fixture::Blocked, 2e-3)] {
            let s = strip(fixture);
            for hz in [0.2, 1.0, 7.0] {
                let v = match fixture {
                    Fixture::Free => s.tip_wave(hz, amp, lag),
                    Fixture::Blocked => s.force_wave(hz, amp, lag),
                }
                .unwrap();
                let y = s.harmonic(hz, &v).unwrap();
                let out = if fixture == Fixture::Free {
                    y.tip_m
                } else {
                    y.force_n
                };
                assert!(
                    (out - Phasor::from_sine(amp, 0.0)).amplitude() < 1e-9 * amp,
                    "{out:?}"
                );
                // Equal moments, each lag behind the one before, in spite of
                // the segments' own R1 and K and the crosstalk.
                let m0 = y.moments_nm[0];
                for i in 1..3 {
                    let want = m0 * Phasor::unit(-lag * i as f64);
                    assert!(
                        (y.moments_nm[i] - want).amplitude() < 1e-9 * m0.amplitude(),
                        "{hz} {i}"
                    );
                }
                // The segments' voltages differ: the inverse did something.
                assert!((v[1].amplitude() / v[0].amplitude() - 1.0).abs() > 0.01);
            }
        }
        // A strip that does not bend has no wave.
        let mut s = strip(Fixture::Free);
        s.set_moment_gain(0.0);
        assert_eq!(s.tip_wave(1.0, 5e-3, lag), Err(HarmonicError::NoResponse));
    }

    #[test]
    fn the_board_s_f32_blocks_give_the_same_wave() {
        // What the board would compute from its own f32 model: 3.5e-5 apart
        // at 0.1 Hz (measured), where the relaxation's pole `c = e^{−p Δt}`
        // sits 1e-4 from `e^{jθ}` and f32's rounding of `c` shows; 7e-7 at
        // 10 Hz.
        let p = Params::table_4_2_2006();
        let ext = Extensions {
            damping_ratio: 0.05,
            crosstalk: 0.1,
            ..Extensions::NONE
        };
        let wide = Strip::<f64, 3, 1, 18>::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
        let board = Strip::<f32, 3, 1, 18>::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
        for hz in [0.1, 1.0, 10.0] {
            let (a, b) = (
                wide.tip_wave(hz, 1e-3, 1.0).unwrap(),
                board.tip_wave(hz, 1e-3, 1.0).unwrap(),
            );
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (*x - *y).amplitude() < 1e-4 * x.amplitude(),
                    "{hz} Hz: {x:?} against {y:?}"
                );
            }
        }
    }

    #[test]
    fn what_has_no_single_sinusoid_is_refused() {
        let p = Params::main_m_2006();
        let v = [Phasor::from_sine(1.0, 0.0); 3];
        let s = Strip3::new(&p, Fixture::Free, 1e-3).unwrap();
        for hz in [0.0, -1.0, 500.0, f64::NAN] {
            assert!(
                matches!(s.harmonic(hz, &v), Err(HarmonicError::Frequency { .. })),
                "{hz}"
            );
        }
        let ext = Extensions {
            leak_cubic_per_v2: 0.01,
            ..Extensions::NONE
        };
        let s = Strip3::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
        assert_eq!(
            s.harmonic(1.0, &v),
            Err(HarmonicError::Nonlinear {
                field: "leak_cubic_per_v2"
            })
        );
        // Undamped, on the first mode's own frequency.
        let s = Strip3::new(&p, Fixture::Free, 1e-3).unwrap();
        let f1 = s.natural_frequencies_hz().next().unwrap();
        // The discrete rotation's own angle is ω Δt exactly.
        assert!(matches!(
            s.harmonic(f1, &v),
            Err(HarmonicError::Resonant { mode: 0 })
        ));
        assert!(s.harmonic(0.9 * f1, &v).is_ok());
    }

    /// What a board's load cell reads at the end of each sample period,
    /// against the voltage held through it, by lock-in over the last ten
    /// periods of a long run: each segment's sampled force per volt, on
    /// the damped strip with every linear effect, within 1e-6.
    #[test]
    fn the_sampled_force_per_volt_is_what_the_load_cell_reads() {
        let s = strip(Fixture::Blocked);
        let hz = 2.0;
        let per_volt = s.sampled_force_per_volt(hz).unwrap();
        let theta = 2.0 * core::f64::consts::PI * hz * s.dt_s();
        let v: [Phasor; 3] = core::array::from_fn(|i| Phasor::from_sine(1.0, -0.7 * i as f64));
        let (steps, last) = (250_000u64, 5_000u64);
        let mut x = s.rest();
        let mut f = Phasor::ZERO;
        for k in 0..steps {
            let vk: [f64; 3] = core::array::from_fn(|i| v[i].at(theta, k));
            s.step(&mut x, &vk);
            if k >= steps - last {
                // Read after the period in which v_k was held.
                let w = Phasor::unit(-theta * k as f64).scale(2.0 / last as f64);
                f += w.scale(s.blocking_force_n(&x));
            }
        }
        let want = per_volt[0] * v[0] + per_volt[1] * v[1] + per_volt[2] * v[2];
        assert!(
            (f - want).amplitude() < 1e-6 * want.amplitude(),
            "{f:?} against {want:?}"
        );
        // A free strip has no force.
        let free = strip(Fixture::Free).sampled_force_per_volt(hz).unwrap();
        assert!(free.iter().all(|p| p.amplitude() == 0.0));
    }
}
