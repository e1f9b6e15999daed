//! The recorder: decoder events in, an `ipmc-bench/1` blocked recording and
//! an account of everything lost or damaged out.

use std::fmt::Write as _;

use finrs_frames::{DecodedSample, Decoder, Event, Fault, FaultCode, Info, SampleFlags, Tracking};

use super::clock::{Clock, ClockError};
use super::refusal::Refusal;
use crate::recording::Geometry;
use crate::recording::{
    Channel, Fixture, Medium, Metadata, Recording, RecordingError, Voltages, SAFE_VOLTAGE_LIMIT_V,
};

/// What the recording's metadata says that the stream does not.
#[derive(Clone, Debug, PartialEq)]
pub struct Setup {
    /// Geometry of the strip on the load cell.
    pub geometry: Geometry,
    /// What surrounds the strip.
    pub medium: Medium,
    /// Sample id, if given.
    pub sample: Option<String>,
    /// Where the bytes came from, for the notes (e.g. `probe, chip STM32F407VGTx`).
    pub source: String,
}

/// Who found a hole in the sequence numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GapSource {
    /// The firmware, in a Dropped frame.
    Reported,
    /// The host: numbers jumped with no Dropped frame covering them (lost
    /// in transit or in a corrupted frame).
    Detected,
}

/// Samples that never reached the recording, by sequence number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Gap {
    /// Sequence number of the first missing Sample.
    pub first_seq: u32,
    /// How many consecutive Samples, from `first_seq` on (wrapping at 2³²).
    pub count: u32,
    /// Who found it.
    pub source: GapSource,
}

/// The sequence numbers went back: the firmware restarted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Restart {
    /// The number that should have come next.
    pub expected_seq: u32,
    /// The one that came.
    pub got_seq: u32,
}

/// A Sample that decoded but cannot be a row of a valid recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Rejected {
    /// Its sequence number.
    pub seq: u32,
    /// The field and the rule it breaks.
    pub reason: Refusal,
}

/// Totals for a live display and the final report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Rows recorded.
    pub rows: u64,
    /// Gaps, reported and detected.
    pub gaps: u64,
    /// Samples missing from those gaps.
    pub lost_samples: u64,
    /// Fault frames.
    pub faults: u64,
    /// Bytes discarded by the decoder.
    pub corrupt_bytes: u64,
    /// Runs of discarded bytes.
    pub corrupt_runs: u64,
    /// Samples decoded but refused (see [`Rejected`]).
    pub rejected: u64,
    /// Samples after a restart, not recorded.
    pub after_restart: u64,
    /// Samples whose voltages the firmware's limiter clamped to the limit.
    pub limited: u64,
    /// Samples whose voltages the limiter held to the slew limit.
    pub slewed: u64,
    /// Samples taken during a tare (force against the previous zero).
    pub taring: u64,
    /// Samples taken with a fault latched.
    pub faulted: u64,
}

/// Builds a blocked-fixture recording from the firmware's frame stream.
///
/// Rows are the Samples in the order they come, which is sequence order:
/// the decoder reports any jump as a gap. Nothing is interpolated: a lost
/// Sample is a gap in the list, never a row. A Sample that decodes but
/// would break the recording format (another segment count than the first
/// Sample's, NaN or infinity, a voltage beyond ±4 V, a time that does not
/// advance) is refused and listed. After a restart (sequence numbers going
/// back) the firmware's time restarts too and cannot be placed on this
/// recording's time axis, so later Samples are counted, not recorded.
#[derive(Clone, Debug)]
pub struct Recorder {
    setup: Setup,
    decoder: Decoder,
    clock: Clock,
    segments: Option<usize>,
    t_s: Vec<f64>,
    /// One flat row of voltages per sample (no allocation per row).
    v_v: Option<Voltages>,
    currents_a: Vec<Vec<f64>>,
    force_n: Vec<f64>,
    gaps: Vec<Gap>,
    faults: Vec<Fault>,
    rejected: Vec<Rejected>,
    restart: Option<Restart>,
    stopped_early: Option<String>,
    summary: Summary,
    /// The firmware's first Info frame, and any later one whose
    /// configuration differs from it.
    infos: Vec<Info>,
    /// Events the operator marked, at the time of the last row then, s.
    marks: Vec<Option<f64>>,
    /// The gain tracker's reports, as they came.
    tracking: Vec<Tracking>,
}

