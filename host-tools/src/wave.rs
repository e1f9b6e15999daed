//! The one parser of the `--wave` syntax, shared by `finrs simulate` and
//! `finrs wave`: `step:V[,V..]`, `sine:AMP,HZ,LAG_DEG`, `standing:AMP,HZ`,
//! `chirp:AMP,HZ0,HZ1`, `pulses:AMP,ON_S,OFF_S`,
//! `harmonic:HZ,AMP,PHASE_DEG[,AMP,PHASE_DEG..]` (each segment its own sine),
//! `motion:TIP_AMP_M,HZ,LAG_DEG` (a travelling bending wave asked of the
//! free tip, which only the strip's model turns into voltages:
//! `finrs::model::motion`; the board's gain tracker holds it against the
//! strip's drift), `motion-ff:TIP_AMP_M,HZ,LAG_DEG` (the same, feed-forward
//! only: the model's voltages as they are), `motion-step:TIP_M` (the free
//! tip stepped to `TIP_M` over the ramp-in and held there against the
//! strip's relaxation, through the model), `force:FORCE_AMP_N,HZ,LAG_DEG`
//! (the same travelling wave asked of the strip held by the load cell, its
//! force; the board's tracker holds it by the load cell), `force-ff:` (the
//! same, feed-forward only), and
//! `held:RISE_S,POLE_PER_S,ZERO_PER_S,V[,V..]` (the voltages a
//! `motion-step:` becomes: each segment's level times the inverse of the
//! relaxation `(s + z)/(s + p)` over a raised-cosine rise; `ZERO_PER_S` may
//! be `inf`, a pure lag).
//!
//! [`Wave::parse`] checks the syntax only (kind, number of values, finite
//! numbers). [`Wave::generator`] maps the wave, with its [`WaveOptions`]
//! (offset, ramps, hold, chirp sweep), onto a [`finrs_drive::Program`] and
//! [`finrs_drive::Envelope`] for a segment count, and validates them once:
//! with [`Generator::new`], the firmware's own rules, and the host's check
//! that the peak stays within [`HARD_LIMIT_V`]. The host evaluates waves
//! with nothing else than the firmware's [`Generator`]: [`SegmentGenerator`]
//! holds one for a segment count known at run time.
//!
//! ```
//! use finrs::wave::{Wave, WaveOptions};
//!
//! let wave = Wave::parse("sine:2,1,120").unwrap();
//! let g = wave.generator(3, &WaveOptions::steady(10.0)).unwrap();
//! // A quarter period in, at 1 kHz: the root at the crest, the others lag.
//! let v = g.voltages_at_tick_v(250, 1000);
//! assert!((v[0] - 2.0).abs() < 2.0 * finrs_drive::SINE_MAX_ERROR as f64);
//! assert!((v[1] - 2.0 * (-30f64).to_radians().sin()).abs() < 5e-3);
//!
//! let e = wave.generator(3, &WaveOptions { offset_v: 2.5, ..WaveOptions::steady(10.0) });
//! assert_eq!(
//!     e.unwrap_err().to_string(),
//!     "wave `sine:2,1,120`: peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V"
//! );
//! ```

use finrs_drive::{Envelope, Generator, Program, HARD_LIMIT_V, MAX_SEGMENTS};
use finrs_frames::Motion;

