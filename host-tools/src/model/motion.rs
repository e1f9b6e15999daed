//! A motion asked of the free tip turned into each segment's sine by the
//! strip's model: the host's twin of what the board does once it holds a
//! fitted model (#16), through the same code
//! ([`finrs_controller::shaper`]).
//!
//! `motion:TIP_AMP_M,HZ,LAG_DEG` asks a travelling bending wave: every
//! segment's moment of one amplitude, each `LAG_DEG` behind the one before,
//! the tip moving `TIP_AMP_M · sin(2π HZ t)`. The board's shaper inverts
//! the model exactly at that frequency (each segment's electrics and
//! relaxation, the crosstalk, the beam's modes) on the strip it builds
//! itself: the model's record as `finrs tune` sends it (every value an
//! `f32`), [`ELEMENTS`] element per segment, discretised at the sample
//! rate. The voltages become a `harmonic:` wave for the firmware's one
//! generator. A motion that needs more than the hard limit is refused with
//! the amplitude the limit allows, never clipped (a clipped sine is not the
//! motion asked).
//!
//! `motion-step:TIP_M` asks the free tip to step to `TIP_M` over the
//! ramp-in and stay there: the board's shaper gives each segment the level
//! that holds it once settled (the model's static inverse) times the
//! inverse of the relaxation over a raised-cosine rise
//! (`model_core::Strip::tip_step`), a `held:` wave whose rise is the
//! ramp-in (the envelope then starts at full gain).
//!
//! ```
//! use finrs::model::motion::shaped;
//! use finrs::model::params::ModelFile;
//! use finrs::recording::Geometry;
//! use finrs::wave::{Wave, WaveKind, WaveOptions};
//!
//! let spec = ModelFile::main_m_2006().spec_for(&Geometry::THESIS_2006).unwrap();
//! // 0.2 mm at 1 Hz, 60° a segment: within 4 V for the seed's strip.
//! let steady = WaveOptions::steady(10.0);
//! let (wave, _) = shaped(&Wave::parse("motion:0.0002,1,60").unwrap(), &spec, 3, 1000.0, None, &steady).unwrap();
//! assert!(matches!(wave.kind(), WaveKind::Harmonic { .. }));
//! // 5 mm is not: refused with what 4 V reaches.
//! let e = shaped(&Wave::parse("motion:0.005,1,60").unwrap(), &spec, 3, 1000.0, None, &steady).unwrap_err();
//! assert!(e.to_string().contains("the model reaches 0.254 mm"), "{e}");
//! // A 2 mm step rising over 2 s: 0.38 V once settled (13 mm at 2.5 V),
//! // the seed's pure lag driven up to 8.9 times that while it rises.
//! let rising = WaveOptions { ramp_in_s: 2.0, ..steady };
//! let (wave, options) = shaped(&Wave::parse("motion-step:0.002").unwrap(), &spec, 3, 1000.0, None, &rising).unwrap();
//! assert!(wave.text().starts_with("held:2,0.1,inf,0.38"), "{}", wave.text());
//! assert_eq!(options.ramp_in_s, 0.0);
//! ```

use finrs_controller::shaper::{ShapeRefused, Shaper, ELEMENTS};
use finrs_drive::{Envelope, Program, HARD_LIMIT_V};
use finrs_frames::{ModelRecord, Motion, StripModel};
use model_core::state_len;

use super::predict::ModelSpec;
use crate::recording::Channel;
use crate::wave::{MotionWave, Wave, WaveError, WaveKind, WaveOptions};

/// Why a motion has no voltages.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    /// The board's shaper refuses the model or the motion.
    #[error("wave `{wave}`")]
    Shape {
        /// The wave's text.
        wave: String,
        /// What the shaper refused.
        source: ShapeRefused,
    },
    /// The segments are not a count the board is built for.
    #[error("wave `{wave}`: {segments} segments: the board drives 1..=8")]
    Segments {
        /// The wave's text.
        wave: String,
        /// Segments.
        segments: usize,
    },
    /// The motion needs more than the hard limit.
    #[error(
        "wave `{wave}`: needs {needs_v:.2} V on segment {segment} (the hard limit is ±{HARD_LIMIT_V} V); \
         within it the model reaches {reachable_mm:.3} mm at the tip"
    )]
    Unreachable {
        /// The wave's text.
        wave: String,
        /// The largest amplitude it needs, V.
        needs_v: f64,
        /// Where, counted from 1 at the clamp.
        segment: usize,
        /// The tip amplitude the hard limit allows, mm.
        reachable_mm: f64,
    },
    /// The harmonic wave it becomes is refused (the firmware's rules).
    #[error(transparent)]
    Wave(#[from] WaveError),
}

