//! The live view: keys to commands, the frame drawn, and the whole loop
//! against the fake board on ratatui's test backend.

use std::cell::Cell;
use std::rc::Rc;

use ratatui::backend::TestBackend;

use super::*;
use crate::link::capture::journal;
use crate::link::fake_board::FakeBoard;
use crate::link::stream::Setup;
use crate::recording::{Geometry, Medium, Recording};

fn typed(state: &mut LiveState, text: &str) -> Action {
    for c in text.chars() {
        assert_eq!(state.on_key(Key::Char(c)), Action::None);
    }
    state.on_key(Key::Enter)
}

fn screen(term: &Terminal<TestBackend>) -> String {
    let buf = term.backend().buffer();
    let width = buf.area.width as usize;
    buf.content()
        .chunks(width)
        .map(|row| row.iter().map(|c| c.symbol()).collect::<String>())
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn keys_become_checked_commands() {
    let mut s = LiveState::new();
    assert_eq!(s.on_key(Key::Char('s')), Action::Send(Command::Stop));
    assert_eq!(s.on_key(Key::Char('t')), Action::Send(Command::Tare));
    assert_eq!(s.on_key(Key::Char('c')), Action::Send(Command::ClearFault));
    assert_eq!(s.on_key(Key::Char('m')), Action::Mark);
    // A wave, typed with a slip, checked for 3 segments.
    assert_eq!(s.on_key(Key::Char('w')), Action::None);
    s.on_key(Key::Char('x'));
    s.on_key(Key::Backspace);
    let Action::Send(Command::SetWave { envelope, .. }) = typed(&mut s, "sine:2,1,120") else {
        panic!("not a wave");
    };
    assert_eq!(envelope.ramp_in_s, 1.0, "finrs wave's ramp");
    // Refused on the host, said in the log, nothing sent.
    s.on_key(Key::Char('w'));
    assert_eq!(typed(&mut s, "sine:2,300,0"), Action::None);
    assert!(s.messages.back().unwrap().contains("frequency_hz"));
    s.on_key(Key::Char('l'));
    assert_eq!(
        typed(&mut s, "1.5"),
        Action::Send(Command::SetLimit { max_abs_v: 1.5 })
    );
    s.on_key(Key::Char('l'));
    assert_eq!(typed(&mut s, "9"), Action::None);
    s.on_key(Key::Char('l'));
    assert_eq!(typed(&mut s, "high"), Action::None);
    assert!(s.messages.back().unwrap().contains("not a number"));
    // Esc leaves the line; a second Esc ends.
    s.on_key(Key::Char('w'));
    assert_eq!(s.on_key(Key::Esc), Action::None);
    assert_eq!(s.on_key(Key::Esc), Action::Quit);
    assert_eq!(s.on_key(Key::Char('q')), Action::Quit);
}

#[test]
fn the_frame_shows_the_board_the_wave_and_the_keys() {
    let mut s = LiveState::new();
    let mut term = Terminal::new(TestBackend::new(100, 40)).unwrap();
    term.draw(|f| s.render(f)).unwrap();
    let text = screen(&term);
    assert!(text.contains("no Info frame yet"), "{text}");
    assert!(text.contains("w wave  l limit  s stop"), "{text}");
    s.on_key(Key::Char('w'));
    s.on_key(Key::Char('s'));
    term.draw(|f| s.render(f)).unwrap();
    assert!(screen(&term).contains("Enter to send, Esc to cancel: s"));
}

/// A fresh folder `name-PID` and options that record `source` into its
/// `live.csv`, with no duration.
fn live_options(name: &str, source: &str) -> (std::path::PathBuf, CaptureOptions) {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let opts = CaptureOptions {
        out: dir.join("live.csv"),
        duration_s: None,
        setup: Setup {
            geometry: Geometry::THESIS_2006,
            medium: Medium::Air,
            sample: None,
            source: source.to_string(),
        },
    };
    (dir, opts)
}

/// The loop against the fake board: a wave typed and sent, a mark, the
/// end; the recording has the wave's volts, the mark and no journal left.
#[test]
fn the_loop_records_commands_and_marks() {
    let mut board = FakeBoard::new(Rc::new(Cell::new(0.0)));
    let (dir, opts) = live_options("finrs-live", "the fake board");
    // One key per loop turn (50 ms of the board's time each): wait 0.5 s
    // for the power-up tare, type a wave, let it run 2 s, mark, quit.
    let mut script: VecDeque<Option<Key>> = VecDeque::new();
    script.extend(std::iter::repeat_n(None, 10));
    script.push_back(Some(Key::Char('w')));
    script.extend("step:1".chars().map(|c| Some(Key::Char(c))));
    script.push_back(Some(Key::Enter));
    script.extend(std::iter::repeat_n(None, 40));
    script.push_back(Some(Key::Char('m')));
    script.push_back(None);
    script.push_back(Some(Key::Char('q')));
    // A key, then `None` for the rest of that turn.
    let mut turn_done = false;
    let mut keys = || -> std::io::Result<Option<Key>> {
        if turn_done {
            turn_done = false;
            return Ok(None);
        }
        turn_done = true;
        Ok(script.pop_front().flatten())
    };
    let mut term = Terminal::new(TestBackend::new(100, 40)).unwrap();
    let report = run_live(&mut board, None, &opts, &mut term, &mut keys).unwrap();
    assert!(
        report.contains("no gaps") || report.contains(" 0 lost in 0 gaps"),
        "{report}"
    );
    let rec = Recording::read(&opts.out).unwrap();
    let v: Vec<f64> = rec.v_v.rows().map(|r| r[0]).collect();
    assert!(v.iter().any(|&x| (x - 1.0).abs() < 1e-6), "the wave ran");
    assert_eq!(v[0], 0.0, "stopped until the wave");
    let notes = rec.meta.notes.unwrap();
    assert!(notes.contains("marks: mark 1 at t_s"), "{notes}");
    assert!(!journal::path_for(&opts.out).exists());
    let text = screen(&term);
    assert!(text.contains("wave step:1"), "{text}");
    assert!(text.contains("3 segments, 1000 Hz"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The fake board, failing after `reads` reads.
struct Failing {
    board: FakeBoard,
    reads: usize,
}

impl crate::link::capture::Link for Failing {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, crate::link::probe::ProbeError> {
        if self.reads == 0 {
            return Err(crate::link::probe::ProbeError::Target(
                crate::link::probe::TargetError::new("the probe went away"),
            ));
        }
        self.reads -= 1;
        self.board.read_force(buf)
    }
    fn read_log(&mut self, buf: &mut [u8]) -> Result<usize, crate::link::probe::ProbeError> {
        self.board.read_log(buf)
    }
}

impl Board for Failing {
    fn send(&mut self, c: &Command) -> Result<(), crate::link::probe::ProbeError> {
        self.board.send(c)
    }
}

#[test]
fn a_failing_link_ends_the_view_and_what_came_is_written() {
    let mut board = Failing {
        board: FakeBoard::new(Rc::new(Cell::new(0.0))),
        reads: 20,
    };
    let (dir, opts) = live_options("finrs-live-fail", "a failing board");
    let mut term = Terminal::new(TestBackend::new(100, 40)).unwrap();
    let report = run_live(&mut board, None, &opts, &mut term, &mut || Ok(None)).unwrap();
    assert!(report.contains("1000 samples"), "{report}");
    let notes = Recording::read(&opts.out).unwrap().meta.notes.unwrap();
    assert!(
        notes.contains("stopped early: the link failed: the probe went away"),
        "{notes}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
