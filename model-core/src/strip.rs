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
//!   `r` (the relaxation network's state, V·s), with `r' = -p r + v_C` and
//!   moment `u = C (a v_C + (b − a p) r)`, which is
//!   `u/Q = (a s + b)/(s + p)`, the seed's `K (s+z)/(s+p)` with `a = K`,
//!   `b = K z`.
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

use crate::beam::assemble;
use crate::beam_modes::{loaded, BeamModes};
use crate::circuit::Circuit;
use crate::extensions::Extensions;
use crate::matrix::{dof_zeros, rows, rows_mut, DofMat, Mat, Square};
use crate::params::{ParamError, Params};
use crate::real::Real;
use crate::rounding::round_block;
use crate::zoh::discretise;

mod harmonic;
mod step;
pub use harmonic::{Harmonic, HarmonicError};
pub use step::{StepError, TipStep};

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
/// let strip = Strip::<f64, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3).unwrap();
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
    ext: Extensions,
    fixture: Fixture,
    dt_s: f64,
    /// The modes' own blocks of `Φ`, `[ηη, ηζ, ζη, ζζ]`, indexed by mode
    /// (entries past the `2NE` modes unused).
    rot: [[T; S]; 4],
    /// Per segment, the columns of `Φ` (for `v_C` and `r`) and of `Γ` over
    /// the `η` and `ζ` rows (entries past `4NE` unused).
    drive: [[[T; S]; 3]; N],
    /// The electrics of every segment: the electrical states' own blocks
    /// and the currents.
    circuit: Circuit<T, N>,
    /// Row `d` (of `2NE`, see [`rows`]): freedom `d` (deflection in m,
    /// slope in rad) from `η`.
    dof_from_modal: DofMat<T, N, E, S>,
    /// Blocking force (N) from the whole state.
    force_row: [T; S],
    /// Angular frequencies of the active modes, rad/s, ascending.
    omega_rad_s: [f64; S],
    modes: usize,
    /// `C a` of every segment: moment per volt of `v_C`, N·m/V.
    instant: [T; N],
    /// `C (b − a p)` of every segment: moment per unit of `r`, N·m/(V·s).
    lag: [T; N],
    /// `κ`, the moment a segment puts on each neighbour.
    crosstalk: T,
    /// Scale of every moment (1 unless dehydration lowers it).
    moment_gain: T,
    /// The quadratic drag's `c₂ ℓ h` (N·s³/m²): an interior node's share
    /// of it over one step (the tip's is half); 0 when off.
    drag_per_node: T,
    /// `ωₖ` of the modes the drag acts on, rad/s (0 past them).
    drag_omega: [T; DRAGGED_MODES],
    /// `1/ωₖ` of the same, s (0 past them).
    drag_inv_omega: [T; DRAGGED_MODES],
}

/// Modes the quadratic drag acts on: the lowest, which carry a swinging
/// strip's speed. A mode above them is stiff enough that the drag moves
/// it by next to nothing, and a fixed count keeps the step's solve small
/// (`4 × 4`) and its stack fixed.
pub const DRAGGED_MODES: usize = 4;

/// What the modal analysis of the beam gives, in `f64`: only what the
/// discretisation and the outputs need, so that the beam's matrices do not
/// stay on the stack while the model is built.
struct Analysis<'m, const N: usize, const E: usize, const S: usize> {
    /// Element length `ℓ`, m.
    element_m: f64,
    /// The tip deflection's rows of `M` and `K` (the load cell's force).
    m_tip: [f64; S],
    k_tip: [f64; S],
    /// The tip deflection's row of `F` with crosstalk: load per unit moment
    /// of segment `i`.
    f_tip: [f64; N],
    /// Mass-normalised modes as columns (rows: freedoms).
    psi: &'m Square<N, E>,
    omega2: &'m [f64; S],
    omega: [f64; S],
    /// `g[k][i]`: modal force of mode `k` per unit moment of segment `i`,
    /// crosstalk included.
    g: [[f64; N]; S],
    /// `2ζω` of every mode, 1/s.
    two_zeta_omega: [f64; S],
    modes: usize,
}

