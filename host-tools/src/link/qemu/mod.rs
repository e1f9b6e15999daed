//! The virtual bench: the firmware built for QEMU with `qemu-serial`
//! (`cd firmware && cargo build --release --no-default-features --features
//! qemu-serial`), run in `qemu-system-arm`'s netduinoplus2 with the model
//! core as the strip, and held as a [`Board`] like the real one, so that
//! `finrs bench run --qemu` goes through the same session code as a board.
//!
//! The firmware's frames and commands cross USART1, which QEMU connects to
//! a Unix socket this process holds (`-chardev socket,…,server=on,wait=on`:
//! the guest starts only once it is connected, so the stream is whole from
//! the boot on); its defmt log comes on QEMU's standard output
//! (semihosting). USART2, on a second socket, is the world around the
//! board ([`world`]): the strip free or blocked as the protocol says, and
//! a camera whose frames become a tracker's CSV for `finrs merge-camera`. QEMU counts the guest's time by its instructions
//! (`-icount shift=5,sleep=off`: 31 M instructions per simulated second,
//! slower than the board's 168 MHz, so a deadline kept here is kept there),
//! so the simulated clock does not depend on this machine's load, and it
//! runs faster than real time when the host keeps up. When this process
//! does not read, QEMU's writes wait and the guest's time stands still:
//! the virtual board drops nothing for a slow host.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, Command as Process, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use finrs_frames::Command;

pub mod world;

use crate::link::board::{Board, TrackStretch};
use crate::link::capture::Link;
use crate::link::defmt_log::{read_table, Table};
use crate::link::probe::{self, ProbeError, TargetError};

/// The QEMU this starts when not told otherwise (Debian's
/// `qemu-system-arm`, which `scripts/setup` installs).
pub const QEMU: &str = "qemu-system-arm";

/// Instructions' duration for `-icount`, as a power of two in ns (2^5 =
/// 32 ns: the firmware's SIL tests run at the same).
const ICOUNT_SHIFT: u32 = 5;

/// How the guest's clock runs against the wall's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pace {
    /// Idle time skipped (`sleep=off`): a session as fast as QEMU can run
    /// it (times are counted in the board's samples).
    Fast,
    /// Idle time slept and execution held back to the wall's clock
    /// (`sleep=on,align=on`): the board's clock keeps to the wall's where
    /// QEMU keeps up, for a live view.
    RealTime,
}

