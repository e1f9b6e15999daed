//! A small synthetic session for the fit's tests: the model itself at four
//! elements per segment, driven by the example session's protocol kinds,
//! with the rig's sensors (noise, 30 frames/s camera in whole pixels, rest
//! offsets). It tests that the fit recovers what it can see; the rig that
//! hides effects the fit does not know is separate.

#![allow(dead_code)]

pub mod pty;

use std::path::Path;

use finrs::model::predict::{predict, ModelSpec};
use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::{Channel, Fixture, Recording};
use finrs::wave::Wave;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// Three recordings of the contract's example session `baseline-air`,
/// shipped with the repository (see the folder's README).
pub fn baseline_air_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/baseline-air")
}

/// The parameters `baseline-air` was written with (its README), as a file.
pub fn baseline_air_model() -> finrs::model::params::ModelFile {
    let mut f = finrs::model::params::ModelFile::main_m_2006();
    let p = model_core::Params::baseline_air_example();
    f.relaxation = finrs::model::params::Relaxation {
        a_nm_per_c: p.a_nm_per_c,
        b_nm_per_c_s: p.b_nm_per_c_s,
        p_per_s: p.p_per_s,
    };
    f
}

/// The `.csv` files of [`baseline_air_dir`], in name order; a missing
/// folder fails the test (the data ship with the repository).
pub fn baseline_air_files() -> Vec<std::path::PathBuf> {
    let dir = baseline_air_dir();
    let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (the test data ship with the repository)",
            dir.display()
        )
    });
    csv_files(entries)
}

/// The `.csv` files of a folder's `entries`, in name order.
fn csv_files(entries: std::fs::ReadDir) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    files
}

/// The `.csv` files (recordings) of the session folder `dir`, in name
/// order.
pub fn recordings_in(dir: &Path) -> Vec<std::path::PathBuf> {
    csv_files(std::fs::read_dir(dir).unwrap())
}

/// Sensor noise of the example session's README.
pub const CURRENT_NOISE_A: f64 = 1e-4;
/// Camera noise before quantisation, m.
pub const CAMERA_NOISE_M: f64 = 5e-5;
/// Camera pixel, m.
pub const PIXEL_M: f64 = 1.09e-4;
/// Load-cell noise, N.
pub const FORCE_NOISE_N: f64 = 2e-5;

/// One recording of a protocol: name, wave, fixture, rest, hold, off.
pub struct Run {
    pub name: &'static str,
    pub wave: &'static str,
    pub fixture: Fixture,
    pub rest_s: f64,
    pub hold_s: f64,
    pub off_s: f64,
}

/// A short session of the example's kinds: steps at three voltages, one
/// segment alone, a travelling sine, a blocked step.
pub fn short_protocol() -> Vec<Run> {
    let free = |name, wave, hold_s| Run {
        name,
        wave,
        fixture: Fixture::Free,
        rest_s: 1.5,
        hold_s,
        off_s: 2.0,
    };
    vec![
        free("01_free_step_1.0V", "step:1", 3.0),
        free("02_free_step_2.5V", "step:2.5", 3.0),
        free("03_free_step_4.0V", "step:4", 3.0),
        free("04_free_single_seg2", "step:0,2.5,0", 3.0),
        free("05_free_sine_travel", "sine:2.5,1,120", 4.0),
        Run {
            name: "06_blocked_step_2.0V",
            wave: "step:2",
            fixture: Fixture::Blocked,
            rest_s: 1.5,
            hold_s: 3.0,
            off_s: 2.0,
        },
    ]
}

/// Writes the session of `runs` under `spec` into `dir`, 10 s apart.
pub fn write_session(dir: &Path, spec: &ModelSpec, runs: &[Run], seed: u64) {
    write_session_edited(dir, spec, runs, seed, &|_, _| {}, &|_, _| {});
}