/// One segment's electrical and relaxation values: the shared ones, or
/// its own under `segment-variation`.
#[derive(Clone, Copy)]
struct Segment {
    r1_ohm: f64,
    c_f: f64,
    /// The moment gain's factor over the shared network's.
    gain: f64,
}

impl Segment {
    /// Every segment's values.
    fn all<const N: usize>(params: &Params, ext: &Extensions) -> [Segment; N] {
        core::array::from_fn(|i| {
            let (r1_ohm, c_f, gain) =
                ext.segment_variation
                    .segment(i, params.r1_ohm, params.c_f, 1.0);
            Segment { r1_ohm, c_f, gain }
        })
    }

    /// `1/τ1 = 1/(R1 C)`, 1/s.
    fn inv_tau1(&self) -> f64 {
        1.0 / (self.r1_ohm * self.c_f)
    }

    /// The moment's coefficients on `v_C` and `r`: `C a` and
    /// `C (b − a p)`, times the segment's gain (exactly the shared
    /// network's at gain 1).
    fn moment(&self, params: &Params) -> (f64, f64) {
        let c = self.c_f;
        (
            c * params.a_nm_per_c * self.gain,
            c * (params.b_nm_per_c_s - params.a_nm_per_c * params.p_per_s) * self.gain,
        )
    }
}

impl<T: Real, const N: usize, const E: usize, const S: usize> Strip<T, N, E, S> {
    /// Beam freedoms: deflection and slope of every node but the clamp.
    const DOF: usize = 2 * N * E;
    /// Index of the first electrical state.
    const ELEC: usize = 2 * Self::DOF;
    /// Index of the tip's deflection freedom.
    const TIP: usize = Self::DOF - 2;

    /// Builds the model and its exact discretisation at sample time `dt_s`.
    ///
    /// The exponential is taken block by block, which is exact because the
    /// modes couple only through the electrical states: one 4-state
    /// exponential per mode (its rotation driven by one segment's electrics
    /// with unit coupling) gives the mode's rotation and, scaled by each
    /// segment's coupling, its columns of `Φ` and `Γ`. Segments whose `τ1`
    /// differs (`segment-variation`) get their own exponential. No `S × S`
    /// exponential is formed, which keeps the stack small enough to
    /// re-discretise on the board.
    pub fn new(params: &Params, fixture: Fixture, dt_s: f64) -> Result<Self, ParamError> {
        Self::with_extensions(params, &Extensions::NONE, fixture, dt_s)
    }

    /// Builds the model with the optional terms of `ext` (see
    /// [`Extensions`]) and its exact discretisation at sample time `dt_s`.
    pub fn with_extensions(
        params: &Params,
        ext: &Extensions,
        fixture: Fixture,
        dt_s: f64,
    ) -> Result<Self, ParamError> {
        Self::check(params, ext)?;
        check_sample_time(dt_s)?;
        let modes = BeamModes::new(params, ext, fixture)?;
        Ok(Self::built(&modes, params, ext, dt_s))
    }

    /// Builds the model of `params` and `ext` on a beam's kept `modes`
    /// (see [`BeamModes`]): the strip [`Strip::with_extensions`] builds in
    /// the modes' fixture, bit for bit, without solving the beam again.
    /// Modes of another beam (not [`BeamModes::is_for`] these values) are
    /// solved anew, so the strip is always the one `params` describe.
    pub fn with_modes(
        modes: &BeamModes<N, E, S>,
        params: &Params,
        ext: &Extensions,
        dt_s: f64,
    ) -> Result<Self, ParamError> {
        Self::check(params, ext)?;
        check_sample_time(dt_s)?;
        if modes.is_for(params, ext) {
            Ok(Self::built(modes, params, ext, dt_s))
        } else {
            let fresh = BeamModes::new(params, ext, modes.fixture())?;
            Ok(Self::built(&fresh, params, ext, dt_s))
        }
    }