/// Why the virtual board could not start.
#[derive(Debug, thiserror::Error)]
pub enum VirtualError {
    /// The ELF could not be read.
    #[error(transparent)]
    Elf(#[from] ProbeError),
    /// Its defmt table is malformed.
    #[error("{elf}: its defmt table cannot be read: {reason}")]
    DefmtTable {
        /// The ELF.
        elf: String,
        /// defmt-decoder's reason.
        reason: String,
    },
    /// The folder for the socket could not be made.
    #[error("cannot create {}", dir.display())]
    Folder {
        /// The folder.
        dir: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// QEMU could not be started.
    #[error("cannot start {qemu} (is QEMU installed? scripts/setup installs it)")]
    Spawn {
        /// The program.
        qemu: String,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// QEMU stopped before its link carried anything.
    #[error("QEMU stopped ({status}) before the firmware sent a frame; it said: {stderr}")]
    Exited {
        /// Its exit status.
        status: String,
        /// What it printed on standard error.
        stderr: String,
    },
    /// QEMU did not open its socket in time.
    #[error("QEMU did not open {} within {timeout_s} s", path.display())]
    NoSocket {
        /// The socket's path.
        path: PathBuf,
        /// The wait, s.
        timeout_s: f64,
    },
    /// Nothing came on the link in time.
    #[error("no frame from the firmware in QEMU within {timeout_s} s (was {elf} built with --features qemu-serial?)")]
    Silent {
        /// The ELF.
        elf: String,
        /// The wait, s.
        timeout_s: f64,
    },
}

/// The firmware running in QEMU, as a board.
pub struct VirtualBoard {
    qemu: Qemu,
    socket: UnixStream,
    /// The world's channel (USART2), read whenever the link is, so that
    /// QEMU never waits on it.
    world: UnixStream,
    world_log: world::WorldLog,
    /// Link bytes read before the caller asked (the first frame's, read
    /// to know the USART listens; those read while waiting on the world).
    pending: Vec<u8>,
    log: Receiver<Vec<u8>>,
    log_pending: Vec<u8>,
    /// How long a command may wait for room in the socket.
    call_timeout: Duration,
}

/// The started board and the ELF's defmt table (if it has one).
pub struct Started {
    /// The board.
    pub board: VirtualBoard,
    /// The ELF's defmt table.
    pub table: Option<Table>,
}

/// The QEMU process and its socket's folder: both gone when dropped, on
/// every path out.
struct Qemu {
    child: Child,
    stderr: Option<ChildStderr>,
    dir: PathBuf,
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl Qemu {
    /// An error if QEMU has stopped, with what it said.
    fn check_running(&mut self) -> Result<(), VirtualError> {
        match self.child.try_wait() {
            Ok(Some(status)) => Err(VirtualError::Exited {
                status: status.to_string(),
                stderr: self.stderr_text(),
            }),
            _ => Ok(()),
        }
    }

    /// What QEMU printed on standard error; read only once it has stopped
    /// (before, the read would wait for it).
    fn stderr_text(&mut self) -> String {
        let mut text = String::new();
        if let Some(mut e) = self.stderr.take() {
            let _ = e.read_to_string(&mut text);
        }
        text.trim().to_string()
    }

    fn io_error(&self, source: std::io::Error) -> VirtualError {
        VirtualError::Folder {
            dir: self.dir.clone(),
            source,
        }
    }

    /// Connects to QEMU's socket once it is there.
    fn connect(&mut self, path: &Path, timeout: Duration) -> Result<UnixStream, VirtualError> {
        let start = Instant::now();
        loop {
            if let Ok(s) = UnixStream::connect(path) {
                return Ok(s);
            }
            self.check_running()?;
            if start.elapsed() > timeout {
                return Err(VirtualError::NoSocket {
                    path: path.to_path_buf(),
                    timeout_s: timeout.as_secs_f64(),
                });
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Reads until the firmware's first bytes come and returns them; the
    /// socket is then left non-blocking.
    fn first_bytes(
        &mut self,
        socket: &mut UnixStream,
        elf: &str,
        timeout: Duration,
    ) -> Result<Vec<u8>, VirtualError> {
        socket
            .set_read_timeout(Some(Duration::from_millis(50)))
            .map_err(|e| self.io_error(e))?;
        let start = Instant::now();
        let mut buf = [0u8; 4096];
        loop {
            match socket.read(&mut buf) {
                Ok(0) => {}
                Ok(n) => {
                    socket.set_nonblocking(true).map_err(|e| self.io_error(e))?;
                    return Ok(buf[..n].to_vec());
                }
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) => return Err(self.io_error(e)),
            }
            self.check_running()?;
            if start.elapsed() > timeout {
                return Err(VirtualError::Silent {
                    elf: elf.to_string(),
                    timeout_s: timeout.as_secs_f64(),
                });
            }
        }
    }
}

impl VirtualBoard {
    /// Starts `qemu` (see [`QEMU`]) on `elf` and waits up to `timeout`
    /// for the firmware's first bytes: until then its USART would drop
    /// what it is sent.
    pub fn start(
        qemu: &str,
        elf: &Path,
        pace: Pace,
        timeout: Duration,
    ) -> Result<Started, VirtualError> {
        let bytes = probe::read_elf(elf)?;
        let name = elf.display().to_string();
        let table = read_table(&bytes).map_err(|reason| VirtualError::DefmtTable {
            elf: name.clone(),
            reason,
        })?;
        let dir = socket_dir();
        std::fs::create_dir_all(&dir).map_err(|source| VirtualError::Folder {
            dir: dir.clone(),
            source,
        })?;
        let socket_path = dir.join("link.sock");
        let world_path = dir.join("world.sock");
        // Real time: idle periods slept, and execution held back whenever
        // the guest's clock runs ahead of the wall's (`align`).
        let (align, sleep) = match pace {
            Pace::Fast => ("off", "off"),
            Pace::RealTime => ("on", "on"),
        };
        let icount = format!("shift={ICOUNT_SHIFT},align={align},sleep={sleep}");
        let chardev = |id: &str, path: &Path| {
            format!("socket,id={id},path={},server=on,wait=on", path.display())
        };
        let spawned = Process::new(qemu)
            .args(["-cpu", "cortex-m4", "-machine", "netduinoplus2"])
            // No -nographic: it would put QEMU's monitor on the standard
            // output, where the defmt log comes.
            .args(["-display", "none", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .args(["-icount", &icount])
            // USART1, then USART2: QEMU waits for a client on each in turn.
            .args(["-chardev", &chardev("link", &socket_path)])
            .args(["-chardev", &chardev("world", &world_path)])
            .args(["-serial", "chardev:link", "-serial", "chardev:world"])
            .arg("-kernel")
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match spawned {
            Ok(c) => c,
            Err(source) => {
                let _ = std::fs::remove_dir_all(&dir);
                return Err(VirtualError::Spawn {
                    qemu: qemu.to_string(),
                    source,
                });
            }
        };
        let log = log_reader(child.stdout.take());
        let stderr = child.stderr.take();
        let mut qemu = Qemu { child, stderr, dir };
        let mut socket = qemu.connect(&socket_path, timeout)?;
        let world = qemu.connect(&world_path, timeout)?;
        world.set_nonblocking(true).map_err(|e| qemu.io_error(e))?;
        let first = qemu.first_bytes(&mut socket, &name, timeout)?;
        Ok(Started {
            board: VirtualBoard {
                qemu,
                socket,
                world,
                world_log: world::WorldLog::default(),
                pending: first,
                log,
                log_pending: Vec::new(),
                call_timeout: timeout,
            },
            table,
        })
    }

    fn link_error(&mut self, what: &str, source: Option<std::io::Error>) -> ProbeError {
        let status = match self.qemu.child.try_wait() {
            Ok(Some(s)) => format!("; QEMU stopped ({s}): {}", self.qemu.stderr_text()),
            _ => String::new(),
        };
        let what = format!("the virtual board's link: {what}{status}");
        ProbeError::Target(match source {
            Some(e) => TargetError::caused(what, e),
            None => TargetError::new(what),
        })
    }

    /// Reads what the link's socket holds now (0 when nothing came).
    fn read_link(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        match self.socket.read(buf) {
            Ok(0) if !buf.is_empty() => Err(self.link_error("QEMU closed it", None)),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(0),
            Err(e) => Err(self.link_error("reading", Some(e))),
        }
    }

    /// Reads what the world's channel holds now into the log.
    fn drain_world(&mut self) -> Result<(), ProbeError> {
        let mut buf = [0u8; 4096];
        loop {
            match self.world.read(&mut buf) {
                Ok(0) => return Err(self.link_error("QEMU closed the world's channel", None)),
                Ok(n) => self.world_log.push(&buf[..n]),
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(()),
                Err(e) => return Err(self.link_error("reading the world's channel", Some(e))),
            }
        }
    }

    /// Writes all of `bytes` to `socket` within the call's bound (a full
    /// socket is waited on: QEMU takes a byte at a time, as the guest
    /// reads them).
    fn write_bounded(&mut self, to_world: bool, bytes: &[u8]) -> Result<(), ProbeError> {
        let mut rest = bytes;
        let start = Instant::now();
        while !rest.is_empty() {
            let socket = if to_world {
                &mut self.world
            } else {
                &mut self.socket
            };
            match socket.write(rest) {
                Ok(n) => rest = &rest[n..],
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    if start.elapsed() > self.call_timeout {
                        return Err(self.link_error("no room to write", Some(e)));
                    }
                    // Keep the world read meanwhile: QEMU may be waiting
                    // on it before it takes more.
                    self.drain_world()?;
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(self.link_error("writing", Some(e))),
            }
        }
        Ok(())
    }
}

impl Link for VirtualBoard {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        self.drain_world()?;
        if !self.pending.is_empty() {
            let n = self.pending.len().min(buf.len());
            buf[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            return Ok(n);
        }
        self.read_link(buf)
    }

    fn read_log(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        while let Ok(chunk) = self.log.try_recv() {
            self.log_pending.extend_from_slice(&chunk);
        }
        let n = self.log_pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.log_pending[..n]);
        self.log_pending.drain(..n);
        Ok(n)
    }
}

impl Board for VirtualBoard {
    fn send(&mut self, command: &Command) -> Result<(), ProbeError> {
        self.write_bounded(false, &crate::link::command::encode(command))
    }

    fn set_fixture(&mut self, free: bool, dots_s_m: &[f64]) -> Result<(), ProbeError> {
        let before = self.world_log.clamped();
        self.write_bounded(true, &world::setup_bytes(free, dots_s_m))?;
        // Done only once the world says so: its bytes and the link's cross
        // different sockets, and a recording must not start before its
        // fixture. The link is read meanwhile (kept for the caller), so
        // that QEMU never waits on it.
        let start = Instant::now();
        let mut buf = [0u8; 4096];
        while self.world_log.clamped() == before {
            if start.elapsed() > self.call_timeout {
                return Err(self.link_error("the world did not take the fixture in time", None));
            }
            self.drain_world()?;
            match self.read_link(&mut buf)? {
                0 => std::thread::sleep(Duration::from_millis(1)),
                n => self.pending.extend_from_slice(&buf[..n]),
            }
        }
        Ok(())
    }

    fn camera_track(
        &mut self,
        first: u32,
        last: u32,
        stretch: &TrackStretch<'_>,
    ) -> Option<String> {
        // The stretch's last frames may still be on their way (the board
        // sends them every 20 ms): while the strip is free, frames keep
        // coming, so wait for one past the stretch, within a bound.
        let start = Instant::now();
        while self.drain_world().is_ok()
            && self
                .world_log
                .newest_frame()
                .is_some_and(|t| (first..=last).contains(&t))
            && start.elapsed() < Duration::from_secs(1)
        {
            std::thread::sleep(Duration::from_millis(2));
        }
        self.world_log.take_track(
            first,
            last,
            stretch.sample_hz,
            stretch.dots_s_m,
            stretch.length_m,
        )
    }
}

/// A fresh folder for the socket, short enough for a socket's path.
fn socket_dir() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static STARTS: AtomicUsize = AtomicUsize::new(0);
    let k = STARTS.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("finrs-qemu-{}-{k}", std::process::id()))
}

/// QEMU's standard output (the firmware's defmt log) read on a thread as
/// it comes, so that its pipe never fills and stops the guest.
fn log_reader(stdout: Option<std::process::ChildStdout>) -> Receiver<Vec<u8>> {
    let (tx, rx) = mpsc::channel();
    if let Some(mut out) = stdout {
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = out.read(&mut buf) {
                if n == 0 || tx.send(buf[..n].to_vec()).is_err() {
                    break;
                }
            }
        });
    }
    rx
}
