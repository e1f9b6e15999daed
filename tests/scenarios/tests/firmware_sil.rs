//! Software in the loop: the whole fin driver firmware, built for QEMU's
//! netduinoplus2 (`finrs-firmware --features qemu,inject-overcurrent`), runs
//! 12 simulated seconds against the model core as plant; this test decodes
//! its frames with `finrs_frames::Decoder` and checks them. It does so for
//! the default 3 segments and for 8 (`FINRS_SEGMENTS=8`, the largest fin:
//! the plant's set-up must fit the stack), with the same checks below.
//!
//! - Lossless: every Sample arrives, numbered 0, 1, 2, … with no gap, no
//!   Dropped report and no corrupt byte; it covers at least 10 s.
//! - Commands: the down channel (a host file in QEMU) carries garbage, the
//!   2 V default program (the firmware boots stopped and drives only when
//!   asked), a limit raise to 5 V (refused) and a limit of 1.5 V (taken):
//!   every commanded voltage is within 1.5 V, the program is clipped at
//!   exactly 1.5 V, and successive voltages are within the slew limit.
//! - Force: the logged force matches a host simulation of the same plant
//!   (`model_core::Strip<f32>`, seed parameters, blocked, 1 ms) driven by the
//!   logged voltages. Tolerance, in load-cell counts times the scale: the
//!   firmware's load cell reads the plant's force plus noise of at most
//!   `LOAD_CELL_NOISE_COUNTS`, rounded to a count (0.5); the tare averages
//!   counts at rest, so its error is at most that much too. The
//!   two `f32` plants do the same operations in the same order and were
//!   measured bit-identical on x86 and the M4F (`qemu_vs_x86.rs`); 1e-6 of
//!   the force's range covers a legitimate difference in instruction choice.
//! - Currents: before the fault, each logged segment current is the host
//!   plant's current under the voltage applied since the previous tick,
//!   as a bridge's two levels through the shunt's filter read it at the
//!   segment's phase (`sim::SHUNT_SAMPLE_PHASE`), within `SHUNT_NOISE_COUNTS` and half a count of the shunt's scale (the
//!   input's noise and the ADC's rounding).
//! - Fault: the overcurrent injected on segment `INJECT_SEGMENT` from tick
//!   `INJECT_TICK` on is reported in exactly one Fault frame naming it, no
//!   fault comes before it, and every Sample from then on commands 0 V on
//!   every segment.
//!
//! - Log: the defmt log (semihosting stdout, decoded with defmt-decoder)
//!   names each refused command with its reason, the accepted one, and the
//!   latched fault.
//! - Stack: the log's stack line (`firmware/src/stack.rs`) gives init's and
//!   the tasks' high-water marks, both above 0 and at least
//!   [`STACK_MARGIN_B`] below the stack's size.
//!
//! QEMU runs with `-icount shift=ICOUNT_SHIFT,sleep=off`: the guest's clock
//! follows its instruction count, so the run is deterministic and does not
//! depend on the host's load, and idle time is skipped (12 simulated
//! seconds take a few wall seconds). At 2^5 ns per instruction the emulated
//! core runs 31 M instructions per second, slower than the real 168 MHz
//! M4F: a sample task that meets its 1 ms deadline here meets it on the
//! board, so "no missed deadline" is a conservative check.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use finrs_frames::{
    encode_command, Command as FinCommand, DecodedSample, Decoder, Event, FaultCode, Stats,
    MAX_COMMAND_LEN,
};
use model_core::{Fixture, Params, Strip};

use finrs_firmware_support::{config, sim};

mod common;

/// Stack the firmware must leave untouched at both of its high-water marks
/// (init and the running tasks), bytes: room for what a run did not reach
/// (another interrupt nesting, a longer log call).
const STACK_MARGIN_B: usize = 16 * 1024;
const ICOUNT_SHIFT: u32 = 5;

/// Builds the QEMU firmware for `segments` segments (`FINRS_SEGMENTS`)
/// from `firmware/`, so that its own `.cargo/config.toml` (linker,
/// DEFMT_LOG) applies as for a user, into its own target directory (this
/// `cargo test` holds the workspace's lock), and copies the ELF aside per
/// segment count: the builds share the target directory (only the firmware
/// crate differs), so they take turns and each test runs its own copy.
fn build_elf(segments: usize) -> PathBuf {
    build_elf_with(segments, "qemu,inject-overcurrent")
}

