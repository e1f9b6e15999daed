//! The strip's electrics alone: per segment the RC circuit of eq. 2.1–2.2
//! and the relaxation network's state, discretised exactly.
//!
//! The circuit is upstream of the beam: the currents depend on `R1`, `R2`,
//! `C` and the electrochemical terms, never on the beam's motion. [`Strip`]
//! steps its electrical states with this same code; a fit that estimates
//! the circuit from the currents runs it alone, without the beam's modes.
//!
//! # State
//! Per segment `[v_C, r]`: the capacitor's voltage `Q/C`, V, and the
//! relaxation network's state, V·s (`r' = v_C − p r`), as in [`Strip`]'s
//! electrical states.
//!
//! ```
//! use model_core::{Circuit, Extensions, Params};
//! let p = Params::main_m_2006();
//! let circuit = Circuit::<f64, 3>::new(&p, &Extensions::NONE, 1e-3).unwrap();
//! let mut x = circuit.rest();
//! // At a step the current jumps to v/R1 + v/R2 ...
//! let jump = circuit.currents_a(&x, &[2.5; 3])[0];
//! assert!((jump - (2.5 / p.r1_ohm + 2.5 / p.r2_ohm)).abs() < 1e-12);
//! // ... and settles to v/R2 once the double layer is charged (τ1 = R1 C).
//! for _ in 0..1_000 {
//!     circuit.step(&mut x, &[2.5; 3]);
//! }
//! assert!((circuit.currents_a(&x, &[2.5; 3])[0] - 2.5 / p.r2_ohm).abs() < 1e-6);
//! ```
//!
//! [`Strip`]: crate::Strip

use crate::extensions::Extensions;
use crate::params::{ParamError, Params};
use crate::reaction::Reaction;
use crate::real::Real;
use crate::strip::check_sample_time;
use crate::zoh::discretise;

/// The electrics of `N` segments, discretised exactly (zero-order hold).
#[derive(Clone, Debug)]
pub struct Circuit<T, const N: usize> {
    /// Per segment, `v_C ← a v_C + g₀ v`, `r ← b v_C + c r + g₁ v`, as
    /// `[a, b, c, g₀, g₁]` (all alike unless `segment-variation` sets them
    /// apart).
    pub(crate) elec: [[T; 5]; N],
    /// `1/R1` of every segment.
    inv_r1: [T; N],
    inv_r2: T,
    /// `a` of the double layer's `v (1 + a v²)`.
    charge_cubic: T,
    /// `b` of the leak's `v/R2 (1 + b v²)`.
    leak_cubic: T,
    /// The reaction behind each double layer, where it is on.
    reaction: Option<Reaction>,
}

impl<T: Real, const N: usize> Circuit<T, N> {
    /// Builds the circuit of `params` with the electrical terms of `ext`
    /// (the electrochemical cubics, each segment's `R1` and `C`), checking
    /// them as [`Strip`](crate::Strip) does, discretised at `dt_s`.
    pub fn new(params: &Params, ext: &Extensions, dt_s: f64) -> Result<Self, ParamError> {
        const { assert!(N >= 1 && N <= 8, "segments N must be 1..=8") };
        params.validate_relaxation(ext.back_relaxation)?;
        ext.validate()?;
        ext.segment_variation.validate_for(N)?;
        check_sample_time(dt_s)?;
        Ok(Self::built(params, ext, dt_s))
    }

    /// The circuit of checked values.
    pub(crate) fn built(params: &Params, ext: &Extensions, dt_s: f64) -> Self {
        let r1_c: [(f64, f64); N] = core::array::from_fn(|i| {
            let (r1, c, _) = ext
                .segment_variation
                .segment(i, params.r1_ohm, params.c_f, 1.0);
            (r1, c)
        });
        Circuit {
            elec: r1_c.map(|(r1, c)| Self::discretised(params, 1.0 / (r1 * c), dt_s)),
            inv_r1: r1_c.map(|(r1, _)| T::from_f64(1.0 / r1)),
            inv_r2: T::from_f64(1.0 / params.r2_ohm),
            charge_cubic: T::from_f64(ext.charge_cubic_per_v2),
            leak_cubic: T::from_f64(ext.leak_cubic_per_v2),
            reaction: (ext.reaction_ratio > 0.0).then(|| {
                Reaction::new(
                    ext.reaction_ratio,
                    ext.reaction_ref_v,
                    ext.reaction_tafel_v,
                    params.r2_ohm,
                )
            }),
        }
    }

