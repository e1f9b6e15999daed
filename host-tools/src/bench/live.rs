//! `finrs bench live`: a terminal view while recording, and keys that
//! command the board through the same link.
//!
//! The view shows the force and each segment's current over the last
//! [`WINDOW_S`], the wave and the limit in force, what was lost (gaps,
//! corrupt bytes, faults) and the firmware's log. Keys: `w` a wave (typed,
//! checked as `finrs wave` checks it, sent on Enter), `l` a lower limit,
//! `s` stop, `t` tare, `c` clear a fault, `m` mark an event (written into
//! the recording's notes with its time), `q` end and write the recording.
//! The recording, its journal and its account are `finrs log`'s.
//!
//! The state ([`LiveState`]) is pure: keys in, commands out, a frame drawn
//! on any ratatui backend, so the tests drive it, and the whole loop
//! ([`run_live`]), with the fake board and ratatui's test backend.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use finrs_frames::{Command, Decoder, Event, Info};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Paragraph};
use ratatui::{Frame, Terminal};

use crate::link::board::Board;
use crate::link::capture::journal::Journal;
use crate::link::capture::{finish, CaptureError, CaptureOptions, Monitor};
use crate::link::command::{limit_command, wave_command};
use crate::link::defmt_log::{Log, Table};
use crate::link::stream::{Recorder, Summary};
use crate::wave::WaveOptions;

/// The traces' span, s.
pub const WINDOW_S: f64 = 5.0;

/// Log lines kept on screen.
const MESSAGES: usize = 6;

/// A key, as the view takes it (the binary maps the terminal's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// A printable character.
    Char(char),
    /// Enter.
    Enter,
    /// Escape.
    Esc,
    /// Backspace.
    Backspace,
}

/// What a key asks of the loop.
// A Command carries a SetModel's 254-byte record by value (it is
// `no_std`); an action is handed over once, not stored.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Nothing beyond the view.
    None,
    /// Send this command.
    Send(Command),
    /// Mark an event in the recording.
    Mark,
    /// End and write the recording.
    Quit,
}

/// A line being typed.
#[derive(Clone, Debug, PartialEq)]
enum Input {
    Wave(String),
    Limit(String),
}

/// What the view shows.
#[derive(Clone, Debug, Default)]
pub struct LiveState {
    info: Option<Info>,
    wave: Option<String>,
    input: Option<Input>,
    messages: VecDeque<String>,
    force: VecDeque<(f64, f64)>,
    currents: Vec<VecDeque<(f64, f64)>>,
    summary: Summary,
    marks: usize,
}

impl LiveState {
    /// Nothing seen yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes a decoder event: the Info, a Sample into the traces.
    pub fn on_event(&mut self, e: &Event) {
        match e {
            Event::Info(i) => self.info = Some(*i),
            Event::Sample(s) => {
                let t = f64::from(s.t_us) / 1e6;
                push(&mut self.force, (t, f64::from(s.force_n)));
                if self.currents.len() != s.n {
                    self.currents = vec![VecDeque::new(); s.n];
                }
                for (trace, &i) in self.currents.iter_mut().zip(s.currents()) {
                    push(trace, (t, f64::from(i)));
                }
            }
            _ => {}
        }
    }

    /// The recorder's totals, for the status line.
    pub fn set_summary(&mut self, s: Summary) {
        self.summary = s;
    }

    /// A line for the log pane (the firmware's log, a refusal, a mark).
    pub fn message(&mut self, text: impl Into<String>) {
        if self.messages.len() == MESSAGES {
            self.messages.pop_front();
        }
        self.messages.push_back(text.into());
    }

    /// Segments, from the Info (3 until it comes).
    fn segments(&self) -> usize {
        self.info.map_or(3, |i| usize::from(i.segments))
    }

    /// A key: a command, a mark, the end, or an edit of the line typed.
    pub fn on_key(&mut self, key: Key) -> Action {
        if let Some(input) = &mut self.input {
            let text = match input {
                Input::Wave(t) | Input::Limit(t) => t,
            };
            match key {
                Key::Char(c) => text.push(c),
                Key::Backspace => {
                    text.pop();
                }
                Key::Esc => self.input = None,
                Key::Enter => {
                    let input = self.input.take().expect("typing");
                    return self.submit(input);
                }
            }
            return Action::None;
        }
        match key {
            Key::Char('w') => self.input = Some(Input::Wave(String::new())),
            Key::Char('l') => self.input = Some(Input::Limit(String::new())),
            Key::Char('s') => return Action::Send(Command::Stop),
            Key::Char('t') => return Action::Send(Command::Tare),
            Key::Char('c') => return Action::Send(Command::ClearFault),
            Key::Char('m') => {
                self.marks += 1;
                return Action::Mark;
            }
            Key::Char('q') | Key::Esc => return Action::Quit,
            _ => {}
        }
        Action::None
    }

