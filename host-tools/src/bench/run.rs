//! `finrs bench run`: a whole session from the board, through one link.
//!
//! For each recording of the protocol, in order: the operator's prompt if
//! any, the samples the board buffered meanwhile dropped (an Info request
//! as the barrier), a tare for a blocked one, then a recorder fed from the one stream
//! while the board rests at 0 V for `rest_s`, runs the wave for `hold_s`
//! (its envelope ends it) and rests again for `off_s`. Times are counted
//! in the board's samples (its Info gives the rate), never on the host's
//! clock; a recording's `t_session_start_s` is its first sample's number
//! less the session's first, over the rate, so drying over a session is
//! measured on the board's clock. Each recording is written as soon as it
//! ends, so a session stopped half-way keeps what it recorded.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use finrs_frames::{Command, Event, Info, SampleFlags};

use crate::link::board::{request_info, Board, Frames, TrackStretch};
use crate::link::calibrate::{apply_model, CalibrateOptions};
use crate::link::capture::Monitor;
use crate::link::command::{at_session_time, wave_command};
use crate::link::defmt_log::Table;
use crate::link::probe::ProbeError;
use crate::link::qemu::world::VIRTUAL_M_PER_PX;
use crate::link::stream::{Recorder, Setup};
use crate::model::motion;
use crate::model::params::ModelFile;
use crate::protocol::{Protocol, Step};
use crate::recording::{Channel, Fixture, Recording, RecordingError};
use crate::wave::{WaveError, WaveOptions};

/// Why a session stopped.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The probe failed.
    #[error(transparent)]
    Probe(#[from] ProbeError),
    /// The board did not send its Info frame.
    #[error("no Info frame from the board within {timeout_s} s (is the firmware running, and is it this board's?)")]
    NoInfo {
        /// The wait, s.
        timeout_s: f64,
    },
    /// A recording's wave is refused for this board.
    #[error("recording {k} ({name})")]
    Wave {
        /// Its number, from 1.
        k: usize,
        /// Its name.
        name: String,
        /// The wave's field and rule.
        #[source]
        source: WaveError,
    },
    /// A file the session would write is there already.
    #[error("{} exists: a session is not written over another; choose another --out", path.display())]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// The session's folder could not be created.
    #[error("cannot create {}", dir.display())]
    Folder {
        /// The folder.
        dir: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// No samples came within the wait.
    #[error("no samples from the board for {timeout_s} s during recording {k} ({name})")]
    Stalled {
        /// The recording's number.
        k: usize,
        /// Its name.
        name: String,
        /// The wait, s.
        timeout_s: f64,
    },
    /// The board latched a fault: a recording it ended is written, the
    /// session stops.
    #[error("the board has a fault latched (seq {seq}) at recording {k} ({name}); the recordings before it are written (this one too if the fault came during it, with the fault in its notes), the session stops here: find the cause, finrs clear-fault, and record the rest")]
    Faulted {
        /// The recording's number.
        k: usize,
        /// Its name.
        name: String,
        /// The Fault frame's sequence number.
        seq: u32,
    },
    /// A recording could not be made or written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The operator's prompt failed (stdin closed).
    #[error("the prompt failed: {0}")]
    Prompt(String),
    /// The protocol's model could not be read, or the board refused it.
    #[error("model {}", path.display())]
    Model {
        /// The model's file.
        path: PathBuf,
        /// Why.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A motion wave with no model on the board and none in the protocol.
    #[error("recording {k} ({name}): a motion needs a model on the board: give the protocol `model = \"FIT.toml\"`, or send one with finrs tune first")]
    NoModel {
        /// Its number, from 1.
        k: usize,
        /// Its name.
        name: String,
    },
}

/// How long to wait for the board.
#[derive(Clone, Copy, Debug)]
pub struct BenchOptions {
    /// Longest wait for anything from the board, wall-clock.
    pub timeout: Duration,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(10),
        }
    }
}

