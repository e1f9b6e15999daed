//! A whole bench session from the rig: the example session's protocol
//! kinds, measured by the rig's sensors, written in `ipmc-bench/1`.

use std::f64::consts::PI;
use std::path::Path;

use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::{Channel, Fixture, Medium, Recording};
use finrs::wave::Wave;
use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::beam::{Beam, Tip};
use crate::bench::{self, Bench};
use crate::sample::{Hidden, Sample, SEGMENTS};
use crate::strip::{run, section, Mesh, Truth, BLOCKED_MESH, MESH};

/// One recording of a protocol.
#[derive(Clone, Debug)]
pub struct Run {
    /// File name without `.csv`.
    pub name: String,
    /// Wave as `finrs simulate --wave` takes it.
    pub wave: String,
    /// How the tip is held.
    pub fixture: Fixture,
    /// Rest before, s.
    pub rest_s: f64,
    /// Drive, s.
    pub hold_s: f64,
    /// Rest after, s.
    pub off_s: f64,
    /// What the notes say.
    pub description: String,
}

/// The example session's ten kinds (`shared/bench/examples`), with holds
/// shortened so that a session is about 80 s of data.
pub fn protocol() -> Vec<Run> {
    protocol_scaled(1.0)
}

/// The same kinds with every hold scaled by `hold_scale` and shorter rests
/// (1.2 s before, 2 s after): the tests' sessions, about 55 s at 0.6.
pub fn short_protocol(hold_scale: f64) -> Vec<Run> {
    protocol_scaled(hold_scale)
        .into_iter()
        .map(|r| Run {
            rest_s: 1.2,
            off_s: 2.0,
            ..r
        })
        .collect()
}

/// A session the board records alone: the same kinds, every one with the
/// tip on the load cell and no camera (no positions, so neither
/// `large-deflection` nor the free strip's ringing can be seen), holds
/// scaled by `hold_scale` as in [`short_protocol`].
pub fn board_protocol(hold_scale: f64) -> Vec<Run> {
    short_protocol(hold_scale)
        .into_iter()
        .map(|r| Run {
            name: r.name.replace("free", "blocked"),
            description: r.description.replace("free", "blocked"),
            fixture: Fixture::Blocked,
            ..r
        })
        .collect()
}

fn protocol_scaled(scale: f64) -> Vec<Run> {
    let run = |name: &str, wave: &str, fixture, hold_s: f64, description: &str| Run {
        name: name.to_string(),
        wave: wave.to_string(),
        fixture,
        rest_s: 1.5,
        hold_s: hold_s * scale,
        off_s: 2.5,
        description: description.to_string(),
    };
    use Fixture::{Blocked, Free};
    vec![
        run(
            "01_free_step_1.0V",
            "step:1",
            Free,
            4.0,
            "free step 1.0 V on all segments",
        ),
        run(
            "02_free_step_2.5V",
            "step:2.5",
            Free,
            4.0,
            "free step 2.5 V on all segments",
        ),
        run(
            "03_free_step_4.0V",
            "step:4",
            Free,
            4.0,
            "free step 4.0 V on all segments",
        ),
        run(
            "04_free_chirp",
            "chirp:2,0.1,20",
            Free,
            8.0,
            "free logarithmic chirp 0.1 to 20 Hz, 2.0 V, all segments in phase",
        ),
        run(
            "05_free_sine_travel",
            "sine:2.5,1,120",
            Free,
            6.0,
            "free travelling sine 1 Hz, 2.5 V, 120 deg lag per segment",
        ),
        run(
            "06_free_single_seg1",
            "step:2.5,0,0",
            Free,
            3.0,
            "free step 2.5 V on segment 1 only",
        ),
        run(
            "07_free_single_seg2",
            "step:0,2.5,0",
            Free,
            3.0,
            "free step 2.5 V on segment 2 only",
        ),
        run(
            "08_free_single_seg3",
            "step:0,0,2.5",
            Free,
            3.0,
            "free step 2.5 V on segment 3 only",
        ),
        run(
            "09_blocked_step_2.0V",
            "step:2",
            Blocked,
            4.0,
            "blocked step 2.0 V on all segments",
        ),
        run(
            "10_blocked_step_4.0V",
            "step:4",
            Blocked,
            4.0,
            "blocked step 4.0 V on all segments",
        ),
    ]
}

/// Sensor noise, as in the example session's README, times a factor
/// drawn per session.
#[derive(Clone, Copy, Debug)]
pub struct Sensors {
    /// Current noise, A rms.
    pub current_a: f64,
    /// Camera noise before the pixels, m rms.
    pub camera_m: f64,
    /// Camera pixel, m.
    pub pixel_m: f64,
    /// Load-cell noise, N rms.
    pub force_n: f64,
    /// The DAQ's count (current, A, and force, N, alike).
    pub daq_step: f64,
    /// How far off the rest shape is found, m: each camera channel's
    /// offset is drawn within ±this.
    pub rest_offset_m: f64,
}