/// The record `finrs tune` sends for `spec`: the board's model. The
/// circuit's drying (`circuit_drying_per_s`) is not in it: the board's
/// gain tracker measures the strip's admittance as it goes
/// (docs/model.md, "Holding a motion: the gain tracker").
pub fn record(spec: &ModelSpec) -> ModelRecord {
    ModelRecord::encode(&StripModel {
        params: spec.params,
        extensions: spec.ext,
        dehydration_per_s: spec.dehydration_per_s,
        dehydration_curvature: spec.dehydration_curvature,
    })
}

/// `wave` itself under `options`, or for a motion the wave the board
/// would drive for it (`harmonic:` for a `motion:` or a `force:`, `held:`
/// for a `motion-step:`) on `segments` segments sampled at `rate_hz`, holding
/// the model of `spec`, starting at `t_session_s` on its drying law's
/// clock (needed if the model dries: the wave is then the one the board
/// starts with; its corrections as the strip dries are the controller's,
/// in time, not in a fixed wave), and the options to drive it with (a
/// step's ramp-in is its rise, inside the `held:` wave).
pub fn shaped(
    wave: &Wave,
    spec: &ModelSpec,
    segments: usize,
    rate_hz: f64,
    t_session_s: Option<f64>,
    options: &WaveOptions,
) -> Result<(Wave, WaveOptions), MotionError> {
    let Some(MotionWave {
        motion,
        asked: asked_m,
        ..
    }) = wave.motion()
    else {
        return Ok((wave.clone(), *options));
    };
    let text = wave.text();
    let t_session_s = t_session_s.map_or(f32::NAN, |t| t as f32);
    let envelope = Envelope {
        ramp_in_s: options.ramp_in_s as f32,
        hold_s: options.hold_s as f32,
        ramp_out_s: options.ramp_out_s as f32,
    };
    let (program, envelope) = board_program(
        &record(spec),
        segments,
        rate_hz,
        &motion,
        envelope,
        HARD_LIMIT_V,
        t_session_s,
    )
    .map_err(|e| match e {
        BoardRefused::Shape(ShapeRefused::Unreachable {
            needs_v,
            segment,
            limit_v,
            ..
        }) => MotionError::Unreachable {
            wave: text.to_string(),
            needs_v: f64::from(needs_v),
            segment: usize::from(segment),
            // From the amplitude asked, not its f32: the same ratio.
            reachable_mm: 1e3 * asked_m.abs() * f64::from(limit_v) / f64::from(needs_v),
        },
        BoardRefused::Shape(source) => MotionError::Shape {
            wave: text.to_string(),
            source,
        },
        BoardRefused::Segments(segments) => MotionError::Segments {
            wave: text.to_string(),
            segments,
        },
    })?;
    // Each f32 as `{}` writes it: the shortest text that reads back as it.
    let text = match program {
        Program::Harmonic {
            frequency_hz,
            amplitudes_v,
            phases_deg,
            ..
        } => (0..segments).fold(format!("harmonic:{frequency_hz}"), |t, k| {
            t + &format!(",{},{}", amplitudes_v[k], phases_deg[k])
        }),
        Program::HeldStep {
            levels_v,
            rise_s,
            pole_per_s,
            zero_per_s,
        } => (0..segments).fold(
            format!("held:{rise_s},{pole_per_s},{zero_per_s}"),
            |t, k| t + &format!(",{}", levels_v[k]),
        ),
        other => unreachable!("the shaper makes harmonic and held programs only: {other:?}"),
    };
    let options = WaveOptions {
        ramp_in_s: f64::from(envelope.ramp_in_s),
        ..*options
    };
    Ok((Wave::parse(&text)?, options))
}

/// Why the board's shaper, run on the host, gives no program.
#[derive(Debug, thiserror::Error)]
pub enum BoardRefused {
    /// The shaper's refusal.
    #[error(transparent)]
    Shape(ShapeRefused),
    /// Not 1..=8 segments.
    #[error("{0} segments: the board drives 1..=8")]
    Segments(usize),
}

