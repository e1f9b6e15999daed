//! The bench's faults, found in a session's data alone (no model): a
//! contact that did not carry a voltage to the strip, a sensor out of its
//! range, a sensor clipped at its range (docs/diagnosis.md, "The bench's
//! faults"). None is the strip's: a diagnosis names them as the bench's,
//! and the fit leaves their samples out ([`kept_out`]) and drives the
//! model with what the strip saw ([`strip_drive`]).
//!
//! Every threshold is in units of the channel's own reading of its
//! opening rest: its offset (median), its noise (rms about it) and its
//! step (resolution), whose band is the format's `5·√(σ² + Δ²/12)`
//! ([`REST_SIGMAS`]), as a voltage's rest is judged (docs/FORMAT.md,
//! "What a DAQ measures").

use std::ops::Range;

use crate::recording::{Channel, Recording, RestReading, REST_BAND_LIMIT_V, REST_SIGMAS};

/// Rows a voltage must read one level for to be a held level: a step
/// read mid-slew, or a sine's rows, are not.
pub const HOLD_ROWS: usize = 3;

/// Rows between two held levels that a change may take (a step read on
/// its way) besides a slew's: rows that each move the voltage the
/// change's way by more than a change's least step (a drive's slew
/// limiter: 0.2 V a row at 200 V/s and 1 kHz). A slower change is a
/// ramp, which drives its current gently and is not judged.
pub const TRANSITION_ROWS: usize = 2;

/// How many of its rest bands the current a change must push at once
/// ([`ContactJudge`]) must clear for the change to be judged: a
/// contact that conducts puts a fraction of the session's usual response
/// past the band, not a quarter of it inside.
pub const JUDGED_BANDS: f64 = 4.0;

/// Rows a contact fault must last, counted from the row where the
/// voltage settles at its new level: that row, the next (a bench may read
/// a row's current before it applies the row's voltage) and one more, so
/// that a single reading lost is no fault.
pub const FAULT_ROWS: usize = 3;

/// Samples a channel must miss in a row for an out-of-range stretch: a
/// camera's dropped frame or two is not a sensor out of its range.
pub const MISSED_SAMPLES: usize = 3;

/// Consecutive samples a clipped run holds at least.
pub const CLIP_SAMPLES: usize = 3;

/// How far from its rest a clipped extreme lies at least, in rest bands:
/// no reading of the rest, nor of a signal that barely leaves it.
pub const CLIP_FAR_BANDS: f64 = 2.0;

/// The chance below which a run of equal readings is not the channel's
/// noise: at rest, two consecutive readings are equal with a share `p`
/// (its noise against its step); `L` equal readings in a row come by
/// noise with chance `p^(L−1)`.
pub const CLIP_CHANCE: f64 = 1e-3;

/// What kind of fault, with what it needs to be told and undone.
#[derive(Clone, Debug, PartialEq)]
pub enum FaultKind {
    /// Segment `segment`'s voltage changed level but its current stayed
    /// within its rest band where the change must push a current through
    /// the series resistance at once: the voltage did not reach the
    /// strip until the current left the band.
    Contact {
        /// The segment (0-based).
        segment: usize,
        /// The level before the change, V (the hold's mean).
        before_v: f64,
        /// The level after it, V.
        after_v: f64,
        /// Whether the level before was the channel's rest: the strip
        /// then stayed at rest, and is driven so.
        from_rest: bool,
        /// The current's rest offset, A.
        current_offset_a: f64,
        /// The current's rest band, A.
        current_band_a: f64,
    },
    /// The channel has no reading over a stretch of samples (empty
    /// fields): the sensor was out of its range.
    OutOfRange,
    /// The channel reads its extreme over a run of samples, flatter than
    /// its noise allows: it saturated.
    Clipped {
        /// The value it is held at (the channel's unit).
        at: f64,
        /// The channel's rest band (the channel's unit).
        band: f64,
    },
}

impl FaultKind {
    /// As the verdict names it (never a catalogue name).
    pub fn name(&self) -> &'static str {
        match self {
            FaultKind::Contact { .. } => "contact-fault",
            FaultKind::OutOfRange => "out-of-range",
            FaultKind::Clipped { .. } => "clipped",
        }
    }
}

/// A fault of one recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    /// What it is.
    pub kind: FaultKind,
    /// The channel that shows it (a contact fault's: its segment's
    /// current).
    pub channel: Channel,
    /// The rows it covers: from the voltage's change to the current
    /// leaving its band; the empty rows; the clipped run.
    pub rows: Range<usize>,
}

