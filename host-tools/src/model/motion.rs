//! A motion asked of the free tip turned into each segment's sine by the
//! strip's model: the host's twin of what the board will do once it holds
//! a fitted model (#16).
//!
//! `motion:TIP_AMP_M,HZ,LAG_DEG` asks a travelling bending wave: every
//! segment's moment of one amplitude, each `LAG_DEG` behind the one before,
//! the tip moving `TIP_AMP_M · sin(2π HZ t)`. The model's exact harmonic
//! inverse (`model_core::Strip::tip_wave`: each segment's electrics and
//! relaxation, the crosstalk, the beam's modes) gives the voltages, which
//! become a `harmonic:` wave for the firmware's one generator. A motion
//! that needs more than the hard limit is refused with the amplitude the
//! limit allows, never clipped (a clipped sine is not the motion asked).
//!
//! ```
//! use finrs::model::motion::shaped;
//! use finrs::model::params::ModelFile;
//! use finrs::recording::Geometry;
//! use finrs::wave::{Wave, WaveKind};
//!
//! let spec = ModelFile::main_m_2006().spec_for(&Geometry::THESIS_2006).unwrap();
//! // 0.2 mm at 1 Hz, 60° a segment: within 4 V for the seed's strip.
//! let wave = shaped(&Wave::parse("motion:0.0002,1,60").unwrap(), &spec, 3, 1, 1000.0).unwrap();
//! assert!(matches!(wave.kind(), WaveKind::Harmonic { .. }));
//! // 5 mm is not: refused with what 4 V reaches.
//! let e = shaped(&Wave::parse("motion:0.005,1,60").unwrap(), &spec, 3, 1, 1000.0).unwrap_err();
//! assert!(e.to_string().contains("the model reaches 0.254 mm"), "{e}");
//! ```

use finrs_drive::HARD_LIMIT_V;
use model_core::{state_len, Fixture, Phasor, Strip};

use super::predict::ModelSpec;
use crate::wave::{Wave, WaveError, WaveKind};

