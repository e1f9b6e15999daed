//! The recording loop with a stand-in link: stopping by Ctrl-C, by the
//! duration, and by a failing link all write what came so far.

use std::collections::VecDeque;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use finrs_frames::{encode_dropped, encode_sample, Dropped, Sample, MAX_FRAME_LEN};

use super::*;
use crate::link::probe::tests::{timeouts, Act, FakeTarget};
use crate::recording::Geometry;
use crate::recording::{Medium, Recording};

/// Hands out `chunks`, then either sets `stop` (as Ctrl-C would), fails,
/// or reads nothing for ever.
struct FakeLink {
    chunks: VecDeque<Vec<u8>>,
    then: Then,
    stop: Arc<AtomicBool>,
    log_reads: usize,
}

#[derive(Clone, Copy)]
enum Then {
    CtrlC,
    Fail,
    Idle,
}

impl Link for FakeLink {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        match self.chunks.pop_front() {
            Some(c) => {
                buf[..c.len()].copy_from_slice(&c);
                Ok(c.len())
            }
            None => match self.then {
                Then::CtrlC => {
                    self.stop.store(true, Ordering::SeqCst);
                    Ok(0)
                }
                Then::Fail => Err(crate::link::probe::TargetError::new("probe unplugged").into()),
                Then::Idle => Ok(0),
            },
        }
    }

    fn read_log(&mut self, _buf: &mut [u8]) -> Result<usize, ProbeError> {
        self.log_reads += 1;
        Ok(0)
    }
}

