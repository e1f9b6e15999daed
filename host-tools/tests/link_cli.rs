//! The firmware-link commands as users run them: without a probe (there is
//! no USB here) they fail fast and say so; `log --from-bytes` records a
//! byte dump.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use finrs::recording::{Channel, Fixture, Recording};
use finrs_frames::{encode_dropped, encode_sample, Dropped, Sample, MAX_FRAME_LEN};

mod common;

fn finrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_finrs"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("finrs-link-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the command, which must fail within `limit` and say no probe was found.
fn fails_fast_without_probe(args: &[&str], limit: Duration) {
    let started = Instant::now();
    let mut child = finrs()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Poll so that a hang fails the test instead of blocking it.
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > limit {
            child.kill().unwrap();
            panic!("finrs {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!status.success(), "finrs {args:?} succeeded: {stderr}");
    assert!(
        stderr.contains("no debug probe found"),
        "finrs {args:?} said: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn log_without_a_probe_fails_fast() {
    let dir = temp_dir("log");
    let out = dir.join("never.csv");
    fails_fast_without_probe(
        &["log", "--duration-s", "1", "--out", out.to_str().unwrap()],
        Duration::from_secs(10),
    );
    assert!(!out.exists(), "no recording without a probe");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn run_without_a_probe_fails_fast() {
    let dir = temp_dir("run");
    let out = dir.join("never.csv");
    // Any readable file passes the first check; the probe is looked for
    // before the ELF is parsed.
    let elf = env!("CARGO_BIN_EXE_finrs");
    fails_fast_without_probe(
        &["run", elf, "--out", out.to_str().unwrap()],
        Duration::from_secs(10),
    );
    fails_fast_without_probe(
        &[
            "run",
            elf,
            "--probe",
            "0483:374b",
            "--out",
            out.to_str().unwrap(),
        ],
        Duration::from_secs(10),
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_probe_selector_is_refused_by_name() {
    let out = finrs()
        .args(["log", "--probe", "not-a-probe", "--out", "x.csv"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--probe \"not-a-probe\": expected VID:PID[:SERIAL]"),
        "{stderr}"
    );
}

#[test]
fn log_from_bytes_records_a_dump_and_reports_its_gaps() {
    let dir = temp_dir("bytes");
    let dump = dir.join("up1.bin");
    let out = dir.join("rec").join("log.csv");
    let mut bytes = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for seq in 0..20u32 {
        if seq == 10 {
            let n = encode_dropped(
                &Dropped {
                    first_seq: 10,
                    count: 2,
                },
                &mut buf,
            )
            .unwrap();
            bytes.extend_from_slice(&buf[..n]);
        }
        if (10..12).contains(&seq) || seq == 15 {
            continue;
        }
        let s = Sample::<2> {
            seq,
            t_us: 500 * seq,
            force_n: 0.002 * seq as f32,
            flags: finrs_frames::SampleFlags::default(),
            voltages_v: [1.5, -1.5],
            currents_a: [0.01, -0.01],
        };
        let n = encode_sample(&s, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    bytes.extend_from_slice(b"\xF1\x5E\x01"); // a frame cut short at the end
    std::fs::write(&dump, &bytes).unwrap();

    let res = finrs()
        .args([
            "log",
            "--from-bytes",
            dump.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--sample",
            "dump-1",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "{stderr}");
    assert!(
        stderr.contains("17 samples; 3 lost in 2 gaps; 0 faults; 3 corrupt bytes; 0 refused"),
        "{stderr}"
    );
    assert!(
        stderr.contains("gap: seq 10..=11 (2 samples) dropped by the firmware (reported)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("gap: seq 15..=15 (1 samples) lost on the way (detected)"),
        "{stderr}"
    );

    let rec = Recording::read(&out).unwrap();
    assert_eq!(rec.meta.segments, 2);
    assert_eq!(rec.meta.fixture, Fixture::Blocked);
    assert_eq!(rec.meta.sample.as_deref(), Some("dump-1"));
    assert_eq!(rec.t_s.len(), 17);
    assert!(!rec.t_s.contains(&0.0075), "no row for the lost seq 15");
    // Measured channels are written to their resolution (0.1 nN here).
    let force_n = rec.channel(Channel::Force).unwrap()[16].unwrap();
    let sent_n = f64::from(0.002f32 * 19.0);
    assert!((force_n - sent_n).abs() <= finrs::recording::max_written_error(sent_n));
    let notes = rec.meta.notes.unwrap();
    assert!(notes.contains("10+2 reported, 15+1 detected"), "{notes}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_from_bytes_without_samples_writes_nothing_and_says_why() {
    let dir = temp_dir("empty");
    let dump = dir.join("empty.bin");
    std::fs::write(&dump, b"hello from semihosting\n").unwrap();
    let out = dir.join("log.csv");
    let res = finrs()
        .args([
            "log",
            "--from-bytes",
            dump.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!res.status.success());
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(stderr.contains("no valid Sample frame"), "{stderr}");
    assert!(stderr.contains("23 corrupt bytes"), "{stderr}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn commands_without_a_probe_fail_fast() {
    for args in [
        &["tare"][..],
        &["stop"],
        &["clear-fault"],
        &["limit", "2.5"],
        &["wave", "sine:2,1,120", "--segments", "4"],
        &["calibrate", "show"],
        &["bench", "live", "--out", "/tmp/finrs-never-written.csv"],
        &["calibrate", "shunts"],
        &["calibrate", "set", "--newtons-per-count", "2.6e-5"],
        &[
            "bench",
            "run",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../examples/bench/protocol.toml"
            ),
            "--out",
            "/tmp/finrs-never-written",
        ],
        &[
            "wave",
            "step:1,-1",
            "--segments",
            "2",
            "--probe",
            "0483:374b",
        ],
    ] {
        fails_fast_without_probe(args, Duration::from_secs(10));
    }
}

#[test]
fn invalid_commands_are_refused_on_the_host_before_any_probe() {
    for (args, says) in [
        (
            &["wave", "sine:2,300,0"][..],
            "wave `sine:2,300,0`: Travelling.frequency_hz must be within 0.001..=100 Hz",
        ),
        (
            &["wave", "sine:3,1,0", "--offset-v", "1.5"],
            "peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V",
        ),
        (
            &["wave", "chirp:2,1,5", "--sweep-s", "0"],
            "Chirp.duration_s must be above 0",
        ),
        (
            &["limit", "5"],
            "limit 5 V: max_abs_v must not exceed HARD_LIMIT_V (4 V)",
        ),
        (
            &[
                "run",
                "fw.elf",
                "--out",
                "x.csv",
                "--wave",
                "sine:3,1,0",
                "--offset-v",
                "1.5",
            ],
            "peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V",
        ),
        (&["tare", "--speed-khz", "0"], "--speed-khz must be above 0"),
        (
            &["run", "fw.elf", "--out", "x.csv", "--ramp-in-s", "2"],
            "--ramp-in-s shapes a wave: give it with --wave",
        ),
        (
            &["run", "fw.elf", "--out", "x.csv", "--flash-timeout-s", "0"],
            "--flash-timeout-s must be a positive number of seconds, got 0.0",
        ),
        (
            &[
                "run",
                "fw.elf",
                "--out",
                "x.csv",
                "--flash-timeout-s",
                "1e300",
            ],
            "--flash-timeout-s must be a positive number of seconds, got 1e300",
        ),
    ] {
        let out = finrs().args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(stderr.contains(says), "{args:?} said: {stderr}");
        assert!(
            !stderr.contains("probe"),
            "{args:?} looked for a probe: {stderr}"
        );
    }
}

#[test]
fn a_bad_probe_timeout_is_refused_by_name() {
    for (value, shown) in [("NaN", "NaN"), ("0", "0.0"), ("1e300", "1e300")] {
        let out = finrs()
            .args(["log", "--out", "x.csv", "--probe-timeout-s", value])
            .output()
            .unwrap();
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!(
                "--probe-timeout-s must be a positive number of seconds, got {shown}"
            )),
            "{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn log_from_bytes_reads_the_standard_input() {
    use std::io::Write as _;
    let dir = temp_dir("stdin");
    let out = dir.join("log.csv");
    let mut bytes = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for seq in 0..5u32 {
        let s = Sample::<3> {
            seq,
            t_us: 1000 * seq,
            force_n: 0.0,
            flags: finrs_frames::SampleFlags::default(),
            voltages_v: [0.0; 3],
            currents_a: [0.0; 3],
        };
        let n = encode_sample(&s, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    let mut child = finrs()
        .args(["log", "--from-bytes", "-", "--out", out.to_str().unwrap()])
        .stdin(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&bytes).unwrap();
    let res = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "{stderr}");
    assert!(stderr.contains("5 samples; 0 lost in 0 gaps"), "{stderr}");
    assert_eq!(Recording::read(&out).unwrap().meta.segments, 3);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A capture killed mid-run (SIGKILL: no handler, no flush) leaves its
/// journal with every byte it had read, and `finrs log --from-bytes` on it
/// gives the recording, gaps accounted.
#[cfg(unix)]
#[test]
fn a_killed_capture_leaves_a_journal_that_recovers_every_sample() {
    use std::io::Write;
    let dir = temp_dir("killed");
    let out = dir.join("blocked-01.csv");
    let journal = dir.join("blocked-01.csv.frames");
    let _ = std::fs::remove_file(&journal);
    let mut child = finrs()
        .args(["log", "--from-bytes", "-", "--out"])
        .arg(&out)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    // 2000 samples with seq 700..=701 dropped (reported), sent in pieces.
    let mut bytes = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for seq in 0..2000u32 {
        if (700..702).contains(&seq) {
            continue;
        }
        if seq == 702 {
            let n = encode_dropped(
                &Dropped {
                    first_seq: 700,
                    count: 2,
                },
                &mut buf,
            )
            .unwrap();
            bytes.extend_from_slice(&buf[..n]);
        }
        let s = Sample::<3> {
            seq,
            t_us: seq * 1000,
            force_n: 1e-3 * (seq as f32 * 0.01).sin(),
            flags: Default::default(),
            voltages_v: [1.0, 0.0, -1.0],
            currents_a: [0.01, 0.0, -0.01],
        };
        let n = encode_sample(&s, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    for piece in bytes.chunks(997) {
        stdin.write_all(piece).unwrap();
    }
    stdin.flush().unwrap();
    // The capture reads as it comes: wait until the journal holds it all.
    let started = Instant::now();
    while std::fs::metadata(&journal).map_or(0, |m| m.len()) < bytes.len() as u64 {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "the journal did not fill"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    drop(stdin);
    assert!(!out.exists(), "killed before it wrote the recording");
    assert_eq!(std::fs::read(&journal).unwrap(), bytes);
    let recovered = dir.join("recovered.csv");
    let report = finrs()
        .args(["log", "--from-bytes"])
        .arg(&journal)
        .arg("--out")
        .arg(&recovered)
        .output()
        .unwrap();
    assert!(report.status.success(), "{report:?}");
    let stderr = String::from_utf8_lossy(&report.stderr);
    assert!(
        stderr.contains("1998 samples; 2 lost in 1 gaps"),
        "{stderr}"
    );
    let rec = Recording::read(&recovered).unwrap();
    assert_eq!(rec.t_s.len(), 1998);
    assert!(rec.meta.notes.unwrap().contains("700+2 reported"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A protocol that breaks a rule is refused before any probe is looked
/// for, naming the file, the recording's field and the rule.
#[test]
fn a_bad_protocol_is_refused_before_any_probe() {
    let dir = temp_dir("bad-protocol");
    let path = dir.join("p.toml");
    std::fs::write(
        &path,
        "format = \"finrs-protocol/1\"\nmedium = \"air\"\n[[recording]]\nname = \"x\"\nfixture = \"blocked\"\nwave = \"step:2\"\nhold_s = -3\n",
    )
    .unwrap();
    let out = finrs()
        .args(["bench", "run"])
        .arg(&path)
        .args(["--out", "/tmp/finrs-never-written"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("p.toml: recording[1].hold_s: -3 must be above 0 seconds"),
        "{stderr}"
    );
    assert!(!stderr.contains("probe"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `finrs bench live` under a pseudo-terminal (util-linux `script`): it
/// draws its view, plays a dump, takes `q` from the terminal, restores
/// it, and writes the recording.
#[cfg(unix)]
#[test]
fn the_live_view_runs_under_a_pseudo_terminal() {
    let dir = temp_dir("live-pty");
    let dump = dir.join("dump.bin");
    let out = dir.join("live.csv");
    let _ = std::fs::remove_file(&out);
    let mut bytes = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for seq in 0..3000u32 {
        let s = Sample::<3> {
            seq,
            t_us: seq * 1000,
            force_n: 1e-3,
            flags: Default::default(),
            voltages_v: [1.0, 0.0, -1.0],
            currents_a: [0.01, 0.0, -0.01],
        };
        let n = encode_sample(&s, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    std::fs::write(&dump, &bytes).unwrap();
    let mut pty = common::pty::Pty::spawn(&format!(
        "{} bench live --from-bytes {} --out {}",
        env!("CARGO_BIN_EXE_finrs"),
        dump.display(),
        out.display()
    ));
    pty.keys(b"", 1500);
    pty.keys(b"q", 0);
    let (status, screen) = pty.finish(Duration::from_secs(20), "finrs bench live did not end on q");
    assert!(status.success(), "{status:?}: {screen}");
    // The view was drawn (the terminal moves the cursor between words),
    // the terminal put back, then the report printed.
    assert!(screen.contains("┌finrs"), "{screen}");
    assert!(screen.contains("\u{1b}[?1049h"), "alternate screen entered");
    assert!(screen.contains("\u{1b}[?1049l"), "and left: {screen}");
    assert!(
        screen.contains("3000 samples; 0 lost in 0 gaps"),
        "{screen}"
    );
    let rec = Recording::read(&out).unwrap();
    assert_eq!(rec.t_s.len(), 3000);
    std::fs::remove_dir_all(&dir).unwrap();
}
