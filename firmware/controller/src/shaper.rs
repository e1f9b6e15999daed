//! Motions turned into voltages by the fitted model the board holds (#16):
//! the one inverse that the firmware runs and that `finrs simulate`
//! runs as its twin.
//!
//! A [`Shaper`] holds the model a SetModel sent (checked by
//! [`Shaper::check`]: a layout the firmware reads, parameters the model
//! accepts, a strip that answers a sine). A SetMotion's motion becomes a
//! [`Program::Harmonic`]: each segment's voltage amplitude and phase from
//! the model's exact harmonic inverse (`model_core::Strip::tip_wave`:
//! each segment's electrics and relaxation, the crosstalk and the beam's
//! modes at the motion's frequency, on the strip discretised at the
//! board's sample time, so that the sampled sine the generator writes is
//! what the inverse assumed). A step of the tip ([`Motion::Step`])
//! becomes a [`Program::HeldStep`]: each segment's level from the model's
//! static inverse (`model_core::Strip::tip_step`) times the relaxation's
//! inverse over a raised-cosine rise, the motion's ramp-in (the envelope
//! then starts at full gain). A travelling wave of the strip held by the
//! load cell ([`Motion::Force`]) is shaped as the free one, on the model's
//! held strip built for it, with each segment's force per volt for the
//! tracker. A motion that needs more than the limit in force is refused
//! with the amplitude that is reachable, never clipped.
//! Where the model dries, the motion starts at `1/g(t₀)` of its undried
//! voltages, `t₀` the session time the SetMotion carries; the controller's
//! [`crate::tracker`] then follows the law, and the currents if tracked.
//!
//! Building the model's strip takes milliseconds of `f64` arithmetic
//! (soft-float on the M4F), so [`command`] shapes outside the
//! controller's lock and takes it only to hand the result over.
//!
//! ```
//! use finrs_controller::shaper::{command, Shaper, Shaped, ELEMENTS};
//! use finrs_controller::{Config, Controller};
//! use finrs_frames::{Command, ModelRecord, Motion, StripModel};
//! use finrs_drive::Envelope;
//! use model_core::{state_len, Extensions, Params};
//! # use finrs_controller::Calibration;
//! # use finrs_drive::{Limits, HARD_LIMIT_V};
//! # let config = Config {
//! #     sample_hz: 1000,
//! #     limits: Limits::new(HARD_LIMIT_V, 100.0).unwrap(),
//! #     calibration: Calibration { newtons_per_count: 1e-5, current_zero_counts: [2048; 8] },
//! #     adc_full_scale: 4095,
//! #     saturation_margin_counts: 2,
//! #     amps_per_count: 1e-3,
//! #     overcurrent_a: 0.5,
//! #     tare_samples: 100,
//! # };
//!
//! let mut controller = Controller::<3>::new(config).unwrap();
//! let mut shaper = Shaper::<3, ELEMENTS, { state_len(3, ELEMENTS) }>::new();
//! let model = StripModel {
//!     params: Params::main_m_2006(),
//!     extensions: Extensions { damping_ratio: 0.05, ..Extensions::NONE },
//!     dehydration_per_s: 0.0,
//!     dehydration_curvature: 0.0,
//! };
//! let mut lock = finrs_controller::shaper::Exclusive(&mut controller);
//! let set_model = Command::SetModel(ModelRecord::encode(&model));
//! assert_eq!(command(set_model, &mut shaper, 1e-3, &mut lock), Ok(Shaped::ModelSet));
//! // 0.2 mm at 1 Hz, 60° a segment: within the seed's strip's reach.
//! let motion = Motion::Travelling { tip_amp_m: 2e-4, frequency_hz: 1.0, lag_deg_per_segment: 60.0 };
//! let envelope = Envelope { ramp_in_s: 1.0, hold_s: f32::INFINITY, ramp_out_s: 1.0 };
//! let set_motion = Command::SetMotion { motion, envelope, t_session_s: f32::NAN, tracked: true };
//! assert_eq!(command(set_motion, &mut shaper, 1e-3, &mut lock), Ok(Shaped::WaveSet));
//! assert!(controller.tracking());
//! ```

