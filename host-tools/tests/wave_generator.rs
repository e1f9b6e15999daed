//! `finrs simulate --wave` drives what the firmware drives: the recording
//! made from a wave text holds, sample by sample, the voltages of the
//! firmware's `Generator<N>` counted in sample ticks from the wave's start
//! (as the controller calls it), for every kind of wave and N = 1, 3, 8;
//! and `finrs wave` sends the same program for the same text.

use finrs::link::command::wave_command;
use finrs::model::synth::{drive_recording, drive_recording_shaped, Drive};
use finrs::recording::{Fixture, Voltages};
use finrs::wave::{Wave, WaveOptions};
use finrs_drive::{Envelope, Generator, Limiter, Limits, Program, SINE_MAX_ERROR};
use finrs_frames::Command;

const RATE_HZ: u32 = 1000;
const REST_S: f64 = 0.25;
const DURATION_S: f64 = 3.0;
const OFF_S: f64 = 0.5;

fn drive(segments: usize) -> Drive {
    Drive {
        segments,
        fixture: Fixture::Free,
        rest_s: REST_S,
        duration_s: DURATION_S,
        off_s: OFF_S,
        rate_hz: f64::from(RATE_HZ),
    }
}

/// Each kind's text for N segments and the program written out by hand.
fn cases(n: usize) -> Vec<(String, Program)> {
    let levels: Vec<f64> = (0..n).map(|k| 0.5 * k as f64 - 1.5).collect();
    let mut levels_v = [0.0f32; 8];
    for (l, v) in levels_v.iter_mut().zip(&levels) {
        *l = *v as f32;
    }
    let text: Vec<String> = levels.iter().map(f64::to_string).collect();
    vec![
        (
            "sine:2.5,1.3,120".into(),
            Program::Travelling {
                amplitude_v: 2.5,
                frequency_hz: 1.3,
                lag_deg_per_segment: 120.0,
                offset_v: 0.0,
            },
        ),
        (
            "standing:2,0.7".into(),
            Program::Standing {
                amplitude_v: 2.0,
                frequency_hz: 0.7,
                offset_v: 0.0,
            },
        ),
        (
            format!("step:{}", text.join(",")),
            Program::Steps { levels_v },
        ),
        (
            "pulses:2.5,0.3,0.2".into(),
            Program::Pulses {
                amplitude_v: 2.5,
                on_s: 0.3,
                off_s: 0.2,
            },
        ),
        (
            "chirp:2,0.5,20".into(),
            Program::Chirp {
                amplitude_v: 2.0,
                start_hz: 0.5,
                end_hz: 20.0,
                duration_s: DURATION_S as f32,
            },
        ),
    ]
}

/// The firmware's outputs: zero until the wave starts, then the generator
/// at the tick since the start, through the limiter if there is one.
fn firmware<const N: usize>(
    program: Program,
    envelope: Envelope,
    start_row: u64,
    rows: u64,
    limits: Option<Limits>,
) -> Vec<Vec<f64>> {
    let g = Generator::<N>::new(program, envelope).unwrap();
    let mut limiter = limits.map(Limiter::<N>::new);
    let dt_s = 1.0 / RATE_HZ as f32;
    (0..rows)
        .map(|row| {
            let wanted = match row.checked_sub(start_row) {
                Some(tick) => g.voltages_at_tick_v(tick, RATE_HZ),
                None => [0.0; N],
            };
            let out = match &mut limiter {
                Some(l) => l.apply(wanted, dt_s),
                None => wanted,
            };
            out.iter().map(|&v| f64::from(v)).collect()
        })
        .collect()
}

fn firmware_n(
    n: usize,
    program: Program,
    envelope: Envelope,
    start_row: u64,
    rows: u64,
    limits: Option<Limits>,
) -> Vec<Vec<f64>> {
    match n {
        1 => firmware::<1>(program, envelope, start_row, rows, limits),
        3 => firmware::<3>(program, envelope, start_row, rows, limits),
        8 => firmware::<8>(program, envelope, start_row, rows, limits),
        _ => unreachable!("the test runs N = 1, 3, 8"),
    }
}

fn assert_same_rows(what: &str, simulated: &Voltages, expected: &[Vec<f64>]) {
    assert_eq!(simulated.len(), expected.len(), "{what}: rows");
    for (row, (s, e)) in simulated.rows().zip(expected).enumerate() {
        assert_eq!(s, e, "{what}: row {row}");
    }
}