impl Recorder {
    /// A recorder that has seen nothing yet.
    pub fn new(setup: Setup) -> Self {
        Recorder {
            setup,
            decoder: Decoder::new(),
            clock: Clock::new(),
            segments: None,
            t_s: Vec::new(),
            v_v: None,
            currents_a: Vec::new(),
            force_n: Vec::new(),
            gaps: Vec::new(),
            faults: Vec::new(),
            rejected: Vec::new(),
            restart: None,
            stopped_early: None,
            summary: Summary::default(),
            infos: Vec::new(),
            marks: Vec::new(),
            tracking: Vec::new(),
        }
    }

    /// Marks an event at the last row's time (for the notes); returns the
    /// mark in words.
    pub fn mark(&mut self) -> String {
        let t = self.t_s.last().copied();
        self.marks.push(t);
        describe_mark(self.marks.len(), t)
    }

    /// Decodes the next bytes of the stream, in chunks of any size.
    pub fn push_bytes(&mut self, bytes: &[u8]) {
        let mut events = Vec::new();
        self.decoder.push(bytes, &mut |e| events.push(e));
        for e in events {
            self.event(e);
        }
    }

    /// Ends the stream: bytes held back for an incomplete frame count as
    /// corrupt.
    pub fn finish(&mut self) {
        let mut events = Vec::new();
        self.decoder.finish(&mut |e| events.push(e));
        for e in events {
            self.event(e);
        }
    }

    /// Takes one decoder event (for callers that run their own decoder).
    pub fn event(&mut self, event: Event) {
        if self.restart.is_some() {
            if let Event::Sample(_) = event {
                self.summary.after_restart += 1;
            }
            return;
        }
        match event {
            Event::Sample(s) => self.sample(&s),
            Event::Dropped(d) => self.gap(Gap {
                first_seq: d.first_seq,
                count: d.count,
                source: GapSource::Reported,
            }),
            Event::Gap {
                expected_seq,
                got_seq,
            } => {
                let count = got_seq.wrapping_sub(expected_seq);
                // The decoder's rule: half the number space ahead is a jump
                // forward, further is a restart.
                if count < 1 << 31 {
                    self.gap(Gap {
                        first_seq: expected_seq,
                        count,
                        source: GapSource::Detected,
                    });
                } else {
                    self.restart = Some(Restart {
                        expected_seq,
                        got_seq,
                    });
                }
            }
            Event::Fault(f) => {
                self.summary.faults += 1;
                self.faults.push(f);
            }
            Event::Corrupt { skipped_bytes } => {
                self.summary.corrupt_runs += 1;
                self.summary.corrupt_bytes += skipped_bytes as u64;
            }
            Event::Tracking(t) => self.tracking.push(t),
            Event::Info(info) => {
                let seen = self
                    .infos
                    .iter()
                    .any(|i| i.config_crc() == info.config_crc() && i.version == info.version);
                if !seen {
                    self.infos.push(info);
                }
            }
        }
    }

    /// The gain tracker's reports (Tracking frames), in the order they came.
    pub fn tracking(&self) -> &[Tracking] {
        &self.tracking
    }

    /// The firmware's Info frames: the first, then any whose configuration
    /// or version differs.
    pub fn infos(&self) -> &[Info] {
        &self.infos
    }

    fn gap(&mut self, gap: Gap) {
        self.summary.gaps += 1;
        self.summary.lost_samples += u64::from(gap.count);
        self.gaps.push(gap);
    }

    fn sample(&mut self, s: &DecodedSample) {
        let count = |bit: u8| u64::from(s.flags.has(bit));
        self.summary.limited += count(SampleFlags::LIMITED);
        self.summary.slewed += count(SampleFlags::SLEWED);
        self.summary.taring += count(SampleFlags::TARING);
        self.summary.faulted += count(SampleFlags::FAULT);
        match self.check(s) {
            Ok(t_us) => {
                self.segments.get_or_insert(s.n);
                if self.currents_a.is_empty() {
                    self.currents_a = vec![Vec::new(); s.n];
                }
                // Division rounds correctly: 7000 µs is the double nearest 0.007 s.
                self.t_s.push(t_us as f64 / 1e6);
                let volts: [f64; finrs_frames::MAX_SEGMENTS] =
                    std::array::from_fn(|k| s.voltages().get(k).map_or(0.0, |&v| f64::from(v)));
                self.v_v
                    .get_or_insert_with(|| Voltages::with_capacity(s.n, 1024))
                    .push(&volts[..s.n]);
                for (column, &i) in self.currents_a.iter_mut().zip(s.currents()) {
                    column.push(f64::from(i));
                }
                self.force_n.push(f64::from(s.force_n));
                self.summary.rows += 1;
            }
            Err(reason) => {
                self.summary.rejected += 1;
                self.rejected.push(Rejected { seq: s.seq, reason });
            }
        }
    }