/// A recording as the detectors need it: its data, its opening rest's
/// rows and its voltages' readings of a rest.
#[derive(Clone, Copy)]
pub struct Input<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Rows of its opening rest.
    pub rest_rows: usize,
    /// Each segment's voltage channel's reading of a rest.
    pub rests: &'a [RestReading],
}

/// Every fault of every recording of a session, in the recordings'
/// order. Contact faults are judged against the session's own response
/// of each segment's current (one strip, one series resistance); the
/// rest recording by recording.
pub fn find(recs: &[Input]) -> Vec<Vec<Fault>> {
    let judge = ContactJudge::new(recs);
    recs.iter()
        .map(|r| {
            let mut out = contact_faults(r, &judge);
            for (ch, values) in &r.rec.channels {
                out.extend(out_of_range(*ch, values));
                if !ch.is_camera() {
                    out.extend(clipped(*ch, values, r.rest_rows));
                }
            }
            out
        })
        .collect()
}

/// Rows (of `rows` in all) whose sample of `ch` stays out of the fit
/// because of `faults`: a clipped run on its own channel; a contact
/// fault's stretch on every channel, or, where the fault did not start
/// from the rest, every row from its start (what the strip saw after it
/// is unknown).
pub fn kept_out(faults: &[Fault], ch: Channel, rows: usize) -> Vec<bool> {
    let mut out = vec![false; rows];
    for f in faults {
        let span = match f.kind {
            FaultKind::Contact {
                from_rest: false, ..
            } => f.rows.start..rows,
            FaultKind::Contact { .. } => f.rows.clone(),
            FaultKind::Clipped { .. } if f.channel == ch => f.rows.clone(),
            _ => continue,
        };
        for k in &mut out[span.start.min(rows)..span.end.min(rows)] {
            *k = true;
        }
    }
    out
}

/// The drive the strip saw, where `faults` say it differs from `rec`'s:
/// a contact fault that starts from the rest leaves the strip at rest
/// (no current flowed), so over its stretch the segment is driven at the
/// level before it. `None` where no fault changes the drive.
pub fn strip_drive(rec: &Recording, faults: &[Fault]) -> Option<Recording> {
    let mut held = faults.iter().filter_map(|f| match f.kind {
        FaultKind::Contact {
            segment,
            before_v,
            from_rest: true,
            ..
        } => Some((segment, before_v, f.rows.clone())),
        _ => None,
    });
    let first = held.next()?;
    // The model reads the metadata, the time and the voltages only.
    let mut drive = Recording {
        meta: rec.meta.clone(),
        t_s: rec.t_s.clone(),
        v_v: rec.v_v.clone(),
        channels: Vec::new(),
    };
    for (segment, before_v, rows) in std::iter::once(first).chain(held) {
        for row in rows {
            drive.v_v[row][segment] = before_v;
        }
    }
    Some(drive)
}

/// A measured channel's reading of its opening rest.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Band {
    /// The rest's median.
    offset: f64,
    /// How far from it a rest reads: `5·√(σ² + Δ²/12)`.
    half: f64,
    /// The share of consecutive rest readings that are equal.
    repeats: f64,
}

impl Band {
    /// The reading of `values` over its first `rest_rows` rows, its step
    /// the smallest between any two of its values; `None` with fewer than
    /// two readings at rest.
    fn of(values: &[Option<f64>], rest_rows: usize) -> Option<Band> {
        let opening = &values[..rest_rows.min(values.len())];
        let rest: Vec<f64> = opening.iter().flatten().copied().collect();
        if rest.len() < 2 {
            return None;
        }
        let offset = median(rest.clone())?;
        let noise =
            (rest.iter().map(|v| (v - offset).powi(2)).sum::<f64>() / rest.len() as f64).sqrt();
        let mut all: Vec<f64> = values.iter().flatten().copied().collect();
        all.sort_unstable_by(f64::total_cmp);
        let step = all
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|&d| d > 0.0)
            .min_by(f64::total_cmp)
            .unwrap_or(0.0);
        let (mut pairs, mut equal) = (0usize, 0usize);
        for w in opening.windows(2) {
            if let (Some(a), Some(b)) = (w[0], w[1]) {
                pairs += 1;
                equal += usize::from(a == b);
            }
        }
        // Laplace's rule: a rest of a hundred readings, none repeated,
        // does not prove repeats impossible.
        let repeats = (equal as f64 + 1.0) / (pairs as f64 + 2.0);
        Some(Band {
            offset,
            half: REST_SIGMAS * (noise.powi(2) + step.powi(2) / 12.0).sqrt(),
            repeats,
        })
    }

    fn holds(&self, x: f64) -> bool {
        (x - self.offset).abs() <= self.half
    }
}

