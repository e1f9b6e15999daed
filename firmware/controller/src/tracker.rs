//! The gain tracker (#16): holds a shaped motion where the model put it
//! while the strip drifts from its model (it dries, or the fit was off).
//!
//! The model's inverse gives each segment a voltage phasor `V`; in the
//! model its current is then `I = Y V`, `Y` the segment's admittance at
//! the wave's frequency. The tracker measures each segment's own
//! admittance `Ŷ` as it drives: a lock-in of the voltage the segment had
//! and of the current it drew over each period of the wave, then a least
//! squares fit of `I = Ŷ V` over the periods with exponential forgetting,
//! `λ = e^{−1/M}` for a memory of `M` = [`MEMORY_PERIODS`] periods:
//!
//! `P ← λ P + |V|²`, `S ← λ S + I V̄`, `Ŷ = S / P`.
//!
//! Each segment's voltage phasor becomes the model's times `c = Y / Ŷ`,
//! so that the segment draws the current, and so takes the charge, the
//! model asked of it, whatever its `R1`, `R2` and `C` have become. The
//! voltage does not enter `Ŷ`'s estimate except as the input it is: the
//! correction changes no estimate, so nothing here can oscillate.
//!
//! What the currents cannot see is a change of the moment per charge (in
//! the model, the dehydration extension's moment gain): on a free strip
//! nothing the board measures sees it. On the strip held by the load cell
//! (a force motion, [`Sine::force_n_per_v`]) the tracker reads the force
//! instead: the force the model predicts for the voltages each segment
//! had, `F̂ = Σₖ Hₖ Vₖ` (`Hₖ` the model's force per volt, sampled as the
//! load cell reads it), against the one measured, least squares with the
//! same forgetting (`P ← λP + |F̂|²`, `S ← λS + F F̂*`, `ĝ = S/P`), and
//! every segment's voltage times `c = 1/ĝ`: whatever changed between the
//! voltage and the force, electrics or moment per charge, alike on every
//! segment.
//!
//! The drying law: where the model dries (the record's
//! `dehydration_per_s`), the moment gain it predicts falls over the
//! session, `g(t)` ([`model_core::drying_gain`]); the shaper drives the
//! motion's start with `1/g(t₀)` and at each period's end the tracker
//! multiplies every correction by `1/g(t)`, `t` the session time then (the
//! motion's start, as the SetMotion said, plus the samples since). That is
//! feed-forward from the fit, not a measurement: it holds a motion
//! untracked too, and it is the only part that follows a moment per
//! charge that weakens.
//!
//! A held step (`motion-step:`, [`Shape::Step`]) has no sine to lock in
//! to: only the drying law holds it, every [`STEP_UPDATE_S`].
//!
//! Bounds: a correction's gain stays within `[1/B, B]`, `B` =
//! [`MAX_CORRECTION`] (a strip further off is not the model's: refit it),
//! and a corrected amplitude is held at the voltage limit in force; either
//! is flagged ([`TrackingFlags`]) in the Tracking frame sent at the end of
//! each period. The first [`SETTLE_PERIODS`] periods after the motion
//! starts are not used: the electrics settle from rest in them.
//!
//! ```
//! use finrs_controller::tracker::{Shape, Sine, Target, Tracker};
//! // One segment whose admittance is half the model's (its R1 doubled,
//! // say): the tracker finds twice the model's voltage.
//! let target = Target::<1> {
//!     shape: Shape::Sine(Sine {
//!         frequency_hz: 10.0,
//!         amplitudes_v: [1.0],
//!         phases_deg: [0.0],
//!         admittance_a_per_v: [[0.02, 0.0]],
//!         force_n_per_v: None,
//!     }),
//!     tracked: true,
//!     drying: None,
//! };
//! let mut tracker = Tracker::new(target, 1000);
//! let mut last = None;
//! for k in 0..1000 {
//!     let v = libm::sinf(2.0 * core::f32::consts::PI * 10.0 * k as f32 / 1000.0);
//!     if let Some(c) = tracker.feed(&[v], &[0.01 * v], 0.0) {
//!         last = Some(c);
//!     }
//! }
//! let c = last.unwrap();
//! assert!((c.gains[0] - 2.0).abs() < 1e-3 && c.phases_deg[0].abs() < 0.1);
//! ```

