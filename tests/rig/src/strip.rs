//! The rig's strip in time: electrics and relaxation by fourth-order
//! Runge–Kutta on a tenth of the DAQ's sample time (they are nonlinear
//! here), the beam mode by mode, each integrated exactly for a moment that
//! is linear across the sub-step (first-order hold), not the fitted
//! models' zero-order hold. Modes above the mesh's dynamic limit answer
//! statically. [`run`] starts every recording with the strip at rest;
//! [`run_lab`] adds what a lab bench has ([`Lab`]): a recording that
//! starts from the state the last one left, the strip's own curl, an open
//! contact, a moment that differs by sign. The literature strip
//! ([`crate::literature`]) runs through the same loop with its own
//! electrics (each segment a line of patches, each patch its own moment)
//! and its modes stepped with their relaxation spectrum.

use finrs::recording::Voltages;
use nalgebra::{DVector, Matrix4};

use crate::beam::{Beam, Tip};
use crate::literature::{Lines, ViscoStep};
use crate::rotation::{Rotation, MAX_OMEGA_H};
use crate::sample::{Hidden, Sample, WATER_KG_M3};

/// Sub-steps per DAQ row.
pub const SUBSTEPS: usize = 10;

/// Drag acts through the modes below this frequency, Hz: held over a
/// sub-step, it would destabilise the stiff ones, whose velocities are
/// nanometres a second.
pub const DRAG_LIMIT_HZ: f64 = 2_000.0;

/// How finely the rig resolves the beam.
#[derive(Clone, Copy, Debug)]
pub struct Mesh {
    /// Elements per segment.
    pub per_segment: usize,
    /// Modes above this frequency follow their load statically, Hz.
    pub dynamic_limit_hz: f64,
}

/// The rig's mesh for a free tip: twice the finest fitted one; modes to
/// 20 kHz in time.
pub const MESH: Mesh = Mesh {
    per_segment: 8,
    dynamic_limit_hz: 20_000.0,
};

/// The rig's mesh for a blocked tip: the fitted models' own, every mode in
/// time. The undamped pinned beam's force has no converged value: every
/// mode rings in it for ever and those above 500 Hz alias into the 1 kHz
/// samples (measured with this rig after a 2 V step: 8 against 16
/// elements a segment differ by 1.2 mN rms, 60 times the load cell's
/// noise, and still by many times its noise below 20 Hz). A finer mesh
/// here would hide a mesh artefact in every session, not an effect.
pub const BLOCKED_MESH: Mesh = Mesh {
    per_segment: 4,
    dynamic_limit_hz: f64::INFINITY,
};

/// What the strip did at every DAQ row.
pub struct Truth {
    /// Current into each segment, A (`[segment][row]`).
    pub currents_a: Vec<Vec<f64>>,
    /// `(along, across)` of each tracked point (the tip last) at camera rows
    /// (`[point][row]`, NaN elsewhere); empty when blocked.
    pub points_m: Vec<Vec<(f64, f64)>>,
    /// Force on the load cell, N (empty when free).
    pub force_n: Vec<f64>,
}

/// Per-segment electrical state: charge, the lead network's state, the
/// back-relaxation branch, the lagged charge its neighbours feel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Elec {
    q: f64,
    r: f64,
    b: f64,
    /// The charge as the neighbours see it through the crosstalk's lag.
    l: f64,
    /// The double layer's voltage, kept as Newton's start.
    v: f64,
}

/// The strip's electrical state where a recording (or a pause) ended:
/// what the next one starts from on a bench that carries it over. The
/// default is at rest. The beam's motion is not kept: after a pause the
/// strip stands still under its moment (see [`run_lab`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    elec: Vec<Elec>,
}

impl State {
    /// Each segment's charge, C.
    pub fn charge_c(&self) -> Vec<f64> {
        self.elec.iter().map(|e| e.q).collect()
    }

    /// Whether the strip is at rest: no charge and no relaxation left.
    pub fn is_rest(&self) -> bool {
        self.elec.iter().all(|e| *e == Elec::default())
    }
}