use core::fmt;

use finrs_drive::{Envelope, Program, WaveError};
use finrs_frames::{Command, ModelFormatError, ModelRecord, Motion, StripModel};
use model_core::{Fixture, HarmonicError, ParamError, StepError, Strip};
/// The lock [`command`] takes the controller through (RTIC's), and its
/// plain form for a controller owned outright.
pub use rtic_core::{Exclusive, Mutex};

use crate::controller::{CommandRefused, Controller};
use crate::model_holder::HoldsModel;
use crate::tracker::{Drying, HeldStep, Shape, Sine, Target, STEP_UPDATE_S};

/// Elements per segment of the board's model: one, whose cubic shape
/// functions give a piecewise-constant moment's static deflection exactly
/// (the modes above the first few are coarser, and a motion's frequency is
/// far below them).
pub const ELEMENTS: usize = 1;

/// Most segments whose model the board checks: building the model's strip
/// and inverting it takes the command task's stack 62 KB at N = 5, 84 KB
/// at N = 6 (of 112 KB), more than the margin at N = 7, and overflows at
/// N = 8 (QEMU, measured by `tests/scenarios/tests/firmware_sil.rs`):
/// above this a model is refused until that set-up is made leaner.
pub const MAX_SHAPED_SEGMENTS: usize = 6;

/// The frequency at which [`Shaper::check`] asks the model for a wave: a
/// model that moves nothing there is refused when it is sent, not at the
/// first motion, Hz.
const CHECK_HZ: f64 = 1.0;

/// Why a model or a motion was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeRefused {
    /// SetModel: the record is not one this firmware reads.
    Format(ModelFormatError),
    /// SetModel on a build of more than [`MAX_SHAPED_SEGMENTS`] segments
    /// (its segment count), whose stack cannot hold the model's check.
    TooManySegments(usize),
    /// SetModel: the model refuses a value (field and rule).
    Model(ParamError),
    /// SetModel: the model has no steady response to a sine at 1 Hz (why).
    NotInvertible(HarmonicError),
    /// SetMotion before any SetModel.
    NoModel,
    /// SetMotion: the model has no steady sine for this motion (why).
    Harmonic(HarmonicError),
    /// SetMotion: the model cannot hold this step (why).
    Step(StepError),
    /// SetMotion: a step on a model with no instant moment (`a = 0`),
    /// without a rise (the envelope's ramp-in): its inverse would be an
    /// impulse.
    NeedsRise,
    /// SetMotion: a step asked to be tracked (a step has no sine for the
    /// currents' lock-in).
    StepTracked,
    /// SetMotion: the motion needs more than the limit in force.
    Unreachable {
        /// The largest amplitude it needs, V.
        needs_v: f32,
        /// Where, counted from 1 at the clamp.
        segment: u8,
        /// The limit in force, V.
        limit_v: f32,
        /// The tip amplitude the limit allows, m.
        reachable_m: f32,
    },
    /// SetMotion: a force wave needs more than the limit in force.
    UnreachableForce {
        /// The largest amplitude it needs, V.
        needs_v: f32,
        /// Where, counted from 1 at the clamp.
        segment: u8,
        /// The limit in force, V.
        limit_v: f32,
        /// The force amplitude the limit allows, N.
        reachable_n: f32,
    },
    /// SetMotion: the voltages break a wave rule (field and rule).
    Wave(WaveError),
    /// SetMotion without its session time, on a model that dries: the
    /// moment it would drive for is unknown.
    NoSessionTime,
    /// The controller refused what the model gave (a fault latched, the
    /// outputs driven while a model was sent, …).
    Controller(CommandRefused),
}

