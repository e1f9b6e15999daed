//! [`Bounded`]: a thread that owns the [`Target`] (the probe-rs session and
//! its RTT) and serves one call at a time, while the caller waits at most a
//! bound for each answer. A call still running at its bound is abandoned
//! on its thread (a blocked USB transfer cannot be cancelled) and the link
//! is marked stalled: the call fails with a message naming what stalled
//! and for how long, and every later call fails at once, so the command
//! ends instead of hanging.

use std::path::Path;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use super::{ProbeError, Target};

/// How long each kind of call may take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timeouts {
    /// Reset, halt, run, memory writes, an RTT attach attempt, each RTT
    /// read or write.
    pub call: Duration,
    /// Writing an ELF image into flash (erasing and programming take
    /// seconds).
    pub flash: Duration,
}

type Job<T> = Box<dyn FnOnce(&mut T) + Send>;

/// A [`Target`] on its own thread, each call bounded in time.
pub struct Bounded<T: Target> {
    jobs: Option<mpsc::Sender<Job<T>>>,
    /// Disconnected when the thread has ended (and dropped the target).
    ended: mpsc::Receiver<()>,
    timeouts: Timeouts,
    /// What stalled, once a call has overrun its bound.
    stalled: Option<String>,
}

impl<T: Target> Bounded<T> {
    /// Moves `target` onto a new thread that serves the calls.
    pub fn new(target: T, timeouts: Timeouts) -> Result<Self, ProbeError> {
        let (jobs, inbox) = mpsc::channel::<Job<T>>();
        let (ended_tx, ended) = mpsc::channel::<()>();
        std::thread::Builder::new()
            .name("probe link".to_string())
            .spawn(move || {
                let _ended = ended_tx;
                let mut target = target;
                for job in inbox {
                    job(&mut target);
                }
                // The target (the probe-rs session) is dropped here, before
                // `_ended`: dropping the link waits for this.
                drop(target);
            })
            .map_err(|source| ProbeError::Thread {
                what: "the probe link".to_string(),
                source,
            })?;
        Ok(Bounded {
            jobs: Some(jobs),
            ended,
            timeouts,
            stalled: None,
        })
    }

    /// The bounds in force.
    pub fn timeouts(&self) -> Timeouts {
        self.timeouts
    }

    /// What stalled, if a call has overrun its bound (the link is then
    /// unusable).
    pub fn stalled(&self) -> Option<&str> {
        self.stalled.as_deref()
    }

    /// Runs `f` on the target's thread and waits at most `timeout` for it.
    fn call<R: Send + 'static>(
        &mut self,
        what: String,
        timeout: Duration,
        f: impl FnOnce(&mut T) -> Result<R, ProbeError> + Send + 'static,
    ) -> Result<R, ProbeError> {
        if let Some(earlier) = &self.stalled {
            return Err(ProbeError::Stuck {
                what,
                earlier: earlier.clone(),
            });
        }
        let (tx, rx) = mpsc::sync_channel(1);
        let job: Job<T> = Box::new(move |target| {
            let _ = tx.send(f(target));
        });
        if self
            .jobs
            .as_ref()
            .and_then(|jobs| jobs.send(job).ok())
            .is_none()
        {
            return Err(ProbeError::Ended { what });
        }
        match rx.recv_timeout(timeout) {
            Ok(answer) => answer,
            Err(RecvTimeoutError::Timeout) => {
                let stall = format!(
                    "{what} did not finish within {:.1} s",
                    timeout.as_secs_f64()
                );
                self.stalled = Some(stall.clone());
                Err(ProbeError::Stalled { stall })
            }
            // The job was dropped unanswered: it panicked on the thread.
            Err(RecvTimeoutError::Disconnected) => {
                self.stalled = Some(format!("{what} panicked in the probe link's thread"));
                Err(ProbeError::Panicked { what })
            }
        }
    }

    /// Writes the ELF image at `elf` into flash, within the flash bound.
    pub fn flash(&mut self, elf: &Path) -> Result<(), ProbeError> {
        let path = elf.to_path_buf();
        let what = format!("flashing {}", elf.display());
        let timeout = self.timeouts.flash;
        self.call(what, timeout, move |t| Ok(t.flash(&path)?))
    }

    /// Resets core 0 and halts it.
    pub fn reset_and_halt(&mut self) -> Result<(), ProbeError> {
        let timeout = self.timeouts.call;
        self.call("resetting and halting the core".into(), timeout, |t| {
            Ok(t.reset_and_halt()?)
        })
    }

    /// Writes `bytes` into target memory at `address`.
    pub fn write_memory(&mut self, address: u64, bytes: &[u8]) -> Result<(), ProbeError> {
        let bytes = bytes.to_vec();
        let what = format!("writing {} bytes at {address:#010x}", bytes.len());
        let timeout = self.timeouts.call;
        self.call(what, timeout, move |t| Ok(t.write_memory(address, &bytes)?))
    }

    /// Lets the halted core run.
    pub fn run(&mut self) -> Result<(), ProbeError> {
        let timeout = self.timeouts.call;
        self.call("starting the core".into(), timeout, |t| Ok(t.run()?))
    }

    /// One attempt to attach to the RTT control block.
    pub fn attach_rtt_once(&mut self, address: Option<u64>) -> Result<(), ProbeError> {
        let what = match address {
            Some(a) => format!("looking for the RTT control block at {a:#010x}"),
            None => "scanning RAM for the RTT control block".to_string(),
        };
        let timeout = self.timeouts.call;
        self.call(what, timeout, move |t| Ok(t.attach_rtt(address)?))
    }

    /// Reads what RTT up channel `channel` holds now into `buf`.
    pub fn read_up(&mut self, channel: usize, buf: &mut [u8]) -> Result<usize, ProbeError> {
        let len = buf.len();
        let timeout = self.timeouts.call;
        let got = self.call(
            format!("reading RTT up channel {channel}"),
            timeout,
            move |t| {
                let mut tmp = vec![0u8; len];
                let n = t.read_up(channel, &mut tmp)?;
                // A target claiming more than it was given is refused, not
                // sliced into a panic.
                if n > len {
                    return Err(ProbeError::ReadOverrun {
                        channel,
                        got: n,
                        room: len,
                    });
                }
                tmp.truncate(n);
                Ok(tmp)
            },
        )?;
        buf[..got.len()].copy_from_slice(&got);
        Ok(got.len())
    }

    /// Writes what fits now of `bytes` into RTT down channel `channel`.
    pub fn write_down(&mut self, channel: usize, bytes: &[u8]) -> Result<usize, ProbeError> {
        let bytes = bytes.to_vec();
        let len = bytes.len();
        let timeout = self.timeouts.call;
        let n = self.call(
            format!("writing RTT down channel {channel}"),
            timeout,
            move |t| Ok(t.write_down(channel, &bytes)?),
        )?;
        if n > len {
            return Err(ProbeError::WriteOverrun {
                channel,
                got: n,
                given: len,
            });
        }
        Ok(n)
    }
}

impl<T: Target> Drop for Bounded<T> {
    /// Ends the thread and waits (at most the call bound) for it to drop
    /// the target, so that the probe is released before the process exits.
    /// A stalled thread is left behind: the process exit ends it.
    fn drop(&mut self) {
        drop(self.jobs.take());
        if self.stalled.is_none() {
            let _ = self.ended.recv_timeout(self.timeouts.call);
        }
    }
}