/// What a session wrote.
#[derive(Clone, Debug)]
pub struct SessionReport {
    /// The board's Info at the start.
    pub info: Info,
    /// The recordings written, in order, with their report lines.
    pub written: Vec<(PathBuf, String)>,
    /// The camera tracks written (the virtual bench's free recordings).
    pub tracks: Vec<PathBuf>,
}

/// Records the session `protocol` into `out_dir`; `prompt` asks the
/// operator and returns on Enter, `monitor` hears progress and, given the
/// ELF's defmt `table`, the firmware's log.
pub fn run_session(
    board: &mut impl Board,
    protocol: &Protocol,
    out_dir: &Path,
    opts: &BenchOptions,
    table: Option<&Table>,
    prompt: &mut dyn FnMut(&str) -> std::io::Result<()>,
    monitor: &dyn Monitor,
) -> Result<SessionReport, BenchError> {
    let info = request_info(board, opts.timeout)?.ok_or(BenchError::NoInfo {
        timeout_s: opts.timeout.as_secs_f64(),
    })?;
    let segments = usize::from(info.segments);
    // Every wave checked for this board, every file free, before anything
    // moves.
    let mut commands = Vec::with_capacity(protocol.recordings.len());
    for (i, step) in protocol.recordings.iter().enumerate() {
        let options = WaveOptions {
            hold_s: step.hold_s,
            ..WaveOptions::steady(step.hold_s)
        };
        let command =
            wave_command(&step.wave, segments, &options).map_err(|source| BenchError::Wave {
                k: i + 1,
                name: step.name.clone(),
                source,
            })?;
        if matches!(command, Command::SetMotion { .. })
            && protocol.model.is_none()
            && info.model_crc.is_none()
        {
            return Err(BenchError::NoModel {
                k: i + 1,
                name: step.name.clone(),
            });
        }
        commands.push(command);
        let path = out_dir.join(step.file_name(i + 1));
        if path.exists() {
            return Err(BenchError::Exists { path });
        }
    }
    std::fs::create_dir_all(out_dir).map_err(|source| BenchError::Folder {
        dir: out_dir.to_path_buf(),
        source,
    })?;
    board.send(&Command::Stop)?;
    if let Some(path) = &protocol.model {
        tune(board, path, protocol, &info, opts, monitor)?;
    }
    let mut stream = Frames::new(table);
    let mut session_first_seq: Option<u32> = None;
    let mut written = Vec::new();
    let mut tracks = Vec::new();
    let count = protocol.recordings.len();
    for (i, (step, command)) in protocol.recordings.iter().zip(&commands).enumerate() {
        let k = i + 1;
        if let Some(text) = &step.prompt {
            prompt(&format!(
                "recording {k} of {count} ({}): {text}; then press Enter",
                step.name
            ))
            .map_err(|e| BenchError::Prompt(e.to_string()))?;
        }
        let ctx = Ctx {
            k,
            name: &step.name,
            timeout: opts.timeout,
            monitor,
        };
        board.set_fixture(
            step.fixture == Fixture::Free,
            protocol.dots_s_m.as_deref().unwrap_or(&[]),
        )?;
        // What the board buffered while nobody read (the prompt) is from
        // before: it is dropped, and the recording starts in the present.
        let Some(info_now) = stream.barrier(board, opts.timeout, monitor)? else {
            return Err(ctx.stalled());
        };
        if step.tare {
            board.send(&Command::Tare)?;
            // The tare's samples carry its flag; it is done at the first
            // sample without it after one with it.
            ctx.skip_until(board, &mut stream, |f| f.has(SampleFlags::TARING))?;
            ctx.skip_until(board, &mut stream, |f| !f.has(SampleFlags::TARING))?;
        }
        monitor.line(&format!(
            "recording {k} of {count}: {} ({})",
            step.name, step.wave
        ));
        let Recorded {
            recording,
            first_seq,
            last_seq,
            fault_seq,
            report,
            tracking_csv,
        } = record_one(
            board,
            &mut stream,
            protocol,
            step,
            command,
            &info_now,
            session_first_seq,
            ctx,
            monitor,
        )?;
        let first = *session_first_seq.get_or_insert(first_seq);
        let path = out_dir.join(step.file_name(k));
        let mut recording = recording;
        recording.meta.t_session_start_s =
            Some(f64::from(first_seq.wrapping_sub(first)) / f64::from(info.sample_hz));
        recording.write(&path)?;
        monitor.line(&format!("wrote {}: {}", path.display(), report.trim_end()));
        written.push((path, report));
        if let Some(csv) = tracking_csv {
            let path = write_beside(out_dir, "tracking", &step.file_name(k), &csv)?;
            monitor.line(&format!(
                "wrote {} (the board's gain tracker, once a period)",
                path.display()
            ));
        }
        if step.fixture == Fixture::Free {
            let stretch = TrackStretch {
                sample_hz: f64::from(info.sample_hz),
                dots_s_m: protocol.dots_s_m.as_deref().unwrap_or(&[]),
                length_m: protocol.geometry.length_m,
            };
            if let Some(csv) = board.camera_track(first_seq, last_seq, &stretch) {
                let path = write_beside(out_dir, "tracks", &step.file_name(k), &csv)?;
                monitor.line(&format!(
                    "wrote {} (the virtual camera, {} m per pixel: finrs merge-camera --m-per-px {})",
                    path.display(),
                    VIRTUAL_M_PER_PX,
                    VIRTUAL_M_PER_PX
                ));
                tracks.push(path);
            }
        }
        if let Some(seq) = fault_seq {
            return Err(BenchError::Faulted {
                k,
                name: step.name.clone(),
                seq,
            });
        }
    }
    board.send(&Command::Stop)?;
    Ok(SessionReport {
        info,
        written,
        tracks,
    })
}