impl Sensors {
    /// The example's sensors, their noise scaled by a factor in 0.7..1.5.
    pub fn draw(rng: &mut impl Rng) -> Sensors {
        let f = rng.gen_range(0.7..1.5);
        Sensors {
            current_a: 1e-4 * f,
            camera_m: 5e-5 * f,
            pixel_m: 1.09e-4,
            force_n: 2e-5 * f,
            daq_step: 1e-6,
            rest_offset_m: 2e-4,
        }
    }

    /// The same sensors with every error `scale` times as large: noise,
    /// counts, pixels and the rest shape's offset. Each draw consumes the
    /// random stream as before, so a session written with scaled sensors
    /// is its twin with the measurement's errors shrunk, the strip, the
    /// protocol and the bench's draws the same (`rig-coverage`'s
    /// pseudo-truths).
    pub fn scaled(&self, scale: f64) -> Sensors {
        Sensors {
            current_a: self.current_a * scale,
            camera_m: self.camera_m * scale,
            pixel_m: self.pixel_m * scale,
            force_n: self.force_n * scale,
            daq_step: self.daq_step * scale,
            rest_offset_m: self.rest_offset_m * scale,
        }
    }
}

/// Dots tracked by the camera, m from the clamp (the tip is the last).
pub const DOTS_S_M: [f64; 5] = [0.01, 0.02, 0.03, 0.04, 0.05];
/// DAQ rate, Hz, and camera rate, frames/s.
pub const DAQ_HZ: f64 = 1000.0;
/// Camera frames per second.
pub const CAMERA_HZ: f64 = 30.0;
/// Pause between recordings, s.
pub const PAUSE_S: f64 = 10.0;

/// Writes the session of `runs` from `sample` with `hidden`, measured on
/// `bench`, into `dir`; `label` goes into each file's notes.
#[allow(clippy::too_many_arguments)]
pub fn write(
    dir: &Path,
    sample: &Sample,
    hidden: &Hidden,
    sensors: &Sensors,
    bench: &Bench,
    runs: &[Run],
    label: &str,
    rng: &mut impl Rng,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut t_session = 0.0;
    for (index, r) in runs.iter().enumerate() {
        let wave = Wave::parse(&r.wave).map_err(anyhow::Error::msg)?;
        let drive = Drive {
            segments: SEGMENTS,
            fixture: r.fixture,
            rest_s: r.rest_s,
            duration_s: r.hold_s,
            off_s: r.off_s,
            rate_hz: DAQ_HZ,
        };
        let mut rec = drive_recording(&wave, &drive)?;
        rec.meta.sample = Some(label.to_string());
        // A ruler's and a micrometer's readings on the literature strip.
        let [length, width, thickness] =
            hidden.literature.as_ref().map_or([1.0; 3], |l| l.measured);
        rec.meta.thickness_m = sample.thickness_m() * thickness;
        rec.meta.length_m = sample.length_m * length;
        rec.meta.width_m = sample.width_m * width;
        rec.meta.medium = if hidden.water.is_some() {
            Medium::Water
        } else {
            Medium::Air
        };
        rec.meta.dots_s_m = Some(DOTS_S_M.iter().map(|s| s * length).collect());
        rec.meta.notes = Some(format!(
            "t_session_start_s = {t_session:.3}; run {} of {}; {} ({} s rest, {} s drive, {} s off); finrs-rig",
            index + 1,
            runs.len(),
            r.description,
            r.rest_s,
            r.hold_s,
            r.off_s
        ));
        let rows = rec.t_s.len();
        let camera: Vec<bool> = camera_rows(rows);
        let exposure_rows = bench
            .exposure_s
            .map_or(1, |e| ((e * DAQ_HZ).round() as usize).max(1));
        let (mesh, tip) = if r.fixture == Fixture::Blocked {
            (BLOCKED_MESH, load_cell(sample, hidden, bench))
        } else {
            (MESH, Tip::Free)
        };
        let mut truth = run(
            sample,
            hidden,
            mesh,
            tip,
            &rec.v_v,
            1.0 / DAQ_HZ,
            t_session,
            &exposed_rows(&camera, exposure_rows),
            &DOTS_S_M,
        );
        if exposure_rows > 1 {
            expose(&mut truth, &camera, exposure_rows);
        }
        measure(&mut rec, &truth, &camera, hidden, sensors, bench, rng);
        rec.write(&dir.join(format!("{}.csv", r.name)))?;
        t_session += rec.t_s.last().copied().unwrap_or(0.0) + PAUSE_S;
    }
    Ok(())
}

