//! The bounds and the flash-and-run sequence with a fake target that
//! hangs, fails or models the RTT control block in RAM (no probe here).

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::*;
use crate::link::causes::with_causes;

/// The ID at the start of an RTT control block, as the firmware's RTT
/// writes it once running.
const RTT_ID: [u8; RTT_ID_LEN] = *b"SEGGER RTT\0\0\0\0\0\0";

#[cfg(feature = "probe")]
#[test]
fn the_fakes_rtt_id_is_probe_rs_s() {
    assert_eq!(RTT_ID, probe_rs::rtt::Rtt::RTT_ID);
}

/// Where the fake firmware's `_SEGGER_RTT` is (the real release build's).
pub(crate) const RTT_AT: u64 = 0x2001_d970;

/// What a fake call does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Act {
    /// Answers normally.
    Answer,
    /// Never returns (a stalled USB transfer).
    Hang,
    /// Returns an error.
    Fail,
}

/// Blocks the calling thread for ever.
fn hang() -> ! {
    loop {
        std::thread::park();
    }
}

/// A target whose calls answer, hang or fail as set, which logs every call
/// and models the RTT control block's ID in RAM: the previous run's block
/// is there at first, and the "firmware" writes a new one on its
/// `init_after`-th attach attempt after `run`.
pub(crate) struct FakeTarget {
    pub(crate) calls: Arc<Mutex<Vec<String>>>,
    pub(crate) flash: Act,
    pub(crate) attach: Act,
    /// Chunks the force channel hands out, then `after_up`.
    pub(crate) up: VecDeque<Vec<u8>>,
    pub(crate) after_up: Act,
    pub(crate) write: Act,
    /// Bytes the down channel takes per call.
    pub(crate) room: usize,
    pub(crate) received: Arc<Mutex<Vec<u8>>>,
    /// The ID at `RTT_AT`.
    pub(crate) id: [u8; 16],
    /// Attach attempts after `run` before the new firmware's `rtt_init!`
    /// has written its block; `None`: it never does.
    pub(crate) init_after: Option<usize>,
    pub(crate) running: bool,
    pub(crate) attempts: usize,
    /// Set when the link's thread drops the target.
    pub(crate) dropped: Arc<AtomicBool>,
}

impl FakeTarget {
    pub(crate) fn new() -> Self {
        FakeTarget {
            calls: Arc::default(),
            flash: Act::Answer,
            attach: Act::Answer,
            up: VecDeque::new(),
            after_up: Act::Answer,
            write: Act::Answer,
            room: usize::MAX,
            received: Arc::default(),
            id: RTT_ID,
            init_after: Some(0),
            running: true,
            attempts: 0,
            dropped: Arc::default(),
        }
    }

    fn log(&self, call: String) {
        self.calls.lock().unwrap().push(call);
    }
}

impl Drop for FakeTarget {
    fn drop(&mut self) {
        self.dropped.store(true, Ordering::SeqCst);
    }
}

impl Target for FakeTarget {
    fn flash(&mut self, elf: &Path) -> Result<(), TargetError> {
        self.log(format!("flash {}", elf.display()));
        match self.flash {
            Act::Answer => Ok(()),
            Act::Hang => hang(),
            Act::Fail => Err(TargetError::new("flash algorithm failed")),
        }
    }

    fn reset_and_halt(&mut self) -> Result<(), TargetError> {
        self.log("reset_and_halt".into());
        // RAM, and with it the old control block, survives the reset.
        self.running = false;
        self.attempts = 0;
        Ok(())
    }

    fn write_memory(&mut self, address: u64, bytes: &[u8]) -> Result<(), TargetError> {
        self.log(format!("write {bytes:?} at {address:#x}"));
        if address == RTT_AT && bytes.len() == 16 {
            self.id.copy_from_slice(bytes);
        }
        Ok(())
    }

    fn run(&mut self) -> Result<(), TargetError> {
        self.log("run".into());
        self.running = true;
        Ok(())
    }

    fn attach_rtt(&mut self, address: Option<u64>) -> Result<(), TargetError> {
        match self.attach {
            Act::Answer => {}
            Act::Hang => hang(),
            Act::Fail => return Err(TargetError::new("probe error")),
        }
        if self.running && self.init_after.is_some_and(|k| self.attempts >= k) {
            self.id = RTT_ID;
        }
        self.attempts += 1;
        if address != Some(RTT_AT) || self.id != RTT_ID {
            return Err(TargetError::new("control block not found"));
        }
        let new = self.init_after.is_some_and(|k| self.attempts > k);
        self.log(format!(
            "attached to the {} block",
            if new { "new" } else { "stale" }
        ));
        Ok(())
    }