    /// A typed line, checked as `finrs wave` and `finrs limit` check it.
    fn submit(&mut self, input: Input) -> Action {
        match input {
            Input::Wave(text) => {
                let options = WaveOptions {
                    ramp_in_s: 1.0,
                    ..WaveOptions::steady(10.0)
                };
                match wave_command(text.trim(), self.segments(), &options) {
                    Ok(c) => {
                        self.wave = Some(text.trim().to_string());
                        Action::Send(c)
                    }
                    Err(e) => {
                        self.message(format!("refused: {e}"));
                        Action::None
                    }
                }
            }
            Input::Limit(text) => match text.trim().parse::<f64>() {
                Ok(v) => match limit_command(v) {
                    Ok(c) => Action::Send(c),
                    Err(e) => {
                        self.message(format!("refused: {e}"));
                        Action::None
                    }
                },
                Err(_) => {
                    self.message(format!("refused: limit {text:?} is not a number of volts"));
                    Action::None
                }
            },
        }
    }

    /// Draws the view.
    pub fn render(&self, f: &mut Frame) {
        let [status, force, currents, log, help] = Layout::vertical([
            // Two lines inside the border.
            Constraint::Length(4),
            Constraint::Min(6),
            Constraint::Min(6),
            Constraint::Length(MESSAGES as u16 + 2),
            Constraint::Length(1),
        ])
        .areas(f.area());
        let s = &self.summary;
        let board = match &self.info {
            Some(i) => format!(
                "{} segments, {} Hz, limit {} V",
                i.segments, i.sample_hz, i.max_abs_v
            ),
            None => "no Info frame yet".to_string(),
        };
        let text = vec![
            Line::from(format!(
                "{} samples, {} lost in {} gaps, {} corrupt bytes, {} faults, {} marks",
                s.rows, s.lost_samples, s.gaps, s.corrupt_bytes, s.faults, self.marks
            )),
            Line::from(format!(
                "{board}; wave {}",
                self.wave.as_deref().unwrap_or("none sent")
            )),
        ];
        f.render_widget(
            Paragraph::new(text).block(Block::bordered().title("finrs bench live")),
            status,
        );
        // The chart borrows its points for the frame: copied out of the
        // ring buffers, drawn, dropped.
        let force_points: Vec<(f64, f64)> = self.force.iter().copied().collect();
        f.render_widget(chart("force (N)", &[&force_points]), force);
        let current_points: Vec<Vec<(f64, f64)>> = self
            .currents
            .iter()
            .map(|t| t.iter().copied().collect())
            .collect();
        let traces: Vec<&[(f64, f64)]> = current_points.iter().map(Vec::as_slice).collect();
        f.render_widget(chart("currents (A)", &traces), currents);
        let lines: Vec<Line> = self
            .messages
            .iter()
            .map(|m| Line::from(m.as_str()))
            .collect();
        f.render_widget(
            Paragraph::new(lines).block(Block::bordered().title("log")),
            log,
        );
        let help_text = match &self.input {
            Some(Input::Wave(t)) => {
                format!("wave (e.g. sine:2,1,120), Enter to send, Esc to cancel: {t}")
            }
            Some(Input::Limit(t)) => format!("new limit, V (lower only), Enter to send: {t}"),
            None => "w wave  l limit  s stop  t tare  c clear fault  m mark  q quit and write"
                .to_string(),
        };
        f.render_widget(Paragraph::new(help_text), help);
    }
}

/// Appends `p` and drops what fell out of the window.
fn push(trace: &mut VecDeque<(f64, f64)>, p: (f64, f64)) {
    // A time that went back (a restart) starts the trace anew.
    if trace.back().is_some_and(|&(t, _)| p.0 < t) {
        trace.clear();
    }
    trace.push_back(p);
    while trace.front().is_some_and(|&(t, _)| p.0 - t > WINDOW_S) {
        trace.pop_front();
    }
}

const COLOURS: [Color; 8] = [
    Color::Yellow,
    Color::Cyan,
    Color::Magenta,
    Color::Green,
    Color::Red,
    Color::Blue,
    Color::White,
    Color::LightRed,
];