/// What a lab bench adds to a run of the strip ([`run_lab`]); the default
/// adds nothing, and [`run_lab`] is then [`run`] bit for bit.
#[derive(Clone, Copy, Default)]
pub struct Lab<'a> {
    /// The electrical state to start from (carried over from the last
    /// recording); `None`: at rest.
    pub start: Option<&'a State>,
    /// The strip's own curl: a moment on every segment, N·m, at session
    /// time `t`, s (a uniform curvature `κ` is a moment `EI κ` along the
    /// whole strip).
    pub curl_nm: Option<&'a dyn Fn(f64) -> f64>,
    /// `open[segment][row]`: the segment's electrode contact is open on
    /// that row: no current flows and it does not charge.
    pub open: Option<&'a [Vec<bool>]>,
    /// `a`: each segment's own moment is `(1 + a/2)` times the model's when
    /// positive and `(1 - a/2)` times when negative, so that the strip
    /// bends `(1 + a/2)/(1 - a/2) ≈ 1 + a` times more one way.
    pub asymmetry: f64,
}

struct Electrics<'a> {
    s: &'a Sample,
    h: &'a Hidden,
    /// [`Lab::asymmetry`].
    asym: f64,
}

impl Electrics<'_> {
    /// Segment `i`'s capacitance, F.
    fn c_f(&self, i: usize) -> f64 {
        self.s.c_f * self.h.segment(i).c
    }

    /// Segment `i`'s series resistance, Ω.
    fn r1_ohm(&self, i: usize) -> f64 {
        self.s.r1_ohm * self.h.segment(i).r1
    }

    /// Double-layer voltage of segment `i` from charge,
    /// `q = C (v + c₂ v³/3)`, by Newton.
    fn voltage(&self, i: usize, q: f64, guess: f64) -> f64 {
        let c = self.c_f(i);
        let Some((_, c2)) = self.h.electrochemistry else {
            return q / c;
        };
        let mut v = guess;
        for _ in 0..6 {
            let g = c * (v + c2 * v * v * v / 3.0) - q;
            v -= g / (c * (1.0 + c2 * v * v));
        }
        v
    }

    fn leak_a(&self, v: f64) -> f64 {
        match self.h.electrochemistry {
            Some((v0, _)) => v0 / self.s.r2_ohm * (v / v0).sinh(),
            None => v / self.s.r2_ohm,
        }
    }

    /// Segment `i`'s own moment, N·m.
    fn own_moment(&self, i: usize, e: &Elec) -> f64 {
        let s = self.s;
        let k = s.k_nm_per_c * self.h.segment(i).k;
        let lead = k * (e.q + (s.z_per_s - s.p_per_s) * e.r);
        let m = match self.h.back_branch {
            Some((beta, _)) => lead - beta * k * s.z_per_s / s.p_per_s * e.b,
            None => lead,
        };
        if self.asym == 0.0 {
            m
        } else {
            m * (1.0 + 0.5 * self.asym * m.signum())
        }
    }

    /// Moments on every segment, N·m, before the drying gain.
    fn segment_moments(&self, x: &[Elec], out: &mut [f64]) {
        let kappa = self.h.crosstalk.unwrap_or(0.0);
        let k = self.s.k_nm_per_c;
        // What a neighbour passes on: its charge now, or through the lag.
        let felt = |e: &Elec| {
            if self.h.crosstalk_lag_s.is_some() {
                e.l
            } else {
                e.q
            }
        };
        for (i, o) in out.iter_mut().enumerate() {
            let before = if i > 0 { felt(&x[i - 1]) } else { 0.0 };
            let after = x.get(i + 1).map_or(0.0, felt);
            *o = self.own_moment(i, &x[i]) + kappa * k * (before + after);
        }
    }

    /// `open[i]`: segment `i`'s contact is open; its strip floats and the
    /// double layer discharges through `R1` and `R2` in series (the linear
    /// leak even with the `sinh` one: a fault lasts seconds at most).
    fn derivative(&self, x: &[Elec], volts: &[f64], open: Option<&[bool]>, dx: &mut [Elec]) {
        let s = self.s;
        for i in 0..x.len() {
            let v = self.voltage(i, x[i].q, x[i].v);
            let dq = match open {
                Some(o) if o[i] => -v / (self.r1_ohm(i) + s.r2_ohm),
                _ => (volts[i] - v) / self.r1_ohm(i),
            };
            let tau_b = self.h.back_branch.map_or(1.0, |(_, t)| t);
            dx[i] = Elec {
                q: dq,
                r: -s.p_per_s * x[i].r + x[i].q,
                b: if self.h.back_branch.is_some() {
                    (x[i].q - x[i].b) / tau_b
                } else {
                    0.0
                },
                l: self
                    .h
                    .crosstalk_lag_s
                    .map_or(0.0, |tau| (x[i].q - x[i].l) / tau),
                v: 0.0,
            };
        }
    }

    fn rk4(&self, x: &mut [Elec], volts: &[f64], open: Option<&[bool]>, h: f64) {
        let n = x.len();
        let mut k = [
            vec![Elec::default(); n],
            vec![Elec::default(); n],
            vec![Elec::default(); n],
            vec![Elec::default(); n],
        ];
        let mut y = x.to_vec();
        let add = |y: &mut [Elec], x: &[Elec], k: &[Elec], f: f64| {
            for ((y, x), k) in y.iter_mut().zip(x).zip(k) {
                y.q = x.q + f * k.q;
                y.r = x.r + f * k.r;
                y.b = x.b + f * k.b;
                y.l = x.l + f * k.l;
                y.v = x.v;
            }
        };
        self.derivative(x, volts, open, &mut k[0]);
        add(&mut y, x, &k[0], 0.5 * h);
        self.derivative(&y, volts, open, &mut k[1]);
        add(&mut y, x, &k[1], 0.5 * h);
        self.derivative(&y, volts, open, &mut k[2]);
        add(&mut y, x, &k[2], h);
        self.derivative(&y, volts, open, &mut k[3]);
        for (i, e) in x.iter_mut().enumerate() {
            e.q += h / 6.0 * (k[0][i].q + 2.0 * k[1][i].q + 2.0 * k[2][i].q + k[3][i].q);
            e.r += h / 6.0 * (k[0][i].r + 2.0 * k[1][i].r + 2.0 * k[2][i].r + k[3][i].r);
            e.b += h / 6.0 * (k[0][i].b + 2.0 * k[1][i].b + 2.0 * k[2][i].b + k[3][i].b);
            e.l += h / 6.0 * (k[0][i].l + 2.0 * k[1][i].l + 2.0 * k[2][i].l + k[3][i].l);
            e.v = self.voltage(i, e.q, e.v);
        }
    }
}