/// Why a wave was refused: its text, or the firmware's rules for it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum WaveError {
    /// No `KIND:` before the values.
    #[error("wave `{wave}`: expected KIND:VALUES, e.g. step:2.5")]
    NoKind {
        /// The wave's text.
        wave: String,
    },
    /// A value is not a finite number.
    #[error("wave `{wave}`: `{value}` is not a finite number")]
    NotANumber {
        /// The wave's text.
        wave: String,
        /// The value as written.
        value: String,
    },
    /// The kind takes another number of values.
    #[error("wave `{wave}`: {kind} takes {usage}, got {got} value(s)")]
    Count {
        /// The wave's text.
        wave: String,
        /// The kind.
        kind: String,
        /// The values it takes.
        usage: &'static str,
        /// The values given.
        got: usize,
    },
    /// No such kind.
    #[error(
        "wave `{wave}`: unknown kind `{kind}` (step, sine, standing, chirp, pulses, harmonic, held, motion, motion-ff, motion-step, force, force-ff)"
    )]
    UnknownKind {
        /// The wave's text.
        wave: String,
        /// The kind given.
        kind: String,
    },
    /// A step or held step names neither one level nor one per segment.
    #[error("wave `{wave}`: {levels} levels for {segments} segments")]
    Levels {
        /// The wave's text.
        wave: String,
        /// Levels given.
        levels: usize,
        /// Segments driven.
        segments: usize,
    },
    /// The segment count is not one the firmware drives.
    #[error("segments must be 1..={MAX_SEGMENTS}, got {0}")]
    Segments(usize),
    /// A harmonic wave names neither one segment's sine nor one per segment.
    #[error("wave `{wave}`: harmonic has {sines} amplitude-phase pairs for {segments} segments")]
    Sines {
        /// The wave's text.
        wave: String,
        /// Pairs given.
        sines: usize,
        /// Segments driven.
        segments: usize,
    },
    /// A motion wave where no model turns it into voltages.
    #[error(
        "wave `{wave}`: a motion needs the strip's model to become voltages: \
         `finrs simulate --wave` computes them from --params, the board from the model \
         `finrs tune` gave it"
    )]
    NeedsModel {
        /// The wave's text.
        wave: String,
    },
    /// An offset for a wave that has none.
    #[error("offset_v applies to sine:, standing: and harmonic: waves only, not `{wave}`")]
    Offset {
        /// The wave's text.
        wave: String,
    },
    /// The firmware's generator refuses the program or envelope.
    #[error("wave `{wave}`: {rule}")]
    Firmware {
        /// The wave's text.
        wave: String,
        /// The field and rule broken.
        rule: finrs_drive::WaveError,
    },
    /// The firmware's generator refuses a program or envelope (no text
    /// known: [`SegmentGenerator::new`]).
    #[error("{0}")]
    Generator(finrs_drive::WaveError),
    /// The wave's peak is above the hard limit.
    #[error(
        "wave `{wave}`: peak {peak_v} V ({peak_is}) exceeds the hard limit of ±{HARD_LIMIT_V} V"
    )]
    Peak {
        /// The wave's text.
        wave: String,
        /// Its peak, V.
        peak_v: f64,
        /// What makes the peak.
        peak_is: &'static str,
    },
}

/// A wave as its text gives it: what each segment does, before the options
/// and the segment count turn it into a drive program.
#[derive(Clone, Debug, PartialEq)]
pub enum WaveKind {
    /// Constant voltages; one value means every segment.
    Step {
        /// Voltage per segment, V.
        levels_v: Vec<f64>,
    },
    /// Travelling sine: segment `k` (0-based) lags by `k` times the lag.
    Sine {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Phase lag per segment, degrees.
        lag_deg: f64,
    },
    /// Standing wave: root and tip in antiphase, node in the middle (see
    /// [`Program::Standing`]).
    Standing {
        /// Amplitude at the root and tip, V.
        amplitude_v: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
    },
    /// Logarithmic chirp, all segments in phase; the sweep's length is an
    /// option ([`WaveOptions::sweep_s`]).
    Chirp {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
    },
    /// Pulse train: `on` seconds at the amplitude, `off` at zero (the seed's
    /// 20 s pulses).
    Pulses {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Time on, s.
        on_s: f64,
        /// Time off, s.
        off_s: f64,
    },
    /// A travelling bending wave asked of the free tip: every segment's
    /// moment of one amplitude, each `lag_deg` behind the one before,
    /// scaled so that the tip moves `tip_amp_m` (`model_core::Strip::tip_wave`).
    Motion {
        /// The tip's amplitude, m.
        tip_amp_m: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Each segment's moment behind the one before, degrees.
        lag_deg: f64,
        /// Whether the board's gain tracker holds it (`motion:`), or the
        /// model's voltages are driven as they are (`motion-ff:`).
        tracked: bool,
    },
    /// A travelling bending wave asked of the strip held by the load cell:
    /// as [`WaveKind::Motion`], scaled so that the force on the load cell
    /// moves `force_amp_n` (`model_core::Strip::force_wave`).
    Force {
        /// The force's amplitude, N.
        force_amp_n: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Each segment's moment behind the one before, degrees.
        lag_deg: f64,
        /// Whether the board's tracker holds it by the load cell
        /// (`force:`), or the model's voltages are driven as they are
        /// (`force-ff:`).
        tracked: bool,
    },
    /// A step of the free tip held against the strip's relaxation
    /// (`model_core::Strip::tip_step`), rising over the ramp-in.
    MotionStep {
        /// The tip's deflection once settled, m.
        tip_m: f64,
    },
    /// A held step's voltages (see [`Program::HeldStep`]); one level means
    /// every segment.
    HeldStep {
        /// The raised-cosine rise, s.
        rise_s: f64,
        /// The relaxation's pole, 1/s.
        pole_per_s: f64,
        /// Its zero, 1/s (`+∞` for a pure lag).
        zero_per_s: f64,
        /// Each segment's level, V.
        levels_v: Vec<f64>,
    },
    /// Each segment its own sine (see [`Program::Harmonic`]); one pair
    /// means every segment.
    Harmonic {
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Each segment's amplitude, V.
        amplitudes_v: Vec<f64>,
        /// Each segment's phase, degrees.
        phases_deg: Vec<f64>,
    },
}