/// A change of a segment's voltage from one held level to another.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Change {
    /// The first row past the level before.
    row: usize,
    /// The first row of the level after.
    settled: usize,
    before_v: f64,
    after_v: f64,
}

/// Segment `k`'s level changes in `rec`: between two holds of at least
/// [`HOLD_ROWS`] rows each (every reading within twice the channel's rest
/// band of the hold's first: two readings of one level differ by no
/// more), whose levels differ by more than twice the band and than the
/// format's line between a rest and a drive ([`REST_BAND_LIMIT_V`]), the
/// change's least step, and between which the voltage slews (every row
/// moves it the change's way by more than that step) or takes at most
/// [`TRANSITION_ROWS`] rows.
fn level_changes(rec: &Recording, k: usize, rest: &RestReading) -> Vec<Change> {
    let v: Vec<f64> = rec.v_v.rows().map(|r| r[k]).collect();
    let width = 2.0 * rest.band_v();
    let least = width.max(REST_BAND_LIMIT_V);
    // Rows `from..to` each move the voltage by more than `least` the way
    // of `sign` (the new level's first row may end a slew by less).
    let slews = |from: usize, to: usize, sign: f64| {
        (from.max(1)..to).all(|r| (v[r] - v[r - 1]) * sign > least)
    };
    let mut holds: Vec<(Range<usize>, f64)> = Vec::new();
    let mut start = 0;
    while start < v.len() {
        let end = (start..v.len())
            .find(|&r| (v[r] - v[start]).abs() > width)
            .unwrap_or(v.len());
        if end - start >= HOLD_ROWS {
            let mean = v[start..end].iter().sum::<f64>() / (end - start) as f64;
            holds.push((start..end, mean));
        }
        start = end;
    }
    holds
        .windows(2)
        .filter(|w| (w[1].1 - w[0].1).abs() > least)
        .filter(|w| {
            let (a, b) = (&w[0].0, &w[1].0);
            b.start - a.end <= TRANSITION_ROWS || slews(a.end, b.start, w[1].1 - w[0].1)
        })
        .map(|w| Change {
            row: w[0].0.end,
            settled: w[1].0.start,
            before_v: w[0].1,
            after_v: w[1].1,
        })
        .collect()
}

/// What a level change of each segment pushes through its current, over
/// the session: the median over its changes of the current's largest
/// departure, within the change's first rows, from its last reading
/// before, per volt of the change. The strip's series resistance passes
/// a change at once; the median is the session's own, which a contact
/// fault (a minority of changes) does not move.
struct ContactJudge {
    /// Per segment, A/V (`None`: no change to judge by).
    response_a_per_v: Vec<Option<f64>>,
}

impl ContactJudge {
    fn new(recs: &[Input]) -> ContactJudge {
        let segments = recs.first().map_or(0, |r| r.rec.meta.segments);
        let response_a_per_v = (0..segments)
            .map(|k| {
                let mut ratios = Vec::new();
                for r in recs {
                    let Some(current) = r.rec.channel(Channel::Current(k)) else {
                        continue;
                    };
                    for c in level_changes(r.rec, k, &r.rests[k]) {
                        if let Some(moved) = response(current, &c) {
                            ratios.push(moved / (c.after_v - c.before_v).abs());
                        }
                    }
                }
                median(ratios)
            })
            .collect();
        ContactJudge { response_a_per_v }
    }

    /// Whether change `c` of segment `k` must move a current whose rest
    /// band is `band_a` out of it: by [`JUDGED_BANDS`] bands at the
    /// session's response.
    fn judges(&self, k: usize, c: &Change, band_a: f64) -> bool {
        self.response_a_per_v[k]
            .is_some_and(|g| g * (c.after_v - c.before_v).abs() >= JUDGED_BANDS * band_a)
    }
}

/// The rows in which a change's current must respond: from its first row
/// to the row after it settles (a bench may read a row's current before
/// it applies the row's voltage).
fn window(c: &Change, rows: usize) -> Range<usize> {
    c.row..(c.settled + 2).min(rows)
}

