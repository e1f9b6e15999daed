//! The whole strip: `N` segments of electrics and relaxation driving the
//! cantilever (seed eq. 2.28), discretised exactly for a fixed sample time.
//!
//! # State
//! The state `x` (length `S = 2N(2E+1)`, the seed's `6N` for `E = 1`) is
//! `x = [η, ζ, e]`:
//! - `η` (`2NE`): modal coordinates of the beam, `q = Ψ η` with `Ψ` the
//!   mass-normalised modes;
//! - `ζ` (`2NE`): modal velocities divided by the mode's angular frequency,
//!   `ζₖ = η̇ₖ/ωₖ`, so that every mode is a rotation `[[0, ω], [-ω, 0]]` and
//!   the whole matrix stays well scaled for the exponential and for `f32`;
//! - `e` (`2N`): per segment `v_C` (the capacitor's voltage `Q/C`, V) and
//!   `r` (the lead network's state, V·s), with `r' = -p r + v_C` and
//!   moment `u = K C (v_C + (z - p) r)`, which is `u/Q = K (s+z)/(s+p)`.
//!
//! The seed's `x = {q, q̇, Z}` is this state in other coordinates; the modal
//! form is what keeps the stiff beam accurate (see `DESIGN.md`).
//!
//! # Signs (as in `FORMAT.md`)
//! A positive voltage gives a positive moment, positive curvature, positive
//! tip deflection `w` (across the strip), and, with the tip blocked, a
//! positive force on the load cell.
//!
//! # Blocked fixture
//! The tip's deflection is held at zero and its slope is free: the tip's
//! deflection freedom is removed before the modes are found. The state keeps
//! its size; the slot of the removed freedom stays zero.

// Index loops mirror the block structure of the state (η, ζ, e).
#![allow(clippy::needless_range_loop)]

use crate::beam::{assemble, modes};
use crate::matrix::Mat;
use crate::params::{ParamError, Params};
use crate::real::Real;
use crate::zoh::discretise;

/// How the tip is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fixture {
    /// Tip free: the strip bends, a camera watches.
    Free,
    /// Tip deflection held at zero by the load cell, slope free.
    Blocked,
}

/// State length `S` for `n` segments of `e` elements: `2n(2e + 1)`.
pub const fn state_len(n: usize, e: usize) -> usize {
    2 * n * (2 * e + 1)
}