#[test]
fn simulate_and_the_firmware_generator_agree_sample_by_sample() {
    let start_row = (REST_S * f64::from(RATE_HZ)) as u64;
    let end_row = ((REST_S + DURATION_S) * f64::from(RATE_HZ)) as u64;
    let rows = ((REST_S + DURATION_S + OFF_S) * f64::from(RATE_HZ)) as u64 + 1;
    for n in [1, 3, 8] {
        for (text, program) in cases(n) {
            let what = format!("{text}, N = {n}");
            let wave = Wave::parse(&text).unwrap();
            let rec = drive_recording(&wave, &drive(n)).unwrap();
            let envelope = Envelope {
                ramp_in_s: 0.0,
                hold_s: DURATION_S as f32,
                ramp_out_s: 0.0,
            };
            let expected = firmware_n(n, program, envelope, start_row, rows, None);
            assert_same_rows(&what, &rec.v_v, &expected);
            // Not vacuous: the wave is on in its window and off outside.
            let (flat, on) = (
                rec.v_v.as_flat(),
                start_row as usize * n..end_row as usize * n,
            );
            assert!(flat[on.clone()].iter().any(|v| v.abs() > 0.4), "{what}");
            assert!(flat[..on.start]
                .iter()
                .chain(&flat[on.end..])
                .all(|&v| v == 0.0));
            // `finrs wave` sends that very program for the same text.
            let options = WaveOptions {
                hold_s: DURATION_S,
                ..WaveOptions::steady(DURATION_S)
            };
            assert_eq!(
                wave_command(&text, n, &options).unwrap(),
                Command::SetWave { program, envelope },
                "{what}"
            );
        }
    }
}

#[test]
fn ramps_offset_and_limiter_are_the_firmwares() {
    let start_row = (REST_S * f64::from(RATE_HZ)) as u64;
    let rows = ((REST_S + DURATION_S + OFF_S) * f64::from(RATE_HZ)) as u64 + 1;
    let limits = Limits::new(1.8, 40.0).unwrap();
    let shaping = WaveOptions {
        offset_v: 0.5,
        ramp_in_s: 0.6,
        ramp_out_s: 0.4,
        ..WaveOptions::steady(DURATION_S)
    };
    for n in [1, 3, 8] {
        let (text, program) = ("sine:2.5,1.3,120", cases(n)[0].1);
        let Program::Travelling {
            amplitude_v,
            frequency_hz,
            lag_deg_per_segment,
            ..
        } = program
        else {
            unreachable!()
        };
        let program = Program::Travelling {
            amplitude_v,
            frequency_hz,
            lag_deg_per_segment,
            offset_v: 0.5,
        };
        let envelope = Envelope {
            ramp_in_s: 0.6,
            hold_s: (DURATION_S - 0.6 - 0.4) as f32,
            ramp_out_s: 0.4,
        };
        let rec = drive_recording_shaped(
            &Wave::parse(text).unwrap(),
            &drive(n),
            &shaping,
            Some(limits),
        )
        .unwrap();
        let expected = firmware_n(n, program, envelope, start_row, rows, Some(limits));
        assert_same_rows(&format!("{text}, N = {n}"), &rec.v_v, &expected);
        // The limiter acted: clipped at 1.8 V, and slewed back to 0 after.
        let peak = rec.v_v.as_flat().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((peak - 1.8).abs() < 1e-6, "{peak}");
        for (before, after) in rec.v_v.rows().zip(rec.v_v.rows().skip(1)) {
            for (a, b) in before.iter().zip(after) {
                assert!((b - a).abs() <= 40.0 / 1000.0 + 1e-6);
            }
        }
        assert!(rec.v_v.rows().last().unwrap().iter().all(|&v| v == 0.0));
    }
}

/// The generator's f32 sine against the exact f64 travelling wave the host
/// used to evaluate: within the documented sine error plus the f32
/// rounding of the frequency's phase (13 cycles here).
#[test]
fn travelling_wave_stays_within_the_sine_error_of_the_exact_wave() {
    let rec = drive_recording(&Wave::parse("sine:2.5,1.3,120").unwrap(), &drive(3)).unwrap();
    let start_row = (REST_S * f64::from(RATE_HZ)) as usize;
    let end_row = ((REST_S + DURATION_S) * f64::from(RATE_HZ)) as usize;
    let mut worst: f64 = 0.0;
    for row in start_row..end_row {
        let t_s = (row - start_row) as f64 / f64::from(RATE_HZ);
        for k in 0..3 {
            let exact = 2.5
                * (2.0 * std::f64::consts::PI * 1.3 * t_s - k as f64 * 120f64.to_radians()).sin();
            worst = worst.max((rec.v_v[row][k] - exact).abs());
        }
    }
    // 1.3 Hz in f32 is off by 4.8e-8 Hz: 2π·1.4e-7 rad over 3 s, far below.
    assert!(
        worst <= 2.5 * f64::from(SINE_MAX_ERROR) + 1e-5,
        "worst {worst}"
    );
}