/// What drives the beam: the segments' electrics and the moments they
/// make, in the rig's own form ([`Electrics`]) or as the literature
/// strip's electrode lines ([`crate::literature`]).
pub(crate) trait Electrical {
    /// The electrical state.
    type X: Clone;
    /// Equal patches along each segment, each with a moment of its own.
    fn patches(&self) -> usize;
    /// The state at rest of a strip of `segments` segments.
    fn rest(&self, segments: usize) -> Self::X;
    /// Moments on every patch, N·m, at session time `t_s` (the rig's own
    /// drying gain is applied after).
    fn moments(&self, x: &Self::X, t_s: f64, out: &mut [f64]);
    /// Current into each segment, A, with the row's voltages `volts` just
    /// applied (`open[i]`: segment `i`'s contact is open).
    fn currents(
        &self,
        x: &Self::X,
        volts: &[f64],
        open: Option<&[bool]>,
        t_s: f64,
        out: &mut [f64],
    );
    /// One sub-step of `h` seconds from session time `t_s`.
    fn step(&self, x: &mut Self::X, volts: &[f64], open: Option<&[bool]>, t_s: f64, h: f64);
}

impl Electrical for Electrics<'_> {
    type X = Vec<Elec>;

    fn patches(&self) -> usize {
        1
    }

    fn rest(&self, segments: usize) -> Vec<Elec> {
        vec![Elec::default(); segments]
    }

    fn moments(&self, x: &Vec<Elec>, _t_s: f64, out: &mut [f64]) {
        self.segment_moments(x, out);
    }

    fn currents(
        &self,
        x: &Vec<Elec>,
        volts: &[f64],
        open: Option<&[bool]>,
        _t_s: f64,
        out: &mut [f64],
    ) {
        for (i, c) in out.iter_mut().enumerate() {
            *c = if open.is_some_and(|o| o[i]) {
                // An open contact: nothing flows, the leak neither.
                0.0
            } else {
                self.leak_a(volts[i]) + (volts[i] - x[i].v) / self.r1_ohm(i)
            };
        }
    }

    fn step(&self, x: &mut Vec<Elec>, volts: &[f64], open: Option<&[bool]>, _t_s: f64, h: f64) {
        self.rk4(x, volts, open, h);
    }
}