/// What the board's shaper does with `record` on `segments` segments
/// sampled at `rate_hz`: its check of a SetModel (`motion` `None`), or
/// the program a SetMotion of `motion` becomes under `limit_v`.
fn shape(
    record: &ModelRecord,
    segments: usize,
    rate_hz: f64,
    motion: Option<MotionRequest>,
) -> Result<Option<(Program, Envelope)>, BoardRefused> {
    fn go<const N: usize, const S: usize>(
        record: &ModelRecord,
        dt_s: f64,
        motion: Option<MotionRequest>,
    ) -> Result<Option<(Program, Envelope)>, ShapeRefused> {
        let mut shaper = Shaper::<N, ELEMENTS, S>::new();
        shaper.install(Shaper::check(record, dt_s)?);
        motion
            .map(|(m, envelope, limit_v, t_session_s)| {
                shaper
                    .program(&m, envelope, limit_v, t_session_s)
                    .map(|s| (s.program, s.envelope))
            })
            .transpose()
    }
    let dt_s = 1.0 / rate_hz;
    // One monomorphisation per segment count, as the firmware's builds.
    macro_rules! dispatch {
        ($($n:literal),*) => {
            match segments {
                $($n => go::<$n, { state_len($n, ELEMENTS) }>(record, dt_s, motion),)*
                _ => return Err(BoardRefused::Segments(segments)),
            }
        };
    }
    dispatch!(1, 2, 3, 4, 5, 6, 7, 8).map_err(BoardRefused::Shape)
}

/// A SetMotion's motion, envelope, limit (V) and session time (s).
type MotionRequest = (Motion, Envelope, f32, f32);

/// The board's check of a SetModel of `record` (`finrs tune` runs it
/// before sending).
pub fn board_check(
    record: &ModelRecord,
    segments: usize,
    rate_hz: f64,
) -> Result<(), BoardRefused> {
    shape(record, segments, rate_hz, None).map(|_| ())
}

/// The program the board's shaper makes of `motion` under `envelope` and
/// `limit_v`, starting at `t_session_s` on the drying law's clock (NaN
/// unknown), and the envelope it drives it with.
pub fn board_program(
    record: &ModelRecord,
    segments: usize,
    rate_hz: f64,
    motion: &Motion,
    envelope: Envelope,
    limit_v: f32,
    t_session_s: f32,
) -> Result<(Program, Envelope), BoardRefused> {
    shape(
        record,
        segments,
        rate_hz,
        Some((*motion, envelope, limit_v, t_session_s)),
    )?
    .ok_or(BoardRefused::Segments(segments))
}

/// A channel as a motion asks it, sample by sample (`None` where nothing
/// is asked).
pub type Asked = (Channel, Vec<Option<f64>>);

/// What a motion asks at each of `t_s` (`None` for another wave), and of
/// which channel: the tip, m, `TIP_AMP_M · sin(2π HZ (t − start_s))` for
/// a `motion:`, `TIP_M` for a `motion-step:`; the load cell's force, N,
/// `FORCE_AMP_N · sin(2π HZ (t − start_s))` for a `force:`; while the
/// wave is held (`hold_s`, from and to, s), `None` outside it, where the
/// envelope's ramps (a step's rise) and the relaxation's settling are not
/// what was asked.
pub fn asked(wave: &Wave, t_s: &[f64], start_s: f64, hold_s: (f64, f64)) -> Option<Asked> {
    let sine = |amplitude: f64, hz: f64| -> Box<dyn Fn(f64) -> f64> {
        let omega = 2.0 * std::f64::consts::PI * hz;
        Box::new(move |t| amplitude * (omega * (t - start_s)).sin())
    };
    let (channel, value): (Channel, Box<dyn Fn(f64) -> f64>) = match *wave.kind() {
        WaveKind::Motion {
            tip_amp_m,
            frequency_hz,
            ..
        } => (Channel::TipY, sine(tip_amp_m, frequency_hz)),
        WaveKind::MotionStep { tip_m } => (Channel::TipY, Box::new(move |_| tip_m)),
        WaveKind::Force {
            force_amp_n,
            frequency_hz,
            ..
        } => (Channel::Force, sine(force_amp_n, frequency_hz)),
        _ => return None,
    };
    let values = t_s
        .iter()
        .map(|&t| (hold_s.0..=hold_s.1).contains(&t).then(|| value(t)))
        .collect();
    Some((channel, values))
}