/// Writes a file beside the session's recordings, in the folder `folder`
/// (`tracks/`, the camera's; `tracking/`, the gain tracker's), not among
/// the recordings, which `finrs diagnose` reads.
fn write_beside(
    out_dir: &Path,
    folder: &str,
    file_name: &str,
    csv: &str,
) -> Result<PathBuf, BenchError> {
    let dir = out_dir.join(folder);
    std::fs::create_dir_all(&dir).map_err(|source| BenchError::Folder {
        dir: dir.clone(),
        source,
    })?;
    let path = dir.join(file_name);
    std::fs::write(&path, csv).map_err(|source| BenchError::Folder {
        dir: dir.clone(),
        source,
    })?;
    Ok(path)
}

/// The recording under way, for messages and waits.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    k: usize,
    name: &'a str,
    timeout: Duration,
    monitor: &'a dyn Monitor,
}

impl Ctx<'_> {
    fn stalled(&self) -> BenchError {
        BenchError::Stalled {
            k: self.k,
            name: self.name.to_string(),
            timeout_s: self.timeout.as_secs_f64(),
        }
    }

    /// Reads and drops events up to the first Sample whose flags satisfy
    /// `done`.
    fn skip_until(
        &self,
        board: &mut impl Board,
        stream: &mut Frames<'_>,
        done: impl Fn(SampleFlags) -> bool,
    ) -> Result<(), BenchError> {
        // Bounded too while samples flow: a flag that never comes (a tare
        // the board ignores) is a stall, not a wait for ever.
        let started = Instant::now();
        loop {
            match stream.next(board, self.timeout, self.monitor)? {
                None => return Err(self.stalled()),
                Some(Event::Sample(s)) if done(s.flags) => return Ok(()),
                Some(_) if started.elapsed() >= self.timeout => return Err(self.stalled()),
                Some(_) => {}
            }
        }
    }
}