/// As [`write_session`] (the same seed, the same noise), with the bench's
/// faults: `strip(name, drive)` edits the drive the strip itself saw (a
/// contact that lifted leaves a segment at rest) before the model runs on
/// it, while the file keeps the drive as commanded; `measured(name,
/// recording)` edits what the sensors wrote (a clipped amplifier).
pub fn write_session_edited(
    dir: &Path,
    spec: &ModelSpec,
    runs: &[Run],
    seed: u64,
    strip: &dyn Fn(&str, &mut Recording),
    measured: &dyn Fn(&str, &mut Recording),
) {
    std::fs::create_dir_all(dir).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut t_session = 0.0;
    for run in runs {
        let wave = Wave::parse(run.wave).unwrap();
        let drive = Drive {
            segments: 3,
            fixture: run.fixture,
            rest_s: run.rest_s,
            duration_s: run.hold_s,
            off_s: run.off_s,
            rate_hz: 1000.0,
        };
        let mut rec = drive_recording(&wave, &drive).unwrap();
        rec.meta.dots_s_m = Some(vec![0.01, 0.02, 0.03, 0.04, 0.05]);
        // Only water shows added mass and drag (docs/FORMAT.md).
        let ext = &spec.ext;
        if ext.added_mass_kg_per_m > 0.0
            || ext.drag_n_s_per_m2 > 0.0
            || ext.drag_quadratic_n_s2_per_m3 > 0.0
        {
            rec.meta.medium = finrs::recording::Medium::Water;
        }
        rec.meta.notes = Some(format!("t_session_start_s = {t_session:.3}; {}", run.name));
        let mut seen = rec.clone();
        strip(run.name, &mut seen);
        let traces = predict(&seen, spec, 4, 1e-3, t_session, None, &mut |_| {}).unwrap();
        measure(&mut rec, &traces, &mut rng);
        measured(run.name, &mut rec);
        rec.write(&dir.join(format!("{}.csv", run.name))).unwrap();
        t_session += rec.t_s.last().unwrap() + 10.0;
    }
}

fn measure(rec: &mut Recording, t: &finrs::model::predict::Traces, rng: &mut impl Rng) {
    let noise = |sigma: f64| Normal::new(0.0, sigma).unwrap();
    let rows = rec.t_s.len();
    for (k, c) in t.currents_a.iter().enumerate() {
        let n = noise(CURRENT_NOISE_A);
        let v = c
            .iter()
            .map(|x| Some(round(x + n.sample(rng), 1e-6)))
            .collect();
        rec.channels.push((Channel::Current(k), v));
    }
    match rec.meta.fixture {
        Fixture::Free => {
            // Frames at 30/s on the nearest DAQ row.
            let mut frame = vec![false; rows];
            let mut f = 0;
            loop {
                let row = (f as f64 / 30.0 * 1000.0).round() as usize;
                if row >= rows {
                    break;
                }
                frame[row] = true;
                f += 1;
            }
            let n = noise(CAMERA_NOISE_M);
            let camera = |series: &[f64], rng: &mut dyn rand::RngCore| -> Vec<Option<f64>> {
                // The rest shape is off by a fraction of a millimetre.
                let offset = rng.gen_range(-2e-4..2e-4);
                (0..rows)
                    .map(|r| frame[r].then(|| round(series[r] + offset + n.sample(rng), PIXEL_M)))
                    .collect()
            };
            let ty = camera(&t.tip_y_m, rng);
            let tx = camera(&t.tip_x_m, rng);
            rec.channels.push((Channel::TipY, ty));
            rec.channels.push((Channel::TipX, tx));
            for j in 0..t.dots_y_m.len() {
                let y = camera(&t.dots_y_m[j], rng);
                let x = camera(&t.dots_x_m[j], rng);
                rec.channels.push((Channel::DotY(j), y));
                rec.channels.push((Channel::DotX(j), x));
            }
        }
        Fixture::Blocked => {
            let n = noise(FORCE_NOISE_N);
            let v = t
                .force_n
                .iter()
                .map(|x| Some(round(x + n.sample(rng), 1e-6)))
                .collect();
            rec.channels.push((Channel::Force, v));
        }
    }
}

fn round(x: f64, q: f64) -> f64 {
    (x / q).round() * q
}