/// A parsed `--wave` text.
#[derive(Clone, Debug, PartialEq)]
pub struct Wave {
    text: String,
    kind: WaveKind,
}

/// A motion wave as the board's shaper takes it ([`Wave::motion`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionWave {
    /// The SetMotion's motion (its values as `f32`).
    pub motion: Motion,
    /// Whether the board's tracker holds it (`motion:`, `force:`).
    pub tracked: bool,
    /// What is asked, as written: the tip's amplitude or step, m, or the
    /// force's amplitude, N.
    pub asked: f64,
}

/// What shapes a wave beyond its text: the one description `finrs wave`
/// sends to the firmware and `finrs simulate --wave` drives a recording
/// with (`model::synth::drive_recording_shaped`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WaveOptions {
    /// Constant added to a `sine:`, `standing:` or `harmonic:` wave, V (0
    /// for others).
    pub offset_v: f64,
    /// Time to full amplitude, s.
    pub ramp_in_s: f64,
    /// Time at full amplitude, s (infinite: for ever).
    pub hold_s: f64,
    /// Time from full amplitude to zero, s.
    pub ramp_out_s: f64,
    /// Length of one `chirp:` sweep, s.
    pub sweep_s: f64,
}

impl WaveOptions {
    /// No offset, no ramps, held for ever, chirps sweeping over `sweep_s`.
    pub fn steady(sweep_s: f64) -> Self {
        WaveOptions {
            offset_v: 0.0,
            ramp_in_s: 0.0,
            hold_s: f64::INFINITY,
            ramp_out_s: 0.0,
            sweep_s,
        }
    }
}