    /// The Sample's unwrapped time in µs if it can be a row, else the field
    /// and the rule it breaks. The clock moves only for an accepted Sample.
    fn check(&mut self, s: &DecodedSample) -> Result<u64, Refusal> {
        if let Some(first) = self.segments {
            if s.n != first {
                return Err(Refusal::SegmentCount { got: s.n, first });
            }
        }
        if !s.force_n.is_finite() {
            return Err(Refusal::NotFinite {
                column: "force_N".to_string(),
                value: s.force_n,
            });
        }
        for (k, (&v, &i)) in s.voltages().iter().zip(s.currents()).enumerate() {
            if !v.is_finite() {
                return Err(Refusal::NotFinite {
                    column: format!("v{}_V", k + 1),
                    value: v,
                });
            }
            if f64::from(v).abs() > SAFE_VOLTAGE_LIMIT_V {
                return Err(Refusal::Unsafe {
                    column: format!("v{}_V", k + 1),
                    value_v: v,
                });
            }
            if !i.is_finite() {
                return Err(Refusal::NotFinite {
                    column: format!("i{}_A", k + 1),
                    value: i,
                });
            }
        }
        let mut clock = self.clock;
        let t_us = clock.unwrap(s.t_us).map_err(|e| match e {
            ClockError::Stalled { .. } => Refusal::Stalled { t_us: s.t_us },
            ClockError::Backwards { previous_us } => Refusal::Backwards {
                t_us: s.t_us,
                previous_us,
            },
        })?;
        self.clock = clock;
        Ok(t_us)
    }

    /// Totals so far.
    pub fn summary(&self) -> Summary {
        self.summary
    }

    /// Every gap, in the order found.
    pub fn gaps(&self) -> &[Gap] {
        &self.gaps
    }

    /// Every fault, in the order received.
    pub fn faults(&self) -> &[Fault] {
        &self.faults
    }

    /// Every refused Sample.
    pub fn rejected(&self) -> &[Rejected] {
        &self.rejected
    }

    /// The restart, if the sequence numbers went back.
    pub fn restart(&self) -> Option<Restart> {
        self.restart
    }

    /// Records why the recording ended before it was asked to (e.g. the
    /// probe link stalled), for the notes.
    pub fn stopped_early(&mut self, why: impl Into<String>) {
        self.stopped_early = Some(why.into());
    }

    /// Times of the rows so far, s.
    pub fn times_s(&self) -> &[f64] {
        &self.t_s
    }

    /// The account of the stream, for the metadata's `notes` and the
    /// report at the end: every gap by sequence number, every fault, the
    /// corrupt bytes, refused Samples and a restart.
    pub fn notes(&self) -> String {
        let s = &self.summary;
        let mut out = format!(
            "recorded by finrs from {}: {} samples",
            self.setup.source, s.rows
        );
        match self.infos.split_first() {
            None => out.push_str("; no Info frame from the firmware"),
            Some((first, later)) => {
                let _ = write!(out, "; {}", describe(first));
                for i in later {
                    let _ = write!(out, "; then {}", describe(i));
                }
            }
        }
        if self.gaps.is_empty() {
            out.push_str("; no gaps");
        } else {
            let _ = write!(
                out,
                "; {} samples lost in {} gaps (first_seq+count):",
                s.lost_samples, s.gaps
            );
            for g in &self.gaps {
                let by = match g.source {
                    GapSource::Reported => "reported",
                    GapSource::Detected => "detected",
                };
                let _ = write!(out, " {}+{} {by},", g.first_seq, g.count);
            }
            out.pop();
        }
        if self.faults.is_empty() {
            out.push_str("; no faults");
        } else {
            let _ = write!(out, "; {} faults:", s.faults);
            for f in &self.faults {
                let what = match f.code {
                    FaultCode::Overcurrent => "overcurrent",
                    FaultCode::AdcSaturation => "ADC saturation",
                    FaultCode::MissedDeadline => "missed deadline",
                    FaultCode::Other => "watchdog or other",
                    FaultCode::Supply => "a supply out of range at boot",
                };
                let _ = write!(out, " seq {} t_us {} {what}", f.seq, f.t_us);
                if let Some(k) = f.segment {
                    let _ = write!(out, " on segment {}", k + 1);
                }
                out.push(',');
            }
            out.pop();
        }
        if s.limited + s.slewed > 0 {
            let _ = write!(
                out,
                "; the firmware's limiter clamped {} samples to the voltage limit and slew-limited {}",
                s.limited, s.slewed
            );
        }
        if s.taring > 0 {
            let _ = write!(out, "; {} samples during a tare", s.taring);
        }
        if s.faulted > 0 {
            let _ = write!(out, "; {} samples with a fault latched", s.faulted);
        }
        if s.corrupt_bytes == 0 {
            out.push_str("; no corrupt bytes");
        } else {
            let _ = write!(
                out,
                "; {} corrupt bytes in {} runs",
                s.corrupt_bytes, s.corrupt_runs
            );
        }
        if !self.rejected.is_empty() {
            let _ = write!(out, "; {} samples refused:", s.rejected);
            for r in &self.rejected {
                let _ = write!(out, " seq {} ({}),", r.seq, r.reason);
            }
            out.pop();
        }
        if let Some(r) = self.restart {
            let _ = write!(
                out,
                "; firmware restarted (seq {} after {}): {} later samples not recorded",
                r.got_seq,
                r.expected_seq.wrapping_sub(1),
                s.after_restart
            );
        }
        if !self.marks.is_empty() {
            let marks: Vec<String> = self
                .marks
                .iter()
                .enumerate()
                .map(|(k, &t)| describe_mark(k + 1, t))
                .collect();
            let _ = write!(out, "; marks: {}", marks.join(", "));
        }
        if let Some(why) = &self.stopped_early {
            let _ = write!(out, "; stopped early: {why}");
        }
        out
    }