#[cfg(test)]
mod tests {
    use super::{asked, shaped, MotionError};
    use crate::model::params::{ModelFile, Preset};
    use crate::model::predict::ModelSpec;
    use crate::model::simulate::predict_recording;
    use crate::model::synth::{drive_recording_shaped, Drive};
    use crate::recording::{Channel, Fixture, Geometry};
    use crate::wave::{Wave, WaveKind, WaveOptions};
    use model_core::Phasor;

    /// `file`'s model, damped (an undamped mode would ring for ever), on the
    /// seed's geometry.
    fn damped(mut file: ModelFile) -> ModelSpec {
        let mut ext = file.extensions.clone().unwrap_or_default();
        ext.damping_ratio = 0.05;
        file.extensions = Some(ext);
        file.spec_for(&Geometry::THESIS_2006).unwrap()
    }

    /// The free tip of `spec`'s strip driven by `wave` under `options`
    /// from rest, 3 segments at 1 kHz, over `options.sweep_s`.
    fn model_tip(wave: &Wave, options: &WaveOptions, spec: &ModelSpec) -> Vec<f64> {
        model_output(wave, options, spec, Fixture::Free, Channel::TipY)
    }

    /// `channel` of `spec`'s strip in `fixture`, as [`model_tip`].
    fn model_output(
        wave: &Wave,
        options: &WaveOptions,
        spec: &ModelSpec,
        fixture: Fixture,
        channel: Channel,
    ) -> Vec<f64> {
        let drive = Drive {
            segments: 3,
            fixture,
            rest_s: 0.0,
            duration_s: options.sweep_s,
            off_s: 0.0,
            rate_hz: 1000.0,
        };
        let rec = drive_recording_shaped(wave, &drive, options, None).unwrap();
        let mut sim = predict_recording("motion", &rec, spec, 1, &mut |_| {}).unwrap();
        let at = sim.channels.iter().position(|(c, _)| *c == channel);
        sim.channels.swap_remove(at.expect("the channel asked")).1
    }

    /// The model's own simulation of the shaped wave moves the tip as
    /// asked: amplitude and phase by lock-in over whole periods, once the
    /// relaxation (τ = 10 s) has settled.
    #[test]
    fn the_simulated_tip_moves_as_asked() {
        let spec = damped(ModelFile::main_m_2006());
        let wave = Wave::parse("motion:0.0002,1,60").unwrap();
        let (shaped, _) = shaped(&wave, &spec, 3, 1000.0, None, &WaveOptions::steady(1.0)).unwrap();
        let tip = model_tip(&shaped, &WaveOptions::steady(120.0), &spec);
        let theta = 2.0 * std::f64::consts::PI / 1000.0;
        // The last ten periods.
        let (from, to) = (tip.len() - 1 - 10_000, tip.len() - 1);
        let mut y = Phasor::ZERO;
        for (k, &v) in tip.iter().enumerate().take(to).skip(from) {
            y += Phasor::unit(-theta * k as f64).scale(2.0 * v / 10_000.0);
        }
        // The generator's f32 sine is good to 1e-3 or so.
        assert!(
            (y.amplitude() / 0.0002 - 1.0).abs() < 0.01,
            "{}",
            y.amplitude()
        );
        assert!(
            y.sine_phase_rad().to_degrees().abs() < 1.0,
            "{}",
            y.sine_phase_rad().to_degrees()
        );
    }

    /// The host's twin of a force wave: the `harmonic:` wave the board
    /// would drive for it, simulated on the held strip by the same model
    /// (the example session's strip: an instant moment), moves the force
    /// as asked over the last ten periods.
    #[test]
    fn the_simulated_force_moves_as_asked() {
        let mut file = ModelFile::main_m_2006();
        let p = model_core::Params::baseline_air_example();
        file.relaxation.a_nm_per_c = p.a_nm_per_c;
        file.relaxation.b_nm_per_c_s = p.b_nm_per_c_s;
        let spec = damped(file);
        let wave = Wave::parse("force:0.001,1,60").unwrap();
        let steady = WaveOptions::steady(60.0);
        let (shaped, _) = shaped(&wave, &spec, 3, 1000.0, None, &steady).unwrap();
        assert!(matches!(shaped.kind(), WaveKind::Harmonic { .. }));
        let force = model_output(&shaped, &steady, &spec, Fixture::Blocked, Channel::Force);
        let theta = 2.0 * std::f64::consts::PI / 1000.0;
        let (from, to) = (force.len() - 1 - 10_000, force.len() - 1);
        let mut y = Phasor::ZERO;
        for (k, &v) in force.iter().enumerate().take(to).skip(from) {
            y += Phasor::unit(-theta * k as f64).scale(2.0 * v / 10_000.0);
        }
        assert!((y.amplitude() / 1e-3 - 1.0).abs() < 0.01, "{y:?}");
        assert!(y.sine_phase_rad().to_degrees().abs() < 1.0, "{y:?}");
    }