impl Wave {
    /// Parses `kind:a,b,c`; the message names the wave, the value and the
    /// rule broken. Only the syntax is checked here: the values' ranges are
    /// the firmware's ([`Wave::generator`]).
    pub fn parse(spec: &str) -> Result<Wave, WaveError> {
        let (kind, args) = spec.split_once(':').ok_or_else(|| WaveError::NoKind {
            wave: spec.to_string(),
        })?;
        let values = args
            .split(',')
            .enumerate()
            .map(|(i, a)| {
                // A held step's zero alone may be `inf`: a pure lag.
                let infinite_ok = kind == "held" && i == 2;
                a.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() || (infinite_ok && *v == f64::INFINITY))
                    .ok_or_else(|| WaveError::NotANumber {
                        wave: spec.to_string(),
                        value: a.to_string(),
                    })
            })
            .collect::<Result<Vec<f64>, WaveError>>()?;
        let need = |n: usize, usage: &'static str| {
            if values.len() == n {
                Ok(())
            } else {
                Err(WaveError::Count {
                    wave: spec.to_string(),
                    kind: kind.to_string(),
                    usage,
                    got: values.len(),
                })
            }
        };
        let kind = match kind {
            "step" => WaveKind::Step {
                levels_v: values.clone(),
            },
            "sine" => {
                need(3, "AMPLITUDE_V,FREQUENCY_HZ,LAG_DEG")?;
                WaveKind::Sine {
                    amplitude_v: values[0],
                    frequency_hz: values[1],
                    lag_deg: values[2],
                }
            }
            "standing" => {
                need(2, "AMPLITUDE_V,FREQUENCY_HZ")?;
                WaveKind::Standing {
                    amplitude_v: values[0],
                    frequency_hz: values[1],
                }
            }
            "chirp" => {
                need(3, "AMPLITUDE_V,START_HZ,END_HZ")?;
                WaveKind::Chirp {
                    amplitude_v: values[0],
                    start_hz: values[1],
                    end_hz: values[2],
                }
            }
            "pulses" => {
                need(3, "AMPLITUDE_V,ON_S,OFF_S")?;
                WaveKind::Pulses {
                    amplitude_v: values[0],
                    on_s: values[1],
                    off_s: values[2],
                }
            }
            "harmonic" => {
                if values.len() < 3 || values.len() % 2 == 0 {
                    return Err(WaveError::Count {
                        wave: spec.to_string(),
                        kind: kind.to_string(),
                        usage: "FREQUENCY_HZ then AMPLITUDE_V,PHASE_DEG per segment (or one pair for all)",
                        got: values.len(),
                    });
                }
                WaveKind::Harmonic {
                    frequency_hz: values[0],
                    amplitudes_v: values[1..].iter().step_by(2).copied().collect(),
                    phases_deg: values[2..].iter().step_by(2).copied().collect(),
                }
            }
            "held" => {
                if values.len() < 4 {
                    return Err(WaveError::Count {
                        wave: spec.to_string(),
                        kind: kind.to_string(),
                        usage: "RISE_S,POLE_PER_S,ZERO_PER_S then V per segment (or one for all)",
                        got: values.len(),
                    });
                }
                WaveKind::HeldStep {
                    rise_s: values[0],
                    pole_per_s: values[1],
                    zero_per_s: values[2],
                    levels_v: values[3..].to_vec(),
                }
            }
            "force" | "force-ff" => {
                need(3, "FORCE_AMPLITUDE_N,FREQUENCY_HZ,LAG_DEG")?;
                WaveKind::Force {
                    force_amp_n: values[0],
                    frequency_hz: values[1],
                    lag_deg: values[2],
                    tracked: kind == "force",
                }
            }
            "motion-step" => {
                need(1, "TIP_M")?;
                WaveKind::MotionStep { tip_m: values[0] }
            }
            "motion" | "motion-ff" => {
                need(3, "TIP_AMPLITUDE_M,FREQUENCY_HZ,LAG_DEG")?;
                WaveKind::Motion {
                    tip_amp_m: values[0],
                    frequency_hz: values[1],
                    lag_deg: values[2],
                    tracked: kind == "motion",
                }
            }
            other => {
                return Err(WaveError::UnknownKind {
                    wave: spec.to_string(),
                    kind: other.to_string(),
                })
            }
        };
        Ok(Wave {
            text: spec.to_string(),
            kind,
        })
    }

    /// The wave's text, as given.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// What the text describes.
    pub fn kind(&self) -> &WaveKind {
        &self.kind
    }

    /// A motion wave as a SetMotion carries it to the board's shaper;
    /// `None` for a voltage wave.
    pub fn motion(&self) -> Option<MotionWave> {
        let f = |x: f64| x as f32;
        Some(match self.kind {
            WaveKind::Motion {
                tip_amp_m,
                frequency_hz,
                lag_deg,
                tracked,
            } => MotionWave {
                motion: Motion::Travelling {
                    tip_amp_m: f(tip_amp_m),
                    frequency_hz: f(frequency_hz),
                    lag_deg_per_segment: f(lag_deg),
                },
                tracked,
                asked: tip_amp_m,
            },
            WaveKind::Force {
                force_amp_n,
                frequency_hz,
                lag_deg,
                tracked,
            } => MotionWave {
                motion: Motion::Force {
                    force_amp_n: f(force_amp_n),
                    frequency_hz: f(frequency_hz),
                    lag_deg_per_segment: f(lag_deg),
                },
                tracked,
                asked: force_amp_n,
            },
            // Held by the drying law alone: a step has no sine to track.
            WaveKind::MotionStep { tip_m } => MotionWave {
                motion: Motion::Step { tip_m: f(tip_m) },
                tracked: false,
                asked: tip_m,
            },
            _ => return None,
        })
    }

    /// Checks that a step names one level or one per segment.
    pub fn check_segments(&self, segments: usize) -> Result<(), WaveError> {
        match &self.kind {
            WaveKind::Step { levels_v } | WaveKind::HeldStep { levels_v, .. }
                if levels_v.len() != 1 && levels_v.len() != segments =>
            {
                Err(WaveError::Levels {
                    wave: self.text.clone(),
                    levels: levels_v.len(),
                    segments,
                })
            }
            WaveKind::Harmonic { amplitudes_v, .. }
                if amplitudes_v.len() != 1 && amplitudes_v.len() != segments =>
            {
                Err(WaveError::Sines {
                    wave: self.text.clone(),
                    sines: amplitudes_v.len(),
                    segments,
                })
            }
            _ => Ok(()),
        }
    }

    /// The firmware's program and envelope for `segments` segments, checked
    /// as the firmware checks them ([`Generator::new`]) and for a peak
    /// within [`HARD_LIMIT_V`], ready to evaluate.
    pub fn generator(
        &self,
        segments: usize,
        options: &WaveOptions,
    ) -> Result<SegmentGenerator, WaveError> {
        if !(1..=MAX_SEGMENTS).contains(&segments) {
            return Err(WaveError::Segments(segments));
        }
        self.check_segments(segments)?;
        let spec = &self.text;
        let offset_v = match self.kind {
            WaveKind::Sine { .. } | WaveKind::Standing { .. } | WaveKind::Harmonic { .. } => {
                options.offset_v
            }
            _ if options.offset_v == 0.0 => 0.0,
            _ => {
                return Err(WaveError::Offset {
                    wave: spec.to_string(),
                })
            }
        };
        let (program, peak_v, peak_is) = self
            .program(segments, offset_v, options.sweep_s)
            .ok_or_else(|| WaveError::NeedsModel {
                wave: spec.to_string(),
            })?;
        let f = |x: f64| x as f32;
        let envelope = Envelope {
            ramp_in_s: f(options.ramp_in_s),
            hold_s: f(options.hold_s),
            ramp_out_s: f(options.ramp_out_s),
        };
        let generator =
            SegmentGenerator::new(segments, program, envelope).map_err(|e| match e {
                WaveError::Generator(rule) => WaveError::Firmware {
                    wave: spec.to_string(),
                    rule,
                },
                other => other,
            })?;
        // The firmware's limiter would clip a larger wave out of shape.
        if peak_v.is_nan() || peak_v > f64::from(HARD_LIMIT_V) {
            return Err(WaveError::Peak {
                wave: spec.to_string(),
                peak_v,
                peak_is,
            });
        }
        Ok(generator)
    }

    /// The firmware's program for `segments` segments (offset and chirp
    /// sweep given), its peak voltage, V, and what makes that peak; `None`
    /// for a motion, which only the strip's model turns into voltages.
    fn program(
        &self,
        segments: usize,
        offset_v: f64,
        sweep_s: f64,
    ) -> Option<(Program, f64, &'static str)> {
        let f = |x: f64| x as f32;
        let per_segment = |values: &[f64]| {
            let mut out = [0.0f32; MAX_SEGMENTS];
            for (k, v) in out.iter_mut().take(segments).enumerate() {
                *v = f(values[if values.len() == 1 { 0 } else { k }]);
            }
            out
        };
        Some(match &self.kind {
            WaveKind::Motion { .. } | WaveKind::MotionStep { .. } | WaveKind::Force { .. } => {
                return None
            }
            &WaveKind::HeldStep {
                rise_s,
                pole_per_s,
                zero_per_s,
                ref levels_v,
            } => {
                let program = Program::HeldStep {
                    levels_v: per_segment(levels_v),
                    rise_s: f(rise_s),
                    pole_per_s: f(pole_per_s),
                    zero_per_s: f(zero_per_s),
                };
                // The generator's own peak (its rules are checked before the
                // peak is: a refused program's NaN is never read).
                let peak = Generator::<MAX_SEGMENTS>::new(program, Envelope::STEADY)
                    .map_or(f64::NAN, |g| f64::from(g.peak_abs_v()));
                (program, peak, "largest level times the step's peak")
            }
            WaveKind::Step { levels_v } => {
                let peak = levels_v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                (
                    Program::Steps {
                        levels_v: per_segment(levels_v),
                    },
                    peak,
                    "largest level",
                )
            }
            &WaveKind::Sine {
                amplitude_v,
                frequency_hz,
                lag_deg,
            } => (
                Program::Travelling {
                    amplitude_v: f(amplitude_v),
                    frequency_hz: f(frequency_hz),
                    lag_deg_per_segment: f(lag_deg),
                    offset_v: f(offset_v),
                },
                amplitude_v.abs() + offset_v.abs(),
                "amplitude plus offset",
            ),
            &WaveKind::Standing {
                amplitude_v,
                frequency_hz,
            } => (
                Program::Standing {
                    amplitude_v: f(amplitude_v),
                    frequency_hz: f(frequency_hz),
                    offset_v: f(offset_v),
                },
                amplitude_v.abs() + offset_v.abs(),
                "amplitude plus offset",
            ),
            &WaveKind::Chirp {
                amplitude_v,
                start_hz,
                end_hz,
            } => (
                Program::Chirp {
                    amplitude_v: f(amplitude_v),
                    start_hz: f(start_hz),
                    end_hz: f(end_hz),
                    duration_s: f(sweep_s),
                },
                amplitude_v.abs(),
                "amplitude",
            ),
            &WaveKind::Pulses {
                amplitude_v,
                on_s,
                off_s,
            } => (
                Program::Pulses {
                    amplitude_v: f(amplitude_v),
                    on_s: f(on_s),
                    off_s: f(off_s),
                },
                amplitude_v.abs(),
                "amplitude",
            ),
            WaveKind::Harmonic {
                frequency_hz,
                amplitudes_v,
                phases_deg,
            } => {
                let largest = amplitudes_v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
                // As many phases as amplitudes (one pair, or one a segment).
                (
                    Program::Harmonic {
                        frequency_hz: f(*frequency_hz),
                        offset_v: f(offset_v),
                        amplitudes_v: per_segment(amplitudes_v),
                        phases_deg: per_segment(phases_deg),
                    },
                    largest + offset_v.abs(),
                    "largest amplitude plus offset",
                )
            }
        })
    }
}