impl fmt::Display for ShapeRefused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Format(e) => write!(f, "SetModel refused: {e}"),
            Self::TooManySegments(n) => too_many(f, *n),
            Self::Model(e) => write!(f, "SetModel refused: {e}"),
            Self::NotInvertible(e) => {
                write!(
                    f,
                    "SetModel refused: the model cannot be inverted at 1 Hz: {e}"
                )
            }
            Self::NoModel => f.write_str(NO_MODEL),
            Self::Harmonic(e) => write!(f, "SetMotion refused: {e}"),
            Self::Step(e) => write!(f, "SetMotion refused: {e}"),
            Self::NeedsRise => f.write_str(NEEDS_RISE),
            Self::StepTracked => f.write_str(STEP_TRACKED),
            Self::Unreachable {
                needs_v,
                segment,
                limit_v,
                reachable_m,
            } => unreachable(
                f,
                *needs_v,
                *segment,
                *limit_v,
                (*reachable_m, "um at the tip"),
            ),
            Self::UnreachableForce {
                needs_v,
                segment,
                limit_v,
                reachable_n,
            } => unreachable(
                f,
                *needs_v,
                *segment,
                *limit_v,
                (*reachable_n, "uN at the load cell"),
            ),
            Self::Wave(e) => write!(f, "SetMotion refused: {e}"),
            Self::NoSessionTime => f.write_str(NO_SESSION_TIME),
            Self::Controller(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for ShapeRefused {}

const NO_MODEL: &str = "SetMotion refused: no model (finrs tune FIT.toml first)";

const NEEDS_RISE: &str = "SetMotion refused: the model has no instant moment (a = 0): a held \
     step needs a rise (a ramp-in above 0)";

const STEP_TRACKED: &str =
    "SetMotion refused: a step cannot be tracked (no sine for the currents' lock-in)";

const NO_SESSION_TIME: &str = "SetMotion refused: the model dries (dehydration_per_s), and the \
     motion came without its session time (finrs wave --session-s)";

fn too_many(f: &mut fmt::Formatter<'_>, n: usize) -> fmt::Result {
    write!(
        f,
        "SetModel refused: a build of {n} segments cannot hold a model's check in its stack \
         (at most {MAX_SHAPED_SEGMENTS})"
    )
}

/// In whole mV and millionths of the reachable's unit (`what`: `um at
/// the tip`, `uN at the load cell`): an f32 `Display` would link core's
/// float formatting (about 14 KB of flash).
fn unreachable(
    f: &mut fmt::Formatter<'_>,
    needs_v: f32,
    segment: u8,
    limit_v: f32,
    (reachable, what): (f32, &str),
) -> fmt::Result {
    write!(
        f,
        "SetMotion refused: needs {} mV on segment {segment}, above the {} mV limit; \
         within it the model reaches {} {what}",
        (needs_v * 1e3) as u32,
        (limit_v * 1e3) as u32,
        (reachable * 1e6) as u32
    )
}

impl ShapeRefused {
    /// The refusal in words without any float, for the firmware's log:
    /// formatting an `f64` with `core::fmt` links some 10 KB of flash (the
    /// host, which has room, prints [`Display`](fmt::Display)'s values).
    pub fn brief(&self) -> Brief<'_> {
        Brief(self)
    }
}

/// [`ShapeRefused::brief`]'s form: names and integers only.
pub struct Brief<'a>(&'a ShapeRefused);

