//! A terminal program run under a pseudo-terminal (util-linux `script`)
//! and fed keys, as a user at a terminal would.

use std::io::{Read, Write};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The program under its pseudo-terminal.
pub struct Pty {
    child: Child,
    stdin: ChildStdin,
    /// All it drew so far, read as it comes by `reader`.
    screen: Arc<Mutex<Vec<u8>>>,
    reader: JoinHandle<()>,
    /// The terminal's screen, as drawn so far.
    terminal: vt100::Parser,
    /// How much of `screen` `terminal` has drawn.
    drawn: usize,
}

impl Pty {
    /// Runs the shell line `command` on a 100 × 40 pseudo-terminal.
    pub fn spawn(command: &str) -> Pty {
        if Command::new("script").arg("--version").output().is_err() {
            panic!("util-linux `script` is needed for this test (Debian: bsdutils)");
        }
        let line = format!("stty cols 100 rows 40; {command}");
        let mut child = Command::new("script")
            .args(["-qec", &line, "/dev/null"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let mut stdout = child.stdout.take().unwrap();
        let screen = Arc::new(Mutex::new(Vec::new()));
        let into = Arc::clone(&screen);
        let reader = std::thread::spawn(move || {
            let mut chunk = [0u8; 4096];
            while let Ok(n) = stdout.read(&mut chunk) {
                if n == 0 {
                    break;
                }
                into.lock().unwrap().extend_from_slice(&chunk[..n]);
            }
        });
        Pty {
            child,
            stdin,
            screen,
            reader,
            terminal: vt100::Parser::new(40, 100, 0),
            drawn: 0,
        }
    }

    /// Types `bytes`, then waits `wait_ms`.
    pub fn keys(&mut self, bytes: &[u8], wait_ms: u64) {
        self.stdin.write_all(bytes).unwrap();
        self.stdin.flush().unwrap();
        std::thread::sleep(Duration::from_millis(wait_ms));
    }

    /// Waits up to `limit` until the screen, as a terminal shows it
    /// (its text, row by row), passes `shows`, else fails with the screen
    /// and `what` it waited for. The screen's text and not the bytes
    /// drawn: a terminal program redraws only the cells that changed.
    /// Returns the screen that passed.
    pub fn wait_until(
        &mut self,
        what: &str,
        limit: Duration,
        shows: impl Fn(&str) -> bool,
    ) -> String {
        let started = Instant::now();
        loop {
            {
                let bytes = self.screen.lock().unwrap();
                self.terminal.process(&bytes[self.drawn..]);
                self.drawn = bytes.len();
            }
            let text = self.terminal.screen().contents();
            if shows(&text) {
                return text;
            }
            if started.elapsed() > limit {
                panic!("not shown within {limit:?}: {what}; the screen:\n{text}");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Waits up to `limit` for the program to end (else kills it and
    /// fails, saying it `did_not`); its status and all it drew.
    pub fn finish(mut self, limit: Duration, did_not: &str) -> (ExitStatus, String) {
        let started = Instant::now();
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if started.elapsed() > limit {
                self.child.kill().unwrap();
                panic!("{did_not}");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        drop(self.stdin);
        self.reader.join().unwrap();
        let screen = String::from_utf8_lossy(&self.screen.lock().unwrap()).to_string();
        (status, screen)
    }
}