    /// The recording so far (blocked fixture; voltages, currents and force
    /// per row), checked against the format as if written to `name`.
    pub fn recording(&self, name: &str) -> Result<Recording, RecordingError> {
        self.clone().into_recording(name)
    }

    /// The recording, as [`recording`](Self::recording) makes it, from the
    /// recorder itself: its columns move into the recording (one column at
    /// a time is copied to the format's optional values), so that the end
    /// of a long capture does not hold every sample twice.
    pub fn into_recording(mut self, name: &str) -> Result<Recording, RecordingError> {
        let Some(segments) = self.segments else {
            return Err(RecordingError::file(
                name,
                "the stream held no valid Sample frame: nothing to record",
            ));
        };
        let notes = self.notes();
        let g = self.setup.geometry;
        let optional = |c: Vec<f64>| c.into_iter().map(Some).collect::<Vec<_>>();
        let mut channels: Vec<(Channel, Vec<Option<f64>>)> =
            Vec::with_capacity(self.currents_a.len() + 1);
        for (k, c) in std::mem::take(&mut self.currents_a).into_iter().enumerate() {
            channels.push((Channel::Current(k), optional(c)));
        }
        channels.push((Channel::Force, optional(std::mem::take(&mut self.force_n))));
        let rec = Recording {
            meta: Metadata {
                sample: self.setup.sample.take(),
                notes: Some(notes),
                ..Metadata::new(segments, g, Fixture::Blocked, self.setup.medium)
            },
            t_s: std::mem::take(&mut self.t_s),
            v_v: self
                .v_v
                .take()
                .unwrap_or_else(|| Voltages::with_capacity(segments, 0)),
            channels,
        };
        rec.validate(name)?;
        Ok(rec)
    }
}

/// Mark `k` (from 1) at `t_s` in words.
fn describe_mark(k: usize, t_s: Option<f64>) -> String {
    match t_s {
        Some(t) => format!("mark {k} at t_s {t:.3}"),
        None => format!("mark {k} before the first row"),
    }
}

/// An Info frame in words, for the notes.
fn describe(i: &Info) -> String {
    let [major, minor, patch] = i.version;
    let dac: Vec<String> = i
        .dac_segments
        .iter()
        .flatten()
        .map(|s| (s + 1).to_string())
        .collect();
    // The driven segments' zeros only: the others are carried, unused.
    let n = usize::from(i.segments).min(i.calibration.current_zero_counts.len());
    let zeros = i.calibration.current_zero_counts[..n]
        .iter()
        .map(u16::to_string)
        .collect::<Vec<_>>()
        .join("/");
    format!(
        "firmware {major}.{minor}.{patch} (git {:08x}), {} segments ({}), {} Hz, \
         limit {} V, slew {} V/s, bridge supply {} V, overcurrent {} A, \
         load cell {:e} N/count, shunts {:e} A/count from zeros of {} counts \
         (calibration: {}), reset cause {}, configuration CRC {:04x}",
        i.git_hash,
        i.segments,
        if dac.is_empty() {
            "all H-bridges".to_string()
        } else {
            format!("DAC on segment {}", dac.join(" and "))
        },
        i.sample_hz,
        i.max_abs_v,
        i.slew_v_per_s,
        i.bridge_supply_v,
        i.overcurrent_a,
        i.calibration.newtons_per_count,
        i.amps_per_count,
        zeros,
        i.calibration_origin.name(),
        i.reset_cause.name(),
        i.config_crc().unwrap_or(0),
    )
}