/// Sends the board the model at `path` for the protocol's strip (as
/// `finrs tune` does), once its outputs are at 0 V (it refuses a model
/// while they are driven), and waits for the Info that names it.
fn tune(
    board: &mut impl Board,
    path: &Path,
    protocol: &Protocol,
    info: &Info,
    opts: &BenchOptions,
    monitor: &dyn Monitor,
) -> Result<(), BenchError> {
    let model_error = |source: Box<dyn std::error::Error + Send + Sync>| BenchError::Model {
        path: path.to_path_buf(),
        source,
    };
    let spec = ModelFile::read(path)
        .and_then(|m| m.spec_for(&protocol.geometry))
        .map_err(|e| model_error(e.into()))?;
    let record = motion::record(&spec);
    motion::board_check(
        &record,
        usize::from(info.segments),
        f64::from(info.sample_hz),
    )
    .map_err(|e| model_error(e.into()))?;
    // Stopped: the first sample at 0 V on every segment.
    let mut frames = Frames::new(None);
    let started = Instant::now();
    loop {
        match frames.next(board, opts.timeout, &crate::link::capture::Silent)? {
            Some(Event::Sample(s)) if s.voltages().iter().all(|&v| v == 0.0) => break,
            Some(_) if started.elapsed() < opts.timeout => {}
            _ => {
                return Err(model_error(
                    format!(
                        "the outputs did not come to 0 V within {} s of a Stop",
                        opts.timeout.as_secs_f64()
                    )
                    .into(),
                ))
            }
        }
    }
    let calibrate_opts = CalibrateOptions {
        timeout: opts.timeout,
        ..CalibrateOptions::default()
    };
    let confirmed =
        apply_model(board, &calibrate_opts, &record).map_err(|e| model_error(e.into()))?;
    monitor.line(&format!(
        "model {:04x} from {} in use on the board",
        confirmed.model_crc.unwrap_or_default(),
        path.display()
    ));
    Ok(())
}

/// What [`record_one`] made.
struct Recorded {
    /// The recording, its time from 0.
    recording: Recording,
    /// Its first sample's number.
    first_seq: u32,
    /// Its last sample's number.
    last_seq: u32,
    /// The fault that ended it early, if one did.
    fault_seq: Option<u32>,
    /// The recorder's report.
    report: String,
    /// The gain tracker's reports as CSV, if the board sent any.
    tracking_csv: Option<String>,
}