    /// The host's twin of a step: the `held:` wave the board would drive,
    /// simulated by the same model, holds the tip from the rise's end on
    /// (Table 4-2's creeping strip, damped; its charging takes τ1 = 1.6 s).
    #[test]
    fn the_simulated_tip_holds_a_step() {
        let spec = damped(ModelFile::preset(Preset::Table4_2_2006));
        let wave = Wave::parse("motion-step:0.003").unwrap();
        let rising = WaveOptions {
            ramp_in_s: 1.0,
            ..WaveOptions::steady(60.0)
        };
        let (held, options) = shaped(&wave, &spec, 3, 1000.0, None, &rising).unwrap();
        assert!(
            held.text().starts_with("held:1,0.1,0.2399"),
            "{}",
            held.text()
        );
        assert_eq!(options.ramp_in_s, 0.0);
        let tip = model_tip(&held, &options, &spec);
        // From 15 s (past the rise and the charging) to the end.
        let worst = tip[15_000..]
            .iter()
            .fold(0.0f64, |m, t| m.max((t / 0.003 - 1.0).abs()));
        assert!(worst < 3e-3, "worst {worst}");
    }

    #[test]
    fn the_asked_tip_is_the_motion_while_the_wave_is_held() {
        let wave = Wave::parse("motion:0.001,2,60").unwrap();
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        let (channel, asked) = asked(&wave, &t, 0.1, (0.3, 0.8)).unwrap();
        assert_eq!(channel, Channel::TipY);
        assert!(asked[..30].iter().all(Option::is_none) && asked[81..].iter().all(Option::is_none));
        for k in 30..=80 {
            let want = 0.001 * (2.0 * std::f64::consts::PI * 2.0 * (t[k] - 0.1)).sin();
            assert!((asked[k].unwrap() - want).abs() < 1e-15, "{k}");
        }
        assert!(super::asked(&Wave::parse("sine:1,1,0").unwrap(), &t, 0.0, (0.0, 1.0)).is_none());
        // A force wave asks the load cell's force; a step its tip, held.
        let force = Wave::parse("force:0.002,2,60").unwrap();
        let (channel, f) = super::asked(&force, &t, 0.1, (0.3, 0.8)).unwrap();
        assert_eq!(channel, Channel::Force);
        assert!((f[30].unwrap() - 0.002 * (2.0 * std::f64::consts::PI * 0.4).sin()).abs() < 1e-15);
        let step = Wave::parse("motion-step:0.003").unwrap();
        let (_, s) = super::asked(&step, &t, 0.1, (0.3, 0.8)).unwrap();
        assert_eq!((s[29], s[30], s[80]), (None, Some(0.003), Some(0.003)));
    }

    #[test]
    fn what_the_limit_cannot_reach_is_refused_with_what_it_can() {
        let spec = ModelFile::main_m_2006()
            .spec_for(&Geometry::THESIS_2006)
            .unwrap();
        let steady = WaveOptions::steady(1.0);
        let e = shaped(
            &Wave::parse("motion:0.005,1,60").unwrap(),
            &spec,
            3,
            1000.0,
            None,
            &steady,
        )
        .unwrap_err();
        let MotionError::Unreachable {
            needs_v,
            reachable_mm,
            ..
        } = e
        else {
            panic!("{e}");
        };
        assert!(needs_v > 70.0 && (reachable_mm * needs_v / 4.0 - 5.0).abs() < 1e-9);
        // Other waves pass through untouched; a motion's own generator is
        // refused without a model.
        let sine = Wave::parse("sine:1,1,0").unwrap();
        assert_eq!(
            shaped(&sine, &spec, 3, 1000.0, None, &steady).unwrap(),
            (sine, steady)
        );
        let motion = Wave::parse("motion:0.0002,1,60").unwrap();
        assert!(motion
            .generator(3, &WaveOptions::steady(1.0))
            .unwrap_err()
            .to_string()
            .contains("needs the strip's model"));
        assert!(matches!(
            shaped(&motion, &spec, 9, 1000.0, None, &steady),
            Err(MotionError::Segments { .. })
        ));
    }
}