/// A mode's exact sub-step: constant modal damping ([`ModeStep`]), or the
/// literature strip's viscoelastic spectrum ([`ViscoStep`]), whose
/// internal terms follow `η`.
enum Stepper {
    Modal(ModeStep),
    Visco(ViscoStep),
}

impl Stepper {
    /// The coordinate the stiffness sees, from `[η, η̇/ω, s..]`.
    fn elastic(&self, x: &[f64]) -> f64 {
        match self {
            Stepper::Modal(_) => x[0],
            Stepper::Visco(v) => v.elastic(x),
        }
    }

    /// `η̈` at `[η, η̇/ω, s..]` under modal force `f`, unit mass.
    fn acceleration(&self, x: &[f64], f: f64, omega: f64, zeta: f64) -> f64 {
        match self {
            Stepper::Modal(_) => f - omega * omega * x[0] - 2.0 * zeta * omega * omega * x[1],
            Stepper::Visco(v) => f - omega * omega * v.elastic(x),
        }
    }

    fn advance(&self, x: &mut [f64], f0: f64, slope: f64) {
        match self {
            Stepper::Modal(s) => {
                let m = &s.m;
                let (e, z) = (x[0], x[1]);
                x[0] = m[0][0] * e + m[0][1] * z + m[0][2] * f0 + m[0][3] * slope;
                x[1] = m[1][0] * e + m[1][1] * z + m[1][2] * f0 + m[1][3] * slope;
            }
            Stepper::Visco(v) => v.advance(x, f0, slope),
        }
    }
}

/// One mode's exact sub-step: `[η, η̇/ω]` from itself, the modal force at
/// the start and its slope across the step.
struct ModeStep {
    m: [[f64; 4]; 2],
}

impl ModeStep {
    fn new(omega: f64, zeta: f64, h: f64) -> ModeStep {
        // Scaled by ω so that the exponential stays well conditioned.
        let a = Matrix4::new(
            0.0,
            omega,
            0.0,
            0.0,
            -omega,
            -2.0 * zeta * omega,
            1.0 / omega,
            0.0,
            0.0,
            0.0,
            0.0,
            1.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ) * h;
        let e = a.exp();
        let row = |r: usize| [e[(r, 0)], e[(r, 1)], e[(r, 2)], e[(r, 3)] / h];
        ModeStep {
            m: [row(0), row(1)],
        }
    }
}

/// The true strip's bending stiffness, N·m², and mass per length with the
/// water's added mass, kg/m: what its beam is built from.
pub fn section(sample: &Sample, hidden: &Hidden) -> (f64, f64) {
    let width = sample.width_m;
    let added = hidden.water.map_or(0.0, |w| {
        w.added_mass_factor * WATER_KG_M3 * std::f64::consts::PI * width * width / 4.0
    });
    let ei = sample.laminate_ei_nm2() * hidden.ei_factor.unwrap_or(1.0);
    let mass = sample.mass_kg_per_m() * hidden.literature.as_ref().map_or(1.0, |l| l.mass_factor);
    (ei, mass + added)
}

/// Runs the strip through the voltages `volts[row][segment]` held for
/// `dt_s` each, starting `t_session_s` into the session, its tip held as
/// `tip` says. `camera[row]` says where positions are wanted, at arc
/// lengths `points_s_m`. The strip starts at rest.
#[allow(clippy::too_many_arguments)]
pub fn run(
    sample: &Sample,
    hidden: &Hidden,
    mesh: Mesh,
    tip: Tip,
    volts: &Voltages,
    dt_s: f64,
    t_session_s: f64,
    camera: &[bool],
    points_s_m: &[f64],
) -> Truth {
    let lab = Lab::default();
    run_lab(
        sample,
        hidden,
        mesh,
        tip,
        volts,
        dt_s,
        t_session_s,
        camera,
        points_s_m,
        &lab,
    )
    .0
}