/// One recording: rest, wave, rest, from the stream into a recorder.
#[allow(clippy::too_many_arguments)]
fn record_one(
    board: &mut impl Board,
    stream: &mut Frames<'_>,
    protocol: &Protocol,
    step: &Step,
    command: &Command,
    info: &Info,
    session_first_seq: Option<u32>,
    ctx: Ctx<'_>,
    monitor: &dyn Monitor,
) -> Result<Recorded, BenchError> {
    let hz = f64::from(info.sample_hz);
    let periods = |s: f64| (s * hz).round() as u64;
    let rest = periods(step.rest_s);
    let total = rest + periods(step.hold_s) + periods(step.off_s);
    let mut rec = Recorder::new(Setup {
        geometry: protocol.geometry,
        medium: protocol.medium,
        sample: protocol.sample.clone(),
        source: format!("finrs bench, recording {} ({})", ctx.k, step.name),
    });
    // The barrier's Info, asked for just before: the firmware and set-up
    // this recording was made with, in its notes.
    rec.event(Event::Info(*info));
    // Events before this recording's first Sample (a Dropped frame for
    // periods missed while the operator was asked) belong to no recording.
    let (first_seq, first_t_us) = loop {
        match stream.next(board, ctx.timeout, monitor)? {
            None => return Err(ctx.stalled()),
            // A fault latched before the recording: the board would refuse
            // the wave; nothing is recorded.
            Some(Event::Sample(s)) if s.flags.has(SampleFlags::FAULT) => {
                return Err(BenchError::Faulted {
                    k: ctx.k,
                    name: step.name.clone(),
                    seq: s.seq,
                })
            }
            Some(Event::Sample(s)) => {
                rec.event(Event::Sample(s));
                break (s.seq, s.t_us);
            }
            Some(_) => {}
        }
    };
    let mut sent = false;
    let mut fault_seq = None;
    let mut last = 0u64;
    let mut shown = Instant::now();
    while last + 1 < total {
        if shown.elapsed() >= Duration::from_millis(250) {
            shown = Instant::now();
            let s = rec.summary();
            monitor.status(&format!(
                "recording {} ({}): {:.1} of {:.1} s, {}, {} samples lost in {} gaps, {} faults",
                ctx.k,
                step.name,
                last as f64 / hz,
                total as f64 / hz,
                if !sent {
                    "resting"
                } else if last < rest + periods(step.hold_s) {
                    "wave on"
                } else {
                    "resting after"
                },
                s.lost_samples,
                s.gaps,
                s.faults
            ));
        }
        let Some(e) = stream.next(board, ctx.timeout, monitor)? else {
            return Err(ctx.stalled());
        };
        if let Event::Sample(s) = &e {
            // Periods since the first sample, dropped ones counted.
            last = u64::from(s.seq.wrapping_sub(first_seq));
        }
        if let Event::Fault(f) = &e {
            fault_seq = Some(f.seq);
            rec.event(e);
            break;
        }
        rec.event(e);
        if !sent && last + 1 >= rest {
            // A motion's start on the session's clock (the drying law's):
            // the sample just read is the session's first one's that many
            // periods on; the board shapes it from the next.
            let session_first = session_first_seq.unwrap_or(first_seq);
            let now = first_seq
                .wrapping_add(last as u32)
                .wrapping_sub(session_first);
            let t_session_s = f64::from(now + 1) / hz;
            board.send(&at_session_time(*command, t_session_s))?;
            sent = true;
        }
    }
    board.send(&Command::Stop)?;
    rec.finish();
    let report = crate::link::capture::report(&rec);
    let tracking_csv = tracking_csv(rec.tracking(), first_t_us);
    let mut recording = rec.into_recording(&step.file_name(ctx.k))?;
    let t0 = recording.t_s.first().copied().unwrap_or(0.0);
    for t in &mut recording.t_s {
        *t -= t0;
    }
    let mut notes = step.notes.clone().unwrap_or_default();
    if !notes.is_empty() {
        notes.push_str("; ");
    }
    notes.push_str(&format!(
        "wave {} after {} s at 0 V, held {} s, then {} s at 0 V; ",
        step.wave, step.rest_s, step.hold_s, step.off_s
    ));
    notes.push_str(recording.meta.notes.as_deref().unwrap_or(""));
    recording.meta.notes = Some(notes);
    if step.fixture == Fixture::Free {
        // The board records no positions: the camera's come later
        // (merge-camera); the load cell pushes on nothing.
        recording.meta.fixture = Fixture::Free;
        recording.channels.retain(|(c, _)| *c != Channel::Force);
        recording.meta.dots_s_m = protocol.dots_s_m.clone();
    }
    recording.validate(&step.file_name(ctx.k))?;
    if !sent {
        monitor.line("the recording ended before its wave was sent (a fault?)");
    }
    Ok(Recorded {
        recording,
        first_seq,
        last_seq: first_seq.wrapping_add(last as u32),
        fault_seq,
        report,
        tracking_csv,
    })
}

/// The gain tracker's reports as CSV (`t_s` from the recording's first
/// sample, its flags, each segment's gain and phase), `None` without any.
fn tracking_csv(reports: &[finrs_frames::Tracking], first_t_us: u32) -> Option<String> {
    let n = reports.first()?.n;
    let mut csv = String::from("t_s,flags");
    for what in ["gain", "phase_deg"] {
        for k in 1..=n {
            csv.push_str(&format!(",{what}_{k}"));
        }
    }
    csv.push('\n');
    for t in reports {
        // The board's µs clock wraps at 2³²: the difference does not.
        let t_s = f64::from(t.t_us.wrapping_sub(first_t_us)) / 1e6;
        csv.push_str(&format!("{t_s},{}", t.flags.0));
        for v in t.gains[..t.n].iter().chain(&t.phases_deg[..t.n]) {
            csv.push_str(&format!(",{v}"));
        }
        csv.push('\n');
    }
    Some(csv)
}

#[cfg(test)]
mod tests;