/// A built ELF: its segment count, its features, its path.
type Built = (usize, &'static str, PathBuf);

/// The QEMU firmware for `segments` with `features`, built once per test
/// run.
fn build_elf_with(segments: usize, features: &'static str) -> PathBuf {
    static BUILD: Mutex<()> = Mutex::new(());
    static ELFS: OnceLock<Mutex<Vec<Built>>> = OnceLock::new();
    let _turn = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let elfs = ELFS.get_or_init(|| Mutex::new(Vec::new()));
    if let Some((_, _, elf)) = elfs
        .lock()
        .unwrap()
        .iter()
        .find(|(n, f, _)| *n == segments && *f == features)
    {
        return elf.clone();
    }
    let elf = build_elf_once(segments, features);
    elfs.lock().unwrap().push((segments, features, elf.clone()));
    elf
}

fn build_elf_once(segments: usize, features: &str) -> PathBuf {
    let start = Instant::now();
    let release = common::build_release(
        &common::workspace().join("firmware"),
        "finrs-firmware",
        |c| {
            c.env("FINRS_SEGMENTS", segments.to_string())
                .env_remove("FINRS_DAC_SEGMENTS")
                .args(["--no-default-features", "--features", features]);
        },
        "building the QEMU firmware failed (target, flip-link installed? run scripts/setup)",
    );
    eprintln!(
        "built the QEMU firmware, N = {segments}, in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    let copy = release.join(format!(
        "finrs-firmware-n{segments}-{}",
        features.replace(',', "-")
    ));
    std::fs::copy(release.join("finrs-firmware"), &copy).expect("the ELF copies");
    copy
}

/// Runs the firmware in a fresh directory with `-icount shift` and the
/// given command bytes on its down channel; returns the frames file's
/// bytes.
fn run_qemu(elf: &Path, shift: u32, commands: &[u8]) -> (Vec<u8>, Vec<u8>) {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("finrs-sil-{}-{shift}-{run}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    if !commands.is_empty() {
        std::fs::write(dir.join("finrs-commands.bin"), commands).unwrap();
    }
    let icount = format!("shift={shift},align=off,sleep=off");
    let start = Instant::now();
    let mut child = Command::new("qemu-system-arm")
        .current_dir(&dir)
        .args([
            "-cpu",
            "cortex-m4",
            "-machine",
            "netduinoplus2",
            "-nographic",
        ])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-icount", &icount, "-kernel"])
        .arg(elf)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qemu-system-arm is installed (run scripts/setup)");
    // defmt's bytes on stdout: read them as they come so the pipe never
    // fills.
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut bytes).map(|_| bytes)
    });
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            assert!(
                status.success(),
                "the firmware failed in QEMU ({status}): {}",
                String::from_utf8_lossy(&out.stderr)
            );
            break;
        }
        if start.elapsed() > Duration::from_secs(180) {
            child.kill().unwrap();
            panic!("QEMU did not finish in 180 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    eprintln!(
        "QEMU ran {} simulated s in {:.1} wall s",
        sim::RUN_S,
        start.elapsed().as_secs_f64()
    );
    let bytes = std::fs::read(dir.join("finrs-frames.bin")).expect("the firmware wrote frames");
    let _ = std::fs::remove_dir_all(&dir);
    (bytes, reader.join().unwrap().unwrap())
}

/// The defmt log's messages, `LEVEL message` per line.
fn defmt_lines(elf: &Path, bytes: &[u8]) -> Vec<String> {
    let elf_bytes = std::fs::read(elf).unwrap();
    let table = defmt_decoder::Table::parse(&elf_bytes)
        .unwrap()
        .expect("the firmware has a defmt table");
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = Vec::new();
    while let Ok(frame) = decoder.decode() {
        let level = frame.level().map(|l| l.as_str()).unwrap_or("PRINT");
        lines.push(format!(
            "{} {}",
            level.to_uppercase(),
            frame.display_message()
        ));
    }
    lines
}

/// Stands for the stack line in the expected log (its numbers are checked
/// apart, by [`check_stack`]).
const STACK_LINE: &str = "INFO stack: …";