#[test]
fn simulate_refuses_what_the_firmware_refuses_and_bad_shaping() {
    let refuse = |text: &str, shaping: WaveOptions, d: Drive| {
        drive_recording_shaped(&Wave::parse(text).unwrap(), &d, &shaping, None)
            .unwrap_err()
            .to_string()
    };
    let steady = WaveOptions::steady(3.0);
    assert_eq!(
        refuse("sine:2,300,0", steady, drive(3)),
        "wave `sine:2,300,0`: Travelling.frequency_hz must be within 0.001..=100 Hz"
    );
    assert_eq!(
        refuse("chirp:2,5,1", steady, drive(3)),
        "wave `chirp:2,5,1`: Chirp.end_hz must be above start_hz"
    );
    let ramps = WaveOptions {
        ramp_in_s: 2.0,
        ramp_out_s: 1.5,
        ..steady
    };
    assert_eq!(
        refuse("sine:2,1,0", ramps, drive(3)),
        "ramp_in_s + ramp_out_s must not exceed duration_s: 2 + 1.5 > 3"
    );
    let hold = WaveOptions {
        ramp_in_s: 1.0,
        hold_s: 2.5,
        ..steady
    };
    assert_eq!(
        refuse("sine:2,1,0", hold, drive(3)),
        "ramp_in_s + hold_s + ramp_out_s must not exceed duration_s: 1 + 2.5 + 0 > 3"
    );
    let d = Drive {
        rate_hz: 999.5,
        ..drive(3)
    };
    assert!(refuse("step:1", steady, d).starts_with("rate_hz must be a whole number of Hz"));
    assert_eq!(
        refuse("step:1", steady, drive(9)),
        "segments must be 1..=8, got 9"
    );
}

/// The `finrs simulate --wave` command itself, options and all: its output
/// file's voltage columns are the firmware's outputs, digit for digit.
#[test]
fn the_simulate_command_writes_the_firmware_voltages() {
    let dir = std::env::temp_dir().join(format!("finrs-wave-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("sim.csv");
    let run = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_finrs"))
            .args(["simulate", "--segments", "3", "--rest-s", "0.25"])
            .args(["--duration-s", "3", "--off-s", "0.5", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let start_row = (REST_S * f64::from(RATE_HZ)) as u64;
    let rows = ((REST_S + DURATION_S + OFF_S) * f64::from(RATE_HZ)) as u64 + 1;
    let limits = Limits::new(1.8, 40.0).unwrap();
    let envelope = Envelope {
        ramp_in_s: 0.5,
        hold_s: 2.0,
        ramp_out_s: 0.5,
    };
    for (text, program) in cases(3) {
        let o = run(&[
            "--wave",
            &text,
            "--ramp-in-s",
            "0.5",
            "--ramp-out-s",
            "0.5",
            "--limit-v",
            "1.8",
            "--slew-v-per-s",
            "40",
        ]);
        assert!(o.status.success(), "{text}: {o:?}");
        let rec = finrs::recording::Recording::read(&out).unwrap();
        let expected = firmware_n(3, program, envelope, start_row, rows, Some(limits));
        assert_same_rows(&text, &rec.v_v, &expected);
    }
    // Shaping options belong to --wave, and bad ones are named.
    std::fs::copy(&out, dir.join("in.csv")).unwrap();
    let input = dir.join("in.csv");
    let run_input = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_finrs"))
            .args(["simulate", "--input"])
            .arg(&input)
            .arg("--out")
            .arg(dir.join("from-input.csv"))
            .args(extra)
            .output()
            .unwrap()
    };
    // Without wave options, a recording simulates.
    let o = run_input(&[]);
    assert!(o.status.success(), "{o:?}");
    // Every option that describes a wave is refused by name: a recording
    // has its own drive, segments, fixture and timing.
    for extra in [
        &["--limit-v", "1", "--slew-v-per-s", "5"][..],
        &["--segments", "3"],
        &["--rate-hz", "500"],
        &["--fixture", "blocked"],
        &["--offset-v", "0.5"],
        &["--sweep-s", "2"],
    ] {
        let o = run_input(extra);
        assert!(!o.status.success(), "{extra:?} with --input was accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("the argument '--input <INPUT>' cannot be used with")
                && err.contains(extra[0]),
            "{extra:?}: {err}"
        );
    }
    let o = run(&[
        "--wave",
        "sine:1,1,0",
        "--limit-v",
        "4.5",
        "--slew-v-per-s",
        "5",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr)
        .contains("--limit-v 4.5: max_abs_v must not exceed HARD_LIMIT_V (4 V)"));
    // The library names its fields; the command line names its flags.
    for (extra, message) in [
        (
            &["--wave", "sine:1,1,0", "--rate-hz", "999.5"][..],
            "--rate-hz must be a whole number of Hz",
        ),
        (
            &[
                "--wave",
                "sine:1,1,0",
                "--ramp-in-s",
                "2",
                "--ramp-out-s",
                "2",
            ],
            "--ramp-in-s + --ramp-out-s must not exceed --duration-s: 2 + 2 > 3",
        ),
        (
            &["--wave", "pulses:1,1,1", "--offset-v", "0.5"],
            "--offset-v applies to sine: and standing: waves only",
        ),
    ] {
        let o = run(extra);
        assert!(!o.status.success(), "{extra:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(message), "{extra:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
