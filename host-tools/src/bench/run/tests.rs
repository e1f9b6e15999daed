//! A session against the fake board (the firmware's own controller on a
//! simulated strip): every recording written, numbered, timed on the
//! board's clock, with the wave where the protocol puts it.

use std::cell::Cell;
use std::rc::Rc;

use super::*;
use crate::link::capture::Silent;
use crate::link::fake_board::{FakeBoard, NOMINAL_SCALE, TRUE_SCALE};

const PROTOCOL: &str = r#"
format = "finrs-protocol/1"
sample = "fake-01"
medium = "water"
dots_s_m = [0.025, 0.05]

[[recording]]
name = "free_step_1.0V"
fixture = "free"
wave = "step:1"
rest_s = 0.5
hold_s = 1.0
off_s = 0.5

[[recording]]
name = "blocked_step_2.0V"
fixture = "blocked"
wave = "step:2"
rest_s = 0.4
hold_s = 1.5
off_s = 0.6
prompt = "put the tip on the load cell"
notes = "blocked step"
"#;

/// A test's own output directory, removed when the test ends, failed or
/// not.
struct OutDir(PathBuf);

impl std::ops::Deref for OutDir {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::path::Path> for OutDir {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn out_dir(name: &str) -> OutDir {
    let dir = std::env::temp_dir().join(format!("finrs-bench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    OutDir(dir)
}

/// Runs `protocol` on `board` into `dir` with the default options, no
/// table, no operator and no monitor.
fn run_quietly(
    board: &mut FakeBoard,
    protocol: &Protocol,
    dir: &std::path::Path,
) -> Result<super::SessionReport, BenchError> {
    run_session(
        board,
        protocol,
        dir,
        &BenchOptions::default(),
        None,
        &mut |_: &str| Ok(()),
        &Silent,
    )
}

#[test]
fn a_session_is_recorded_in_order_on_the_boards_clock() {
    let protocol = Protocol::parse("p.toml", PROTOCOL).unwrap();
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let dir = out_dir("session");
    let mut prompts = Vec::new();
    let report = run_session(
        &mut board,
        &protocol,
        &dir,
        &BenchOptions::default(),
        None,
        &mut |text: &str| {
            prompts.push(text.to_string());
            Ok(())
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(prompts.len(), 1);
    assert!(prompts[0].contains("recording 2 of 2 (blocked_step_2.0V): put the tip"));
    let names: Vec<String> = report
        .written
        .iter()
        .map(|(p, _)| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["01_free_step_1.0V.csv", "02_blocked_step_2.0V.csv"]);

    let free = Recording::read(&dir.join(&names[0])).unwrap();
    assert_eq!(free.meta.fixture, Fixture::Free);
    assert_eq!(free.meta.t_session_start_s, Some(0.0));
    assert_eq!(free.meta.dots_s_m, Some(vec![0.025, 0.05]));
    assert!(free.channels.iter().all(|(c, _)| *c != Channel::Force));
    // 2 s at 1 kHz, from t = 0.
    assert_eq!(free.t_s.len(), 2000);
    assert_eq!(free.t_s[0], 0.0);
    // 0 V during the rest, 1 V held (after the slew), 0 V at the end.
    let v = |r: &Recording, row: usize| r.v_v.row(row).unwrap()[0];
    assert_eq!(v(&free, 100), 0.0);
    assert!((v(&free, 1200) - 1.0).abs() < 1e-6, "{}", v(&free, 1200));
    assert_eq!(v(&free, 1990), 0.0);
    // The wave starts within a command poll of the rest's end.
    let start = (0..free.t_s.len()).find(|&r| v(&free, r) != 0.0).unwrap();
    assert!((500..=560).contains(&start), "wave from row {start}");

    let blocked = Recording::read(&dir.join(&names[1])).unwrap();
    assert_eq!(blocked.meta.fixture, Fixture::Blocked);
    assert_eq!(blocked.t_s.len(), 2500);
    let notes = blocked.meta.notes.clone().unwrap();
    assert!(
        notes.starts_with("blocked step; wave step:2 after 0.4 s"),
        "{notes}"
    );
    assert!(
        notes.contains("firmware 0.1.0") || notes.contains("no Info frame"),
        "{notes}"
    );
    // After the first recording and the tare (200 samples and change).
    let start = blocked.meta.t_session_start_s.unwrap();
    assert!((2.19..2.4).contains(&start), "t_session_start_s {start}");
    // The strip pushes while driven: 2 mN at 2 V, read at the board's
    // nominal scale (the fake's true one is 3.1e-5 N/count).
    let force = blocked
        .channels
        .iter()
        .find(|(c, _)| *c == Channel::Force)
        .unwrap();
    let held: Vec<f64> = force.1[1000..1800].iter().map(|f| f.unwrap()).collect();
    let mean = held.iter().sum::<f64>() / held.len() as f64;
    let want = 2e-3 * f64::from(NOMINAL_SCALE) / TRUE_SCALE;
    assert!(
        (mean / want - 1.0).abs() < 0.02,
        "{mean} N against {want} N"
    );
    assert!(force.1[100].unwrap().abs() < 2e-4, "tared");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_session_is_not_written_over_another_and_bad_waves_are_refused_first() {
    let protocol = Protocol::parse("p.toml", PROTOCOL).unwrap();
    let dir = out_dir("exists");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("02_blocked_step_2.0V.csv"), "x").unwrap();
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let e = run_quietly(&mut board, &protocol, &dir).unwrap_err();
    assert!(matches!(e, BenchError::Exists { .. }), "{e}");
    assert!(
        !dir.join("01_free_step_1.0V.csv").exists(),
        "nothing recorded"
    );
    // A wave above the board's limit: refused before anything moves.
    let text = PROTOCOL.replace("step:2\"", "step:5\"");
    let protocol = Protocol::parse("p.toml", &text).unwrap();
    let dir = out_dir("bad-wave");
    let e = run_quietly(&mut board, &protocol, &dir).unwrap_err();
    // The cause is said once, as the source, the way `finrs` prints it.
    let shown = format!("{:#}", anyhow::Error::from(e));
    assert!(
        shown.starts_with("recording 2 (blocked_step_2.0V): ")
            && shown.matches("step:5").count() == 1,
        "{shown}"
    );
    assert!(!dir.exists());
}

#[test]
fn protocol_refusals_name_the_field_and_the_rule() {
    for (from, to, what) in [
        (
            "medium = \"water\"",
            "medium = \"oil\"",
            "medium: \"oil\" is not",
        ),
        (
            "rest_s = 0.4",
            "rest_s = -1",
            "recording[2].rest_s: -1 must be 0 or more",
        ),
        (
            "hold_s = 1.5",
            "hold_s = 0",
            "recording[2].hold_s: 0 must be above 0",
        ),
        (
            "name = \"blocked_step_2.0V\"",
            "name = \"free_step_1.0V\"",
            "recording[2].name: \"free_step_1.0V\" is used twice",
        ),
        (
            "name = \"blocked_step_2.0V\"",
            "name = \"a/b\"",
            "recording[2].name: \"a/b\" must be",
        ),
        (
            "fixture = \"blocked\"",
            "fixture = \"clamped\"",
            "recording[2].fixture",
        ),
        (
            "wave = \"step:2\"",
            "wave = \"saw:2\"",
            "recording[2].wave: ",
        ),
        (
            "notes = \"blocked step\"",
            "colour = \"red\"",
            "unknown field `colour`",
        ),
        (
            "format = \"finrs-protocol/1\"",
            "format = \"finrs-protocol/9\"",
            "format: ",
        ),
        (
            "dots_s_m = [0.025, 0.05]",
            "dots_s_m = [0.05, 0.025]",
            "dots_s_m: ",
        ),
    ] {
        let text = PROTOCOL.replace(from, to);
        assert_ne!(text, PROTOCOL, "{from}");
        let e = Protocol::parse("p.toml", &text).unwrap_err().to_string();
        assert!(e.starts_with("p.toml: "), "{e}");
        assert!(e.contains(what), "{to}: {e}");
    }
}

/// The shipped protocol is the example session's: the same files, in
/// order, each with the example's fixture.
#[test]
fn the_example_protocol_is_the_example_sessions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let p = Protocol::read(&root.join("examples/bench/protocol.toml")).unwrap();
    let mut example: Vec<String> = std::fs::read_dir(root.join("examples/rig-session"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".csv"))
        .collect();
    example.sort();
    let names: Vec<String> = p
        .recordings
        .iter()
        .enumerate()
        .map(|(i, s)| s.file_name(i + 1))
        .collect();
    assert_eq!(names, example);
    for (name, step) in example.iter().zip(&p.recordings) {
        let rec = Recording::read(&root.join("examples/rig-session").join(name)).unwrap();
        assert_eq!(rec.meta.fixture, step.fixture, "{name}");
        assert_eq!(rec.meta.dots_s_m, p.dots_s_m, "{name}");
    }
}

/// The example protocol runs whole against the fake board: ten files,
/// each after the last on the session's clock.
#[test]
fn the_example_protocol_runs_whole() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let p = Protocol::read(&root.join("examples/bench/protocol.toml")).unwrap();
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let dir = out_dir("example");
    let report = run_quietly(&mut board, &p, &dir).unwrap();
    assert_eq!(report.written.len(), 10);
    let mut last_end = -1.0;
    for ((path, _), step) in report.written.iter().zip(&p.recordings) {
        let rec = Recording::read(path).unwrap();
        let start = rec.meta.t_session_start_s.unwrap();
        // Back to back, or later (a tare, a prompt).
        assert!(
            start >= last_end - 1e-9,
            "{}: starts at {start}",
            path.display()
        );
        let want = step.rest_s + step.hold_s + step.off_s;
        let got = rec.t_s.last().unwrap() + 1e-3;
        assert!((got - want).abs() < 2e-3, "{}: {got} s", path.display());
        last_end = start + got;
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fault latched before a recording stops the session there: the
/// recordings before it are kept, nothing is recorded for it.
#[test]
fn a_latched_fault_stops_the_session_before_the_next_recording() {
    struct Sink;
    impl finrs_controller::FrameSink for Sink {
        fn try_write(&mut self, _: &[u8]) -> bool {
            true
        }
    }
    let protocol = Protocol::parse("p.toml", PROTOCOL).unwrap();
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    board
        .c
        .fault(finrs_frames::FaultCode::Other, None, &mut Sink);
    let dir = out_dir("faulted");
    let e = run_quietly(&mut board, &protocol, &dir).unwrap_err();
    assert!(matches!(&e, BenchError::Faulted { k: 1, .. }), "{e}");
    assert!(!dir.join("01_free_step_1.0V.csv").exists());
}

/// An operator who takes 5 s at a prompt: the board's buffered samples
/// from then are not the recording's, which starts after the prompt and
/// lasts its protocol's time, the wave where the protocol puts it.
#[test]
fn a_long_prompt_does_not_eat_the_next_recording() {
    // A prompt before the free recording too (no tare to skip the backlog).
    let text = PROTOCOL.replacen(
        "off_s = 0.5\n",
        "off_s = 0.5\nprompt = \"free the tip\"\n",
        1,
    );
    assert_ne!(text, PROTOCOL);
    let protocol = Protocol::parse("p.toml", &text).unwrap();
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let pause = board.pause.clone();
    let dir = out_dir("pause");
    let report = run_session(
        &mut board,
        &protocol,
        &dir,
        &BenchOptions::default(),
        None,
        &mut |_: &str| {
            pause.set((5000, None));
            Ok(())
        },
        &Silent,
    )
    .unwrap();
    let free = Recording::read(&report.written[0].0).unwrap();
    assert_eq!(free.t_s.len(), 2000);
    let v: Vec<f64> = free.v_v.rows().map(|r| r[0]).collect();
    let start = v.iter().position(|&x| x != 0.0).unwrap();
    assert!((500..=560).contains(&start), "wave from row {start}");
    let blocked = Recording::read(&report.written[1].0).unwrap();
    assert_eq!(blocked.t_s.len(), 2500);
    let v: Vec<f64> = blocked.v_v.rows().map(|r| r[0]).collect();
    let start = v.iter().position(|&x| x != 0.0).unwrap();
    assert!((400..=460).contains(&start), "wave from row {start}");
    assert!((v[1500] - 2.0).abs() < 1e-6, "{}", v[1500]);
    let t0 = blocked.meta.t_session_start_s.unwrap();
    assert!(
        t0 > 7.0,
        "after the first recording and the 5 s pause: {t0}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