    /// The sizes (at compile time) and the values a model is built from.
    fn check(params: &Params, ext: &Extensions) -> Result<(), ParamError> {
        const {
            assert!(N >= 1 && N <= 8, "segments N must be 1..=8");
            assert!(E >= 1 && E <= 8, "elements per segment E must be 1..=8");
            assert!(S == state_len(N, E), "S must be state_len(N, E) = 2N(2E+1)");
        }
        params.validate_relaxation(ext.back_relaxation)?;
        ext.validate()?;
        ext.segment_variation.validate_for(N)
    }

    /// The strip on `modes`, from checked values.
    #[inline(always)]
    fn built(modes: &BeamModes<N, E, S>, params: &Params, ext: &Extensions, dt_s: f64) -> Self {
        let fixture = modes.fixture();
        let an = Self::analyse(params, ext, modes);
        let segments = Segment::all::<N>(params, ext);
        // The pieces are inlined: the board re-discretises with the same
        // stack as when they were one function.
        let circuit = Circuit::built(params, ext, dt_s);
        let (rot, drive) = Self::modal_steps(&an, params, &segments, dt_s);
        let dof_from_modal = Self::modal_to_dof(&an);
        let force_row = if fixture == Fixture::Blocked {
            Self::blocking_force_row(&an, params, &segments)
        } else {
            [T::ZERO; S]
        };

        Strip {
            params: *params,
            ext: *ext,
            fixture,
            dt_s,
            rot,
            drive,
            circuit,
            dof_from_modal,
            force_row,
            omega_rad_s: an.omega,
            modes: an.modes,
            instant: segments.map(|seg| T::from_f64(seg.moment(params).0)),
            lag: segments.map(|seg| T::from_f64(seg.moment(params).1)),
            crosstalk: T::from_f64(ext.crosstalk),
            moment_gain: T::from_f64(1.0),
            drag_per_node: T::from_f64(ext.drag_quadratic_n_s2_per_m3 * an.element_m * dt_s),
            drag_omega: core::array::from_fn(|k| {
                T::from_f64(if k < an.modes { an.omega[k] } else { 0.0 })
            }),
            drag_inv_omega: core::array::from_fn(|k| {
                T::from_f64(if k < an.modes { 1.0 / an.omega[k] } else { 0.0 })
            }),
        }
    }