/// Why a motion has no voltages.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    /// The model refuses its parameters.
    #[error("wave `{wave}`: the model: {source}")]
    Model {
        /// The wave's text.
        wave: String,
        /// What the model refused.
        source: model_core::ParamError,
    },
    /// The model has no single-sine response here.
    #[error("wave `{wave}`: {why}")]
    Harmonic {
        /// The wave's text.
        wave: String,
        /// Why not (the model's words).
        why: String,
    },
    /// The segments or elements are not ones the model is built for.
    #[error("wave `{wave}`: {segments} segments of {elements} elements is not a mesh the model is built for (1..=8 segments of 1, 2 or 4)")]
    Mesh {
        /// The wave's text.
        wave: String,
        /// Segments.
        segments: usize,
        /// Elements per segment.
        elements: usize,
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

/// `wave` itself, or for a motion the `harmonic:` wave whose voltages give
/// it on the free strip of `spec` (`segments` of `elements` elements,
/// sampled at `rate_hz`, as the simulation runs it).
pub fn shaped(
    wave: &Wave,
    spec: &ModelSpec,
    segments: usize,
    elements: usize,
    rate_hz: f64,
) -> Result<Wave, MotionError> {
    let &WaveKind::Motion {
        tip_amp_m,
        frequency_hz,
        lag_deg,
    } = wave.kind()
    else {
        return Ok(wave.clone());
    };
    let text = wave.text();
    let v = voltages(
        text,
        spec,
        (segments, elements),
        1.0 / rate_hz,
        frequency_hz,
        tip_amp_m,
        lag_deg,
    )?;
    let (k, needs_v) = v
        .iter()
        .map(|p| p.amplitude())
        .enumerate()
        .fold((0, 0.0), |m, (k, a)| if a > m.1 { (k, a) } else { m });
    if needs_v > f64::from(HARD_LIMIT_V) {
        return Err(MotionError::Unreachable {
            wave: text.to_string(),
            needs_v,
            segment: k + 1,
            // Linear: the voltages scale with the amplitude asked.
            reachable_mm: 1e3 * tip_amp_m.abs() * f64::from(HARD_LIMIT_V) / needs_v,
        });
    }
    let mut harmonic = format!("harmonic:{frequency_hz}");
    for p in &v {
        harmonic += &format!(",{},{}", p.amplitude(), p.sine_phase_rad().to_degrees());
    }
    Ok(Wave::parse(&harmonic)?)
}

/// The tip a motion asks, m, at each of `t_s` (`None` for another wave):
/// `TIP_AMP_M · sin(2π HZ (t − start_s))` while the wave is held
/// (`hold_s`, from and to, s), `None` outside it, where the envelope's
/// ramps and the relaxation's settling are not what was asked.
pub fn asked_tip_m(
    wave: &Wave,
    t_s: &[f64],
    start_s: f64,
    hold_s: (f64, f64),
) -> Option<Vec<Option<f64>>> {
    let &WaveKind::Motion {
        tip_amp_m,
        frequency_hz,
        ..
    } = wave.kind()
    else {
        return None;
    };
    let omega = 2.0 * std::f64::consts::PI * frequency_hz;
    Some(
        t_s.iter()
            .map(|&t| {
                (hold_s.0..=hold_s.1)
                    .contains(&t)
                    .then(|| tip_amp_m * (omega * (t - start_s)).sin())
            })
            .collect(),
    )
}

/// Each segment's voltage phasor for the motion `text`, V, on a mesh of
/// `(segments, elements)`.
fn voltages(
    text: &str,
    spec: &ModelSpec,
    (segments, elements): (usize, usize),
    dt_s: f64,
    hz: f64,
    tip_amp_m: f64,
    lag_deg: f64,
) -> Result<Vec<Phasor>, MotionError> {
    fn go<const N: usize, const E: usize, const S: usize>(
        text: &str,
        spec: &ModelSpec,
        dt_s: f64,
        hz: f64,
        tip_amp_m: f64,
        lag_deg: f64,
    ) -> Result<Vec<Phasor>, MotionError> {
        let strip =
            Strip::<f64, N, E, S>::with_extensions(&spec.params, &spec.ext, Fixture::Free, dt_s)
                .map_err(|source| MotionError::Model {
                    wave: text.to_string(),
                    source,
                })?;
        strip
            .tip_wave(hz, tip_amp_m, lag_deg.to_radians())
            .map(|v| v.to_vec())
            .map_err(|e| MotionError::Harmonic {
                wave: text.to_string(),
                why: e.to_string(),
            })
    }
    // One monomorphisation per mesh, as the simulation has.
    macro_rules! dispatch {
        ($($n:literal),*) => {
            match (segments, elements) {
                $(
                    ($n, 1) => go::<$n, 1, { state_len($n, 1) }>(text, spec, dt_s, hz, tip_amp_m, lag_deg),
                    ($n, 2) => go::<$n, 2, { state_len($n, 2) }>(text, spec, dt_s, hz, tip_amp_m, lag_deg),
                    ($n, 4) => go::<$n, 4, { state_len($n, 4) }>(text, spec, dt_s, hz, tip_amp_m, lag_deg),
                )*
                _ => Err(MotionError::Mesh {
                    wave: text.to_string(),
                    segments,
                    elements,
                }),
            }
        };
    }
    dispatch!(1, 2, 3, 4, 5, 6, 7, 8)
}

#[cfg(test)]
mod tests {
    use super::{asked_tip_m, shaped, MotionError};
    use crate::model::params::ModelFile;
    use crate::model::simulate::predict_recording;
    use crate::model::synth::{drive_recording_shaped, Drive};
    use crate::recording::{Channel, Fixture, Geometry};
    use crate::wave::{Wave, WaveOptions};
    use model_core::Phasor;

    /// The model's own simulation of the shaped wave moves the tip as
    /// asked: amplitude and phase by lock-in over whole periods, once the
    /// relaxation (τ = 10 s) has settled.
    #[test]
    fn the_simulated_tip_moves_as_asked() {
        let mut file = ModelFile::main_m_2006();
        // A damped strip: an undamped mode would ring for ever.
        let mut ext = file.extensions.clone().unwrap_or_default();
        ext.damping_ratio = 0.05;
        file.extensions = Some(ext);
        let spec = file.spec_for(&Geometry::THESIS_2006).unwrap();
        let wave = Wave::parse("motion:0.0002,1,60").unwrap();
        let shaped = shaped(&wave, &spec, 3, 1, 1000.0).unwrap();
        let drive = Drive {
            segments: 3,
            fixture: Fixture::Free,
            rest_s: 0.0,
            duration_s: 120.0,
            off_s: 0.0,
            rate_hz: 1000.0,
        };
        let rec =
            drive_recording_shaped(&shaped, &drive, &WaveOptions::steady(120.0), None).unwrap();
        let sim = predict_recording("motion", &rec, &spec, 1, &mut |_| {}).unwrap();
        let tip = &sim
            .channels
            .iter()
            .find(|(c, _)| *c == Channel::TipY)
            .expect("a free strip's tip")
            .1;
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

    #[test]
    fn the_asked_tip_is_the_motion_while_the_wave_is_held() {
        let wave = Wave::parse("motion:0.001,2,60").unwrap();
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        let asked = asked_tip_m(&wave, &t, 0.1, (0.3, 0.8)).unwrap();
        assert!(asked[..30].iter().all(Option::is_none) && asked[81..].iter().all(Option::is_none));
        for k in 30..=80 {
            let want = 0.001 * (2.0 * std::f64::consts::PI * 2.0 * (t[k] - 0.1)).sin();
            assert!((asked[k].unwrap() - want).abs() < 1e-15, "{k}");
        }
        assert!(asked_tip_m(&Wave::parse("sine:1,1,0").unwrap(), &t, 0.0, (0.0, 1.0)).is_none());
    }

    #[test]
    fn what_the_limit_cannot_reach_is_refused_with_what_it_can() {
        let spec = ModelFile::main_m_2006()
            .spec_for(&Geometry::THESIS_2006)
            .unwrap();
        let e = shaped(
            &Wave::parse("motion:0.005,1,60").unwrap(),
            &spec,
            3,
            1,
            1000.0,
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
        assert_eq!(shaped(&sine, &spec, 3, 1, 1000.0).unwrap(), sine);
        let motion = Wave::parse("motion:0.0002,1,60").unwrap();
        assert!(motion
            .generator(3, &WaveOptions::steady(1.0))
            .unwrap_err()
            .to_string()
            .contains("needs the strip's model"));
        assert!(matches!(
            shaped(&motion, &spec, 9, 1, 1000.0),
            Err(MotionError::Mesh { .. })
        ));
    }
}