/// The numbers of a stack line, `(init_b, tasks_b, size_b)`, if `line` is
/// one: `INFO stack: init used I B, tasks used T B of S B`.
fn stack_line(line: &str) -> Option<(usize, usize, usize)> {
    let rest = line.strip_prefix("INFO stack: init used ")?;
    let (init, rest) = rest.split_once(" B, tasks used ")?;
    let (tasks, rest) = rest.split_once(" B of ")?;
    let size = rest.strip_suffix(" B")?;
    Some((init.parse().ok()?, tasks.parse().ok()?, size.parse().ok()?))
}

/// Exactly one stack line, both marks above 0 and at least
/// [`STACK_MARGIN_B`] below the stack's size, which is the 128 KiB of RAM
/// less the statics.
fn check_stack(log: &[String]) -> (usize, usize, usize) {
    let found: Vec<_> = log.iter().filter_map(|l| stack_line(l)).collect();
    assert_eq!(found.len(), 1, "one stack line in the log: {log:?}");
    let (init_b, tasks_b, size_b) = found[0];
    assert!(
        (64 * 1024..128 * 1024).contains(&size_b),
        "stack size {size_b} B: 128 KiB less statics"
    );
    for (what, used_b) in [("init", init_b), ("tasks", tasks_b)] {
        assert!(
            used_b > 0,
            "{what} used no stack: the measurement is broken"
        );
        assert!(
            used_b + STACK_MARGIN_B <= size_b,
            "{what} used {used_b} B of the {size_b} B stack, less than {STACK_MARGIN_B} B left"
        );
    }
    eprintln!("stack: init {init_b} B, tasks {tasks_b} B of {size_b} B");
    found[0]
}

/// Every event in a frames stream, and the decoder's totals.
fn decode(bytes: &[u8]) -> (Vec<Event>, Stats) {
    let mut decoder = Decoder::new();
    let mut events = Vec::new();
    decoder.push(bytes, &mut |e| events.push(e));
    decoder.finish(&mut |e| events.push(e));
    (events, decoder.stats())
}

/// The Samples among `events`, in order.
fn samples_of(events: &[Event]) -> Vec<DecodedSample> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Sample(s) => Some(*s),
            _ => None,
        })
        .collect()
}

/// The limit the down channel sets, V.
const COMMANDED_LIMIT_V: f32 = 1.5;

/// The fitted model the down channel sends: the plant's own.
fn model_record() -> finrs_frames::ModelRecord {
    finrs_frames::ModelRecord::encode(&finrs_frames::StripModel {
        params: model_core::Params::baseline_air_example(),
        extensions: model_core::Extensions::NONE,
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    })
}