/// The strip model, discretised exactly (zero-order hold) at `dt_s`.
///
/// `N` segments (1..=8), `E` elements per segment (1..=8), `S` the state
/// length, which must be [`state_len`]`(N, E)` (checked at compile time).
///
/// ```
/// use model_core::{Fixture, Params, Strip};
/// // The seed's strip: 3 segments, one element each, 1 kHz.
/// let strip = Strip::<f64, 3, 1, 18>::new(&Params::thesis_2006(), Fixture::Free, 1e-3).unwrap();
/// let mut x = strip.rest();
/// for _ in 0..60_000 {
///     strip.step(&mut x, &[2.5; 3]);
/// }
/// // After 60 s the relaxation has settled: the static 13.0 mm of the seed,
/// // plus the undamped ringing of the first mode around it.
/// let tip = strip.tip_deflection_m(&x);
/// assert!((tip - 13.0e-3).abs() < 6e-3);
/// ```
#[derive(Clone, Debug)]
pub struct Strip<T, const N: usize, const E: usize, const S: usize> {
    params: Params,
    fixture: Fixture,
    dt_s: f64,
    /// `Φ = e^{A h}`.
    phi: [[T; S]; S],
    /// `Γ = ∫₀ʰ e^{A s} ds B`.
    gamma: [[T; N]; S],
    /// Row `d`: freedom `d` (deflection in m, slope in rad) from `η`.
    dof_from_modal: [[T; S]; S],
    /// Blocking force (N) from the whole state.
    force_row: [T; S],
    /// Angular frequencies of the active modes, rad/s, ascending.
    omega_rad_s: [f64; S],
    modes: usize,
    inv_r1: T,
    inv_r2: T,
    kc: T,
    z_minus_p: T,
}

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// Beam freedoms: deflection and slope of every node but the clamp.
    const DOF: usize = 2 * N * E;
    /// Index of the first electrical state.
    const ELEC: usize = 2 * Self::DOF;
    /// Index of the tip's deflection freedom.
    const TIP: usize = Self::DOF - 2;

    /// Builds the model and its exact discretisation at sample time `dt_s`.
    pub fn new(params: &Params, fixture: Fixture, dt_s: f64) -> Result<Self, ParamError> {
        const {
            assert!(N >= 1 && N <= 8, "segments N must be 1..=8");
            assert!(E >= 1 && E <= 8, "elements per segment E must be 1..=8");
            assert!(S == state_len(N, E), "S must be state_len(N, E) = 2N(2E+1)");
        }
        params.validate()?;
        if !dt_s.is_finite() {
            return Err(ParamError::NotFinite {
                field: "dt_s",
                value: dt_s,
            });
        }
        if dt_s <= 0.0 {
            return Err(ParamError::NotPositive {
                field: "dt_s",
                value: dt_s,
            });
        }
        let beam = assemble::<N, E, S>(params);

        let mut active = [0usize; S];
        let mut n_active = 0;
        for d in 0..Self::DOF {
            if !(fixture == Fixture::Blocked && d == Self::TIP) {
                active[n_active] = d;
                n_active += 1;
            }
        }
        let mut psi = [[0.0; S]; S];
        let mut omega2 = [0.0; S];
        modes(&beam.m, &beam.k, &active[..n_active], &mut psi, &mut omega2)?;
        let mut omega = [0.0; S];
        for k in 0..n_active {
            omega[k] = libm::sqrt(omega2[k]);
        }

        let kc = params.k_nm_per_c * params.c_f;
        let z_minus_p = params.z_per_s - params.p_per_s;
        let inv_tau1 = 1.0 / params.tau1_s();
        // g[k][i]: modal force of mode k per unit moment of segment i.
        let mut g = [[0.0; N]; S];
        for (k, gk) in g.iter_mut().enumerate().take(n_active) {
            for (i, gki) in gk.iter_mut().enumerate() {
                *gki = (0..Self::DOF).map(|d| psi[d][k] * beam.f[d][i]).sum();
            }
        }

        // Continuous system in the modal state, then its exact discretisation.
        let mut a: Mat<S, S> = [[0.0; S]; S];
        let mut b: Mat<S, N> = [[0.0; N]; S];
        for k in 0..n_active {
            let (eta, zeta) = (k, Self::DOF + k);
            a[eta][zeta] = omega[k];
            a[zeta][eta] = -omega[k];
            for i in 0..N {
                let (vc, r) = (Self::ELEC + 2 * i, Self::ELEC + 2 * i + 1);
                a[zeta][vc] += g[k][i] * kc / omega[k];
                a[zeta][r] += g[k][i] * kc * z_minus_p / omega[k];
            }
        }
        for i in 0..N {
            let (vc, r) = (Self::ELEC + 2 * i, Self::ELEC + 2 * i + 1);
            a[vc][vc] = -inv_tau1;
            b[vc][i] = inv_tau1;
            a[r][vc] = 1.0;
            a[r][r] = -params.p_per_s;
        }
        let mut phi = [[0.0; S]; S];
        let mut gamma = [[0.0; N]; S];
        discretise(&mut a, &b, dt_s, &mut phi, &mut gamma);

        // Outputs. Freedoms: q = Ψ η; odd rows are ℓθ, so divide by ℓ.
        let mut dof_from_modal = [[T::ZERO; S]; S];
        for d in 0..Self::DOF {
            let scale = if d % 2 == 1 {
                1.0 / beam.element_m
            } else {
                1.0
            };
            for k in 0..n_active {
                dof_from_modal[d][k] = T::from_f64(psi[d][k] * scale);
            }
        }
        // Blocking force on the cell: the tip row of M q̈ + K q = F u,
        // solved for the reaction, F_t u − M_t q̈ − K_t q, with
        // q̈ = Ψ (−Ω² η + g u).
        let mut force_row = [T::ZERO; S];
        if fixture == Fixture::Blocked {
            let t = Self::TIP;
            let mut mt_psi = [0.0; S];
            for k in 0..n_active {
                let mut kt_psi = 0.0;
                for d in 0..Self::DOF {
                    mt_psi[k] += beam.m[t][d] * psi[d][k];
                    kt_psi += beam.k[t][d] * psi[d][k];
                }
                force_row[k] = T::from_f64(-kt_psi + omega2[k] * mt_psi[k]);
            }
            for i in 0..N {
                let mut per_moment = beam.f[t][i];
                for k in 0..n_active {
                    per_moment -= mt_psi[k] * g[k][i];
                }
                force_row[Self::ELEC + 2 * i] = T::from_f64(per_moment * kc);
                force_row[Self::ELEC + 2 * i + 1] = T::from_f64(per_moment * kc * z_minus_p);
            }
        }

        Ok(Strip {
            params: *params,
            fixture,
            dt_s,
            phi: convert(&phi),
            gamma: convert(&gamma),
            dof_from_modal,
            force_row,
            omega_rad_s: omega,
            modes: n_active,
            inv_r1: T::from_f64(1.0 / params.r1_ohm),
            inv_r2: T::from_f64(1.0 / params.r2_ohm),
            kc: T::from_f64(kc),
            z_minus_p: T::from_f64(z_minus_p),
        })
    }

    /// The state at rest: no charge, no motion.
    pub fn rest(&self) -> [T; S] {
        [T::ZERO; S]
    }

    /// Advances one sample: `x ← Φ x + Γ v`, with `v` (V per segment) held
    /// over the step.
    ///
    /// `Φ` is dense only where the physics couples: a mode's `η` and `ζ`
    /// rows see their own pair and the electrical states; electrical rows
    /// see only electrical states. Everything else is exactly zero (the
    /// exponential of a matrix with that structure keeps it), so the loop
    /// skips it: 186 multiply-adds for N = 3 instead of the dense 378.
    #[inline]
    pub fn step(&self, x: &mut [T; S], v: &[T; N]) {
        let mut next = [T::ZERO; S];
        let (beam, elec) = x.split_at(Self::ELEC);
        // One pass per mode: its η and ζ rows share the pair they read.
        for k in 0..Self::DOF {
            let pair = [beam[k], beam[Self::DOF + k]];
            for i in [k, Self::DOF + k] {
                let row = &self.phi[i];
                let mut acc = row[k] * pair[0] + row[Self::DOF + k] * pair[1];
                acc += self.coupled(i, elec, v);
                next[i] = acc;
            }
        }
        for i in Self::ELEC..S {
            next[i] = self.coupled(i, elec, v);
        }
        *x = next;
    }

    /// Row `i` of `Φ` over the electrical states plus row `i` of `Γ v`.
    #[inline(always)]
    fn coupled(&self, i: usize, elec: &[T], v: &[T; N]) -> T {
        let mut acc = T::ZERO;
        for (&p, &e) in self.phi[i][Self::ELEC..].iter().zip(elec) {
            acc += p * e;
        }
        for (&g, &vi) in self.gamma[i].iter().zip(v.iter()) {
            acc += g * vi;
        }
        acc
    }

    /// Tip deflection across the strip, m (zero for the blocked fixture).
    #[inline]
    pub fn tip_deflection_m(&self, x: &[T; S]) -> T {
        dot(&self.dof_from_modal[Self::TIP], x)
    }

    /// Deflection of node `node` (0 = clamp, `N E` = tip), m; `None` past the tip.
    pub fn node_deflection_m(&self, x: &[T; S], node: usize) -> Option<T> {
        match node {
            0 => Some(T::ZERO),
            n if n <= N * E => Some(dot(&self.dof_from_modal[2 * (n - 1)], x)),
            _ => None,
        }
    }

    /// Slope of node `node` (0 = clamp, `N E` = tip), rad; `None` past the tip.
    pub fn node_slope_rad(&self, x: &[T; S], node: usize) -> Option<T> {
        match node {
            0 => Some(T::ZERO),
            n if n <= N * E => Some(dot(&self.dof_from_modal[2 * (n - 1) + 1], x)),
            _ => None,
        }
    }

    /// Bending moment of every segment, N·m.
    pub fn moments_nm(&self, x: &[T; S]) -> [T; N] {
        let mut u = [T::ZERO; N];
        for (i, ui) in u.iter_mut().enumerate() {
            let (vc, r) = (x[Self::ELEC + 2 * i], x[Self::ELEC + 2 * i + 1]);
            *ui = self.kc * (vc + self.z_minus_p * r);
        }
        u
    }

    /// Current into every segment, A, with `v` the voltages applied now:
    /// `i = v/R2 + (v − v_C)/R1` (eq. 2.2), which jumps at a step.
    pub fn currents_a(&self, x: &[T; S], v: &[T; N]) -> [T; N] {
        let mut cur = [T::ZERO; N];
        for (i, c) in cur.iter_mut().enumerate() {
            let vc = x[Self::ELEC + 2 * i];
            *c = v[i] * self.inv_r2 + (v[i] - vc) * self.inv_r1;
        }
        cur
    }

    /// Force on the load cell, N (zero for the free fixture).
    #[inline]
    pub fn blocking_force_n(&self, x: &[T; S]) -> T {
        dot(&self.force_row, x)
    }

    /// Natural frequencies of the beam in this fixture, Hz, ascending.
    pub fn natural_frequencies_hz(&self) -> impl Iterator<Item = f64> + '_ {
        self.omega_rad_s[..self.modes]
            .iter()
            .map(|w| w / (2.0 * core::f64::consts::PI))
    }

    /// The parameters the model was built from.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The fixture the model was built for.
    pub fn fixture(&self) -> Fixture {
        self.fixture
    }

    /// The sample time, s.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// `Φ`, the state transition over one sample.
    pub fn phi(&self) -> &[[T; S]; S] {
        &self.phi
    }

    /// `Γ`, the input matrix over one sample.
    pub fn gamma(&self) -> &[[T; N]; S] {
        &self.gamma
    }
}

#[inline]
fn dot<T: Real, const S: usize>(row: &[T; S], x: &[T; S]) -> T {
    let mut acc = T::ZERO;
    for (&a, &b) in row.iter().zip(x.iter()) {
        acc += a * b;
    }
    acc
}

fn convert<T: Real, const R: usize, const C: usize>(m: &Mat<R, C>) -> [[T; C]; R] {
    let mut out = [[T::ZERO; C]; R];
    for (o, r) in out.iter_mut().zip(m.iter()) {
        for (oo, rr) in o.iter_mut().zip(r.iter()) {
            *oo = T::from_f64(*rr);
        }
    }
    out
}