/// As [`run`], on a lab bench: `lab` says what the strip starts from and
/// what the bench adds. A carried-over state starts the beam standing
/// still in static equilibrium under its moment (and the curl's): the
/// pause before it lets a damped strip's ringing die out, and handling the
/// strip between recordings stops the ideal strip's. Returns what the
/// strip did and its electrical state after the last row.
#[allow(clippy::too_many_arguments)]
pub fn run_lab(
    sample: &Sample,
    hidden: &Hidden,
    mesh: Mesh,
    tip: Tip,
    volts: &Voltages,
    dt_s: f64,
    t_session_s: f64,
    camera: &[bool],
    points_s_m: &[f64],
    lab: &Lab,
) -> (Truth, State) {
    let at = At {
        mesh,
        tip,
        volts,
        dt_s,
        t_session_s,
        camera,
        points_s_m,
    };
    match &hidden.literature {
        Some(lit) => {
            // The literature strip is not run on the lab bench: its state
            // is not carried over, nor its curl or contacts.
            assert!(
                lab.start.is_none() && lab.curl_nm.is_none() && lab.open.is_none(),
                "the literature strip runs on the sweep's bench alone"
            );
            let lines = Lines {
                s: sample,
                h: hidden,
                lit,
            };
            let (truth, _) = run_with(&lines, sample, hidden, &at, lab, None);
            (truth, State::default())
        }
        None => {
            let elec = Electrics {
                s: sample,
                h: hidden,
                asym: lab.asymmetry,
            };
            let start = lab
                .start
                .filter(|state| !state.elec.is_empty())
                .map(|state| {
                    assert_eq!(
                        state.elec.len(),
                        volts.segments(),
                        "a carried state of another strip"
                    );
                    state.elec.clone()
                });
            let (truth, elec) = run_with(&elec, sample, hidden, &at, lab, start);
            (truth, State { elec })
        }
    }
}

/// Where and how a run goes: [`run_lab`]'s arguments but the strip and
/// the bench.
#[derive(Clone, Copy)]
struct At<'a> {
    mesh: Mesh,
    tip: Tip,
    volts: &'a Voltages,
    dt_s: f64,
    t_session_s: f64,
    camera: &'a [bool],
    points_s_m: &'a [f64],
}