/// A line chart of `traces` over the window ending at their last time.
fn chart<'a>(title: &'a str, traces: &[&'a [(f64, f64)]]) -> Chart<'a> {
    let end = traces
        .iter()
        .filter_map(|t| t.last().map(|p| p.0))
        .fold(WINDOW_S, f64::max);
    let (lo, hi) = traces
        .iter()
        .flat_map(|t| t.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 1e-6, lo + 1e-6)
    } else {
        (-1.0, 1.0)
    };
    let datasets = traces
        .iter()
        .enumerate()
        .map(|(k, &points)| {
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(COLOURS[k % COLOURS.len()]))
                .data(points)
        })
        .collect();
    Chart::new(datasets)
        .block(Block::bordered().title(title))
        .x_axis(
            Axis::default()
                .bounds([end - WINDOW_S, end])
                .labels([format!("{:.1} s", end - WINDOW_S), format!("{end:.1} s")]),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([format!("{lo:.3e}"), format!("{hi:.3e}")]),
        )
}

/// Why the live view wrote nothing (a link, terminal or key source that
/// fails ends it, and what came is written with why in its notes).
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The capture (journal, recording) failed.
    #[error(transparent)]
    Capture(#[from] CaptureError),
}

/// Collects monitor lines (the firmware's log) for the view.
#[derive(Default)]
struct Lines(std::cell::RefCell<Vec<String>>);

impl Monitor for Lines {
    fn line(&self, text: &str) {
        self.0.borrow_mut().push(text.to_string());
    }
    fn status(&self, _: &str) {}
}

/// Records from `board` into `opts.out` (with its journal) while drawing
/// the view on `term` and taking keys from `keys` (`None`: no key now)
/// until `q` (or `opts.duration_s`); then writes the recording and
/// returns `finrs log`'s report. A link, terminal or key source that fails
/// ends the view; what came is written, with why in its notes.
pub fn run_live<B: ratatui::backend::Backend>(
    board: &mut impl Board,
    table: Option<&Table>,
    opts: &CaptureOptions,
    term: &mut Terminal<B>,
    keys: &mut dyn FnMut() -> std::io::Result<Option<Key>>,
) -> Result<String, LiveError> {
    let mut journal = Some(Journal::create(&opts.out)?);
    let mut rec = Recorder::new(opts.setup.clone());
    let mut state = LiveState::new();
    let mut decoder = Decoder::new();
    let mut log = table.map(Log::new);
    let lines = Lines::default();
    let mut buf = vec![0u8; 16 * 1024];
    let mut drawn = Instant::now() - Duration::from_secs(1);
    let started = Instant::now();
    if let Err(e) = board.send(&Command::RequestInfo) {
        state.message(format!("not sent: {e}"));
    }
    // Whatever ends the loop, what came is written; why it ended early
    // goes into the notes.
    let stopped: Option<String> = loop {
        let n = match board.read_force(&mut buf) {
            Ok(n) => n,
            Err(e) => break Some(format!("the link failed: {e}")),
        };
        if let Some(j) = &mut journal {
            // A journal that cannot be written (a full disk) does not end
            // the recording, which is still whole in memory.
            if let Err(e) = j.append(&buf[..n]) {
                state.message(format!("{e}; recording on without it"));
                journal = None;
            }
        }
        let mut events = Vec::new();
        decoder.push(&buf[..n], &mut |e| events.push(e));
        for e in events {
            state.on_event(&e);
            rec.event(e);
        }
        let mut m = 0;
        if let Some(log) = log.as_mut() {
            m = match board.read_log(&mut buf) {
                Ok(m) => m,
                Err(e) => break Some(format!("the link failed: {e}")),
            };
            log.show(&buf[..m], &mut |l| lines.line(l));
            for l in lines.0.borrow_mut().drain(..) {
                state.message(l);
            }
        }
        let mut quit = false;
        loop {
            let key = match keys() {
                Ok(Some(key)) => key,
                Ok(None) => break,
                Err(e) => {
                    rec.stopped_early(format!("reading the keys failed: {e}"));
                    quit = true;
                    break;
                }
            };
            match state.on_key(key) {
                Action::None => {}
                Action::Send(c) => {
                    if let Err(e) = board.send(&c) {
                        state.message(format!("not sent: {e}"));
                    }
                }
                Action::Mark => {
                    let text = rec.mark();
                    state.message(text);
                }
                Action::Quit => quit = true,
            }
        }
        // `--duration-s` ends it as `q` does.
        if opts
            .duration_s
            .is_some_and(|d| started.elapsed().as_secs_f64() >= d)
        {
            quit = true;
        }
        if drawn.elapsed() >= Duration::from_millis(100) || quit {
            drawn = Instant::now();
            state.set_summary(rec.summary());
            if let Err(e) = term.draw(|f| state.render(f)) {
                break Some(format!("the terminal failed: {e}"));
            }
        }
        if quit {
            break None;
        }
        if n == 0 && m == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
    };
    if let Some(why) = stopped {
        rec.stopped_early(why);
    }
    let report = finish(rec, &opts.out)?;
    if let Some(j) = journal {
        j.remove()?;
    }
    Ok(report)
}

#[cfg(test)]
mod tests;