/// The firmware's [`Generator<N>`] for a segment count known at run time
/// (N = 1..=8). Built only through [`Generator::new`], so it holds a
/// program the firmware accepts.
#[derive(Clone, Debug)]
pub enum SegmentGenerator {
    /// One segment.
    N1(Generator<1>),
    /// Two segments.
    N2(Generator<2>),
    /// Three segments.
    N3(Generator<3>),
    /// Four segments.
    N4(Generator<4>),
    /// Five segments.
    N5(Generator<5>),
    /// Six segments.
    N6(Generator<6>),
    /// Seven segments.
    N7(Generator<7>),
    /// Eight segments.
    N8(Generator<8>),
}

/// Runs `$body` with `$g` bound to the inner `Generator<N>`, whatever N.
macro_rules! each_generator {
    ($self:expr, $g:ident => $body:expr) => {
        match $self {
            SegmentGenerator::N1($g) => $body,
            SegmentGenerator::N2($g) => $body,
            SegmentGenerator::N3($g) => $body,
            SegmentGenerator::N4($g) => $body,
            SegmentGenerator::N5($g) => $body,
            SegmentGenerator::N6($g) => $body,
            SegmentGenerator::N7($g) => $body,
            SegmentGenerator::N8($g) => $body,
        }
    };
}