impl fmt::Display for Brief<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let harmonic = |f: &mut fmt::Formatter<'_>, e: &HarmonicError| match e {
            HarmonicError::Frequency { .. } => {
                f.write_str("the frequency is not above 0 and below half the sample rate")
            }
            HarmonicError::Nonlinear { field } => {
                write!(f, "{field} is on: the response is not one sine")
            }
            HarmonicError::Resonant { mode } => {
                write!(f, "the drive sits on undamped mode {mode}'s own frequency")
            }
            HarmonicError::NoResponse => f.write_str("no voltage moves the tip"),
        };
        match self.0 {
            ShapeRefused::Model(e) => {
                let field = match e {
                    ParamError::NotFinite { field, .. }
                    | ParamError::NotPositive { field, .. }
                    | ParamError::OutOfRange { field, .. }
                    | ParamError::SegmentDeviation { field, .. }
                    | ParamError::TooMany { field, .. } => field,
                    ParamError::BackRelaxation { .. } => "b_nm_per_c_s",
                    ParamError::SingularMass => "the beam's mass matrix",
                };
                write!(f, "SetModel refused: {field} breaks its rule")
            }
            ShapeRefused::NotInvertible(e) => {
                f.write_str("SetModel refused: the model cannot be inverted at 1 Hz: ")?;
                harmonic(f, e)
            }
            ShapeRefused::Harmonic(e) => {
                f.write_str("SetMotion refused: ")?;
                harmonic(f, e)
            }
            ShapeRefused::Step(e) => f.write_str(match e {
                StepError::Nonlinear { .. } => {
                    "SetMotion refused: an electrochemical cubic is on: no level holds a step"
                }
                StepError::BackRelaxation { .. } => {
                    "SetMotion refused: the moment relaxes back: a held tip needs a voltage \
                     that grows without bound"
                }
                StepError::NoResponse => "SetMotion refused: no held voltage moves the tip",
            }),
            ShapeRefused::NeedsRise => f.write_str(NEEDS_RISE),
            ShapeRefused::StepTracked => f.write_str(STEP_TRACKED),
            // The others' own words hold no float (written out: a call to
            // the whole `Display` would link the float formatting anyway).
            ShapeRefused::Format(e) => write!(f, "SetModel refused: {e}"),
            ShapeRefused::TooManySegments(n) => too_many(f, *n),
            ShapeRefused::NoModel => f.write_str(NO_MODEL),
            ShapeRefused::Unreachable {
                needs_v,
                segment,
                limit_v,
                reachable_m,
            } => unreachable(
                f,
                *needs_v,
                *segment,
                *limit_v,
                (*reachable_m, "um at the tip"),
            ),
            ShapeRefused::UnreachableForce {
                needs_v,
                segment,
                limit_v,
                reachable_n,
            } => unreachable(
                f,
                *needs_v,
                *segment,
                *limit_v,
                (*reachable_n, "uN at the load cell"),
            ),
            ShapeRefused::Wave(e) => write!(f, "SetMotion refused: {e}"),
            ShapeRefused::NoSessionTime => f.write_str(NO_SESSION_TIME),
            ShapeRefused::Controller(e) => write!(f, "{e}"),
        }
    }
}

/// A model that passed [`Shaper::check`], with its strip built: what
/// [`Shaper::install`] takes.
#[derive(Clone, Debug)]
pub struct CheckedModel<const N: usize, const E: usize, const S: usize> {
    record: ModelRecord,
    strip: Strip<f32, N, E, S>,
    /// The drying law's rate, 1/s (0: the model does not dry), and
    /// curvature.
    drying: (f64, f64),
}

/// The model the board holds, for `N` segments of `E` elements (`S` the
/// strip's state length, `model_core::state_len(N, E)`).
#[derive(Clone, Debug, Default)]
pub struct Shaper<const N: usize, const E: usize, const S: usize> {
    model: Option<CheckedModel<N, E, S>>,
}

impl<const N: usize, const E: usize, const S: usize> Shaper<N, E, S> {
    /// No model yet: every motion is refused.
    pub const fn new() -> Self {
        Self { model: None }
    }

