//! The board as a whole-session client sees it: its force stream up
//! ([`Link`]) and commands down, through one owner of the probe
//! ([`Bounded`]) or a fake in the tests. `finrs calibrate` and
//! `finrs bench run` talk to it through this trait.

use std::time::{Duration, Instant};

use finrs_frames::{Command, Decoder, Event, Info};

use crate::link::capture::Link;
use crate::link::probe::{self, Bounded, ProbeError, Target, COMMAND_DOWN_CHANNEL};

/// The board: its stream, and commands down.
pub trait Board: Link {
    /// Sends one command whole.
    fn send(&mut self, command: &Command) -> Result<(), ProbeError>;
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

/// Asks for the board's Info frame and reads until it comes; `None` if it
/// did not within `timeout` (the stream read meanwhile is dropped).
pub fn request_info(board: &mut impl Board, timeout: Duration) -> Result<Option<Info>, ProbeError> {
    board.send(&Command::RequestInfo)?;
    let mut decoder = Decoder::new();
    let mut buf = vec![0u8; 16 * 1024];
    let started = Instant::now();
    while started.elapsed() < timeout {
        let n = board.read_force(&mut buf)?;
        let mut info = None;
        decoder.push(&buf[..n], &mut |e| {
            if let Event::Info(i) = e {
                info.get_or_insert(i);
            }
        });
        if info.is_some() {
            return Ok(info);
        }
        if n == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    Ok(None)
}