impl SegmentGenerator {
    /// `Generator::<segments>::new(program, envelope)`; the error names the
    /// field and rule (or the segment count) broken.
    pub fn new(segments: usize, program: Program, envelope: Envelope) -> Result<Self, WaveError> {
        let e = WaveError::Generator;
        Ok(match segments {
            1 => SegmentGenerator::N1(Generator::new(program, envelope).map_err(e)?),
            2 => SegmentGenerator::N2(Generator::new(program, envelope).map_err(e)?),
            3 => SegmentGenerator::N3(Generator::new(program, envelope).map_err(e)?),
            4 => SegmentGenerator::N4(Generator::new(program, envelope).map_err(e)?),
            5 => SegmentGenerator::N5(Generator::new(program, envelope).map_err(e)?),
            6 => SegmentGenerator::N6(Generator::new(program, envelope).map_err(e)?),
            7 => SegmentGenerator::N7(Generator::new(program, envelope).map_err(e)?),
            8 => SegmentGenerator::N8(Generator::new(program, envelope).map_err(e)?),
            n => return Err(WaveError::Segments(n)),
        })
    }

    /// The segment count N.
    pub fn segments(&self) -> usize {
        match self {
            SegmentGenerator::N1(_) => 1,
            SegmentGenerator::N2(_) => 2,
            SegmentGenerator::N3(_) => 3,
            SegmentGenerator::N4(_) => 4,
            SegmentGenerator::N5(_) => 5,
            SegmentGenerator::N6(_) => 6,
            SegmentGenerator::N7(_) => 7,
            SegmentGenerator::N8(_) => 8,
        }
    }

    /// The program.
    pub fn program(&self) -> Program {
        each_generator!(self, g => g.program())
    }

    /// The envelope.
    pub fn envelope(&self) -> Envelope {
        each_generator!(self, g => g.envelope())
    }

    /// [`Generator::voltages_at_tick_v`], one value per segment, in f64.
    pub fn voltages_at_tick_v(&self, tick: u64, tick_hz: u32) -> Vec<f64> {
        each_generator!(self, g => widen(&g.voltages_at_tick_v(tick, tick_hz)))
    }

    /// Every tick's voltages from tick 0 to `ticks − 1` at `tick_hz`, after
    /// the firmware's [`finrs_drive::Limiter`] with `limits` if given (its
    /// outputs start at 0 V, as on the board; one limiter step per tick).
    pub fn run(
        &self,
        ticks: u64,
        tick_hz: u32,
        limits: Option<finrs_drive::Limits>,
    ) -> Vec<Vec<f64>> {
        each_generator!(self, g => run(g, ticks, tick_hz, limits))
    }
}

fn widen(v: &[f32]) -> Vec<f64> {
    v.iter().map(|&x| f64::from(x)).collect()
}