/// [`run_lab`] for any [`Electrical`] strip, from `start` (`None`: at
/// rest).
fn run_with<E: Electrical>(
    elec: &E,
    sample: &Sample,
    hidden: &Hidden,
    at: &At,
    lab: &Lab,
    start: Option<E::X>,
) -> (Truth, E::X) {
    let At {
        mesh,
        tip,
        volts,
        dt_s,
        t_session_s,
        camera,
        points_s_m,
    } = *at;
    let n = volts.segments();
    let patches = elec.patches();
    assert_eq!(mesh.per_segment % patches, 0, "whole elements per patch");
    let width = sample.width_m;
    let (ei, mass) = section(sample, hidden);
    let beam = Beam::new(
        sample.length_m,
        n * patches,
        mesh.per_segment / patches,
        ei,
        mass,
        tip,
    );
    let (blocked, held) = (tip == Tip::Pinned, tip.is_held());
    let h = dt_s / SUBSTEPS as f64;
    let zeta = |k: usize| hidden.damping_of_mode(k);
    let modes = beam.omega.len();
    let dynamic: Vec<usize> = (0..modes)
        .filter(|&k| beam.omega[k] < 2.0 * std::f64::consts::PI * mesh.dynamic_limit_hz)
        .collect();
    let spectrum = hidden
        .literature
        .as_ref()
        .map_or(&[][..], |l| &l.spectrum[..]);
    let steps: Vec<Stepper> = dynamic
        .iter()
        .map(|&k| {
            if spectrum.is_empty() {
                Stepper::Modal(ModeStep::new(beam.omega[k], zeta(k), h))
            } else {
                Stepper::Visco(ViscoStep::new(beam.omega[k], spectrum, h))
            }
        })
        .collect();
    // Dynamic modes that feel the drag (a leading run: modes are sorted).
    let dragged = dynamic
        .iter()
        .take_while(|&&k| beam.omega[k] < 2.0 * std::f64::consts::PI * DRAG_LIMIT_HZ)
        .count();
    let shapes_drag = beam.shapes.select_columns(&dynamic[..dragged]);
    // Quadratic drag per node: ½ ρ C_d b |v| v over the node's share of length.
    let drag = hidden.water.map(|w| {
        let c = 0.5 * WATER_KG_M3 * w.drag_coefficient * width;
        (0..beam.elements)
            .map(|j| c * if j + 1 == beam.elements { 0.5 } else { 1.0 } * beam.le_m)
            .collect::<Vec<f64>>()
    });
    // The literature strip's large deflection, free: its low modes'
    // inertia with the slope field taken whole (`rotation`); the modes
    // quick for the sub-step keep the linear inertia.
    let mut rotation = (!held && hidden.arcs && hidden.literature.is_some()).then(|| {
        let slow = dynamic
            .iter()
            .take_while(|&&k| beam.omega[k] * h <= MAX_OMEGA_H)
            .count();
        let drag = hidden
            .water
            .map(|w| 0.5 * WATER_KG_M3 * w.drag_coefficient * width);
        Rotation::new(&beam, &dynamic[..slow], mass, drag)
    });
    let turning = rotation.as_ref().map_or(0, Rotation::modes);
    let (mut eta, mut eta_d, mut a_lin, mut turn) = (
        vec![0.0; turning],
        vec![0.0; turning],
        vec![0.0; turning],
        vec![0.0; turning],
    );
    let carried = start.is_some();
    let mut x = start.unwrap_or_else(|| elec.rest(n));
    // Each dynamic mode's `[η, η̇/ω]` and its spectrum's terms.
    let mut xs = vec![vec![0.0; 2 + spectrum.len()]; dynamic.len()];
    let loads = n * patches;
    let mut u0 = vec![0.0; loads];
    let mut u1 = vec![0.0; loads];
    let mut amps = vec![0.0; n];
    let rows = volts.len();
    let mut truth = Truth {
        currents_a: vec![Vec::with_capacity(rows); n],
        points_m: if held {
            Vec::new()
        } else {
            vec![vec![(f64::NAN, f64::NAN); rows]; points_s_m.len()]
        },
        force_n: Vec::with_capacity(if held { rows } else { 0 }),
    };
    let modal_force =
        |u: &[f64], k: usize| -> f64 { (0..loads).map(|i| beam.forcing[(k, i)] * u[i]).sum() };
    let mut drag_modal = vec![0.0; dynamic.len()];
    // Each dynamic mode's force at the sub-step's start.
    let mut f_start = vec![0.0; dynamic.len()];
    // The curl's modal force per unit moment on every segment.
    let curl_forcing: Vec<f64> = dynamic
        .iter()
        .map(|&k| (0..loads).map(|i| beam.forcing[(k, i)]).sum())
        .collect();
    let curl_at = |t: f64| lab.curl_nm.map_or(0.0, |c| c(t));
    let gain_at = |t: f64| hidden.drying_s.map_or(1.0, |tau| 1.0 / (1.0 + t / tau));
    if carried || lab.curl_nm.is_some() {
        // Standing still under the opening moment: each mode at its static
        // deflection.
        elec.moments(&x, t_session_s, &mut u0);
        let (gain, curl) = (gain_at(t_session_s), curl_at(t_session_s));
        u0.iter_mut().for_each(|u| *u = *u * gain + curl);
        for (j, &k) in dynamic.iter().enumerate() {
            xs[j][0] = modal_force(&u0, k) / (beam.omega[k] * beam.omega[k]);
        }
    }
    let mut open_row = vec![false; n];
    for (row, v_row) in volts.rows().enumerate() {
        let t_s = t_session_s + row as f64 * dt_s;
        let gain = gain_at(t_s);
        let open = lab.open.map(|o| {
            for (f, seg) in open_row.iter_mut().zip(o) {
                *f = seg.get(row).copied().unwrap_or(false);
            }
            &open_row[..]
        });
        // Outputs at the row's instant, with the row's voltage just applied.
        elec.currents(&x, v_row, open, t_s, &mut amps);
        for (c, a) in truth.currents_a.iter_mut().zip(&amps) {
            c.push(*a);
        }
        let want_shape = held || camera.get(row).copied().unwrap_or(false);
        if want_shape {
            elec.moments(&x, t_s, &mut u0);
            u0.iter_mut().for_each(|u| *u *= gain);
            if lab.curl_nm.is_some() {
                let curl = curl_at(t_s);
                u0.iter_mut().for_each(|u| *u += curl);
            }
            let mut full = DVector::<f64>::zeros(modes);
            for k in 0..modes {
                full[k] = modal_force(&u0, k) / (beam.omega[k] * beam.omega[k]);
            }
            for (j, &k) in dynamic.iter().enumerate() {
                full[k] = xs[j][0];
            }
            if blocked {
                // Accelerations of the modes in time; the static ones have none.
                let mut acc = DVector::<f64>::zeros(modes);
                // The pinned tip has no position to report: `full` becomes
                // what the stiffness sees, the deflection itself or, on a
                // viscoelastic strip, its relaxed part and the spectrum's.
                for (j, &k) in dynamic.iter().enumerate() {
                    let w = beam.omega[k];
                    full[k] = steps[j].elastic(&xs[j]);
                    acc[k] = steps[j].acceleration(
                        &xs[j],
                        modal_force(&u0, k) + drag_modal[j],
                        w,
                        zeta(k),
                    );
                }
                truth.force_n.push(beam.reaction_n(&full, &acc, &u0));
            } else if let Some(k_s) = beam.spring_n_per_m {
                // The load cell that gives reads its own extension.
                truth.force_n.push(k_s * beam.tip_m(&beam.nodal(&full)));
            } else {
                let q = beam.nodal(&full);
                for (p, &s) in points_s_m.iter().enumerate() {
                    truth.points_m[p][row] = beam.position_m(&q, s, hidden.arcs);
                }
            }
        }
        for sub in 0..SUBSTEPS {
            let t0 = t_s + sub as f64 * h;
            elec.moments(&x, t0, &mut u0);
            elec.step(&mut x, v_row, open, t0, h);
            elec.moments(&x, t0 + h, &mut u1);
            // A turning strip's drag is the rotation's, normal to it.
            if let (Some(d), None) = (&drag, &rotation) {
                // Node velocities from the dynamic modes; drag held over the sub-step.
                let vel = &shapes_drag
                    * DVector::from_iterator(
                        dragged,
                        dynamic[..dragged]
                            .iter()
                            .enumerate()
                            .map(|(j, &k)| xs[j][1] * beam.omega[k]),
                    );
                let mut f = DVector::<f64>::zeros(vel.len());
                for (j, c) in d.iter().enumerate() {
                    if blocked && j + 1 == beam.elements {
                        // The pinned tip does not move.
                        continue;
                    }
                    let v = vel[2 * j];
                    f[2 * j] = -c * v.abs() * v;
                }
                let m = shapes_drag.transpose() * f;
                drag_modal[..dragged].copy_from_slice(m.as_slice());
            }
            // The curl at the sub-step's ends, linear between them as the
            // electrics' moment is.
            let curl = lab.curl_nm.map(|_| (curl_at(t0), curl_at(t0 + h)));
            let force = |j: usize, k: usize, u: &[f64], c: Option<f64>| -> f64 {
                gain * modal_force(u, k) + drag_modal[j] + c.map_or(0.0, |c| c * curl_forcing[j])
            };
            for (j, &k) in dynamic.iter().enumerate() {
                f_start[j] = force(j, k, &u0, curl.map(|c| c.0));
            }
            if let Some(rot) = &mut rotation {
                // The inertia's share, held over the sub-step as the drag is.
                for (j, &k) in dynamic[..turning].iter().enumerate() {
                    let w = beam.omega[k];
                    eta[j] = xs[j][0];
                    eta_d[j] = xs[j][1] * w;
                    a_lin[j] = steps[j].acceleration(&xs[j], f_start[j], w, zeta(k));
                }
                rot.forces(&eta, &eta_d, &a_lin, &mut turn);
            }
            for (j, &k) in dynamic.iter().enumerate() {
                let extra = turn.get(j).copied().unwrap_or(0.0);
                let f0 = f_start[j] + extra;
                let f1 = force(j, k, &u1, curl.map(|c| c.1)) + extra;
                steps[j].advance(&mut xs[j], f0, f1 - f0);
            }
        }
    }
    (truth, x)
}

/// The strip at 0 V for `seconds` from `state` (a pause between
/// recordings: the DAQ holds its outputs at zero, so the strip discharges
/// through `R1` and relaxes), on sub-steps of `dt_s / SUBSTEPS`; the
/// electrics alone, the beam follows at the next recording's start.
pub fn pause(sample: &Sample, hidden: &Hidden, state: &mut State, seconds: f64, dt_s: f64) {
    if state.elec.is_empty() {
        return;
    }
    let elec = Electrics {
        s: sample,
        h: hidden,
        asym: 0.0,
    };
    let h = dt_s / SUBSTEPS as f64;
    let zero = vec![0.0; state.elec.len()];
    let steps = (seconds / h).round() as usize;
    for _ in 0..steps {
        elec.rk4(&mut state.elec, &zero, None, h);
    }
}
