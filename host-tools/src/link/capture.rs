//! `finrs log` and `finrs run`: bytes from the probe (or from a file) into a
//! [`Recorder`], the defmt log and a live status handed to a [`Monitor`] as
//! they come, and at the end the recording and the report of every gap.
//!
//! How the status is shown, and what stops the loop (Ctrl-C in the
//! binary), are the caller's: the loop takes a [`Monitor`] and a stop flag.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::link::causes::with_causes;
use crate::link::defmt_log::{no_table_notice, read_table, Log, Table};
use crate::link::probe::{
    self, Bounded, ProbeError, ProbeOptions, ProbeTarget, Target, DEFMT_UP_CHANNEL,
    FORCE_UP_CHANNEL,
};
use crate::link::stream::{GapSource, Recorder, Setup};

mod error;
pub mod journal;
pub use error::CaptureError;
use journal::Journal;

/// Where the recording goes and when to stop.
#[derive(Clone, Debug)]
pub struct CaptureOptions {
    /// The recording to write (CSV, `ipmc-bench/1`).
    pub out: PathBuf,
    /// Stop after this long, s; `None`: until Ctrl-C.
    pub duration_s: Option<f64>,
    /// Metadata the stream does not carry.
    pub setup: Setup,
}

impl CaptureOptions {
    fn check(&self) -> Result<(), CaptureError> {
        if let Some(d) = self.duration_s {
            if !(d.is_finite() && d > 0.0) {
                return Err(CaptureError::Duration(d));
            }
        }
        Ok(())
    }
}

/// The report printed at the end: totals and every gap, fault and refused
/// Sample by sequence number.
pub fn report(rec: &Recorder) -> String {
    let s = rec.summary();
    let mut out = format!(
        "{} samples; {} lost in {} gaps; {} faults; {} corrupt bytes; {} refused\n",
        s.rows, s.lost_samples, s.gaps, s.faults, s.corrupt_bytes, s.rejected
    );
    for g in rec.gaps() {
        let by = match g.source {
            GapSource::Reported => "dropped by the firmware (reported)",
            GapSource::Detected => "lost on the way (detected)",
        };
        let last = g.first_seq.wrapping_add(g.count.saturating_sub(1));
        out.push_str(&format!(
            "  gap: seq {}..={} ({} samples) {by}\n",
            g.first_seq, last, g.count
        ));
    }
    for f in rec.faults() {
        out.push_str(&format!(
            "  fault: seq {} t_us {} {:?}{}\n",
            f.seq,
            f.t_us,
            f.code,
            f.segment
                .map(|k| format!(" on segment {}", k + 1))
                .unwrap_or_default()
        ));
    }
    for r in rec.rejected() {
        out.push_str(&format!("  refused: seq {}: {}\n", r.seq, r.reason));
    }
    if let Some(r) = rec.restart() {
        out.push_str(&format!(
            "  restart: seq {} came after {}; {} later samples not recorded\n",
            r.got_seq,
            r.expected_seq.wrapping_sub(1),
            s.after_restart
        ));
    }
    out
}

/// Writes the recording (with the account in its notes) and returns the
/// report. Called also after Ctrl-C, with what came so far.
pub fn finish(mut rec: Recorder, out: &Path) -> Result<String, CaptureError> {
    rec.finish();
    let report = report(&rec);
    let name = out.display().to_string();
    let recording = rec
        .into_recording(&name)
        .map_err(|source| CaptureError::NothingWritten {
            report: report.trim_end().to_string(),
            source,
        })?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| CaptureError::Folder {
            dir: dir.to_path_buf(),
            source,
        })?;
    }
    recording.write(out).map_err(CaptureError::Write)?;
    Ok(format!("wrote {name}\n{report}"))
}