fn run<const N: usize>(
    g: &Generator<N>,
    ticks: u64,
    tick_hz: u32,
    limits: Option<finrs_drive::Limits>,
) -> Vec<Vec<f64>> {
    let mut limiter = limits.map(finrs_drive::Limiter::<N>::new);
    // As the firmware's controller: the tick period in f32.
    let dt_s = 1.0 / tick_hz as f32;
    (0..ticks)
        .map(|tick| {
            let wanted = g.voltages_at_tick_v(tick, tick_hz);
            match &mut limiter {
                Some(l) => widen(&l.apply(wanted, dt_s)),
                None => widen(&wanted),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn generator(spec: &str, segments: usize) -> Result<SegmentGenerator, WaveError> {
        Wave::parse(spec)?.generator(segments, &WaveOptions::steady(10.0))
    }

    #[test]
    fn parses_every_kind() {
        assert_eq!(
            Wave::parse("step:2,1,-2").unwrap().kind(),
            &WaveKind::Step {
                levels_v: vec![2.0, 1.0, -2.0]
            }
        );
        assert_eq!(
            Wave::parse("sine:2.5,1,120").unwrap().kind(),
            &WaveKind::Sine {
                amplitude_v: 2.5,
                frequency_hz: 1.0,
                lag_deg: 120.0
            }
        );
        assert_eq!(
            Wave::parse("standing:1, 0.5").unwrap().kind(),
            &WaveKind::Standing {
                amplitude_v: 1.0,
                frequency_hz: 0.5
            }
        );
        assert_eq!(
            Wave::parse("chirp:2,0.1,20").unwrap().kind(),
            &WaveKind::Chirp {
                amplitude_v: 2.0,
                start_hz: 0.1,
                end_hz: 20.0
            }
        );
        assert_eq!(
            Wave::parse("pulses:2.5,20,20").unwrap().kind(),
            &WaveKind::Pulses {
                amplitude_v: 2.5,
                on_s: 20.0,
                off_s: 20.0
            }
        );
        assert_eq!(
            Wave::parse("sine:2.5,1,120").unwrap().text(),
            "sine:2.5,1,120"
        );
    }

    #[test]
    fn every_kind_evaluates_through_the_generator() {
        let sine = generator("sine:2.5,1,120", 3).unwrap();
        let v = sine.voltages_at_tick_v(0, 1000);
        assert_eq!(v.len(), 3);
        assert_eq!(v[0], 0.0);
        let exact = 2.5 * (-120f64).to_radians().sin();
        assert!((v[1] - exact).abs() < 2.5 * 1.1e-3, "{v:?}");
        let chirp = generator("chirp:2,0.1,20", 3).unwrap();
        for tick in (0..12_000).step_by(7) {
            assert!(chirp.voltages_at_tick_v(tick, 1000)[0].abs() <= 2.0);
        }
        let pulses = generator("pulses:2.5,20,20", 1).unwrap();
        assert_eq!(pulses.voltages_at_tick_v(19_900, 1000), [2.5]);
        assert_eq!(pulses.voltages_at_tick_v(20_100, 1000), [0.0]);
        let step = generator("step:1.5", 2).unwrap();
        assert_eq!(step.voltages_at_tick_v(123_456, 1000), [1.5, 1.5]);
        assert_eq!(step.segments(), 2);
        // Standing, N = 3: root and tip in antiphase, the middle a node.
        let standing = generator("standing:1,0.5", 3).unwrap();
        let v = standing.voltages_at_tick_v(500, 1000);
        assert!(
            (v[0] - 1.0).abs() < 1.1e-3 && (v[2] + 1.0).abs() < 1.1e-3,
            "{v:?}"
        );
        assert!(v[1].abs() < 1.1e-3, "{v:?}");
    }

    #[test]
    fn refuses_with_reasons() {
        for (spec, message) in [
            ("step", "wave `step`: expected KIND:VALUES, e.g. step:2.5"),
            (
                "sine:2,1",
                "wave `sine:2,1`: sine takes AMPLITUDE_V,FREQUENCY_HZ,LAG_DEG, got 2 value(s)",
            ),
            (
                "standing:1",
                "wave `standing:1`: standing takes AMPLITUDE_V,FREQUENCY_HZ, got 1 value(s)",
            ),
            (
                "wobble:1",
                "wave `wobble:1`: unknown kind `wobble` (step, sine, standing, chirp, pulses, harmonic, held, motion, motion-ff, motion-step, force, force-ff)",
            ),
            ("step:x", "wave `step:x`: `x` is not a finite number"),
            ("step:nan", "wave `step:nan`: `nan` is not a finite number"),
            (
                "step:1,inf",
                "wave `step:1,inf`: `inf` is not a finite number",
            ),
            // Only a held step's zero may be infinite.
            (
                "held:inf,0.1,inf,1",
                "wave `held:inf,0.1,inf,1`: `inf` is not a finite number",
            ),
            (
                "held:1,0.1,0.2",
                "wave `held:1,0.1,0.2`: held takes RISE_S,POLE_PER_S,ZERO_PER_S then V per segment (or one for all), got 3 value(s)",
            ),
            (
                "motion-step:0.001,1",
                "wave `motion-step:0.001,1`: motion-step takes TIP_M, got 2 value(s)",
            ),
        ] {
            assert_eq!(Wave::parse(spec).unwrap_err().to_string(), message);
        }
        // Ranges are the firmware's, checked when the program is built.
        for (spec, message) in [
            (
                "step:5",
                "wave `step:5`: peak 5 V (largest level) exceeds the hard limit of ±4 V",
            ),
            (
                "sine:2,0,1",
                "wave `sine:2,0,1`: Travelling.frequency_hz must be within 0.001..=100 Hz",
            ),
            (
                "sine:-1,1,0",
                "wave `sine:-1,1,0`: Travelling.amplitude_v must be at least 0",
            ),
            (
                "standing:1,300",
                "wave `standing:1,300`: Standing.frequency_hz must be within 0.001..=100 Hz",
            ),
            (
                "pulses:2,-1,1",
                "wave `pulses:2,-1,1`: Pulses.on_s must be at least 0",
            ),
            (
                "pulses:2,0,0",
                "wave `pulses:2,0,0`: Pulses.on_s + off_s must be above 0",
            ),
            (
                "chirp:2,5,1",
                "wave `chirp:2,5,1`: Chirp.end_hz must be above start_hz",
            ),
            (
                "step:1,2",
                "wave `step:1,2`: 2 levels for 3 segments",
            ),
            (
                "held:1,0.1,0.24,1,2",
                "wave `held:1,0.1,0.24,1,2`: 2 levels for 3 segments",
            ),
            (
                "held:0,0.1,inf,1",
                "wave `held:0,0.1,inf,1`: HeldStep.rise_s must be above 0",
            ),
            (
                "held:0,0.1,10,1",
                "wave `held:0,0.1,10,1`: peak 100 V (largest level times the step's peak) exceeds the hard limit of ±4 V",
            ),
            (
                "step:1e40",
                "wave `step:1e40`: Steps.levels_v must be finite",
            ),
        ] {
            assert_eq!(generator(spec, 3).unwrap_err().to_string(), message);
        }
        assert_eq!(
            generator("sine:1,1,0", 0).unwrap_err(),
            WaveError::Segments(0)
        );
        let wave = Wave::parse("pulses:1,1,1").unwrap();
        let offset = WaveOptions {
            offset_v: 0.5,
            ..WaveOptions::steady(10.0)
        };
        assert_eq!(
            wave.generator(3, &offset).unwrap_err().to_string(),
            "offset_v applies to sine:, standing: and harmonic: waves only, not `pulses:1,1,1`"
        );
    }

    /// A held step: the firmware's program, one level for every segment or
    /// one each, a pure lag's zero written `inf`; a motion step needs the
    /// model.
    #[test]
    fn a_held_step_is_the_firmwares_program() {
        // The pure lag's rise peaks near 1 + π/(2 T p) = 8.9 times the level.
        let g = generator("held:2,0.1,inf,0.4,-0.2,0.125", 3).unwrap();
        assert_eq!(
            g.program(),
            Program::HeldStep {
                levels_v: [0.4, -0.2, 0.125, 0.0, 0.0, 0.0, 0.0, 0.0],
                rise_s: 2.0,
                pole_per_s: 0.1,
                zero_per_s: f32::INFINITY,
            }
        );
        // Settled, the levels.
        assert_eq!(
            g.voltages_at_tick_v(60_000, 1000),
            vec![0.4f32 as f64, -0.2f32 as f64, 0.125]
        );
        let one = generator("held:0,0.1,0.24,0.5", 2).unwrap();
        // A creep's start: z/p times the level.
        let start = one.voltages_at_tick_v(0, 1000);
        assert!(start.iter().all(|v| (v - 1.2).abs() < 1e-6), "{start:?}");
        let step = Wave::parse("motion-step:0.001").unwrap();
        assert_eq!(step.kind(), &WaveKind::MotionStep { tip_m: 0.001 });
        assert!(matches!(
            step.generator(3, &WaveOptions::steady(1.0)),
            Err(WaveError::NeedsModel { .. })
        ));
    }

    #[test]
    fn the_limiter_is_the_firmwares() {
        let g = generator("step:3", 2).unwrap();
        let limits = finrs_drive::Limits::new(2.0, 100.0).unwrap();
        let rows = g.run(50, 1000, Some(limits));
        // 0.1 V per 1 ms tick from 0 V, then held at the 2 V limit.
        for (tick, row) in rows.iter().enumerate() {
            let expected = (0.1 * (tick + 1) as f64).min(2.0);
            assert!((row[0] - expected).abs() < 1e-5, "{tick}: {row:?}");
            assert_eq!(row[0], row[1]);
        }
        assert_eq!(g.run(3, 1000, None), vec![vec![3.0, 3.0]; 3]);
    }
}