    /// Checks `record` for a strip sampled every `dt_s`: its layout, the
    /// model's rules, and that it answers a sine at 1 Hz (a free strip
    /// whose moment does not reach the tip cannot be shaped).
    // Not inlined, nor are its two steps: inlined into the command task,
    // the strip's set-up and the inverse would share one frame, their
    // peaks added (N = 8 then overflowed the board's stack in QEMU).
    #[inline(never)]
    pub fn check(record: &ModelRecord, dt_s: f64) -> Result<CheckedModel<N, E, S>, ShapeRefused> {
        // Before anything is built: the build itself would overflow.
        if N > MAX_SHAPED_SEGMENTS {
            return Err(ShapeRefused::TooManySegments(N));
        }
        let m = record.decode().map_err(ShapeRefused::Format)?;
        let strip = Self::build(&m, Fixture::Free, dt_s)?;
        if CHECK_HZ < 0.5 / dt_s {
            Self::answers(&strip)?;
        }
        Ok(CheckedModel {
            record: *record,
            strip,
            drying: (m.dehydration_per_s, m.dehydration_curvature),
        })
    }

    #[inline(never)]
    fn build(
        m: &StripModel,
        fixture: Fixture,
        dt_s: f64,
    ) -> Result<Strip<f32, N, E, S>, ShapeRefused> {
        Strip::<f32, N, E, S>::with_extensions(&m.params, &m.extensions, fixture, dt_s)
            .map_err(ShapeRefused::Model)
    }

    /// The model's strip held by the load cell, built for a force motion
    /// (not kept: the free strip is what the board holds).
    #[inline(never)]
    fn held(model: &CheckedModel<N, E, S>) -> Result<Strip<f32, N, E, S>, ShapeRefused> {
        // Never reached above the bound (no model is checked there), but
        // said so the build is left out of those firmwares (22 KB at N = 8).
        if N > MAX_SHAPED_SEGMENTS {
            return Err(ShapeRefused::TooManySegments(N));
        }
        let m = model.record.decode().map_err(ShapeRefused::Format)?;
        Self::build(&m, Fixture::Blocked, model.strip.dt_s())
    }

    #[inline(never)]
    fn answers(strip: &Strip<f32, N, E, S>) -> Result<(), ShapeRefused> {
        strip
            .tip_wave(CHECK_HZ, 1e-3, 0.0)
            .map(|_| ())
            .map_err(ShapeRefused::NotInvertible)
    }

    /// Uses `model` from now on.
    pub fn install(&mut self, model: CheckedModel<N, E, S>) {
        self.model = Some(model);
    }

    /// The record of the model in use, if any.
    pub fn record(&self) -> Option<&ModelRecord> {
        self.model.as_ref().map(|m| &m.record)
    }