use core::f32::consts::TAU;

use finrs_drive::Program;
use finrs_frames::{Tracking, TrackingFlags, MAX_SEGMENTS};

/// The memory of the least-squares fit, periods of the wave: long enough
/// to average the shunts' noise, short against drying (minutes).
pub const MEMORY_PERIODS: f32 = 4.0;

/// Largest gain of a correction (and 1/this the smallest).
pub const MAX_CORRECTION: f32 = 2.0;

/// Periods after the start of a motion that the fit does not use.
pub const SETTLE_PERIODS: u32 = 1;

/// How often a held step's levels follow the drying law, s: drying takes
/// minutes.
pub const STEP_UPDATE_S: f32 = 1.0;

/// What the tracker holds a motion to: the model's program (the shaper's,
/// from the model the board holds), and what it follows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target<const N: usize> {
    /// The model's program.
    pub shape: Shape<N>,
    /// Whether the tracker measures and corrects (`motion:`, `force:`): a
    /// sine's currents, or the load cell's force for a force motion; else
    /// (`motion-ff:`, a step) only the drying law is followed.
    pub tracked: bool,
    /// The model's drying law, if it dries.
    pub drying: Option<Drying>,
}

/// The model's program of a motion, as the tracker corrects it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape<const N: usize> {
    /// A travelling wave's sines ([`Program::Harmonic`]).
    Sine(Sine<N>),
    /// A held step ([`Program::HeldStep`]).
    Step(HeldStep<N>),
}

/// Each segment's sine, and its admittance at the sine's frequency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sine<const N: usize> {
    /// The wave's frequency, Hz.
    pub frequency_hz: f32,
    /// Each segment's voltage amplitude in the model's program, V.
    pub amplitudes_v: [f32; N],
    /// Each segment's phase in the model's program, degrees.
    pub phases_deg: [f32; N],
    /// `Y`: each segment's admittance in the model at `frequency_hz`, A/V,
    /// as (re, im) of the phasor ratio `I/V`.
    pub admittance_a_per_v: [[f32; 2]; N],
    /// For a force motion (the strip held by the load cell), `H`: each
    /// segment's force per volt in the model at `frequency_hz`, N/V, as
    /// the load cell reads it; tracked, the force is what is measured.
    pub force_n_per_v: Option<[[f32; 2]; N]>,
}

/// A held step's program ([`Program::HeldStep`]'s fields).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldStep<const N: usize> {
    /// Each segment's level, V.
    pub levels_v: [f32; N],
    /// The rise, s.
    pub rise_s: f32,
    /// The relaxation's pole, 1/s.
    pub pole_per_s: f32,
    /// Its zero, 1/s.
    pub zero_per_s: f32,
    /// The largest voltage per volt of level (the generator's peak over
    /// the largest level): a corrected level is held so that its peak
    /// stays within the limit.
    pub peak_per_level: f32,
}

/// A model's drying law ([`model_core::drying_gain`]) and the session
/// time at which the motion started on its clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drying {
    /// Initial rate, 1/s.
    pub rate_per_s: f64,
    /// Curvature (0 exponential, 1 hyperbolic).
    pub curvature: f64,
    /// The motion's start on the law's clock, s.
    pub t_start_s: f64,
}

impl Drying {
    /// The moment gain `since_s` seconds after the motion's start.
    pub fn gain(&self, since_s: f64) -> f64 {
        model_core::drying_gain(self.rate_per_s, self.curvature, self.t_start_s + since_s)
    }
}

/// A correction of the model's program: each segment's voltage phasor
/// times `gains[k] · e^{j phases_deg[k]}`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correction<const N: usize> {
    /// `|c|` per segment.
    pub gains: [f32; N],
    /// `arg c` per segment, degrees.
    pub phases_deg: [f32; N],
    /// [`TrackingFlags::BOUNDED`] if a gain reached [`MAX_CORRECTION`].
    pub flags: u8,
}

