//! `finrs simulate` end to end: waves, the seed's facts, and the example
//! session (a baseline recording, so the model must reproduce it).

mod common;

use finrs::model::params::ModelFile;
use finrs::model::predict::ModelSpec;
use finrs::model::simulate::{predict_recording, simulate, write_prediction, WRITE_BLOCK_ROWS};
use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::Geometry;
use finrs::recording::{max_written_error, Channel, Fixture, Recording};
use finrs::wave::Wave;

fn seed_params() -> model_core::Params {
    ModelFile::main_m_2006()
        .params_for(&Geometry::THESIS_2006)
        .unwrap()
}

fn drive(fixture: Fixture, rest_s: f64, duration_s: f64) -> Drive {
    Drive {
        segments: 3,
        fixture,
        rest_s,
        duration_s,
        off_s: 0.0,
        rate_hz: 1000.0,
    }
}

fn column(r: &Recording, ch: Channel) -> Vec<f64> {
    r.channel(ch)
        .unwrap_or_else(|| panic!("no {}", ch.name()))
        .iter()
        .map(|v| v.expect("simulation fills every row"))
        .collect()
}

#[test]
fn a_prediction_writes_what_its_recording_writes() {
    // The borrowed prediction, written to a file in chunks, is byte for
    // byte the recording `simulate` makes of it; a NaN it holds is refused
    // by line and column, as in a recording.
    let wave = Wave::parse("sine:2,1,120").unwrap();
    let input = drive_recording(&wave, &drive(Fixture::Free, 0.5, 2.0)).unwrap();
    let spec = ModelSpec::baseline(seed_params());
    let mut pred = predict_recording("sine", &input, &spec, 2, &mut |_| {}).unwrap();
    let whole = simulate("sine", &input, &spec, 2, &mut |_| {}).unwrap();
    assert_eq!(pred.to_recording(), whole);
    let path = std::env::temp_dir().join(format!("finrs-prediction-{}.csv", std::process::id()));
    pred.write(&path).unwrap();
    let written = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert!(
        written.len() > 100_000,
        "{} bytes: more than one chunk",
        written.len()
    );
    assert_eq!(written, whole.to_csv_string());

    pred.channels[1].1[7] = f64::NAN;
    let ch = pred.channels[1].0;
    let err = pred.view().validate("pred.csv").unwrap_err().to_string();
    let header_line = written.lines().position(|l| l.starts_with("t_s")).unwrap() + 1;
    let want = format!("pred.csv:{}", header_line + 8);
    assert!(err.contains(&want) && err.contains(&ch.name()), "{err}");
}

