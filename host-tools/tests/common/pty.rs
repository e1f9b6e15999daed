//! A terminal program run under a pseudo-terminal (util-linux `script`)
//! and fed keys, as a user at a terminal would.

use std::io::{Read, Write};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// The program under its pseudo-terminal.
pub struct Pty {
    child: Child,
    stdin: ChildStdin,
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
        Pty { child, stdin }
    }

    /// Types `bytes`, then waits `wait_ms`.
    pub fn keys(&mut self, bytes: &[u8], wait_ms: u64) {
        self.stdin.write_all(bytes).unwrap();
        self.stdin.flush().unwrap();
        std::thread::sleep(Duration::from_millis(wait_ms));
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
        let mut screen = String::new();
        self.child
            .stdout
            .take()
            .unwrap()
            .read_to_string(&mut screen)
            .unwrap();
        (status, screen)
    }
}