    fn read_up(&mut self, channel: usize, buf: &mut [u8]) -> Result<usize, TargetError> {
        if channel != FORCE_UP_CHANNEL {
            return Ok(0);
        }
        match self.up.pop_front() {
            Some(chunk) => {
                buf[..chunk.len()].copy_from_slice(&chunk);
                Ok(chunk.len())
            }
            None => match self.after_up {
                Act::Answer => Ok(0),
                Act::Hang => hang(),
                Act::Fail => Err(TargetError::new("probe unplugged")),
            },
        }
    }

    fn write_down(&mut self, _channel: usize, bytes: &[u8]) -> Result<usize, TargetError> {
        match self.write {
            Act::Answer => {}
            Act::Hang => hang(),
            Act::Fail => return Err(TargetError::new("probe error")),
        }
        let n = bytes.len().min(self.room);
        self.received.lock().unwrap().extend_from_slice(&bytes[..n]);
        Ok(n)
    }
}

pub(crate) fn timeouts(call_s: f64, flash_s: f64) -> Timeouts {
    Timeouts {
        call: Duration::from_secs_f64(call_s),
        flash: Duration::from_secs_f64(flash_s),
    }
}

/// Asserts that `took` is at least `bound` and not much more.
fn within(took: Duration, bound: Duration) {
    assert!(
        took >= bound && took < bound + Duration::from_secs(1),
        "took {took:?} for a bound of {bound:?}"
    );
}

#[test]
fn a_hanging_write_fails_within_its_bound_and_the_link_then_refuses_at_once() {
    let mut fake = FakeTarget::new();
    fake.write = Act::Hang;
    let mut link = Bounded::new(fake, timeouts(0.2, 10.0)).unwrap();
    let started = Instant::now();
    let e = write_all(
        &mut link,
        COMMAND_DOWN_CHANNEL,
        b"stop",
        Duration::from_secs(5),
    )
    .unwrap_err()
    .to_string();
    within(started.elapsed(), Duration::from_millis(200));
    assert!(
        e.starts_with("writing RTT down channel 0 did not finish within 0.2 s: "),
        "{e}"
    );
    let started = Instant::now();
    let e = link.run().unwrap_err().to_string();
    assert!(started.elapsed() < Duration::from_millis(100));
    assert_eq!(
        e,
        "starting the core: not tried, the probe link is stuck \
         (writing RTT down channel 0 did not finish within 0.2 s)"
    );
    assert_eq!(
        link.stalled(),
        Some("writing RTT down channel 0 did not finish within 0.2 s")
    );
}

#[test]
fn a_write_goes_through_in_pieces_and_a_full_channel_fails_after_its_timeout() {
    let mut fake = FakeTarget::new();
    fake.room = 3;
    let received = fake.received.clone();
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    write_all(&mut link, 0, b"0123456789", Duration::from_secs(1)).unwrap();
    assert_eq!(received.lock().unwrap().as_slice(), b"0123456789");

    let mut fake = FakeTarget::new();
    fake.room = 0;
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    let started = Instant::now();
    let e = write_all(&mut link, 0, b"x", Duration::from_millis(300)).unwrap_err();
    within(started.elapsed(), Duration::from_millis(300));
    assert_eq!(
        e.to_string(),
        "RTT down channel 0 stayed full for 0.3 s: is the firmware reading commands?"
    );
    assert_eq!(link.stalled(), None);
}

#[test]
fn flashing_has_its_own_longer_bound() {
    let mut fake = FakeTarget::new();
    fake.flash = Act::Hang;
    let mut link = Bounded::new(fake, timeouts(0.1, 0.5)).unwrap();
    let started = Instant::now();
    let e = flash_and_run(&mut link, Path::new("fw.elf"), RTT_AT).unwrap_err();
    within(started.elapsed(), Duration::from_millis(500));
    assert!(
        e.to_string()
            .starts_with("flashing fw.elf did not finish within 0.5 s: "),
        "{e}"
    );
}