/// The down channel's bytes: garbage, a fitted model (checked by the
/// board's shaper, which builds the model's strip in the command task:
/// that must fit the stack at N = 8 and starve no sample), the default
/// wave (the firmware boots stopped: nothing drives without it), a raise
/// of the limit (refused: it must change nothing), then a lower limit
/// (taken).
fn commands() -> Vec<u8> {
    let mut bytes = vec![0x00, 0x13, 0x37, 0x5E, 0xF1];
    let (program, envelope) = finrs_drive::default_program();
    for c in [
        FinCommand::SetModel(model_record()),
        FinCommand::SetWave { program, envelope },
        FinCommand::SetLimit { max_abs_v: 5.0 },
        FinCommand::SetLimit {
            max_abs_v: COMMANDED_LIMIT_V,
        },
    ] {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let n = encode_command(&c, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    bytes
}

#[test]
fn firmware_in_qemu_logs_losslessly_within_limits_and_stops_on_overcurrent() {
    check_run::<3, 18>();
}

/// The same run and checks with the largest fin, 8 segments: the plant's
/// set-up (`Strip::new`, S = 48) must fit the stack, and the sample task
/// its deadline.
#[test]
fn firmware_in_qemu_with_8_segments_logs_losslessly_within_limits_and_stops_on_overcurrent() {
    check_run::<8, 48>();
}

/// Runs the firmware built for `N` segments (state length `S`) with the
/// down channel's commands and checks its frames and log against a host
/// plant of `N` segments.
fn check_run<const N: usize, const S: usize>() {
    let elf = build_elf(N);
    let (bytes, log) = run_qemu(&elf, ICOUNT_SHIFT, &commands());
    let log = defmt_lines(&elf, &log);
    eprintln!("defmt log (N = {N}):\n{}", log.join("\n"));
    // Each refusal logged as an error with its reason, the good command
    // taken, the fault latched and logged, in this order.
    let up = format!("INFO fin driver up: {N} segments at 1000 Hz, limit 4.0 V");
    // A model's check fits the stack up to MAX_SHAPED_SEGMENTS; above, it
    // is refused before anything is built.
    let shaped = N <= finrs_controller::shaper::MAX_SHAPED_SEGMENTS;
    let model_line = if shaped {
        "INFO command accepted: SetModel".to_string()
    } else {
        format!(
            "ERROR SetModel refused: a build of {N} segments cannot hold a model's check in its stack (at most {})",
            finrs_controller::shaper::MAX_SHAPED_SEGMENTS
        )
    };
    let expected = [
        up.as_str(),
        "ERROR command refused: 5 bytes without a sync pair skipped",
        model_line.as_str(),
        "INFO command accepted: SetWave",
        "ERROR SetLimit refused: max_abs_v must not exceed HARD_LIMIT_V (4 V)",
        "INFO command accepted: SetLimit",
        "ERROR fault latched at tick 10500: overcurrent (segment Some(1))",
        STACK_LINE,
        "INFO run over after 12 s",
    ];
    let got: Vec<&str> = log
        .iter()
        .map(|line| stack_line(line).map_or(line.as_str(), |_| STACK_LINE))
        .collect();
    assert_eq!(got, expected, "the defmt log");
    check_stack(&log);

    let (events, stats) = decode(&bytes);
    assert_eq!(stats.corrupt_bytes, 0, "corrupt bytes in the stream");
    assert_eq!(stats.dropped_reported, 0, "the firmware dropped samples");
    assert_eq!(stats.gaps_unreported, 0, "gaps in the sequence numbers");

    let mut samples = Vec::new();
    let mut faults = Vec::new();
    let mut infos = Vec::new();
    for e in &events {
        match *e {
            Event::Sample(s) => samples.push(s),
            Event::Fault(f) => faults.push(f),
            Event::Info(i) => infos.push(i),
            other => panic!("unexpected event {other:?}"),
        }
    }
    // The Info frame, first in the stream: this build's set-up; a second
    // once the model is in use, which names it.
    assert!(matches!(events[0], Event::Info(_)), "{:?}", events[0]);
    if shaped {
        assert_eq!(infos.len(), 2, "{infos:?}");
        assert_eq!(infos[1].model_crc, Some(model_record().crc()));
    } else {
        assert_eq!(infos.len(), 1, "{infos:?}");
    }
    let info = infos[0];
    let cfg = config::controller_config().unwrap();
    assert_eq!(
        (info.segments, info.dac_segments, info.sample_hz),
        (N as u8, [None, None], config::SAMPLE_HZ)
    );
    assert_eq!(
        (info.calibration, info.amps_per_count, info.overcurrent_a),
        (cfg.calibration, cfg.amps_per_count, cfg.overcurrent_a)
    );
    // No flash in QEMU: the build's defaults.
    assert_eq!(
        info.calibration_origin,
        finrs_frames::CalibrationOrigin::Defaults
    );
    // The limit in force at the first tick: the power-up one, or the
    // commanded one if the command task read the down channel first (it
    // does for N = 3, whose shorter set-up leaves it time; not for N = 8).
    assert!(
        [config::POWER_UP_LIMIT_V, COMMANDED_LIMIT_V].contains(&info.max_abs_v),
        "{}",
        info.max_abs_v
    );
    assert_eq!(
        info.reset_cause,
        finrs_frames::ResetCause::Unknown,
        "QEMU has no reset flags"
    );
    assert_eq!(info.version, [0, 1, 0]);
    // The commit it was built from, where git can tell (the build script's
    // `git rev-parse HEAD`).
    let head = Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok());
    if let Some(head) = head {
        assert_eq!(format!("{:08x}", info.git_hash), head[..8], "git hash");
    }
    eprintln!("Info: {info:?}");
    // The injected overcurrent, and nothing before it. The faulting tick
    // sends the Fault frame instead of a Sample and consumes no number.
    assert_eq!(faults.len(), 1, "exactly one fault: {faults:?}");
    let fault = faults[0];
    assert_eq!(fault.code, FaultCode::Overcurrent);
    assert_eq!(fault.segment, Some(sim::INJECT_SEGMENT as u8));
    let tick_us = 1_000_000 / u64::from(config::SAMPLE_HZ);
    assert_eq!(
        u64::from(fault.t_us),
        sim::INJECT_TICK * tick_us,
        "reported at the injection"
    );
    assert_eq!(
        u64::from(fault.seq),
        sim::INJECT_TICK,
        "no Sample lost before it"
    );
    let fault_at = fault.seq as usize;
    // The Samples' flags: the power-up tare, the 2 V program clamped to the
    // 1.5 V limit, the latched fault to the end.
    use finrs_frames::SampleFlags as F;
    let tare_ticks = usize::from(config::controller_config().unwrap().tare_samples);
    assert!(samples[..tare_ticks - 1]
        .iter()
        .all(|s| s.flags.has(F::TARING)));
    assert!(samples[tare_ticks..fault_at]
        .iter()
        .all(|s| !s.flags.has(F::TARING)));
    let limited = samples[..fault_at]
        .iter()
        .filter(|s| s.flags.has(F::LIMITED))
        .count();
    assert!(limited > 1000, "{limited} samples clamped to the limit");
    assert!(samples[fault_at..]
        .iter()
        .all(|s| s.flags.has(F::FAULT) && !s.flags.has(F::RUNNING)));

    // Lossless and complete: 0, 1, 2, … one Sample per tick of the run but
    // the faulting one.
    let run_ticks = (sim::RUN_S * config::SAMPLE_HZ) as usize;
    assert_eq!(
        samples.len(),
        run_ticks - 1,
        "one Sample per tick of the run"
    );
    for (k, s) in samples.iter().enumerate() {
        assert_eq!(s.seq as usize, k, "sequence numbers count up from 0");
        assert_eq!(s.n, N);
        let tick = if k < fault_at { k } else { k + 1 };
        assert_eq!(
            u64::from(s.t_us),
            tick as u64 * tick_us,
            "sample {k}'s time"
        );
    }
    assert!(
        u64::from(samples[samples.len() - 1].t_us) >= 10_000_000,
        "at least 10 simulated seconds"
    );
    for s in &samples[fault_at..] {
        assert!(
            s.voltages().iter().all(|&v| v == 0.0),
            "sample {} after the fault commands {:?}",
            s.seq,
            s.voltages()
        );
    }

    // Limits.
    let dt_s = 1.0 / config::SAMPLE_HZ as f32;
    let mut last = [0.0f32; N];
    let mut peak_v = 0.0f32;
    for s in &samples[..fault_at] {
        for (i, &v) in s.voltages().iter().enumerate() {
            assert!(v.abs() <= COMMANDED_LIMIT_V, "sample {}: {v} V", s.seq);
            assert!(
                (v - last[i]).abs() <= config::SLEW_V_PER_S * dt_s * (1.0 + 1e-5) + 1e-6,
                "sample {}: segment {i} slews from {} to {v} V",
                s.seq,
                last[i]
            );
            last[i] = v;
            peak_v = peak_v.max(v.abs());
        }
    }
    assert!(
        peak_v > 1.0,
        "the default program drives the fin ({peak_v} V)"
    );

    // Force against the host's plant, driven by the logged voltages.
    let plant = Strip::<f32, N, 1, S>::new(
        &Params::baseline_air_example(),
        Fixture::Blocked,
        f64::from(dt_s),
    )
    .unwrap();
    let mut x = plant.rest();
    let bound_n = (2.0 * sim::LOAD_CELL_NOISE_COUNTS + 1.0) * config::NEWTONS_PER_COUNT;
    let (mut worst_n, mut peak_n, mut sum_sq) = (0.0f32, 0.0f32, 0.0f64);
    let tare = usize::from(config::controller_config().unwrap().tare_samples);
    let mut compared = 0usize;
    // The shunts read the plant's currents under the voltage still applied
    // (the previous tick's), rounded to a count.
    let current_bound_a = (sim::SHUNT_NOISE_COUNTS + 0.5) * config::AMPS_PER_COUNT;
    let mut applied = [0.0f32; N];
    let mut worst_a = 0.0f32;
    for s in &samples {
        if (s.seq as usize) < fault_at {
            // A bridge's two levels through the shunt's filter, as the
            // QEMU board's plant reads them (their mean is the current
            // under `applied`).
            let phase: [f32; N] = std::array::from_fn(|i| sim::SHUNT_SAMPLE_PHASE[i]);
            let currents = config::SHUNT_FILTER.bridge_readings_a(
                &applied,
                config::BRIDGE_SUPPLY_V,
                &phase,
                |u| plant.currents_a(&x, u),
            );
            for (i, (&got, want)) in s.currents().iter().zip(currents).enumerate() {
                let err = (got - want).abs();
                worst_a = worst_a.max(err);
                assert!(
                    err <= current_bound_a * (1.0 + 1e-4),
                    "sample {}: segment {i} current {got} A, host plant {want} A",
                    s.seq
                );
            }
        }
        let expected = plant.blocking_force_n(&x);
        if s.seq as usize >= tare {
            let err = (s.force_n - expected).abs();
            worst_n = worst_n.max(err);
            peak_n = peak_n.max(expected.abs());
            sum_sq += f64::from(err).powi(2);
            compared += 1;
            assert!(
                err <= bound_n + 1e-6 * peak_n,
                "sample {}: force {} N, host plant {expected} N (bound {bound_n} N)",
                s.seq,
                s.force_n
            );
        }
        let v: [f32; N] = s.voltages().try_into().unwrap();
        plant.step(&mut x, &v);
        applied = v;
        if s.seq as usize + 1 == fault_at {
            // The faulting tick stepped the plant at 0 V and logged no Sample.
            plant.step(&mut x, &[0.0; N]);
            applied = [0.0; N];
        }
    }
    assert!(
        peak_n > 20.0 * bound_n,
        "the force ({peak_n} N) is large beside the tolerance ({bound_n} N)"
    );
    eprintln!(
        "N = {N}: {} samples, {compared} forces compared: worst {worst_n:e} N, rms {:e} N, bound {bound_n:e} N, peak force {peak_n:e} N, peak voltage {peak_v} V; currents: worst {worst_a:e} A, bound {current_bound_a:e} A",
        samples.len(),
        (sum_sq / compared as f64).sqrt()
    );
}

/// The same firmware on a core made too slow for its work: at 2^9 ns per
/// instruction (1953 instructions per 1 ms period) the sample task overruns
/// within its first periods. (Measured: it keeps its deadline up to
/// shift 7, 7812 instructions a period, and misses it from shift 8, 3906:
/// a period's work, plant included, is between the two.) The overrun must
/// be reported as a MissedDeadline fault, first, with every output at zero
/// from then on, and no Sample lost before it.
#[test]
fn firmware_in_qemu_reports_a_missed_deadline_and_stops() {
    let elf = build_elf(3);
    let (bytes, _) = run_qemu(&elf, 9, &[]);
    let (events, stats) = decode(&bytes);
    assert_eq!(
        (stats.corrupt_bytes, stats.gaps_unreported),
        (0, 0),
        "{stats:?}"
    );
    let first_fault = events
        .iter()
        .find_map(|e| match e {
            Event::Fault(f) => Some(*f),
            _ => None,
        })
        .expect("a Fault frame");
    assert_eq!(first_fault.code, FaultCode::MissedDeadline);
    assert_eq!(first_fault.segment, None);
    let samples = samples_of(&events);
    assert!(samples.len() > 10, "samples after the fault keep flowing");
    for s in &samples {
        if s.seq >= first_fault.seq {
            assert!(
                s.voltages().iter().all(|&v| v == 0.0),
                "sample {} after the missed deadline commands {:?}",
                s.seq,
                s.voltages()
            );
        }
    }
}

/// The firmware boots stopped: with no wave on its down channel it drives
/// nothing for the whole 12 s run (the power-up tare, then waiting), while
/// its Samples flow, gap-free. Stopped, it takes a SetCalibration: the
/// shunts read against the new zeros, and an Info frame carries them,
/// "unsaved" (QEMU has no flash to keep them).
#[test]
fn firmware_in_qemu_drives_nothing_until_a_wave_and_takes_a_calibration() {
    use finrs_frames::{Calibration, CalibrationOrigin};
    let elf = build_elf(3);
    let defaults = config::DEFAULT_CALIBRATION;
    let mut zeros = defaults.current_zero_counts;
    zeros[0] += 40;
    zeros[1] -= 40;
    let new = Calibration {
        newtons_per_count: 2.0 * defaults.newtons_per_count,
        current_zero_counts: zeros,
    };
    let mut buf = [0u8; finrs_frames::MAX_COMMAND_LEN];
    let n = encode_command(&FinCommand::SetCalibration(new), &mut buf).unwrap();
    let (bytes, log) = run_qemu(&elf, ICOUNT_SHIFT, &buf[..n]);
    let log = defmt_lines(&elf, &log);
    assert!(
        log.iter()
            .any(|l| l.contains("command accepted: SetCalibration")),
        "{log:#?}"
    );
    let (events, stats) = decode(&bytes);
    let samples = samples_of(&events);
    assert_eq!(
        (stats.corrupt_bytes, stats.gaps_unreported),
        (0, 0),
        "{stats:?}"
    );
    let run_ticks = (sim::RUN_S * config::SAMPLE_HZ) as usize;
    assert!(samples.len() >= run_ticks - 1, "{} samples", samples.len());
    for s in &samples {
        assert!(
            s.voltages().iter().all(|&v| v == 0.0),
            "sample {} commands {:?} with no wave sent",
            s.seq,
            s.voltages()
        );
        assert!(
            !s.flags.has(finrs_frames::SampleFlags::RUNNING),
            "sample {}",
            s.seq
        );
    }
    let infos: Vec<finrs_frames::Info> = events
        .iter()
        .filter_map(|e| match e {
            Event::Info(i) => Some(*i),
            _ => None,
        })
        .collect();
    let last = infos.last().expect("an Info frame");
    assert_eq!(
        (last.calibration, last.calibration_origin),
        (new, CalibrationOrigin::Unsaved),
        "{infos:?}"
    );
    // At 0 V the plant draws no current: segment 1 now reads 40 counts
    // below its zero, segment 2 40 above, segment 3 as before (before this
    // build's injected overcurrent on segment 2).
    let a = config::AMPS_PER_COUNT;
    let end = samples
        .iter()
        .rev()
        .find(|s| u64::from(s.seq) < sim::INJECT_TICK - 100)
        .unwrap()
        .currents();
    for (got, want) in end.iter().zip([-40.0 * a, 40.0 * a, 0.0]) {
        assert!(
            (got - want).abs() <= (sim::SHUNT_NOISE_COUNTS + 0.5) * a,
            "{end:?}"
        );
    }
}

/// A supply out of range at boot (QEMU's `inject-supply-fault`: the bridge
/// supply at 4.3 V): the firmware says so, reports a Supply fault before
/// its first Sample, refuses the wave it is then sent, and drives nothing.
#[test]
fn firmware_in_qemu_with_a_bad_supply_reports_it_and_never_drives() {
    let elf = build_elf_with(3, "qemu,inject-supply-fault");
    let (bytes, log) = run_qemu(&elf, ICOUNT_SHIFT, &commands());
    let log = defmt_lines(&elf, &log);
    assert!(
        log.iter()
            .any(|l| l == "ERROR bridge supply at 4300 mV, outside 4500..=5500 mV: not driving"),
        "{log:?}"
    );
    assert!(
        log.iter()
            .any(|l| l == "ERROR SetWave refused: a fault is latched (ClearFault first)"),
        "{log:?}"
    );
    let (events, _) = decode(&bytes);
    let first_fault = events.iter().position(|e| matches!(e, Event::Fault(_)));
    let first_sample = events.iter().position(|e| matches!(e, Event::Sample(_)));
    assert!(
        first_fault < first_sample && first_fault.is_some(),
        "{:?}",
        &events[..3]
    );
    let Event::Fault(fault) = events[first_fault.unwrap()] else {
        unreachable!()
    };
    assert_eq!(fault.code, FaultCode::Supply);
    let samples = samples_of(&events);
    assert!(samples.len() > 10_000, "{} samples", samples.len());
    assert!(samples
        .iter()
        .all(|s| s.voltages().iter().all(|&v| v == 0.0)
            && s.currents().iter().all(|&i| i.abs() < 1e-3)));
}