    /// The program that makes `motion` under `envelope` on the model held,
    /// starting at `t_session_s` on the clock of its drying law (a model
    /// that does not dry takes any, NaN too), each segment within
    /// `limit_v`; the envelope to drive it with; and what the controller
    /// holds it to (the model's admittances, the drying law).
    #[inline(never)]
    pub fn program(
        &self,
        motion: &Motion,
        envelope: Envelope,
        limit_v: f32,
        t_session_s: f32,
    ) -> Result<ShapedMotion<N>, ShapeRefused> {
        // No model is ever held above the bound (none is checked there),
        // but said so the build leaves the body out: its 30.6 KB frame was
        // taken on every SetMotion at N = 8, and put the stack's bound
        // 9 KB past its room there (scripts/check-stack, 2026-11-29).
        if N > MAX_SHAPED_SEGMENTS {
            return Err(ShapeRefused::NoModel);
        }
        let model = self.model.as_ref().ok_or(ShapeRefused::NoModel)?;
        let (rate_per_s, curvature) = model.drying;
        let drying = if rate_per_s == 0.0 {
            None
        } else if t_session_s.is_finite() && t_session_s >= 0.0 {
            Some(Drying {
                rate_per_s,
                curvature,
                t_start_s: f64::from(t_session_s),
            })
        } else {
            return Err(ShapeRefused::NoSessionTime);
        };
        let wave = match *motion {
            Motion::Travelling {
                tip_amp_m,
                frequency_hz,
                lag_deg_per_segment,
            } => Asked {
                amplitude: tip_amp_m,
                frequency_hz,
                lag_deg_per_segment,
                force: false,
            },
            Motion::Force {
                force_amp_n,
                frequency_hz,
                lag_deg_per_segment,
            } => Asked {
                amplitude: force_amp_n,
                frequency_hz,
                lag_deg_per_segment,
                force: true,
            },
            Motion::Step { tip_m } => {
                let (program, step, drying) =
                    Self::held_step(&model.strip, tip_m, envelope.ramp_in_s, limit_v, drying)?;
                // The rise is the program's own: the envelope only ends it.
                let envelope = Envelope {
                    ramp_in_s: 0.0,
                    ..envelope
                };
                return Ok(ShapedMotion::untracked(
                    program,
                    envelope,
                    Shape::Step(step),
                    drying,
                ));
            }
        };
        // The strip's moment gain is 1; dried, every voltage is 1/g.
        let g0 = drying.map_or(1.0, |d| d.gain(0.0));
        // A force wave is the held strip's, built for it.
        let (program, sine) = if wave.force {
            Self::sines(&Self::held(model)?, &wave, limit_v, g0)?
        } else {
            Self::sines(&model.strip, &wave, limit_v, g0)?
        };
        Ok(ShapedMotion::untracked(
            program,
            envelope,
            Shape::Sine(sine),
            drying,
        ))
    }

    /// A travelling wave's sines (`Strip::tip_wave`, or `force_wave` on
    /// the held `strip`), each amplitude `1/g0` of the undried one, and
    /// the sines undried with each segment's admittance (and force per
    /// volt, for a force).
    // Not inlined, nor is `held_step`: each has its own solve's arrays, and
    // inlined side by side their frames would add up on the command
    // task's stack.
    #[inline(never)]
    fn sines(
        strip: &Strip<f32, N, E, S>,
        asked: &Asked,
        limit_v: f32,
        g0: f64,
    ) -> Result<(Program, Sine<N>), ShapeRefused> {
        let Asked {
            amplitude,
            frequency_hz,
            lag_deg_per_segment,
            force,
        } = *asked;
        let (hz, lag_rad) = (
            f64::from(frequency_hz),
            f64::from(lag_deg_per_segment).to_radians(),
        );
        let v = if force {
            strip.force_wave(hz, f64::from(amplitude), lag_rad)
        } else {
            strip.tip_wave(hz, f64::from(amplitude), lag_rad)
        }
        .map_err(ShapeRefused::Harmonic)?;
        let mut amplitudes_v = [0.0f32; 8];
        let mut phases_deg = [0.0f32; 8];
        let mut undried_v = [0.0f32; N];
        for (k, p) in v.iter().enumerate() {
            undried_v[k] = p.amplitude() as f32;
            amplitudes_v[k] = (p.amplitude() / g0) as f32;
            phases_deg[k] = p.sine_phase_rad().to_degrees() as f32;
        }
        // The f32 amplitudes, as the generator and the controller's limit
        // check will see them.
        let (k, needs_v) = largest(&amplitudes_v[..N]);
        within(needs_v, k, limit_v, amplitude, force)?;
        let program = Program::Harmonic {
            frequency_hz,
            offset_v: 0.0,
            amplitudes_v,
            phases_deg,
        };
        // The generator's own rules (frequency range, finite values); the
        // envelope is the command's, checked where it is used.
        finrs_drive::Generator::<N>::new(program, Envelope::STEADY).map_err(ShapeRefused::Wave)?;
        // Each segment's admittance as its shunt samples it, and its force
        // per volt as the load cell reads it.
        let currents = strip
            .sampled_admittance(hz)
            .map_err(ShapeRefused::Harmonic)?;
        let force_n_per_v = if force {
            let h = strip
                .sampled_force_per_volt(hz)
                .map_err(ShapeRefused::Harmonic)?;
            Some(h.map(|h| [h.re as f32, h.im as f32]))
        } else {
            None
        };
        let sine = Sine {
            frequency_hz,
            amplitudes_v: undried_v,
            phases_deg: core::array::from_fn(|k| phases_deg[k]),
            admittance_a_per_v: currents.map(|y| [y.re as f32, y.im as f32]),
            force_n_per_v,
        };
        Ok((program, sine))
    }