    /// One segment's block, discretised at `dt_s`: `v_C' = (v − v_C)/τ1`,
    /// `r' = v_C − p r`; its `Φ` (three entries, the other is 0) and `Γ`.
    fn discretised(params: &Params, inv_tau1: f64, dt_s: f64) -> [T; 5] {
        let mut a_e = [[-inv_tau1, 0.0], [1.0, -params.p_per_s]];
        let (mut phi_e, mut gamma_e) = ([[0.0; 2]; 2], [[0.0; 1]; 2]);
        discretise(
            &mut a_e,
            &[[inv_tau1], [0.0]],
            dt_s,
            &mut phi_e,
            &mut gamma_e,
        );
        [
            phi_e[0][0],
            phi_e[1][0],
            phi_e[1][1],
            gamma_e[0][0],
            gamma_e[1][0],
        ]
        .map(T::from_f64)
    }

    /// The state at rest: no charge.
    pub fn rest(&self) -> [[T; 2]; N] {
        [[T::ZERO; 2]; N]
    }

    /// The voltage the double layer sees, `v (1 + a v²)`: exact under the
    /// hold, since `v` is held.
    #[inline(always)]
    pub(crate) fn double_layer_v(&self, v: &[T; N]) -> [T; N] {
        core::array::from_fn(|i| v[i] + self.charge_cubic * v[i] * v[i] * v[i])
    }

    /// The drive each segment's double layer takes over the step from
    /// capacitor voltages `v_c(i)` under the layer's voltage `v_dl` (see
    /// [`Circuit::double_layer_v`]): `v_dl` itself, less `R1` times the
    /// reaction's current where one is on ([`Reaction::drive_v`]). The
    /// step's every input column (the electrics', the beam's) takes it.
    #[inline(always)]
    pub(crate) fn drive(&self, v_dl: [T; N], v_c: impl Fn(usize) -> T) -> [T; N] {
        let Some(reaction) = &self.reaction else {
            return v_dl;
        };
        core::array::from_fn(|i| {
            let [a, _, _, g0, _] = self.elec[i].map(T::to_f64);
            let (v, r1) = (v_dl[i].to_f64(), 1.0 / self.inv_r1[i].to_f64());
            let v_lin = a * v_c(i).to_f64() + g0 * v;
            T::from_f64(reaction.drive_v(v, v_lin, g0 * r1, r1))
        })
    }

    /// Segment `i`'s state after one step from `e` under the drive `u`
    /// (see [`Circuit::drive`]).
    #[inline(always)]
    pub(crate) fn next(&self, i: usize, e: [T; 2], u: T) -> [T; 2] {
        let [a, b, c, g0, g1] = self.elec[i];
        [a * e[0] + g0 * u, b * e[0] + c * e[1] + g1 * u]
    }

    /// Advances one sample with `v` (V per segment) held over the step.
    pub fn step(&self, x: &mut [[T; 2]; N], v: &[T; N]) {
        let u = self.drive(self.double_layer_v(v), |i| x[i][0]);
        for (i, e) in x.iter_mut().enumerate() {
            *e = self.next(i, *e, u[i]);
        }
    }

    /// Segment `i`'s current, A, at capacitor voltage `v_c` with `v` applied
    /// now: `v/R2 + (v − v_C)/R1` (eq. 2.2), which jumps at a step; with the
    /// electrochemical terms, `v/R2 (1 + b v²) + (v (1 + a v²) − v_C)/R1`.
    #[inline(always)]
    pub(crate) fn current(&self, i: usize, v: T, v_c: T) -> T {
        let v2 = v * v;
        let leak = v * self.inv_r2 * (T::from_f64(1.0) + self.leak_cubic * v2);
        leak + (v + self.charge_cubic * v2 * v - v_c) * self.inv_r1[i]
    }

    /// Current into every segment, A, with `v` the voltages applied now.
    pub fn currents_a(&self, x: &[[T; 2]; N], v: &[T; N]) -> [T; N] {
        core::array::from_fn(|i| self.current(i, v[i], x[i][0]))
    }
}