/// The load cell for a blocked run: rigid, or on a compliant bench a
/// spring that puts the held strip's first mode at the bench's fraction
/// of the rigid one's.
fn load_cell(sample: &Sample, hidden: &Hidden, bench: &Bench) -> Tip {
    load_cell_of(sample, hidden, bench, SEGMENTS)
}

/// [`load_cell`] for a strip of `segments` segments.
pub(crate) fn load_cell_of(
    sample: &Sample,
    hidden: &Hidden,
    bench: &Bench,
    segments: usize,
) -> Tip {
    let Some(ratio) = bench.load_cell_mode_ratio else {
        return Tip::Pinned;
    };
    let (ei, mass) = section(sample, hidden);
    let Mesh { per_segment, .. } = BLOCKED_MESH;
    let beam = |tip| Beam::new(sample.length_m, segments, per_segment, ei, mass, tip);
    let pinned_hz = beam(Tip::Pinned).omega[0] / (2.0 * PI);
    Beam::spring_for_first_mode(
        sample.length_m,
        segments,
        per_segment,
        ei,
        mass,
        ratio * pinned_hz,
    )
    .map_or(Tip::Pinned, Tip::Spring)
}

/// Rows whose positions a camera exposing for `window` rows up to each
/// frame needs.
pub(crate) fn exposed_rows(camera: &[bool], window: usize) -> Vec<bool> {
    let mut need = vec![false; camera.len()];
    for (r, _) in camera.iter().enumerate().filter(|(_, &f)| f) {
        for n in &mut need[r + 1 - window.min(r + 1)..=r] {
            *n = true;
        }
    }
    need
}

/// Each frame's positions become the mean over its exposure window; the
/// other rows go back to "not sampled".
pub(crate) fn expose(truth: &mut Truth, camera: &[bool], window: usize) {
    for series in &mut truth.points_m {
        let exposed: Vec<(f64, f64)> = (0..series.len())
            .map(|r| {
                if !camera[r] {
                    return (f64::NAN, f64::NAN);
                }
                let w = &series[r + 1 - window.min(r + 1)..=r];
                let n = w.len() as f64;
                (
                    w.iter().map(|p| p.0).sum::<f64>() / n,
                    w.iter().map(|p| p.1).sum::<f64>() / n,
                )
            })
            .collect();
        *series = exposed;
    }
}

/// Camera frames at 30/s, each on the nearest DAQ row.
pub(crate) fn camera_rows(rows: usize) -> Vec<bool> {
    let mut frame = vec![false; rows];
    for f in 0.. {
        let row = (f as f64 / CAMERA_HZ * DAQ_HZ).round() as usize;
        if row >= rows {
            break;
        }
        frame[row] = true;
    }
    frame
}