/// The tracker of one motion (see the module's description).
#[derive(Clone, Copy, Debug)]
pub struct Tracker<const N: usize> {
    target: Target<N>,
    /// The wave's cycles per sample.
    cycles_per_tick: f32,
    /// The lock-in's reference phase, cycles in [0, 1).
    cycles: f32,
    /// `(cos, sin)` of the reference phase, turned by `turn` each sample:
    /// a recurrence, not a sine per sample (libm's `f32` sine works in
    /// `f64`, soft-float on the M4F: 2300 instructions a tick); set afresh
    /// from `cycles` at each period's end, so its rounding never builds up.
    reference: [f32; 2],
    /// `(cos, sin)` of a sample's turn of the reference.
    turn: [f32; 2],
    periods: u32,
    /// Samples fed since the motion started, and the rate they come at.
    ticks: u64,
    sample_hz: u32,
    /// This period's `Σ v e^{−jθ}`, `Σ i e^{−jθ}` and `Σ f e^{−jθ}`.
    v_sum: [[f32; 2]; N],
    i_sum: [[f32; 2]; N],
    f_sum: [f32; 2],
    /// The fit's `P` and `S` per segment (the force's: the first only).
    p: [f32; N],
    s: [[f32; 2]; N],
    /// `λ`.
    forget: f32,
}

impl<const N: usize> Tracker<N> {
    /// A tracker for `target` on a board sampling at `sample_hz`.
    pub fn new(target: Target<N>, sample_hz: u32) -> Self {
        const { assert!(N >= 1 && N <= MAX_SEGMENTS) };
        // A step's "period" is the drying law's update.
        let cycles_per_tick = match target.shape {
            Shape::Sine(s) => s.frequency_hz,
            Shape::Step(_) => 1.0 / STEP_UPDATE_S,
        } / sample_hz as f32;
        let (s, c) = libm::sincosf(TAU * cycles_per_tick);
        Self {
            target,
            cycles_per_tick,
            cycles: 0.0,
            ticks: 0,
            sample_hz,
            reference: [1.0, 0.0],
            turn: [c, s],
            periods: 0,
            v_sum: [[0.0; 2]; N],
            i_sum: [[0.0; 2]; N],
            f_sum: [0.0; 2],
            p: [0.0; N],
            s: [[0.0; 2]; N],
            forget: libm::expf(-1.0 / MEMORY_PERIODS),
        }
    }

    /// One sample: `applied_v` the voltages the segments had over the
    /// sample period that just ended, `currents_a` the currents and
    /// `force_n` the load cell's force read at its end. At the end of each
    /// period of the wave, the correction: the admittance's (or the
    /// force's) from every period so far (once the first
    /// [`SETTLE_PERIODS`] are over, if tracked), times the drying law's
    /// (if the model dries).
    pub fn feed(
        &mut self,
        applied_v: &[f32; N],
        currents_a: &[f32; N],
        force_n: f32,
    ) -> Option<Correction<N>> {
        self.ticks = self.ticks.saturating_add(1);
        let [c, s] = self.reference;
        // Only a tracked motion's fit reads the lock-in, and only what it
        // measures: the force, or the currents.
        if self.tracks() {
            let by_force = self.by_force();
            lock_in(&mut self.v_sum, applied_v, [c, s]);
            if by_force {
                lock_in(core::slice::from_mut(&mut self.f_sum), &[force_n], [c, s]);
            } else {
                lock_in(&mut self.i_sum, currents_a, [c, s]);
            }
        }
        self.cycles += self.cycles_per_tick;
        let [tc, ts] = self.turn;
        self.reference = [c * tc - s * ts, s * tc + c * ts];
        if self.cycles < 1.0 {
            return None;
        }
        // A period's end: its phasors (unscaled: the scale cancels in Ŷ)
        // go into the fit, and the next period starts from zero.
        self.cycles -= 1.0;
        let (s, c) = libm::sincosf(TAU * self.cycles);
        self.reference = [c, s];
        self.periods = self.periods.saturating_add(1);
        let (v, i, f) = (self.v_sum, self.i_sum, self.f_sum);
        self.v_sum = [[0.0; 2]; N];
        self.i_sum = [[0.0; 2]; N];
        self.f_sum = [0.0; 2];
        let tracked = self.tracks() && self.periods > SETTLE_PERIODS;
        if !tracked && self.target.drying.is_none() {
            return None;
        }
        let mut out = Correction {
            gains: [1.0; N],
            phases_deg: [0.0; N],
            flags: 0,
        };
        if tracked {
            self.fit(&v, &i, f, &mut out);
        }
        if let Some(d) = self.target.drying {
            let since_s = self.ticks as f64 / f64::from(self.sample_hz);
            let dried = (1.0 / d.gain(since_s)) as f32;
            out.gains.iter_mut().for_each(|g| *g *= dried);
        }
        Some(out)
    }

