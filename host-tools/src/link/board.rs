//! The board as a whole-session client sees it: its force stream up
//! ([`Link`]) and commands down, through one owner of the probe
//! ([`Bounded`]) or a fake in the tests. `finrs calibrate`, `finrs bench
//! run` and `finrs bench live` talk to it through this trait, and read its
//! stream through [`Frames`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use finrs_frames::{Command, Decoder, Event, Info};

use crate::link::capture::{Link, Monitor, Silent};
use crate::link::defmt_log::{Log, Table};
use crate::link::probe::{self, Bounded, ProbeError, Target, COMMAND_DOWN_CHANNEL};

/// The board: its stream, and commands down; on the virtual bench, the
/// world around it too.
pub trait Board: Link {
    /// Sends one command whole.
    fn send(&mut self, command: &Command) -> Result<(), ProbeError>;

    /// Puts the strip free (the camera on `dots_s_m`) or blocked for the
    /// next recording. At a real bench the operator does it, asked by the
    /// protocol's prompt: nothing to do here.
    fn set_fixture(&mut self, _free: bool, _dots_s_m: &[f64]) -> Result<(), ProbeError> {
        Ok(())
    }

    /// The camera's track of sample periods `first..=last` as a
    /// tracker's CSV (see `camera::track`), on the virtual bench; a real
    /// bench's camera is tracked off-line (none here).
    fn camera_track(
        &mut self,
        _first: u32,
        _last: u32,
        _stretch: &TrackStretch<'_>,
    ) -> Option<String> {
        None
    }
}

/// What a camera track needs of the recording beside its periods.
#[derive(Clone, Copy, Debug)]
pub struct TrackStretch<'a> {
    /// The board's sample rate, Hz.
    pub sample_hz: f64,
    /// The tracked dots, m from the clamp.
    pub dots_s_m: &'a [f64],
    /// The strip's free length (the tip's place), m.
    pub length_m: f64,
}

impl<T: Target> Board for Bounded<T> {
    fn send(&mut self, command: &Command) -> Result<(), ProbeError> {
        let timeout = self.timeouts().call;
        probe::write_all(
            self,
            COMMAND_DOWN_CHANNEL,
            &crate::link::command::encode(command),
            timeout,
        )
    }
}

/// The board's stream decoded into events, one at a time, and its defmt
/// log shown as it comes (when the ELF's table is known).
pub struct Frames<'t> {
    decoder: Decoder,
    pending: VecDeque<Event>,
    buf: Vec<u8>,
    log: Option<Log<'t>>,
}

impl<'t> Frames<'t> {
    /// At the start of the stream, with the ELF's defmt `table` if known.
    pub fn new(table: Option<&'t Table>) -> Self {
        Self {
            decoder: Decoder::new(),
            pending: VecDeque::new(),
            buf: vec![0; 16 * 1024],
            log: table.map(Log::new),
        }
    }

    /// The next event, reading the board as needed; `None` after
    /// `timeout` of silence. The firmware's log lines go to `monitor`.
    pub fn next(
        &mut self,
        board: &mut impl Board,
        timeout: Duration,
        monitor: &dyn Monitor,
    ) -> Result<Option<Event>, ProbeError> {
        let started = Instant::now();
        loop {
            if let Some(e) = self.pending.pop_front() {
                return Ok(Some(e));
            }
            if started.elapsed() >= timeout {
                return Ok(None);
            }
            let n = board.read_force(&mut self.buf)?;
            let pending = &mut self.pending;
            self.decoder
                .push(&self.buf[..n], &mut |e| pending.push_back(e));
            let mut m = 0;
            if let Some(log) = self.log.as_mut() {
                // The firmware's refusals and faults, in its own words.
                m = board.read_log(&mut self.buf)?;
                log.show(&self.buf[..m], &mut |l| monitor.line(l));
            }
            if n == 0 && m == 0 {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }

    /// Asks for an Info frame and drops every event before it: what the
    /// board buffered while the host was not reading (an operator's
    /// prompt) is behind, and the events after it are the board's present.
    /// Returns the Info; `None` if it did not come within `timeout`.
    pub fn barrier(
        &mut self,
        board: &mut impl Board,
        timeout: Duration,
        monitor: &dyn Monitor,
    ) -> Result<Option<Info>, ProbeError> {
        board.send(&Command::RequestInfo)?;
        let started = Instant::now();
        while let Some(left) = timeout.checked_sub(started.elapsed()) {
            match self.next(board, left, monitor)? {
                Some(Event::Info(i)) => return Ok(Some(i)),
                Some(_) => {}
                None => break,
            }
        }
        Ok(None)
    }
}

/// Asks for the board's Info frame and reads until it comes; `None` if it
/// did not within `timeout` (the stream read meanwhile is dropped).
pub fn request_info(board: &mut impl Board, timeout: Duration) -> Result<Option<Info>, ProbeError> {
    Frames::new(None).barrier(board, timeout, &Silent)
}