    /// A held step (`Strip::tip_step`) rising over `rise_s`, its levels
    /// undried and as driven, and the drying law it follows.
    ///
    /// A level's change reaches the moment through the relaxation: at
    /// once by `p/z` of it, the rest with `e^{−z t}`. For the slow drying
    /// the inverse `(s + p) z/((s + z) p) ≈ 1 + (1/p − 1/z) s` is a lead:
    /// the levels follow the law `1/p − 1/z` ahead (and half an update
    /// more, each correction being held for [`STEP_UPDATE_S`]); a law
    /// followed on time leaves a creeping strip's tip 0.9 % behind.
    #[inline(never)]
    fn held_step(
        strip: &Strip<f32, N, E, S>,
        tip_m: f32,
        rise_s: f32,
        limit_v: f32,
        drying: Option<Drying>,
    ) -> Result<(Program, HeldStep<N>, Option<Drying>), ShapeRefused> {
        let step = strip
            .tip_step(f64::from(tip_m))
            .map_err(ShapeRefused::Step)?;
        // A rise that is not a duration is the generator's to refuse.
        if step.zero_per_s.is_infinite() && rise_s == 0.0 {
            return Err(ShapeRefused::NeedsRise);
        }
        let lead_s = 1.0 / step.pole_per_s - 1.0 / step.zero_per_s + 0.5 * f64::from(STEP_UPDATE_S);
        let drying = drying.map(|d| Drying {
            t_start_s: d.t_start_s + lead_s,
            ..d
        });
        let g0 = drying.map_or(1.0, |d| d.gain(0.0));
        let mut levels_v = [0.0f32; 8];
        for (l, &v) in levels_v.iter_mut().zip(&step.levels_v) {
            *l = (v / g0) as f32;
        }
        let program = Program::HeldStep {
            levels_v,
            rise_s,
            pole_per_s: step.pole_per_s as f32,
            zero_per_s: step.zero_per_s as f32,
        };
        let generator = finrs_drive::Generator::<N>::new(program, Envelope::STEADY)
            .map_err(ShapeRefused::Wave)?;
        // The peak of the whole program (a creep's start, a pure lag's
        // rise), on the segment of the largest level.
        let needs_v = generator.peak_abs_v();
        let magnitudes: [f32; N] = core::array::from_fn(|k| levels_v[k].abs());
        let (k, largest_v) = largest(&magnitudes);
        within(needs_v, k, limit_v, tip_m, false)?;
        let held = HeldStep {
            levels_v: step.levels_v.map(|v| v as f32),
            rise_s,
            pole_per_s: step.pole_per_s as f32,
            zero_per_s: step.zero_per_s as f32,
            peak_per_level: if largest_v > 0.0 {
                needs_v / largest_v
            } else {
                1.0
            },
        };
        Ok((program, held, drying))
    }
}

/// A travelling wave asked of the free tip (m) or of the load cell (N).
struct Asked {
    amplitude: f32,
    frequency_hz: f32,
    lag_deg_per_segment: f32,
    force: bool,
}

