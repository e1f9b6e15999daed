//! Large rotation of the free strip: its inertia with the slope field
//! taken whole, for the literature strip's `large-deflection`.
//!
//! The strip is inextensible and its slope field is the beam's low modes',
//! `θ(s) = Σ η_k θ_k(s)`; its points are where that field carries them,
//! `r(s) = ∫₀ˢ (cos θ, sin θ) ds'`, the arc the off-class rig draws. In
//! these coordinates the elastica's bending energy `½ EI ∫ θ'² ds` and the
//! electrodes' work `∫ M θ' ds` are exactly the linear beam's, so the
//! modes keep their stiffness, relaxation spectrum and forcing. What large
//! rotation changes is the kinetic energy `½ ∫ μ |ṙ|² ds`: with
//! `J_k(s) = ∂r/∂η_k = ∫₀ˢ θ_k n ds'` (`n = (−sin θ, cos θ)`, `t = (cos θ,
//! sin θ)`), Lagrange's equations are
//!
//! `M(η) η̈ = Q − K η + ∫ μ J_k · C ds`, `M_kl = ∫ μ J_k · J_l ds`,
//! `C(s) = ∫₀ˢ θ̇² t ds'`,
//!
//! where the linear beam has `M = I` (mass-normalised modes) and `C = 0`.
//! [`Rotation::forces`] gives the difference as a modal force, which the
//! rig's exact modal steps take beside the moments, held over a sub-step
//! as the drag was: on the same grid `M(0)` stands for `I`, so a strip
//! that bends little moves as the linear beam does. In water, the
//! quadratic drag `½ ρ C_d b |v_n| v_n` acts normal to the turned strip,
//! on its velocity `v = Σ J_k η̇_k`, as the modal force `∫ J_k · f ds`.
//!
//! What it leaves out: the fluid's added mass stays in the mass per
//! length, in every direction; the modes above [`Rotation::new`]'s bound
//! keep the linear inertia and feel no drag; the strip's rotary inertia
//! is left out, as the Hermite beam's consistent mass leaves it out. A
//! held tip (load cell) is the linear beam's: the support's reaction is a
//! small-rotation quantity.

use nalgebra::{DMatrix, DVector};

use crate::beam::Beam;

/// Grid points per element for the integrals along the strip (midpoint
/// rule): the modes kept are smooth on an element.
const POINTS_PER_ELEMENT: usize = 4;

/// The largest `ω h` of a mode given the large rotation's inertia: its
/// force is held over a sub-step, which for a mode as quick as its step
/// would be a stiffness taken explicitly.
pub const MAX_OMEGA_H: f64 = 0.3;

/// The large-rotation terms of a free strip's low modes.
pub struct Rotation {
    /// Slope of each kept mode at each grid point, `θ_k(s_g)`, rad per unit `η_k`.
    theta: Vec<Vec<f64>>,
    /// Grid spacing, m.
    ds_m: f64,
    /// Mass per length, kg/m.
    mass_kg_per_m: f64,
    /// `M(0)` on this grid, what stands for the identity.
    m0: DMatrix<f64>,
    /// The kinematics of the last call, their buffers reused: [`Rotation::forces`]
    /// runs on every sub-step.
    scratch: Kinematics,
    /// `½ ρ C_d b` of the fluid's drag, N·s²/m³ (`None`: in air).
    drag: Option<f64>,
}

/// Kinematics at one configuration: positions' sensitivities and the
/// velocity term, per grid point.
#[derive(Default)]
struct Kinematics {
    /// `J_k(s_g)`, `[k][g]`.
    j: Vec<Vec<(f64, f64)>>,
    /// `C(s_g)`.
    c: Vec<(f64, f64)>,
    /// The strip's normal `n(s_g)`.
    n: Vec<(f64, f64)>,
}