    /// Each mode's rotation over one step, and its columns of `Φ` and `Γ`
    /// driven by each segment's electrics.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn modal_steps(
        an: &Analysis<'_, N, E, S>,
        params: &Params,
        segments: &[Segment; N],
        dt_s: f64,
    ) -> ([[T; S]; 4], [[[T; S]; 3]; N]) {
        // The reference segment's moment drives each exponential; another
        // segment's columns are those times its moment over the reference's
        // (both coefficients scale alike: `C` and the gain).
        let (instant, lag) = segments[0].moment(params);
        // A removed freedom's slot (blocked tip) keeps its value, as the
        // exponential of its zero rows would: the identity.
        let mut rot = [[T::ZERO; S]; 4];
        for k in an.modes..Self::DOF {
            rot[0][k] = T::from_f64(1.0);
            rot[3][k] = T::from_f64(1.0);
        }
        let mut drive = [[[T::ZERO; S]; 3]; N];
        for k in 0..an.modes {
            let w = an.omega[k];
            let (mut phi, mut gamma) = ([[0.0; 4]; 4], [[0.0; 1]; 4]);
            // The τ1 of the last exponential: alike segments share it.
            let mut done_inv_tau1 = f64::NAN;
            for (i, (cols, seg)) in drive.iter_mut().zip(segments).enumerate() {
                let inv_tau1 = seg.inv_tau1();
                if inv_tau1 != done_inv_tau1 {
                    // Mode k driven by this segment with unit modal coupling.
                    let mut a = [
                        [0.0, w, 0.0, 0.0],
                        [-w, -an.two_zeta_omega[k], instant / w, lag / w],
                        [0.0, 0.0, -inv_tau1, 0.0],
                        [0.0, 0.0, 1.0, -params.p_per_s],
                    ];
                    let b = [[0.0], [0.0], [inv_tau1], [0.0]];
                    discretise(&mut a, &b, dt_s, &mut phi, &mut gamma);
                    done_inv_tau1 = inv_tau1;
                }
                if i == 0 {
                    // The rotation does not depend on the electrics: the
                    // reference segment's exponential gives it, rounded so
                    // that an undamped mode cannot grow in f32.
                    let r: [[T; 2]; 2] =
                        round_block([[phi[0][0], phi[0][1]], [phi[1][0], phi[1][1]]]);
                    rot[0][k] = r[0][0];
                    rot[1][k] = r[0][1];
                    rot[2][k] = r[1][0];
                    rot[3][k] = r[1][1];
                }
                let scale = seg.c_f * seg.gain / (segments[0].c_f * segments[0].gain);
                let coupling = an.g[k][i] * scale;
                for (row, dof) in [(0, k), (1, Self::DOF + k)] {
                    cols[0][dof] = T::from_f64(coupling * phi[row][2]);
                    cols[1][dof] = T::from_f64(coupling * phi[row][3]);
                    cols[2][dof] = T::from_f64(coupling * gamma[row][0]);
                }
            }
        }
        (rot, drive)
    }

    /// The freedoms from the modal coordinates: `q = Ψ η`; odd rows are
    /// `ℓθ`, so divide by `ℓ`.
    #[inline(always)]
    fn modal_to_dof(an: &Analysis<'_, N, E, S>) -> DofMat<T, N, E, S> {
        let mut dof_from_modal = dof_zeros(T::ZERO);
        let (rows_out, psi) = (rows_mut(&mut dof_from_modal), &an.psi);
        for d in 0..Self::DOF {
            let scale = if d % 2 == 1 { 1.0 / an.element_m } else { 1.0 };
            for k in 0..an.modes {
                rows_out[d][k] = T::from_f64(psi[(d, k)] * scale);
            }
        }
        dof_from_modal
    }

    /// Blocking force on the cell: the tip row of `M q̈ + K q = F u`,
    /// solved for the reaction, `F_t u − M_t q̈ − K_t q`, with
    /// `q̈ = Ψ (−Ω² η − 2ζω η̇ + g u)`; a row over the state. The damping
    /// acts on the modes of the held beam, not on the pinned freedom, so
    /// it enters the force through the accelerations alone (as in the
    /// rig's reference, `tests/rig/tests/against_model.rs`).
    #[inline(always)]
    fn blocking_force_row(
        an: &Analysis<'_, N, E, S>,
        params: &Params,
        segments: &[Segment; N],
    ) -> [T; S] {
        let mut force_row = [T::ZERO; S];
        let (m_t, k_t, psi) = (&an.m_tip, &an.k_tip, &an.psi);
        let mut mt_psi = [0.0; S];
        for k in 0..an.modes {
            let mut kt_psi = 0.0;
            for d in 0..Self::DOF {
                mt_psi[k] += m_t[d] * psi[(d, k)];
                kt_psi += k_t[d] * psi[(d, k)];
            }
            force_row[k] = T::from_f64(-kt_psi + an.omega2[k] * mt_psi[k]);
            // η̇ = ω ζ-coordinate, so −M_t Ψ (−2ζω η̇) is this times it.
            force_row[Self::DOF + k] = T::from_f64(mt_psi[k] * an.two_zeta_omega[k] * an.omega[k]);
        }
        for i in 0..N {
            let (instant, lag) = segments[i].moment(params);
            let mut per_moment = an.f_tip[i];
            for k in 0..an.modes {
                per_moment -= mt_psi[k] * an.g[k][i];
            }
            force_row[Self::ELEC + 2 * i] = T::from_f64(per_moment * instant);
            force_row[Self::ELEC + 2 * i + 1] = T::from_f64(per_moment * lag);
        }
        force_row
    }

    /// The beam's analysis on its `modes`: frequencies, modal forces per
    /// segment (with crosstalk), damping and the load cell's rows.
    ///
    /// Not inlined: the assembled matrices are then freed on return
    /// instead of piling up in the caller's frame, which keeps
    /// [`Strip::new`] within a Cortex-M4's RAM for N = 8.
    #[inline(never)]
    fn analyse<'m>(
        params: &Params,
        ext: &Extensions,
        modes: &'m BeamModes<N, E, S>,
    ) -> Analysis<'m, N, E, S> {
        // Assembled again for `F` and the tip's rows: cheap beside the modes.
        let beam = assemble::<N, E, S>(&loaded(params, ext));
        let (psi, omega2, n_active) = (&modes.psi, &modes.omega2, modes.count);
        let mut omega = [0.0; S];
        for k in 0..n_active {
            omega[k] = libm::sqrt(omega2[k]);
        }
        // Crosstalk: segment i's moment also acts, times κ, on i ± 1.
        let mut f = [[0.0; N]; S];
        for d in 0..Self::DOF {
            for i in 0..N {
                f[d][i] = beam.f[d][i];
                for j in [i.wrapping_sub(1), i + 1] {
                    if j < N {
                        f[d][i] += ext.crosstalk * beam.f[d][j];
                    }
                }
            }
        }
        let mut g = [[0.0; N]; S];
        for (k, gk) in g.iter_mut().enumerate().take(n_active) {
            for (i, gki) in gk.iter_mut().enumerate() {
                *gki = (0..Self::DOF).map(|d| psi[(d, k)] * f[d][i]).sum();
            }
        }
        let mut two_zeta_omega = [0.0; S];
        for k in 0..n_active {
            two_zeta_omega[k] = ext.two_zeta_omega(
                modes.fixture(),
                k,
                omega[k],
                params.mass_per_length_kg_per_m,
            );
        }
        let (mut m_tip, mut k_tip) = ([0.0; S], [0.0; S]);
        m_tip[..Self::DOF].copy_from_slice(beam.m.row(Self::TIP));
        k_tip[..Self::DOF].copy_from_slice(beam.k.row(Self::TIP));
        Analysis {
            element_m: beam.element_m,
            m_tip,
            k_tip,
            f_tip: f[Self::TIP],
            psi,
            omega2,
            omega,
            g,
            two_zeta_omega,
            modes: n_active,
        }
    }

    /// The continuous system `ẋ = A x + B v` in the state of this model,
    /// which [`Strip::new`] discretises: for checks and for export to other
    /// tools. Builds `S × S` arrays, so it is meant for the host.
    ///
    /// The electrochemical input nonlinearity, the moment gain and the
    /// quadratic drag are not part of it (they act on `v`, on the moments
    /// and on the velocities after each step).
    pub fn continuous(
        params: &Params,
        ext: &Extensions,
        fixture: Fixture,
    ) -> Result<(Mat<S, S>, Mat<S, N>), ParamError> {
        Self::check(params, ext)?;
        let modes = BeamModes::new(params, ext, fixture)?;
        let an = Self::analyse(params, ext, &modes);
        let segments = Segment::all::<N>(params, ext);
        let mut a = [[0.0; S]; S];
        let mut b = [[0.0; N]; S];
        for k in 0..an.modes {
            let (eta, zeta, w) = (k, Self::DOF + k, an.omega[k]);
            a[eta][zeta] = w;
            a[zeta][eta] = -w;
            a[zeta][zeta] = -an.two_zeta_omega[k];
            for i in 0..N {
                let (vc, r) = (Self::ELEC + 2 * i, Self::ELEC + 2 * i + 1);
                let (instant, lag) = segments[i].moment(params);
                a[zeta][vc] = an.g[k][i] * instant / w;
                a[zeta][r] = an.g[k][i] * lag / w;
            }
        }
        for i in 0..N {
            let (vc, r) = (Self::ELEC + 2 * i, Self::ELEC + 2 * i + 1);
            let inv_tau1 = segments[i].inv_tau1();
            a[vc][vc] = -inv_tau1;
            b[vc][i] = inv_tau1;
            a[r][vc] = 1.0;
            a[r][r] = -params.p_per_s;
        }
        Ok((a, b))
    }

    /// The state at rest: no charge, no motion.
    pub fn rest(&self) -> [T; S] {
        [T::ZERO; S]
    }

    /// Advances one sample: `x ← Φ x + Γ v`, with `v` (V per segment) held
    /// over the step, then (when on) the quadratic drag's implicit step on
    /// the lowest modes' velocities.
    ///
    /// `Φ` is sparse in a fixed pattern: a mode sees its own pair and the
    /// electrical states; electrical states see only their own segment's.
    /// The step walks the stored blocks (147 multiply-adds for N = 3 instead
    /// of the dense 378), each loop running along a contiguous column so
    /// that it vectorises on the host and pipelines on the Cortex-M4F.
    /// Always inlined, so that a caller compiled for wider vectors (the
    /// host's AVX2 run) compiles it for them too.
    #[inline(always)]
    pub fn step(&self, x: &mut [T; S], v: &[T; N]) {
        let dof = Self::DOF;
        // The double layer sees v (1 + a v²): exact under the hold, since
        // v is held. The beam sees every moment times the gain.
        let v = self.circuit.double_layer_v(v);
        let gain = self.moment_gain;
        // In place: each mode's pair rotated, then every modal row driven
        // by the old electrics, a segment at a time (one column triple,
        // all modal rows: contiguous loads), then the electrics from
        // themselves. The same sums in the same order as into a fresh
        // state, with no state copied back: a memcpy per step was 7 % of a
        // fit (perf 2026-11-27).
        let (beam, elec) = x.split_at_mut(Self::ELEC);
        // A reaction behind the layer takes its share of the drive over the
        // step (off: the layer's voltage itself).
        let v = self.circuit.drive(v, |i| elec[2 * i]);
        {
            let (eta, zeta) = beam.split_at_mut(dof);
            let [r0, r1, r2, r3] = &self.rot;
            for k in 0..dof {
                let (e, z) = (eta[k], zeta[k]);
                eta[k] = r0[k] * e + r1[k] * z;
                zeta[k] = r2[k] * e + r3[k] * z;
            }
        }
        for ((cols, e), &vi) in self.drive.iter().zip(elec.chunks_exact(2)).zip(v.iter()) {
            let (vc, r, vi) = (gain * e[0], gain * e[1], gain * vi);
            for (((n, &c0), &c1), &c2) in beam
                .iter_mut()
                .zip(&cols[0][..2 * dof])
                .zip(&cols[1][..2 * dof])
                .zip(&cols[2][..2 * dof])
            {
                *n += c0 * vc + c1 * r + c2 * vi;
            }
        }
        for (i, (e, &vi)) in elec.chunks_exact_mut(2).zip(v.iter()).enumerate() {
            let next = self.circuit.next(i, [e[0], e[1]], vi);
            e.copy_from_slice(&next);
        }
        if self.drag_per_node != T::ZERO {
            self.quadratic_drag(x);
        }
    }

    /// The quadratic drag over the step just taken: `c₂ |vₙ| vₙ` at every
    /// node, linearly implicit in the speed. With `η̇` the lowest
    /// [`DRAGGED_MODES`] modes' velocities after the exact linear step and
    /// `D = Σₙ cₙ |vₙ| ψₙ ψₙᵀ` (`ψₙ` node `n`'s row of the mass-normalised
    /// modes, `cₙ` its share of `c₂ ℓ h`), the velocities become
    /// `(I + D)⁻¹ η̇`. `I + D` is symmetric positive definite, so the step
    /// only ever takes energy out, however fast the strip swings (an
    /// explicit drag would overshoot and reverse a fast node), and it
    /// tends to the continuous drag as `h` falls (first order: the drag is
    /// split from the exact linear step). The held tip's force leaves the
    /// drag's share out: at a held strip's micrometres per second the
    /// drag, quadratic in them, is far below the load cell's noise.
    // Inlined: as a call, the board's step spilled registers around it
    // even untaken (512 to 568 instructions, `scripts/count-step-cycles`);
    // inlined, 522.
    #[inline(always)]
    fn quadratic_drag(&self, x: &mut [T; S]) {
        const M: usize = DRAGGED_MODES;
        let dof = Self::DOF;
        let m = self.modes.min(M);
        // The solve runs over all four modes, so that it unrolls: a mode
        // past the strip's has zero rows and a velocity of 0, so it adds
        // nothing; only the strip's modes are read from and written to
        // the state (past them, `x` holds other states).
        let mut vel = [T::ZERO; M];
        for k in 0..m {
            vel[k] = self.drag_omega[k] * x[dof + k];
        }
        let mut a = [[T::ZERO; M]; M];
        for (k, row) in a.iter_mut().enumerate() {
            row[k] = T::from_f64(1.0);
        }
        let nodes = N * E;
        for (n, row) in rows(&self.dof_from_modal).iter().step_by(2).enumerate() {
            let psi: [T; M] = core::array::from_fn(|k| row[k]);
            let mut v_n = T::ZERO;
            for k in 0..M {
                v_n += psi[k] * vel[k];
            }
            let speed = if v_n < T::ZERO { -v_n } else { v_n };
            let mut c = self.drag_per_node * speed;
            if n + 1 == nodes {
                c *= T::from_f64(0.5);
            }
            for k in 0..M {
                let ck = c * psi[k];
                for l in 0..M {
                    a[k][l] += ck * psi[l];
                }
            }
        }
        // Gaussian elimination without pivots: `I + D` is symmetric
        // positive definite, so every pivot is at least 1.
        // One division per pivot, its reciprocal used after.
        let mut inv_pivot = [T::ZERO; M];
        for k in 0..M {
            inv_pivot[k] = T::from_f64(1.0) / a[k][k];
            for r in k + 1..M {
                let f = a[r][k] * inv_pivot[k];
                for c in k..M {
                    let akc = a[k][c];
                    a[r][c] -= f * akc;
                }
                let vk = vel[k];
                vel[r] -= f * vk;
            }
        }
        for k in (0..M).rev() {
            let mut sum = vel[k];
            for c in k + 1..M {
                sum -= a[k][c] * vel[c];
            }
            vel[k] = sum * inv_pivot[k];
        }
        for k in 0..m {
            x[dof + k] = vel[k] * self.drag_inv_omega[k];
        }
    }

    /// Tip deflection across the strip, m (zero for the blocked fixture).
    #[inline]
    pub fn tip_deflection_m(&self, x: &[T; S]) -> T {
        dot(&rows(&self.dof_from_modal)[Self::TIP], x, self.modes)
    }

    /// Deflection of node `node` (0 = clamp, `N E` = tip), m; `None` past the tip.
    pub fn node_deflection_m(&self, x: &[T; S], node: usize) -> Option<T> {
        match node {
            0 => Some(T::ZERO),
            n if n <= N * E => Some(dot(&rows(&self.dof_from_modal)[2 * (n - 1)], x, self.modes)),
            _ => None,
        }
    }

    /// Slope of node `node` (0 = clamp, `N E` = tip), rad; `None` past the tip.
    pub fn node_slope_rad(&self, x: &[T; S], node: usize) -> Option<T> {
        match node {
            0 => Some(T::ZERO),
            n if n <= N * E => Some(dot(
                &rows(&self.dof_from_modal)[2 * (n - 1) + 1],
                x,
                self.modes,
            )),
            _ => None,
        }
    }

    /// Bending moment acting on every segment, N·m: its own, plus `κ`
    /// times its neighbours' (crosstalk), times the moment gain.
    pub fn moments_nm(&self, x: &[T; S]) -> [T; N] {
        let own: [T; N] = core::array::from_fn(|i| {
            let (vc, r) = (x[Self::ELEC + 2 * i], x[Self::ELEC + 2 * i + 1]);
            self.instant[i] * vc + self.lag[i] * r
        });
        core::array::from_fn(|i| {
            let mut u = own[i];
            if i > 0 {
                u += self.crosstalk * own[i - 1];
            }
            if i + 1 < N {
                u += self.crosstalk * own[i + 1];
            }
            self.moment_gain * u
        })
    }

    /// Current into every segment, A, with `v` the voltages applied now:
    /// `i = v/R2 + (v − v_C)/R1` (eq. 2.2), which jumps at a step; with the
    /// electrochemical terms, `v/R2 (1 + b v²) + (v (1 + a v²) − v_C)/R1`.
    pub fn currents_a(&self, x: &[T; S], v: &[T; N]) -> [T; N] {
        core::array::from_fn(|i| self.circuit.current(i, v[i], x[Self::ELEC + 2 * i]))
    }

    /// Force on the load cell, N (zero for the free fixture). Always
    /// inlined, as [`Strip::step`] is.
    #[inline(always)]
    pub fn blocking_force_n(&self, x: &[T; S]) -> T {
        // The electrical entries carry the moments, so the gain scales them.
        let (beam, elec) = x.split_at(Self::ELEC);
        let (row_beam, row_elec) = self.force_row.split_at(Self::ELEC);
        let mut inertial = T::ZERO;
        for (&a, &b) in row_beam.iter().zip(beam) {
            inertial += a * b;
        }
        let mut moments = T::ZERO;
        for (&a, &b) in row_elec.iter().zip(elec) {
            moments += a * b;
        }
        inertial + self.moment_gain * moments
    }

    /// Sets the scale of every moment (1 when built). The dehydration
    /// extension lowers it over a session's minutes; the caller computes it
    /// from session time, since the model knows no clock. It applies from
    /// the next step on; a gain that changes slowly against the beam's
    /// modes (seconds against 40 ms) is what it is meant for.
    pub fn set_moment_gain(&mut self, gain: T) {
        self.moment_gain = gain;
    }

    /// The moment gain now.
    pub fn moment_gain(&self) -> T {
        self.moment_gain
    }

    /// The optional terms the model was built with.
    pub fn extensions(&self) -> &Extensions {
        &self.ext
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

    /// `Φ`, the state transition over one sample, assembled from the
    /// stored blocks (`S × S`: for checks and export on the host).
    pub fn phi(&self) -> [[T; S]; S] {
        let dof = Self::DOF;
        let mut phi = [[T::ZERO; S]; S];
        for k in 0..dof {
            phi[k][k] = self.rot[0][k];
            phi[k][dof + k] = self.rot[1][k];
            phi[dof + k][k] = self.rot[2][k];
            phi[dof + k][dof + k] = self.rot[3][k];
        }
        for (i, (cols, &[a, b, c, _, _])) in self.drive.iter().zip(&self.circuit.elec).enumerate() {
            let (vc, r) = (Self::ELEC + 2 * i, Self::ELEC + 2 * i + 1);
            for row in 0..Self::ELEC {
                phi[row][vc] = cols[0][row];
                phi[row][r] = cols[1][row];
            }
            phi[vc][vc] = a;
            phi[r][vc] = b;
            phi[r][r] = c;
        }
        phi
    }

    /// `Γ`, the input matrix over one sample, assembled from the stored
    /// blocks (for checks and export on the host).
    pub fn gamma(&self) -> [[T; N]; S] {
        let mut gamma = [[T::ZERO; N]; S];
        for (i, (cols, &[_, _, _, g0, g1])) in self.drive.iter().zip(&self.circuit.elec).enumerate()
        {
            for row in 0..Self::ELEC {
                gamma[row][i] = cols[2][row];
            }
            gamma[Self::ELEC + 2 * i][i] = g0;
            gamma[Self::ELEC + 2 * i + 1][i] = g1;
        }
        gamma
    }
}

/// A row of the freedoms from `η` times the state: the first `modes`
/// entries alone, where the row is not zero (the rest are `ζ` and the
/// electrics, which a deflection does not read). The same sum as over all
/// `S`, a third of the work for `E = 1`.
#[inline]
fn dot<T: Real, const S: usize>(row: &[T; S], x: &[T; S], modes: usize) -> T {
    let mut acc = T::ZERO;
    for (&a, &b) in row[..modes].iter().zip(&x[..modes]) {
        acc += a * b;
    }
    acc
}

/// A sample time the discretisation accepts: finite and above 0.
pub(crate) fn check_sample_time(dt_s: f64) -> Result<(), ParamError> {
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
    Ok(())
}