/// The current's largest departure over change `c`'s window from its
/// last reading before the change; `None` without readings.
fn response(current: &[Option<f64>], c: &Change) -> Option<f64> {
    let before = current[..c.row].iter().rev().flatten().next()?;
    current[window(c, current.len())]
        .iter()
        .flatten()
        .map(|i| (i - before).abs())
        .max_by(f64::total_cmp)
}

/// Contact faults of `r` (see [`FaultKind::Contact`]): a judged change
/// after which the current reads within its rest band through at least
/// [`FAULT_ROWS`] rows of the new level. The fault lasts until the
/// current leaves its band (the contact closed) or the voltage reads its
/// level before again (the drive and the strip agree once more).
fn contact_faults(r: &Input, judge: &ContactJudge) -> Vec<Fault> {
    let mut out = Vec::new();
    let rows = r.rec.t_s.len();
    for k in 0..r.rec.meta.segments {
        let Some(current) = r.rec.channel(Channel::Current(k)) else {
            continue;
        };
        let Some(band) = Band::of(current, r.rest_rows) else {
            continue;
        };
        let rest = &r.rests[k];
        let mut after = 0;
        for c in level_changes(r.rec, k, rest) {
            if c.row < after || !judge.judges(k, &c, band.half) {
                continue;
            }
            let back = |row: usize| (r.rec.v_v[row][k] - c.before_v).abs() <= 2.0 * rest.band_v();
            let end = (c.row..rows)
                .find(|&row| current[row].is_some_and(|i| !band.holds(i)) || back(row))
                .unwrap_or(rows);
            let read = current[window(&c, rows)].iter().flatten().count();
            if end < c.settled + FAULT_ROWS || read == 0 {
                continue;
            }
            out.push(Fault {
                kind: FaultKind::Contact {
                    segment: k,
                    before_v: c.before_v,
                    after_v: c.after_v,
                    from_rest: rest.at_rest(c.before_v),
                    current_offset_a: band.offset,
                    current_band_a: band.half,
                },
                channel: Channel::Current(k),
                rows: c.row..end,
            });
            after = end;
        }
    }
    out
}

/// The out-of-range stretches of a channel: where it misses at least
/// [`MISSED_SAMPLES`] samples in a row at its own rate (the median spacing
/// of its readings: every row for the DAQ's, every frame for a camera's),
/// at the start, between readings or at the end.
fn out_of_range(ch: Channel, values: &[Option<f64>]) -> Vec<Fault> {
    let read: Vec<usize> = (0..values.len()).filter(|&r| values[r].is_some()).collect();
    let gaps: Vec<f64> = read.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
    let Some(period) = median(gaps) else {
        return Vec::new();
    };
    let missed = |from: usize, to: usize| ((to - from) as f64 / period).round() as usize;
    let mut out = Vec::new();
    let mut push = |rows: Range<usize>| {
        out.push(Fault {
            kind: FaultKind::OutOfRange,
            channel: ch,
            rows,
        })
    };
    // Before the first reading the channel misses `first / period`
    // samples; between two readings one fewer than their spacing.
    if missed(0, read[0]) >= MISSED_SAMPLES {
        push(0..read[0]);
    }
    for w in read.windows(2) {
        if missed(w[0], w[1]) > MISSED_SAMPLES {
            push(w[0] + 1..w[1]);
        }
    }
    let last = read[read.len() - 1];
    if missed(last, values.len() - 1) >= MISSED_SAMPLES {
        push(last + 1..values.len());
    }
    out
}