impl Rotation {
    /// The terms for `modes` (indices into `beam`'s modes, a leading run
    /// of its free tip's), of a strip of `mass_kg_per_m` per length, in a
    /// fluid whose drag is `drag` (`½ ρ C_d b`, N·s²/m³) or in air.
    pub fn new(beam: &Beam, modes: &[usize], mass_kg_per_m: f64, drag: Option<f64>) -> Rotation {
        let points = beam.elements * POINTS_PER_ELEMENT;
        let ds_m = beam.le_m / POINTS_PER_ELEMENT as f64;
        let theta = modes
            .iter()
            .map(|&k| {
                let mut unit = DVector::zeros(beam.omega.len());
                unit[k] = 1.0;
                let q = beam.nodal(&unit);
                (0..points)
                    .map(|g| beam.slope(&q, (g as f64 + 0.5) * ds_m))
                    .collect()
            })
            .collect();
        let mut r = Rotation {
            theta,
            ds_m,
            mass_kg_per_m,
            m0: DMatrix::zeros(0, 0),
            scratch: Kinematics::default(),
            drag,
        };
        let rest = r.kinematics(&vec![0.0; modes.len()], &vec![0.0; modes.len()]);
        r.m0 = r.mass(&rest);
        r
    }

    /// How many modes it holds.
    pub fn modes(&self) -> usize {
        self.theta.len()
    }

    /// `J` and `C` at modal coordinates `eta` and velocities `eta_d`.
    fn kinematics(&self, eta: &[f64], eta_d: &[f64]) -> Kinematics {
        let mut kin = Kinematics::default();
        self.fill(eta, eta_d, &mut kin);
        kin
    }

    /// [`Rotation::kinematics`] into `kin`'s buffers.
    fn fill(&self, eta: &[f64], eta_d: &[f64], kin: &mut Kinematics) {
        let (n, points) = (self.theta.len(), self.theta.first().map_or(0, Vec::len));
        let h = self.ds_m;
        kin.j.resize_with(n, Vec::new);
        for row in &mut kin.j {
            row.resize(points, (0.0, 0.0));
        }
        kin.c.resize(points, (0.0, 0.0));
        kin.n.resize(points, (0.0, 0.0));
        let Kinematics { j, c, n: normal } = kin;
        // Running integrals to the grid point's start; each point's value
        // adds half its own cell (midpoint rule for the cumulative sums).
        let mut acc_j = vec![(0.0, 0.0); n];
        let mut acc_c = (0.0, 0.0);
        for g in 0..points {
            let (mut th, mut th_d) = (0.0, 0.0);
            for k in 0..n {
                th += eta[k] * self.theta[k][g];
                th_d += eta_d[k] * self.theta[k][g];
            }
            let (sin, cos) = th.sin_cos();
            let (nx, ny) = (-sin, cos);
            normal[g] = (nx, ny);
            for k in 0..n {
                let w = self.theta[k][g] * h;
                j[k][g] = (acc_j[k].0 + 0.5 * w * nx, acc_j[k].1 + 0.5 * w * ny);
                acc_j[k].0 += w * nx;
                acc_j[k].1 += w * ny;
            }
            let w = th_d * th_d * h;
            c[g] = (acc_c.0 + 0.5 * w * cos, acc_c.1 + 0.5 * w * sin);
            acc_c.0 += w * cos;
            acc_c.1 += w * sin;
        }
    }

    /// The mass matrix the forces solve with, `I + M(η) − M(0)`.
    fn effective_mass(&self, kin: &Kinematics) -> DMatrix<f64> {
        let n = self.modes();
        DMatrix::identity(n, n) + self.mass(kin) - &self.m0
    }

    /// `M_kl = ∫ μ J_k · J_l ds`.
    fn mass(&self, kin: &Kinematics) -> DMatrix<f64> {
        let n = kin.j.len();
        let w = self.mass_kg_per_m * self.ds_m;
        DMatrix::from_fn(n, n, |k, l| {
            w * kin.j[k]
                .iter()
                .zip(&kin.j[l])
                .map(|(a, b)| a.0 * b.0 + a.1 * b.1)
                .sum::<f64>()
        })
    }