/// Samples 0..20 without 7 and 8 (reported dropped) and 12 (lost), split
/// into 13-byte chunks.
fn chunks() -> VecDeque<Vec<u8>> {
    let mut bytes = Vec::new();
    let mut buf = [0u8; MAX_FRAME_LEN];
    for seq in 0..20u32 {
        if seq == 7 {
            let n = encode_dropped(
                &Dropped {
                    first_seq: 7,
                    count: 2,
                },
                &mut buf,
            )
            .unwrap();
            bytes.extend_from_slice(&buf[..n]);
        }
        if seq == 7 || seq == 8 || seq == 12 {
            continue;
        }
        let s = Sample::<1> {
            seq,
            t_us: 1000 * seq,
            force_n: 0.01,
            flags: finrs_frames::SampleFlags::default(),
            voltages_v: [1.0],
            currents_a: [0.02],
        };
        let n = encode_sample(&s, &mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    bytes.chunks(13).map(|c| c.to_vec()).collect()
}

fn options(name: &str, duration_s: Option<f64>) -> CaptureOptions {
    let dir = std::env::temp_dir().join(format!("finrs-capture-{name}-{}", std::process::id()));
    CaptureOptions {
        out: dir.join("log.csv"),
        duration_s,
        setup: Setup {
            geometry: Geometry::THESIS_2006,
            medium: Medium::Air,
            sample: None,
            source: "a fake link".to_string(),
        },
    }
}

fn link(then: Then) -> (FakeLink, Arc<AtomicBool>) {
    let stop = Arc::new(AtomicBool::new(false));
    let link = FakeLink {
        chunks: chunks(),
        then,
        stop: stop.clone(),
        log_reads: 0,
    };
    (link, stop)
}

#[test]
fn ctrl_c_writes_every_sample_so_far_and_the_gap_report() {
    let (mut link, stop) = link(Then::CtrlC);
    let opts = options("ctrlc", None);
    let report = capture(&mut link, None, &stop, &opts, &Silent).unwrap();
    assert!(report.contains("17 samples; 3 lost in 2 gaps"), "{report}");
    assert!(report.contains("gap: seq 7..=8 (2 samples) dropped by the firmware (reported)"));
    assert!(report.contains("gap: seq 12..=12 (1 samples) lost on the way (detected)"));
    let rec = Recording::read(&opts.out).unwrap();
    assert_eq!(rec.t_s.len(), 17);
    assert!(rec
        .meta
        .notes
        .unwrap()
        .contains("7+2 reported, 12+1 detected"));
    // Without a defmt table the log channel is not read.
    assert_eq!(link.log_reads, 0);
    assert!(
        !journal::path_for(&opts.out).exists(),
        "the journal goes once the recording is written"
    );
    std::fs::remove_dir_all(opts.out.parent().unwrap()).unwrap();
}

/// A journal left by a capture that died is neither overwritten nor lost:
/// the next capture to the same file is refused, saying how to recover it,
/// and recovering it gives the same recording.
#[test]
fn a_journal_left_behind_is_refused_and_recovers_the_same_recording() {
    let (mut link, stop) = link(Then::CtrlC);
    let opts = options("left", None);
    let dir = opts.out.parent().unwrap().to_path_buf();
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let left = journal::path_for(&opts.out);
    let bytes: Vec<u8> = chunks().into_iter().flatten().collect();
    std::fs::write(&left, &bytes).unwrap();
    let e = capture(&mut link, None, &stop, &opts, &Silent).unwrap_err();
    assert!(matches!(e, CaptureError::JournalExists { .. }), "{e}");
    assert_eq!(std::fs::read(&left).unwrap(), bytes, "untouched");
    let report = from_bytes(&left, &opts).unwrap();
    assert!(report.contains("17 samples; 3 lost in 2 gaps"), "{report}");
    assert_eq!(Recording::read(&opts.out).unwrap().t_s.len(), 17);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_failing_link_still_writes_what_came() {
    let (mut link, stop) = link(Then::Fail);
    let opts = options("fail", None);
    let e = capture(&mut link, None, &stop, &opts, &Silent).unwrap_err();
    let text = with_causes(&e);
    assert!(
        text.contains("the link failed; the samples so far are in"),
        "{text}"
    );
    assert!(text.contains("probe unplugged"), "{text}");
    let rec = Recording::read(&opts.out).unwrap();
    assert_eq!(rec.t_s.len(), 17);
    assert!(rec
        .meta
        .notes
        .unwrap()
        .ends_with("; stopped early: the link failed: probe unplugged"));
    std::fs::remove_dir_all(opts.out.parent().unwrap()).unwrap();
}

/// The probe link itself (each read bounded on its own thread) over a
/// fake target whose force channel hangs after the chunks.
fn bounded_link(after: Act, call_s: f64) -> Bounded<FakeTarget> {
    let mut fake = FakeTarget::new();
    fake.up = chunks();
    fake.after_up = after;
    Bounded::new(fake, timeouts(call_s, 10.0)).unwrap()
}

#[test]
fn a_hanging_read_ends_the_capture_within_its_bound_and_the_samples_are_written() {
    let mut link = bounded_link(Act::Hang, 0.4);
    let opts = options("hang", None);
    let stop = AtomicBool::new(false);
    let started = Instant::now();
    let e = capture(&mut link, None, &stop, &opts, &Silent).unwrap_err();
    let took_s = started.elapsed().as_secs_f64();
    assert!((0.4..1.4).contains(&took_s), "took {took_s} s");
    let text = with_causes(&e);
    assert!(
        text.starts_with(&format!(
            "the link failed; the samples so far are in {}: \
             reading RTT up channel 1 did not finish within 0.4 s: ",
            opts.out.display()
        )),
        "{text}"
    );
    let rec = Recording::read(&opts.out).unwrap();
    assert_eq!(rec.t_s.len(), 17);
    let notes = rec.meta.notes.unwrap();
    assert!(notes.contains("7+2 reported, 12+1 detected"), "{notes}");
    assert!(
        notes.contains(
            "; stopped early: the link failed: reading RTT up channel 1 did not finish within 0.4 s"
        ),
        "{notes}"
    );
    std::fs::remove_dir_all(opts.out.parent().unwrap()).unwrap();
}

#[test]
fn a_bounded_link_that_keeps_answering_records_until_the_duration() {
    let mut link = bounded_link(Act::Answer, 0.4);
    let opts = options("bounded-ok", Some(0.3));
    let stop = AtomicBool::new(false);
    let report = capture(&mut link, None, &stop, &opts, &Silent).unwrap();
    assert!(report.contains("17 samples; 3 lost in 2 gaps"), "{report}");
    assert!(!Recording::read(&opts.out)
        .unwrap()
        .meta
        .notes
        .unwrap()
        .contains("stopped early"));
    std::fs::remove_dir_all(opts.out.parent().unwrap()).unwrap();
}

#[test]
fn the_duration_ends_the_recording() {
    let (mut link, stop) = link(Then::Idle);
    let opts = options("duration", Some(0.3));
    let started = Instant::now();
    let report = capture(&mut link, None, &stop, &opts, &Silent).unwrap();
    let took_s = started.elapsed().as_secs_f64();
    assert!((0.3..3.0).contains(&took_s), "took {took_s} s");
    assert!(report.contains("17 samples"), "{report}");
    std::fs::remove_dir_all(opts.out.parent().unwrap()).unwrap();
}

#[test]
fn a_bad_duration_is_refused() {
    let (mut link, stop) = link(Then::Idle);
    let e = capture(&mut link, None, &stop, &options("bad", Some(-1.0)), &Silent).unwrap_err();
    assert_eq!(
        e.to_string(),
        "duration_s must be a positive number of seconds, got -1"
    );
}