/// The clipped runs of a DAQ channel: at least [`CLIP_SAMPLES`]
/// consecutive readings exactly at its maximum or minimum over the
/// recording, that extreme beyond [`CLIP_FAR_BANDS`] rest bands from its
/// rest, and the run flatter than the channel's rest noise allows
/// ([`CLIP_CHANCE`]). A channel that reads its rest as one unchanging
/// value (its noise below its step) shows nothing by its flatness, and
/// no clip is found on it.
fn clipped(ch: Channel, values: &[Option<f64>], rest_rows: usize) -> Vec<Fault> {
    let Some(band) = Band::of(values, rest_rows) else {
        return Vec::new();
    };
    let read: Vec<(usize, f64)> = (0..values.len())
        .filter_map(|r| values[r].map(|v| (r, v)))
        .collect();
    let fold = |f: fn(f64, f64) -> f64, init| read.iter().fold(init, |m, &(_, v)| f(m, v));
    let extremes = [
        fold(f64::max, f64::NEG_INFINITY),
        fold(f64::min, f64::INFINITY),
    ];
    let mut out = Vec::new();
    for at in extremes {
        if (at - band.offset).abs() <= CLIP_FAR_BANDS * band.half {
            continue;
        }
        let mut i = 0;
        while i < read.len() {
            if read[i].1 != at {
                i += 1;
                continue;
            }
            let run = read[i..].iter().take_while(|&&(_, v)| v == at).count();
            let chance = band.repeats.powi(run as i32 - 1);
            if run >= CLIP_SAMPLES && chance < CLIP_CHANCE {
                out.push(Fault {
                    kind: FaultKind::Clipped {
                        at,
                        band: band.half,
                    },
                    channel: ch,
                    rows: read[i].0..read[i + run - 1].0 + 1,
                });
            }
            i += run;
        }
    }
    out
}