#[test]
fn an_error_passes_through_and_leaves_the_link_usable() {
    let mut fake = FakeTarget::new();
    fake.flash = Act::Fail;
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    let e = link.flash(Path::new("fw.elf")).unwrap_err();
    assert_eq!(e.to_string(), "flash algorithm failed");
    assert_eq!(link.stalled(), None);
    link.reset_and_halt().unwrap();
}

#[test]
fn flash_and_run_zeroes_the_old_control_block_so_only_the_new_one_is_attached() {
    let mut fake = FakeTarget::new();
    // The new firmware sets up its block on the 4th attempt after run.
    fake.init_after = Some(3);
    let calls = fake.calls.clone();
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    flash_and_run(&mut link, Path::new("fw.elf"), RTT_AT).unwrap();
    attach_rtt(&mut link, Some(RTT_AT), Duration::from_secs(2)).unwrap();
    assert_eq!(
        *calls.lock().unwrap(),
        vec![
            "flash fw.elf".to_string(),
            "reset_and_halt".to_string(),
            format!("write {:?} at {RTT_AT:#x}", [0u8; 16]),
            "run".to_string(),
            "attached to the new block".to_string(),
        ]
    );
}

#[test]
fn without_new_firmware_the_attach_fails_naming_the_address_instead_of_reading_stale_bytes() {
    let mut fake = FakeTarget::new();
    fake.init_after = None;
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    flash_and_run(&mut link, Path::new("fw.elf"), RTT_AT).unwrap();
    let started = Instant::now();
    let e = attach_rtt(&mut link, Some(RTT_AT), Duration::from_millis(300)).unwrap_err();
    within(started.elapsed(), Duration::from_millis(300));
    assert_eq!(
        with_causes(&e),
        "no RTT control block at 0x2001d970 after 0.3 s (is the firmware running and \
         built with RTT?): control block not found"
    );
}

#[test]
fn a_hanging_attach_is_not_retried() {
    let mut fake = FakeTarget::new();
    fake.attach = Act::Hang;
    let mut link = Bounded::new(fake, timeouts(0.2, 1.0)).unwrap();
    let started = Instant::now();
    let e = attach_rtt(&mut link, Some(RTT_AT), Duration::from_secs(5)).unwrap_err();
    within(started.elapsed(), Duration::from_millis(200));
    assert!(
        e.to_string().starts_with(
            "looking for the RTT control block at 0x2001d970 did not finish within 0.2 s"
        ),
        "{e}"
    );
}

#[test]
fn dropping_the_link_releases_the_target() {
    let fake = FakeTarget::new();
    let dropped = fake.dropped.clone();
    let mut link = Bounded::new(fake, timeouts(1.0, 1.0)).unwrap();
    link.run().unwrap();
    assert!(!dropped.load(Ordering::SeqCst));
    drop(link);
    assert!(dropped.load(Ordering::SeqCst));
}

#[test]
fn a_panicking_call_is_an_error_not_a_crash() {
    struct Panics;
    impl Target for Panics {
        fn flash(&mut self, _: &Path) -> Result<(), TargetError> {
            panic!("inside probe-rs")
        }
        fn reset_and_halt(&mut self) -> Result<(), TargetError> {
            Ok(())
        }
        fn write_memory(&mut self, _: u64, _: &[u8]) -> Result<(), TargetError> {
            Ok(())
        }
        fn run(&mut self) -> Result<(), TargetError> {
            Ok(())
        }
        fn attach_rtt(&mut self, _: Option<u64>) -> Result<(), TargetError> {
            Ok(())
        }
        fn read_up(&mut self, _: usize, _: &mut [u8]) -> Result<usize, TargetError> {
            Ok(0)
        }
        fn write_down(&mut self, _: usize, _: &[u8]) -> Result<usize, TargetError> {
            Ok(0)
        }
    }
    // A minute's timeout, so that "reported at once" and "timed out" are
    // far apart even on a loaded machine (a panic's report can take some
    // hundred milliseconds there).
    let mut link = Bounded::new(Panics, timeouts(60.0, 60.0)).unwrap();
    let started = Instant::now();
    let e = link.flash(&PathBuf::from("fw.elf")).unwrap_err();
    assert!(started.elapsed() < Duration::from_secs(30));
    assert_eq!(
        e.to_string(),
        "flashing fw.elf panicked in the probe link's thread"
    );
    assert!(link.run().is_err());
}