    /// Whether the tracker measures: asked, and a sine to lock in to.
    fn tracks(&self) -> bool {
        self.target.tracked && matches!(self.target.shape, Shape::Sine(_))
    }

    /// Whether what it measures is the load cell's force (a force motion).
    fn by_force(&self) -> bool {
        matches!(
            self.target.shape,
            Shape::Sine(Sine {
                force_n_per_v: Some(_),
                ..
            })
        )
    }

    /// The period's phasors `v`, `i`, `f` into the fit (the force's for a
    /// force motion, else the currents'), and its correction of each
    /// segment into `out`.
    fn fit(&mut self, v: &[[f32; 2]; N], i: &[[f32; 2]; N], f: [f32; 2], out: &mut Correction<N>) {
        let Shape::Sine(sine) = self.target.shape else {
            return;
        };
        if let Some(h) = sine.force_n_per_v {
            self.fit_force(v, &h, f, out);
            return;
        }
        for k in 0..N {
            let [vr, vi] = v[k];
            let [ir, ii] = i[k];
            self.p[k] = self.forget * self.p[k] + vr * vr + vi * vi;
            // I V̄ = (ir + j ii)(vr − j vi).
            self.s[k][0] = self.forget * self.s[k][0] + ir * vr + ii * vi;
            self.s[k][1] = self.forget * self.s[k][1] + ii * vr - ir * vi;
            // c = Y / Ŷ = Y P / S: no division by a small P.
            let [sr, si] = self.s[k];
            let den = sr * sr + si * si;
            if den.is_nan() || den <= 0.0 {
                // A segment not driven (or not drawing): nothing to correct.
                continue;
            }
            let [yr, yi] = sine.admittance_a_per_v[k];
            // Y S̄ / |S|², times P.
            let scale = self.p[k] / den;
            let cr = (yr * sr + yi * si) * scale;
            let ci = (yi * sr - yr * si) * scale;
            if let Some((gain, phase_deg)) = bounded(cr, ci, &mut out.flags) {
                out.gains[k] = gain;
                out.phases_deg[k] = phase_deg;
            }
        }
    }

    /// The force's fit: `F̂ = Σ Hₖ Vₖ` against the measured `F`, one
    /// correction `c = 1/ĝ = P S̄/|S|²` for every segment.
    fn fit_force(
        &mut self,
        v: &[[f32; 2]; N],
        h: &[[f32; 2]; N],
        f: [f32; 2],
        out: &mut Correction<N>,
    ) {
        let (mut pr, mut pi) = (0.0f32, 0.0f32);
        for (&[hr, hi], &[vr, vi]) in h.iter().zip(v) {
            pr += hr * vr - hi * vi;
            pi += hr * vi + hi * vr;
        }
        let [fr, fi] = f;
        self.p[0] = self.forget * self.p[0] + pr * pr + pi * pi;
        // F F̂* = (fr + j fi)(pr − j pi).
        self.s[0][0] = self.forget * self.s[0][0] + fr * pr + fi * pi;
        self.s[0][1] = self.forget * self.s[0][1] + fi * pr - fr * pi;
        let [sr, si] = self.s[0];
        let den = sr * sr + si * si;
        if den.is_nan() || den <= 0.0 {
            // Nothing driven, or no force read: nothing to correct.
            return;
        }
        let scale = self.p[0] / den;
        if let Some((gain, phase_deg)) = bounded(sr * scale, -si * scale, &mut out.flags) {
            out.gains = [gain; N];
            out.phases_deg = [phase_deg; N];
        }
    }