/// The median (the upper of two middle values), `None` when empty.
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_unstable_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One segment at `dt_s` per row: `v(row)` read back by the DAQ, and
    /// `i(row)` (`None`: an empty field).
    fn recording(
        rows: usize,
        dt_s: f64,
        v: impl Fn(usize) -> f64,
        i: impl Fn(usize) -> Option<f64>,
    ) -> Recording {
        let mut text = "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V,i1_A\n".to_string();
        for r in 0..rows {
            let i = i(r).map_or(String::new(), |x| format!("{x:.6}"));
            text += &format!("{:.3},{:.6},{i}\n", r as f64 * dt_s, v(r));
        }
        Recording::parse("r.csv", &text).unwrap()
    }

    fn faults_of(rec: &Recording, rest_rows: usize) -> Vec<Fault> {
        let rests = [RestReading::measure(&rec.t_s, &rec.v_v, 0)];
        let input = Input {
            rec,
            rest_rows,
            rests: &rests,
        };
        find(&[input]).remove(0)
    }

    /// A DAQ's rest: 0.3 mV counts about 0.9 mV.
    fn daq_rest(row: usize) -> f64 {
        0.0003 * (2 + [0, 1, 0, 2, 1, 1, 3][row % 7]) as f64
    }

    /// The seed's circuit (R1 = 160 Ω, τ = 16 ms) under a step of `v`
    /// volts at `from_s`, and back to rest at `off_s`, with a leak through
    /// `r2_ohm`, read in 0.1 mA counts.
    fn current(t_s: f64, v: f64, from_s: f64, off_s: f64, r2_ohm: f64) -> f64 {
        let spike = |t: f64| (-(t / 0.016)).exp() / 160.0;
        let mut i = 0.0;
        if t_s >= from_s {
            i += v * spike(t_s - from_s) + if t_s < off_s { v / r2_ohm } else { 0.0 };
        }
        if t_s >= off_s {
            i -= v * spike(t_s - off_s);
        }
        (i / 1e-4).round() * 1e-4 + 0.0
    }

    /// 100 rows/s: 1.5 s at rest, 3 V from 1.5 s to 6 s, off to 8 s.
    fn stepped(close_s: f64) -> Recording {
        recording(
            800,
            0.01,
            |r| {
                if (150..600).contains(&r) {
                    3.0003
                } else {
                    daq_rest(r)
                }
            },
            |r| Some(current(r as f64 * 0.01, 3.0, close_s, 6.0, 700.0)),
        )
    }

    #[test]
    fn a_contact_that_closes_late_is_a_fault_from_the_step_to_the_current() {
        // The contact closes 1.3 s after the step.
        let rec = stepped(2.8);
        let faults = faults_of(&rec, 150);
        assert_eq!(faults.len(), 1, "{faults:?}");
        let f = &faults[0];
        assert_eq!(f.rows, 150..280, "{f:?}");
        assert_eq!(f.channel, Channel::Current(0));
        let FaultKind::Contact {
            segment,
            before_v,
            after_v,
            from_rest,
            ..
        } = f.kind
        else {
            panic!("{f:?}")
        };
        assert_eq!(segment, 0);
        assert!(from_rest && before_v.abs() < 0.002 && (after_v - 3.0003).abs() < 1e-9);
        // Out of the fit on every channel over the stretch; the strip
        // driven at the rest there, and as read after it.
        let out = kept_out(&faults, Channel::TipY, 800);
        assert_eq!(out.iter().filter(|&&k| k).count(), 130);
        assert!(out[150] && out[279] && !out[149] && !out[280]);
        let drive = strip_drive(&rec, &faults).unwrap();
        assert_eq!(drive.v_v[200][0], before_v);
        assert_eq!(drive.v_v[280][0], 3.0003);
        assert_eq!(drive.v_v[100][0], rec.v_v[100][0]);
        assert!(drive.channels.is_empty());
    }

    #[test]
    fn a_contact_that_carries_the_step_is_no_fault() {
        let rec = stepped(1.5);
        assert_eq!(faults_of(&rec, 150), []);
        assert!(strip_drive(&rec, &[]).is_none());
    }

    /// A long hold whose leak (3 V through 1 MΩ) rounds to 0 mA: the
    /// current reads its rest for 40 s, but the charging spike at the
    /// step showed the contact was good.
    #[test]
    fn a_leak_below_the_resolution_on_a_long_hold_is_no_fault() {
        let rec = recording(
            4500,
            0.01,
            |r| {
                if (150..4150).contains(&r) {
                    3.0003
                } else {
                    daq_rest(r)
                }
            },
            |r| Some(current(r as f64 * 0.01, 3.0, 1.5, 41.5, 1e6)),
        );
        // The hold reads the rest's current: 0 A.
        assert_eq!(rec.channel(Channel::Current(0)).unwrap()[2000], Some(0.0));
        assert_eq!(faults_of(&rec, 150), []);
    }

    /// A contact that lifts as the voltage changes from one drive to
    /// another: what the strip saw after is unknown, so the rest of the
    /// recording stays out, and the drive is not changed.
    #[test]
    fn a_fault_that_starts_from_a_drive_keeps_the_rest_out() {
        let rec = recording(
            800,
            0.01,
            |r| match r {
                150..=349 => 2.0003,
                350..=599 => 3.0003,
                _ => daq_rest(r),
            },
            |r| {
                let t = r as f64 * 0.01;
                let i = match r {
                    // Good at 1.5 s and 6 s; open from 3.5 s to 5 s.
                    350..=499 => 0.0,
                    _ => current(t, 2.0, 1.5, 100.0, 700.0) + current(t, 3.0, 5.0, 6.0, 700.0),
                };
                Some(i)
            },
        );
        let faults = faults_of(&rec, 150);
        assert_eq!(faults.len(), 1, "{faults:?}");
        assert_eq!(faults[0].rows, 350..500);
        assert!(matches!(
            faults[0].kind,
            FaultKind::Contact {
                from_rest: false,
                ..
            }
        ));
        let out = kept_out(&faults, Channel::Current(0), 800);
        assert!(!out[349] && out[350] && out[799]);
        assert!(strip_drive(&rec, &faults).is_none());
    }

    /// A drive through a slew limiter (200 V/s at 1 kHz: a 2 V step over
    /// 10 rows) whose contact lifted: judged as a step is.
    #[test]
    fn a_slewed_step_without_its_current_is_a_fault() {
        let v = |r: usize| match r {
            1500..=1509 => 0.2 * (r - 1499) as f64,
            1510..=3999 => 2.0,
            _ => 0.0,
        };
        // The contact closes at 2.5 s; good at 4 s (an unslewed return).
        let i = |r: usize| {
            let t = r as f64 * 1e-3;
            let x = current(t, 2.0, 2.5, 4.0, 700.0);
            Some(if r < 2500 { 0.0 } else { x })
        };
        let rec = recording(5000, 1e-3, v, i);
        let faults = faults_of(&rec, 1500);
        assert_eq!(faults.len(), 1, "{faults:?}");
        assert_eq!(faults[0].rows, 1500..2500);
        // The contact good, the current read a row late (before the row's
        // voltage is applied): no fault.
        let late = |r: usize| Some(current((r as f64 - 1.0) * 1e-3, 2.0, 1.5, 4.0, 700.0));
        assert_eq!(faults_of(&recording(5000, 1e-3, v, late), 1500), []);
    }

    /// A slow ramp (0.2 V over 2 s) whose current, its capacitor's 10 µA
    /// and a leak below the band, stays at the rest's: no change of level
    /// that must push a current at once, so no fault, however the
    /// session's steps respond.
    #[test]
    fn a_slow_ramp_with_a_quiet_current_is_no_fault() {
        let v = |r: usize| {
            daq_rest(r)
                + match r {
                    150..=349 => 0.2 * (r - 149) as f64 / 200.0,
                    350..=599 => 0.2,
                    650..=799 => 3.0,
                    _ => 0.0,
                }
        };
        // The drop from 0.2 V at 6 s, and a step of 3 V from 6.5 s to 8 s.
        let i = |r: usize| {
            let t = r as f64 * 0.01;
            Some(current(t, 0.2, f64::INFINITY, 6.0, 1e6) + current(t, 3.0, 6.5, 8.0, 700.0))
        };
        let rec = recording(900, 0.01, v, i);
        assert_eq!(faults_of(&rec, 150), []);
    }

    #[test]
    fn out_of_range_stretches_are_counted_and_short_gaps_are_not() {
        // The current every row: empty over rows 200..260 (a stretch), at
        // 300 and 301 (two samples: no stretch), and from 750 to the end.
        let rec = recording(800, 0.01, daq_rest, |r| {
            (!((200..260).contains(&r) || r == 300 || r == 301 || r >= 750)).then_some(0.0)
        });
        let found = faults_of(&rec, 150);
        let rows: Vec<_> = found.iter().map(|f| f.rows.clone()).collect();
        assert_eq!(rows, [200..260, 750..800], "{found:?}");
        assert!(found.iter().all(|f| f.kind == FaultKind::OutOfRange));
        // Nothing more to keep out of the fit: the fields are empty.
        assert!(kept_out(&found, Channel::Current(0), 800)
            .iter()
            .all(|&k| !k));
    }

    #[test]
    fn a_camera_that_drops_a_frame_or_two_is_in_range_and_one_lost_for_a_while_is_not() {
        // Frames every 33 rows; two frames dropped at 330 and 363, six
        // from 660.
        let frame = |r: usize| r % 33 == 0;
        let values: Vec<Option<f64>> = (0..1000)
            .map(|r| {
                let lost = r == 330 || r == 363 || (660..858).contains(&r);
                (frame(r) && !lost).then_some(1e-3)
            })
            .collect();
        let found = out_of_range(Channel::TipY, &values);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].rows, 628..858);
    }

    /// A current amplifier that clips at ±15 mA a spike of 3 V through
    /// 160 Ω; its rest noise (0.05 mA read in µA) never repeats a reading.
    #[test]
    fn a_clipped_spike_is_found_and_a_quantised_rest_is_not_clipped() {
        let noise = |r: usize| 5e-5 * ((r * 7919 % 1000) as f64 / 500.0 - 1.0);
        let spike = |r: usize| {
            let t = r as f64 * 1e-3;
            if t >= 1.5 {
                3.0 / 160.0 * (-(t - 1.5) / 0.016).exp()
            } else {
                0.0
            }
        };
        let values: Vec<Option<f64>> = (0..3000)
            .map(|r| Some((((spike(r) + noise(r)).clamp(-0.015, 0.015)) * 1e6).round() / 1e6))
            .collect();
        let found = clipped(Channel::Current(0), &values, 1500);
        assert_eq!(found.len(), 1, "{found:?}");
        // Above 15 mA for 16 ms × ln(18.75/15) = 3.6 ms.
        assert_eq!(found[0].rows.start, 1500);
        assert!((3..=5).contains(&found[0].rows.len()), "{found:?}");
        assert!(kept_out(&found, Channel::Current(0), 3000)[1501]);
        assert!(!kept_out(&found, Channel::Force, 3000)[1501]);
        // A rest read in 0.1 mA counts, mostly 0, now and then ±0.1 mA:
        // its extremes are readings of the rest.
        let rest: Vec<Option<f64>> = (0..3000)
            .map(|r| Some([0.0, 0.0, 1e-4, 0.0, -1e-4, 0.0, 0.0][r % 7]))
            .collect();
        assert_eq!(clipped(Channel::Current(0), &rest, 1500), []);
    }

    /// A quiet channel in coarse counts (its rest one unchanging value)
    /// holds the same count over a plateau: flat by its nature, not
    /// clipped.
    #[test]
    fn a_quiet_quantised_plateau_is_not_clipped() {
        let values: Vec<Option<f64>> = (0..3000)
            .map(|r| {
                Some(if (1500..2500).contains(&r) {
                    0.0042
                } else {
                    0.0
                })
            })
            .collect();
        assert_eq!(clipped(Channel::Force, &values, 1500), []);
    }
}