/// `finrs log --from-bytes FILE`: a raw dump of the up channel (`-`: the
/// standard input, e.g. piped from QEMU) through the same recorder.
/// Returns the report. The standard input is read as it comes, with a
/// journal (see [`journal`]); a file is its own record.
pub fn from_bytes(path: &Path, opts: &CaptureOptions) -> Result<String, CaptureError> {
    opts.check()?;
    let mut rec = Recorder::new(opts.setup.clone());
    if path != Path::new("-") {
        let bytes = std::fs::read(path).map_err(|source| CaptureError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        rec.push_bytes(&bytes);
        return finish(rec, &opts.out);
    }
    let mut journal = Journal::create(&opts.out)?;
    let mut stdin = std::io::stdin().lock();
    let mut buf = vec![0u8; 64 * 1024];
    loop {
        let n = match std::io::Read::read(&mut stdin, &mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(CaptureError::Stdin(e)),
        };
        journal.append(&buf[..n])?;
        rec.push_bytes(&buf[..n]);
    }
    let report = finish(rec, &opts.out)?;
    journal.remove()?;
    Ok(report)
}

/// Who watches a recording: hears the defmt log and notices line by line,
/// and a live status now and then.
pub trait Monitor {
    /// A line to show: a defmt log frame or a notice.
    fn line(&self, text: &str);
    /// The recording's status so far (samples, rate, gaps), to show in place.
    fn status(&self, text: &str);
}

/// A [`Monitor`] that shows nothing.
pub struct Silent;

impl Monitor for Silent {
    fn line(&self, _: &str) {}
    fn status(&self, _: &str) {}
}

/// Where the bytes come from while recording: the probe's RTT up channels,
/// or a stand-in in tests.
pub trait Link {
    /// Reads what the force stream's channel holds now, without waiting.
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError>;
    /// Reads what the defmt log's channel holds now, without waiting.
    fn read_log(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError>;
}

/// The probe's RTT up channels 1 (force) and 0 (defmt), each read bounded
/// in time.
impl<T: Target> Link for Bounded<T> {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        self.read_up(FORCE_UP_CHANNEL, buf)
    }

    fn read_log(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        self.read_up(DEFMT_UP_CHANNEL, buf)
    }
}

/// The firmware to flash and whose symbols to use.
#[derive(Clone, Debug)]
pub enum Firmware {
    /// `finrs log`: attach to what runs; the ELF (if any) gives `_SEGGER_RTT`
    /// and the defmt table.
    Running(Option<PathBuf>),
    /// `finrs run`: flash this ELF, reset and run it.
    Flash(PathBuf),
}

/// A probe attached to the firmware with RTT up, ready for [`capture`].
pub struct Connected {
    /// The probe's RTT channels, each read bounded in time.
    pub link: Bounded<ProbeTarget>,
    /// The ELF's defmt table, when there is one.
    pub table: Option<Table>,
}

/// `finrs log` / `finrs run` up to the recording: reads the ELF (if any),
/// attaches, flashes and runs it for [`Firmware::Flash`], and finds the RTT
/// block. Notices go to `monitor`.
pub fn connect(
    probe_opts: &ProbeOptions,
    firmware: &Firmware,
    monitor: &dyn Monitor,
) -> Result<Connected, CaptureError> {
    let elf_path = match firmware {
        Firmware::Running(p) => p.clone(),
        Firmware::Flash(p) => Some(p.clone()),
    };
    // Read the file now so that a wrong path fails before any USB work.
    let elf = elf_path.as_deref().map(probe::read_elf).transpose()?;
    let session = probe::attach(probe_opts)?;
    let (rtt_at, table) = match (&elf_path, &elf) {
        (Some(p), Some(bytes)) => {
            let name = p.display().to_string();
            let at = probe::rtt_address(&name, bytes)?;
            let table = read_table(bytes).map_err(|reason| CaptureError::DefmtTable {
                elf: name.clone(),
                reason,
            })?;
            if table.is_none() {
                monitor.line(&no_table_notice(&name));
            }
            (Some(at), table)
        }
        _ => {
            monitor.line("no ELF: RTT block found by scanning RAM; the defmt log is not shown");
            (None, None)
        }
    };
    let mut link = probe::connect(session, probe_opts)?;
    if let Firmware::Flash(p) = firmware {
        // Set above: `finrs run` always reads its ELF.
        let at = rtt_at.ok_or_else(|| CaptureError::NoRttAddress { elf: p.clone() })?;
        monitor.line(&format!("flashing {}", p.display()));
        probe::flash_and_run(&mut link, p, at)?;
    }
    probe::attach_rtt(&mut link, rtt_at, Duration::from_secs(5))?;
    Ok(Connected { link, table })
}

/// The recording loop: reads the link until `stop` is set (by the caller,
/// e.g. on Ctrl-C) or the duration has passed, hands the defmt log and a
/// live status to `monitor`, then writes what came (also when the link
/// fails) and returns the report.
pub fn capture(
    link: &mut impl Link,
    table: Option<&Table>,
    stop: &AtomicBool,
    opts: &CaptureOptions,
    monitor: &dyn Monitor,
) -> Result<String, CaptureError> {
    opts.check()?;
    let mut journal = Some(Journal::create(&opts.out)?);
    if let Some(j) = &journal {
        monitor.line(&format!(
            "journal: {} (should this process die: finrs log --from-bytes {} --out {})",
            j.path().display(),
            j.path().display(),
            opts.out.display()
        ));
    }
    let mut journal_failed = None;
    let mut log = table.map(Log::new);
    let mut rec = Recorder::new(opts.setup.clone());
    let mut buf = vec![0u8; 16 * 1024];
    let started = Instant::now();
    let mut last_status = started;
    let outcome: Result<(), ProbeError> = loop {
        if stop.load(Ordering::SeqCst) {
            monitor.line("stopped");
            break Ok(());
        }
        if opts
            .duration_s
            .is_some_and(|d| started.elapsed().as_secs_f64() >= d)
        {
            break Ok(());
        }
        let n = match link.read_force(&mut buf) {
            Ok(n) => n,
            Err(e) => break Err(e),
        };
        if let Some(j) = &mut journal {
            // A journal that cannot be written (a full disk) does not end
            // the recording, which is still whole in memory.
            if let Err(e) = j.append(&buf[..n]) {
                let text = with_causes(&e);
                monitor.line(&format!("{text}; recording on without it"));
                journal_failed = Some(text);
                journal = None;
            }
        }
        rec.push_bytes(&buf[..n]);
        let mut m = 0;
        if let Some(log) = log.as_mut() {
            m = match link.read_log(&mut buf) {
                Ok(m) => m,
                Err(e) => break Err(e),
            };
            log.show(&buf[..m], &mut |l| monitor.line(l));
        }
        if last_status.elapsed() >= Duration::from_millis(250) {
            last_status = Instant::now();
            monitor.status(&status(&rec, started));
        }
        if n == 0 && m == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
    };
    let malformed_defmt = log.as_ref().map_or(0, Log::malformed);
    let concluded = conclude(rec, outcome, &opts.out, monitor, malformed_defmt);
    if let Some(j) = journal {
        match &concluded {
            // The recording is written: the journal is not needed.
            Ok(_) | Err(CaptureError::LinkFailed { .. }) => j.remove()?,
            Err(_) => monitor.line(&format!(
                "the stream is kept in {}: finrs log --from-bytes {} --out {}",
                j.path().display(),
                j.path().display(),
                opts.out.display()
            )),
        }
    }
    let mut text = concluded?;
    if let Some(why) = journal_failed {
        text.push_str(&format!("  journal: {why}\n"));
    }
    Ok(text)
}

/// The live status: samples, rate, gaps, faults, corrupt bytes.
fn status(rec: &Recorder, started: Instant) -> String {
    let s = rec.summary();
    let secs = started.elapsed().as_secs_f64().max(1e-3);
    format!(
        "{} samples, {:.0}/s, {} gaps ({} lost), {} faults, {} corrupt bytes",
        s.rows,
        s.rows as f64 / secs,
        s.gaps,
        s.lost_samples,
        s.faults,
        s.corrupt_bytes
    )
}

/// After the loop: writes what came (also when the link failed, with why
/// in the notes) and returns the report, or the link's failure.
fn conclude(
    mut rec: Recorder,
    outcome: Result<(), ProbeError>,
    out: &Path,
    monitor: &dyn Monitor,
    malformed_defmt: u64,
) -> Result<String, CaptureError> {
    // Whatever stopped the loop, what came so far is written, and why it
    // ended early goes into the notes.
    if let Err(e) = &outcome {
        rec.stopped_early(format!("the link failed: {}", with_causes(e)));
    }
    let written = finish(rec, out);
    let mut text = match (written, outcome) {
        (Ok(text), Ok(())) => text,
        (Ok(text), Err(e)) => {
            monitor.line(text.trim_end());
            return Err(CaptureError::LinkFailed {
                out: out.to_path_buf(),
                source: e,
            });
        }
        (Err(w), Ok(())) => return Err(w),
        (Err(w), Err(e)) => {
            return Err(CaptureError::LinkAndWrite {
                write: with_causes(&w),
                source: e,
            })
        }
    };
    if malformed_defmt > 0 {
        text.push_str(&format!(
            "  defmt: {malformed_defmt} malformed log frames\n"
        ));
    }
    Ok(text)
}

#[cfg(test)]
mod tests;