    /// The model's program corrected by `c`, each amplitude held at
    /// `limit_v`; and the flags of the Tracking frame
    /// ([`TrackingFlags::AT_LIMIT`] if an amplitude was held).
    pub fn program(&self, c: &Correction<N>, limit_v: f32) -> (Program, u8) {
        let mut flags = c.flags;
        let mut at_limit = |a: f32, most: f32| {
            if a > most {
                flags |= TrackingFlags::AT_LIMIT;
                most
            } else {
                a
            }
        };
        let program = match self.target.shape {
            Shape::Sine(sine) => {
                let mut amplitudes_v = [0.0; MAX_SEGMENTS];
                let mut phases_deg = [0.0; MAX_SEGMENTS];
                for k in 0..N {
                    amplitudes_v[k] = at_limit(sine.amplitudes_v[k] * c.gains[k], limit_v);
                    phases_deg[k] = sine.phases_deg[k] + c.phases_deg[k];
                }
                Program::Harmonic {
                    frequency_hz: sine.frequency_hz,
                    offset_v: 0.0,
                    amplitudes_v,
                    phases_deg,
                }
            }
            Shape::Step(step) => {
                // Each level's magnitude held so that its peak is within
                // the limit; its sign kept.
                let most = limit_v / step.peak_per_level;
                let mut levels_v = [0.0; MAX_SEGMENTS];
                for ((out, level), gain) in levels_v.iter_mut().zip(step.levels_v).zip(c.gains) {
                    let l = level * gain;
                    *out = libm::copysignf(at_limit(libm::fabsf(l), most), l);
                }
                Program::HeldStep {
                    levels_v,
                    rise_s: step.rise_s,
                    pole_per_s: step.pole_per_s,
                    zero_per_s: step.zero_per_s,
                }
            }
        };
        (program, flags)
    }
}

/// Adds each of `x` times `e^{−jθ}` to its sum, `[cos θ, sin θ]` the
/// reference.
fn lock_in(sums: &mut [[f32; 2]], x: &[f32], [c, s]: [f32; 2]) {
    for (sum, &x) in sums.iter_mut().zip(x) {
        sum[0] += x * c;
        sum[1] -= x * s;
    }
}

/// The correction `cr + j ci` as a gain within `[1/B, B]` (flagged
/// [`TrackingFlags::BOUNDED`] in `flags` if it was not) and a phase,
/// degrees; `None` if it is not finite.
fn bounded(cr: f32, ci: f32, flags: &mut u8) -> Option<(f32, f32)> {
    let gain = libm::hypotf(cr, ci);
    if !gain.is_finite() {
        return None;
    }
    let held = gain.clamp(1.0 / MAX_CORRECTION, MAX_CORRECTION);
    if held != gain {
        *flags |= TrackingFlags::BOUNDED;
    }
    Some((held, libm::atan2f(ci, cr).to_degrees()))
}

/// The Tracking frame of correction `c` (with `flags`) at `t_us`.
pub fn frame<const N: usize>(c: &Correction<N>, flags: u8, t_us: u32) -> Tracking {
    let mut t = Tracking {
        t_us,
        flags: TrackingFlags(flags),
        n: N,
        gains: [0.0; MAX_SEGMENTS],
        phases_deg: [0.0; MAX_SEGMENTS],
    };
    t.gains[..N].copy_from_slice(&c.gains);
    t.phases_deg[..N].copy_from_slice(&c.phases_deg);
    t
}