fn measure(
    rec: &mut Recording,
    truth: &Truth,
    camera: &[bool],
    hidden: &Hidden,
    sensors: &Sensors,
    bench: &Bench,
    rng: &mut impl Rng,
) {
    let rows = rec.t_s.len();
    // Mains pickup: 50 Hz and a third of it at 150 Hz, phase unknown.
    let hum = |sigma: f64, rng: &mut dyn rand::RngCore| -> Vec<f64> {
        let Some(a) = hidden.mains_pickup else {
            return vec![0.0; rows];
        };
        let (p1, p3) = (rng.gen_range(0.0..2.0 * PI), rng.gen_range(0.0..2.0 * PI));
        rec.t_s
            .iter()
            .map(|t| {
                a * sigma
                    * ((2.0 * PI * 50.0 * t + p1).sin() + (2.0 * PI * 150.0 * t + p3).sin() / 3.0)
            })
            .collect()
    };
    // White noise keeps what the bench's 1/f noise leaves of the power.
    let white = |sigma: f64| {
        let f = bench.pink_fraction.unwrap_or(0.0);
        Normal::new(0.0, sigma * (1.0 - f).sqrt()).expect("positive noise")
    };
    // The bench's own additions to a DAQ channel: hum and 1/f noise.
    let daq_extra = |sigma: f64, rng: &mut dyn rand::RngCore| -> Option<Vec<f64>> {
        if bench.hum.is_none() && bench.pink_fraction.is_none() {
            return None;
        }
        let mut extra = vec![0.0; rows];
        if let Some(a) = bench.hum {
            for (e, h) in extra.iter_mut().zip(bench::hum(&rec.t_s, a * sigma, rng)) {
                *e += h;
            }
        }
        if let Some(f) = bench.pink_fraction {
            let pink = bench::pink(rows, sigma * f.sqrt(), DAQ_HZ, rng);
            for (e, p) in extra.iter_mut().zip(pink) {
                *e += p;
            }
        }
        Some(extra)
    };
    let mut channels = Vec::new();
    for (k, c) in truth.currents_a.iter().enumerate() {
        let n = white(sensors.current_a);
        let pickup = hum(sensors.current_a, rng);
        let raw: Vec<f64> = c
            .iter()
            .zip(&pickup)
            .map(|(x, p)| x + p + n.sample(rng))
            .collect();
        channels.push((
            Channel::Current(k),
            daq_channel(raw, daq_extra(sensors.current_a, rng), sensors.daq_step),
        ));
    }
    if truth.force_n.is_empty() {
        let n = white(sensors.camera_m);
        let frames = camera.iter().filter(|&&f| f).count();
        let camera_channel = |series: &[(f64, f64)], along: bool, rng: &mut dyn rand::RngCore| {
            // The rest shape is found to a fraction of a millimetre.
            let offset = rng.gen_range(-sensors.rest_offset_m..sensors.rest_offset_m);
            let raw: Vec<Option<f64>> = (0..rows)
                .map(|r| {
                    camera[r].then(|| {
                        let (x, y) = series[r];
                        (if along { x } else { y }) + offset + n.sample(rng)
                    })
                })
                .collect();
            let mut pink = bench
                .pink_fraction
                .map(|f| bench::pink(frames, sensors.camera_m * f.sqrt(), CAMERA_HZ, rng))
                .unwrap_or_default()
                .into_iter();
            raw.into_iter()
                .map(|v| v.map(|v| round(pink.next().map_or(v, |p| v + p), sensors.pixel_m)))
                .collect::<Vec<_>>()
        };
        let tip = truth.points_m.last().expect("the tip is tracked");
        let tip_y = camera_channel(tip, false, rng);
        let tip_x = camera_channel(tip, true, rng);
        channels.push((Channel::TipY, tip_y.clone()));
        channels.push((Channel::TipX, tip_x.clone()));
        let last = truth.points_m.len() - 1;
        for (j, p) in truth.points_m.iter().enumerate() {
            // The last dot is the tip's mark: one measurement in two
            // columns (as in the contract's example session), not two
            // independent looks at the same point.
            if j == last {
                channels.push((Channel::DotY(j), tip_y.clone()));
                channels.push((Channel::DotX(j), tip_x.clone()));
            } else {
                channels.push((Channel::DotY(j), camera_channel(p, false, rng)));
                channels.push((Channel::DotX(j), camera_channel(p, true, rng)));
            }
        }
    } else {
        let n = white(sensors.force_n);
        let pickup = hum(sensors.force_n, rng);
        let raw: Vec<f64> = truth
            .force_n
            .iter()
            .zip(&pickup)
            .map(|(x, p)| x + p + n.sample(rng))
            .collect();
        channels.push((
            Channel::Force,
            daq_channel(raw, daq_extra(sensors.force_n, rng), sensors.daq_step),
        ));
    }
    rec.channels = channels;
}

/// A DAQ channel's samples: the value with its noise and the bench's
/// additions, in the DAQ's counts of `step`.
fn daq_channel(raw: Vec<f64>, extra: Option<Vec<f64>>, step: f64) -> Vec<Option<f64>> {
    match extra {
        None => raw.into_iter().map(|v| Some(round(v, step))).collect(),
        Some(extra) => raw
            .into_iter()
            .zip(extra)
            .map(|(v, e)| Some(round(v + e, step)))
            .collect(),
    }
}

pub(crate) fn round(x: f64, q: f64) -> f64 {
    (x / q).round() * q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exposed_frame_is_the_mean_over_its_window() {
        let rows = 100;
        let camera = camera_rows(rows);
        let need = exposed_rows(&camera, 10);
        // Frame 0 at row 0 needs only itself; frame 1 (row 33) rows 24..=33.
        assert!(need[0] && !need[1] && !need[23] && need[24] && need[33] && !need[34]);
        // A point moving linearly: the mean over rows 24..=33 is row 28.5's.
        let ramp: Vec<(f64, f64)> = (0..rows).map(|r| (0.0, r as f64)).collect();
        let mut truth = Truth {
            currents_a: Vec::new(),
            points_m: vec![ramp],
            force_n: Vec::new(),
        };
        expose(&mut truth, &camera, 10);
        let p = &truth.points_m[0];
        assert_eq!(p[0], (0.0, 0.0));
        assert_eq!(p[33], (0.0, 28.5));
        assert!(p[32].1.is_nan());
    }
}