    /// The modal forces that large rotation adds, into `out`: what makes
    /// the linear model's accelerations `a_lin` (unit mass, every force
    /// but the inertia's) into the large-rotation strip's, at coordinates
    /// `eta` and velocities `eta_d`.
    pub fn forces(&mut self, eta: &[f64], eta_d: &[f64], a_lin: &[f64], out: &mut [f64]) {
        let mut kin = std::mem::take(&mut self.scratch);
        self.fill(eta, eta_d, &mut kin);
        let n = self.modes();
        let m = self.effective_mass(&kin);
        let w = self.mass_kg_per_m * self.ds_m;
        let mut rhs = DVector::from_fn(n, |k, _| {
            a_lin[k]
                + w * kin.j[k]
                    .iter()
                    .zip(&kin.c)
                    .map(|(a, b)| a.0 * b.0 + a.1 * b.1)
                    .sum::<f64>()
        });
        if let Some(drag) = self.drag {
            self.drag_forces(&kin, eta_d, drag, rhs.as_mut_slice());
        }
        let acc = m
            .lu()
            .solve(&rhs)
            .expect("the mass matrix of a strip is positive definite");
        for k in 0..n {
            out[k] = acc[k] - a_lin[k];
        }
        self.scratch = kin;
    }

    /// Adds the modal forces of the drag `½ ρ C_d b |v_n| v_n` (its
    /// coefficient `drag`) normal to the strip to `out`.
    fn drag_forces(&self, kin: &Kinematics, eta_d: &[f64], drag: f64, out: &mut [f64]) {
        for (g, n) in kin.n.iter().enumerate() {
            let (mut vx, mut vy) = (0.0, 0.0);
            for (k, j) in kin.j.iter().enumerate() {
                vx += j[g].0 * eta_d[k];
                vy += j[g].1 * eta_d[k];
            }
            let v_n = vx * n.0 + vy * n.1;
            let f = -drag * v_n.abs() * v_n * self.ds_m;
            for (k, j) in kin.j.iter().enumerate() {
                out[k] += f * (j[g].0 * n.0 + j[g].1 * n.1);
            }
        }
    }

    /// The drag's power at `eta`, `eta_d`, W, from its own formula
    /// `−½ ρ C_d b ∫ |v_n|³ ds` (0 in air), for the tests' energy balance.
    #[cfg(test)]
    fn drag_power_w(&self, eta: &[f64], eta_d: &[f64]) -> f64 {
        let Some(drag) = self.drag else {
            return 0.0;
        };
        let kin = self.kinematics(eta, eta_d);
        (0..kin.n.len())
            .map(|g| {
                let v = (0..self.modes()).fold((0.0, 0.0), |v, k| {
                    (
                        v.0 + kin.j[k][g].0 * eta_d[k],
                        v.1 + kin.j[k][g].1 * eta_d[k],
                    )
                });
                let v_n = v.0 * kin.n[g].0 + v.1 * kin.n[g].1;
                -drag * v_n.abs().powi(3) * self.ds_m
            })
            .sum()
    }

    /// Kinetic energy `½ η̇ᵀ (I + M(η) − M(0)) η̇`, J: the energy the
    /// forces keep with the modes' own.
    pub fn kinetic_j(&self, eta: &[f64], eta_d: &[f64]) -> f64 {
        let m = self.effective_mass(&self.kinematics(eta, eta_d));
        let v = DVector::from_column_slice(eta_d);
        0.5 * v.dot(&(m * &v))
    }