#[test]
fn a_prediction_written_as_computed_is_the_whole_one() {
    // Written a block at a time as the model runs (several blocks and a
    // part of one; free with tracked dots, blocked): byte for byte what
    // the whole prediction writes, and kept whole on request.
    let wave = Wave::parse("sine:2,1,120").unwrap();
    let spec = ModelSpec::baseline(seed_params());
    let dir = std::env::temp_dir().join(format!("finrs-streamed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let mut input = drive_recording(&wave, &drive(fixture, 0.5, 9.7)).unwrap();
        if fixture == Fixture::Free {
            input.meta.dots_s_m = Some(vec![0.01, 0.03]);
        }
        assert!(input.t_s.len() > 2 * WRITE_BLOCK_ROWS && input.t_s.len() % WRITE_BLOCK_ROWS != 0);
        let whole = predict_recording("sine", &input, &spec, 2, &mut |_| {}).unwrap();
        let (a, b) = (dir.join("whole.csv"), dir.join("streamed.csv"));
        whole.write(&a).unwrap();
        let mut done = 0;
        let kept =
            write_prediction("sine", &input, &spec, 2, (&b, true), &mut |n| done = n).unwrap();
        assert_eq!(done, input.t_s.len() as u64);
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{fixture:?}"
        );
        let kept = kept.unwrap();
        assert_eq!(kept.to_recording(), whole.to_recording(), "{fixture:?}");
        assert!(
            write_prediction("sine", &input, &spec, 2, (&b, false), &mut |_| {})
                .unwrap()
                .is_none()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn seed_experiment_writes_a_valid_recording() {
    let wave = Wave::parse("step:2,1,-2").unwrap();
    let input = drive_recording(&wave, &drive(Fixture::Free, 0.0, 10.0)).unwrap();
    let sim = simulate(
        "seed",
        &input,
        &ModelSpec::baseline(seed_params()),
        1,
        &mut |_| {},
    )
    .unwrap();
    sim.validate("seed").unwrap();
    let text = sim.to_csv_string();
    let back = Recording::parse("seed.csv", &text).unwrap();
    assert_eq!(back.t_s.len(), 10_001);
    // What is written is what was simulated: time and drive exactly, every
    // channel within the written resolution.
    assert_eq!((&back.t_s, &back.v_v), (&sim.t_s, &sim.v_v));
    for (ch, values) in &sim.channels {
        for (row, (b, s)) in column(&back, *ch).iter().zip(values).enumerate() {
            let s = s.expect("simulation fills every row");
            assert!(
                (b - s).abs() <= max_written_error(s),
                "{} row {row}: {s} read back as {b}",
                ch.name()
            );
        }
    }
    // Currents jump to V/R1 + V/R2 on every segment at the first row.
    let p = seed_params();
    for (k, v) in [2.0, 1.0, -2.0].into_iter().enumerate() {
        let i0 = column(&back, Channel::Current(k))[0];
        let jump = v / p.r1_ohm + v / p.r2_ohm;
        // Within the written resolution of currents (0.1 nA).
        assert!((i0 - jump).abs() < 1e-10, "segment {k}: {i0} vs {jump}");
    }
    // Small-deflection kinematics: nothing moves along the strip.
    assert!(column(&back, Channel::TipX).iter().all(|&x| x == 0.0));
}

#[test]
fn blocked_step_settles_to_three_u_over_two_l() {
    let wave = Wave::parse("step:2").unwrap();
    let input = drive_recording(&wave, &drive(Fixture::Blocked, 0.5, 120.0)).unwrap();
    let p = seed_params();
    let sim = simulate("blocked", &input, &ModelSpec::baseline(p), 1, &mut |_| {}).unwrap();
    let force = column(&sim, Channel::Force);
    let tail = &force[force.len() - 20_000..];
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    // After 120 s the relaxation is down to e^-12 of its overshoot.
    let expected = 3.0 * p.dc_moment_per_volt() * 2.0 / (2.0 * p.length_m);
    assert!((mean / expected - 1.0).abs() < 2e-3, "{mean} vs {expected}");
    assert!(sim.channel(Channel::TipY).is_none());
}

/// The contract's example session (three of its recordings ship in
/// `data/baseline-air`, see its README) is the baseline model with sensor
/// noise only (4 elements per segment): our simulation of its drive must
/// match its measurements within the noise.
#[test]
fn example_session_is_reproduced_within_noise() {
    let files = common::baseline_air_files();
    assert_eq!(files.len(), 3, "{files:?}");
    for path in files {
        let name = path.display().to_string();
        let measured = Recording::read(&path).unwrap();
        let p = common::baseline_air_model()
            .params_for(&Geometry {
                length_m: measured.meta.length_m,
                width_m: measured.meta.width_m,
                thickness_m: measured.meta.thickness_m,
            })
            .unwrap();
        let sim = simulate(&name, &measured, &ModelSpec::baseline(p), 4, &mut |_| {}).unwrap();
        let (channel, noise) = match measured.meta.fixture {
            // Camera: 0.05 mm rms plus 0.109 mm pixels (uniform, ±0.055 mm).
            Fixture::Free => (Channel::TipY, 0.05e-3_f64.hypot(0.109e-3 / 12f64.sqrt())),
            Fixture::Blocked => (Channel::Force, 0.02e-3),
        };
        let meas = measured.channel(channel).unwrap();
        let model = column(&sim, channel);
        let (mut sq, mut n) = (0.0, 0);
        for (m, s) in meas.iter().zip(&model) {
            if let Some(m) = m {
                sq += (m - s) * (m - s);
                n += 1;
            }
        }
        let rms = (sq / n as f64).sqrt();
        eprintln!(
            "{name}: {} residual {rms:.3e} rms, noise {noise:.3e}",
            channel.name()
        );
        // Measured: 1.02-1.16 x the camera noise (the rest is each file's
        // own rest offset, FORMAT.md), 0.99-1.00 x the load cell's.
        assert!(
            rms < 1.3 * noise,
            "{name}: {} rms residual {rms:e} against noise {noise:e}",
            channel.name()
        );
        let cur = measured.channel(Channel::Current(0)).unwrap();
        let cur_model = column(&sim, Channel::Current(0));
        let cur_rms = (cur
            .iter()
            .zip(&cur_model)
            .map(|(m, s)| (m.unwrap() - s).powi(2))
            .sum::<f64>()
            / cur.len() as f64)
            .sqrt();
        // Current noise: 0.1 mA rms.
        assert!(cur_rms < 0.15e-3, "{name}: current residual {cur_rms:e}");
    }
}