/// Refuses a motion of `asked` (at the tip, m, or of the load cell's
/// `force`, N) whose largest voltage, `needs_v` on segment `k` (from 0),
/// is above `limit_v`, with the motion the limit reaches: the voltages
/// scale with the motion asked.
fn within(
    needs_v: f32,
    k: usize,
    limit_v: f32,
    asked: f32,
    force: bool,
) -> Result<(), ShapeRefused> {
    if needs_v <= limit_v {
        return Ok(());
    }
    let (segment, reachable) = (k as u8 + 1, asked.abs() * limit_v / needs_v);
    Err(if force {
        ShapeRefused::UnreachableForce {
            needs_v,
            segment,
            limit_v,
            reachable_n: reachable,
        }
    } else {
        ShapeRefused::Unreachable {
            needs_v,
            segment,
            limit_v,
            reachable_m: reachable,
        }
    })
}

/// The index and value of the largest of `values` (the first if tied).
fn largest(values: &[f32]) -> (usize, f32) {
    values
        .iter()
        .enumerate()
        .fold((0, 0.0f32), |m, (k, &a)| if a > m.1 { (k, a) } else { m })
}

/// A motion as the model held shapes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapedMotion<const N: usize> {
    /// The voltages: each segment's sine ([`Program::Harmonic`]) or a held
    /// step ([`Program::HeldStep`]).
    pub program: Program,
    /// The envelope to drive it with (a step's ramp-in is its program's
    /// rise).
    pub envelope: Envelope,
    /// The same undried, with the model's admittances and drying law:
    /// what the controller holds it to (its `tracked` false: the
    /// command says).
    pub target: Target<N>,
}

impl<const N: usize> ShapedMotion<N> {
    /// `program` under `envelope`, held by the tracker to `shape` and
    /// `drying` (not tracked: the command says).
    fn untracked(
        program: Program,
        envelope: Envelope,
        shape: Shape<N>,
        drying: Option<Drying>,
    ) -> Self {
        let target = Target {
            shape,
            tracked: false,
            drying,
        };
        Self {
            program,
            envelope,
            target,
        }
    }
}

/// What [`command`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shaped {
    /// A SetModel's model is in use (and handed to the board to store).
    ModelSet,
    /// A SetMotion's voltages drive the outputs.
    WaveSet,
    /// Any other command, handed to the controller as it came.
    Passed,
}

/// Hands `c` to the controller behind `lock`, shaping a SetModel or a
/// SetMotion with `shaper` first, outside the lock (`dt_s` the sample
/// time). A refused command changes nothing.
pub fn command<const N: usize, H: HoldsModel<N>>(
    c: Command,
    shaper: &mut H,
    dt_s: f64,
    lock: &mut impl Mutex<T = Controller<N>>,
) -> Result<Shaped, ShapeRefused> {
    match c {
        Command::SetModel(record) => {
            let model = H::check(&record, dt_s)?;
            lock.lock(|ctl| ctl.model_set(&record))
                .map_err(ShapeRefused::Controller)?;
            shaper.install(model);
            Ok(Shaped::ModelSet)
        }
        Command::SetMotion {
            motion,
            envelope,
            t_session_s,
            tracked,
        } => {
            // A step has no sine whose currents the tracker could lock in to.
            if tracked && matches!(motion, Motion::Step { .. }) {
                return Err(ShapeRefused::StepTracked);
            }
            let limit_v = lock.lock(|ctl| ctl.limits().max_abs_v());
            let shaped = shaper.program(&motion, envelope, limit_v, t_session_s)?;
            let target = Target {
                tracked,
                ..shaped.target
            };
            // Held when tracked, or while the model dries; else as shaped.
            let target = (tracked || target.drying.is_some()).then_some(target);
            lock.lock(|ctl| ctl.motion(shaped.program, shaped.envelope, target))
                .map_err(ShapeRefused::Controller)?;
            Ok(Shaped::WaveSet)
        }
        other => {
            lock.lock(|ctl| ctl.command(other))
                .map_err(ShapeRefused::Controller)?;
            Ok(Shaped::Passed)
        }
    }
}