    /// Position of grid point `g` relative to the clamp, m, at `eta`: the
    /// same midpoint sums as the kinematics (for the tests' differences).
    #[cfg(test)]
    fn point(&self, eta: &[f64], g: usize) -> (f64, f64) {
        let h = self.ds_m;
        let th = |p: usize| -> f64 { (0..self.modes()).map(|k| eta[k] * self.theta[k][p]).sum() };
        let (mut x, mut y) = (0.0, 0.0);
        for p in 0..g {
            let t = th(p);
            x += t.cos() * h;
            y += t.sin() * h;
        }
        let t = th(g);
        (x + 0.5 * h * t.cos(), y + 0.5 * h * t.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::beam::Tip;

    /// A strip of the seed's size (40 mm, three segments), and the tip
    /// slope of its first mode at unit `η`.
    fn beam() -> (Beam, f64, f64) {
        let mass = 0.011;
        let beam = Beam::new(0.04, 3, 4, 3.0e-5, mass, Tip::Free);
        let first = DVector::from_fn(beam.omega.len(), |i, _| if i == 0 { 1.0 } else { 0.0 });
        let tip_slope = beam.slope(&beam.nodal(&first), 0.04);
        (beam, mass, tip_slope)
    }

    #[test]
    fn the_sensitivities_and_the_velocity_term_are_the_positions_derivatives() {
        let (beam, mass, tip_slope) = beam();
        let rot = Rotation::new(&beam, &[0, 1, 2], mass, None);
        // A shape whose tip slope is near 0.85 rad, moving.
        let eta = [0.8 / tip_slope, 0.1 / tip_slope, -0.05 / tip_slope];
        let eta_d = [3.0 / tip_slope, -2.0 / tip_slope, 1.0 / tip_slope];
        let kin = rot.kinematics(&eta, &eta_d);
        let points = kin.c.len();
        for g in [0, points / 3, points - 1] {
            for k in 0..3 {
                let e = 1e-6 / tip_slope;
                let (mut up, mut down) = (eta, eta);
                up[k] += e;
                down[k] -= e;
                let (a, b) = (rot.point(&up, g), rot.point(&down, g));
                let fd = ((a.0 - b.0) / (2.0 * e), (a.1 - b.1) / (2.0 * e));
                let j = kin.j[k][g];
                let off = (fd.0 - j.0).hypot(fd.1 - j.1);
                assert!(
                    off < 1e-6 * j.0.hypot(j.1).max(1e-9),
                    "J_{k} at {g}: {j:?} against {fd:?}"
                );
            }
            // Along η(t) = η + η̇ t the acceleration of a point is −C.
            let t = 1e-4;
            let at = |f: f64| -> (f64, f64) {
                let e: Vec<f64> = (0..3).map(|k| eta[k] + eta_d[k] * f * t).collect();
                rot.point(&e, g)
            };
            let (p, m, q) = (at(1.0), at(0.0), at(-1.0));
            let acc = (
                (p.0 - 2.0 * m.0 + q.0) / (t * t),
                (p.1 - 2.0 * m.1 + q.1) / (t * t),
            );
            let c = kin.c[g];
            let off = (acc.0 + c.0).hypot(acc.1 + c.1);
            assert!(
                off <= 1e-3 * c.0.hypot(c.1).max(1e-9),
                "C at {g}: {c:?} against {acc:?}"
            );
        }
    }

    #[test]
    fn a_strip_that_bends_little_moves_as_the_linear_beam() {
        let (beam, mass, tip_slope) = beam();
        let mut rot = Rotation::new(&beam, &[0, 1], mass, None);
        // A tip slope of a microradian, moving at a milliradian a second.
        let eta = [1e-6 / tip_slope, 0.0];
        let eta_d = [1e-3 / tip_slope, 0.0];
        let a_lin = [-beam.omega[0].powi(2) * eta[0], 0.0];
        let mut out = [0.0; 2];
        rot.forces(&eta, &eta_d, &a_lin, &mut out);
        for f in out {
            assert!(f.abs() < 1e-9 * a_lin[0].abs(), "{out:?} for {a_lin:?}");
        }
    }

    /// Three periods of the first mode from a 0.9 rad tip at rest, by
    /// RK4 on the modal equations with the large rotation's forces, no
    /// spectrum, no moment: the energy's largest departure from its start
    /// less the drag's work so far, over the start; the energy lost; and
    /// the swing's largest distance from the linear beam's first mode.
    fn swing(drag: Option<f64>) -> (f64, f64, f64) {
        let (beam, mass, tip_slope) = beam();
        let rot = std::cell::RefCell::new(Rotation::new(&beam, &[0, 1, 2], mass, drag));
        let w = [beam.omega[0], beam.omega[1], beam.omega[2]];
        let energy = |x: &[f64; 6]| -> f64 {
            rot.borrow().kinetic_j(&x[..3], &x[3..])
                + (0..3).map(|k| 0.5 * w[k] * w[k] * x[k] * x[k]).sum::<f64>()
        };
        // The state and the drag's work so far.
        let deriv = |x: &[f64; 7]| -> [f64; 7] {
            let a_lin: Vec<f64> = (0..3).map(|k| -w[k] * w[k] * x[k]).collect();
            let mut f = [0.0; 3];
            rot.borrow_mut().forces(&x[..3], &x[3..6], &a_lin, &mut f);
            let p = rot.borrow().drag_power_w(&x[..3], &x[3..6]);
            [
                x[3],
                x[4],
                x[5],
                a_lin[0] + f[0],
                a_lin[1] + f[1],
                a_lin[2] + f[2],
                p,
            ]
        };
        let add = |x: &[f64; 7], d: &[f64; 7], s: f64| -> [f64; 7] {
            std::array::from_fn(|i| x[i] + s * d[i])
        };
        let amplitude = 0.9 / tip_slope;
        let h = 2.0 * std::f64::consts::PI / w[2] / 200.0;
        let steps = (3.0 * 2.0 * std::f64::consts::PI / w[0] / h).ceil() as usize;
        let mut x = [amplitude, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let state = |x: &[f64; 7]| -> [f64; 6] { std::array::from_fn(|i| x[i]) };
        let e0 = energy(&state(&x));
        let (mut drift, mut apart): (f64, f64) = (0.0, 0.0);
        for step in 1..=steps {
            let k1 = deriv(&x);
            let k2 = deriv(&add(&x, &k1, h / 2.0));
            let k3 = deriv(&add(&x, &k2, h / 2.0));
            let k4 = deriv(&add(&x, &k3, h));
            x = std::array::from_fn(|i| {
                x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
            drift = drift.max(((energy(&state(&x)) - x[6]) / e0 - 1.0).abs());
            // The linear beam's first mode, exactly.
            let linear = amplitude * (w[0] * step as f64 * h).cos();
            apart = apart.max((x[0] - linear).abs() / amplitude.abs());
        }
        (drift, 1.0 - energy(&state(&x)) / e0, apart)
    }

    /// The undamped, unforced modes with the large rotation's forces keep
    /// their energy: the forces are Lagrange's for the kinetic energy the
    /// module states (a sign or a factor wrong in `C` breaks it); and the
    /// swing at a 0.9 rad tip is not the linear beam's.
    #[test]
    fn the_undamped_strip_keeps_its_energy_and_swings_unlike_the_linear_beam() {
        let (drift, lost, apart) = swing(None);
        assert!(drift < 1e-6, "energy drifts by {drift:e}");
        assert!(lost.abs() < 1e-6, "{lost:e} lost");
        assert!(apart > 0.01, "apart by {apart:.4} of the amplitude");
    }

    /// In water the energy falls by the drag's work `∫ |v_n|³`, reckoned on
    /// its own: the modal forces are the drag's, normal to the strip.
    #[test]
    fn in_water_the_strip_loses_the_drags_work_and_no_more() {
        // Water's ½ ρ C_d b for a 10 mm strip, C_d = 2.
        let (drift, lost, _) = swing(Some(0.5 * 1000.0 * 2.0 * 0.01));
        assert!(lost > 0.1, "the drag took {lost:.3} of the energy");
        assert!(
            drift < 1e-5,
            "energy less the drag's work drifts by {drift:e}"
        );
    }
}
