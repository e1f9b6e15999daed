//! The bench's faults reported as what they are (docs/diagnosis.md, "The
//! bench's faults"): contact faults, out-of-range stretches and clipped
//! sensors, found in the data alone when the session is read
//! (`session::faults`), kept out of every fit, and named per recording
//! in the verdict, never as a catalogue effect.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::recording::Channel;
use crate::session::{FaultKind, Session, SessionRecording};

/// A fault's stretch: its rows, and the value a clipped run holds (NaN
/// for an out-of-range stretch).
type Stretch = (std::ops::Range<usize>, f64);

/// A fault of one recording, as `VERDICT.json` holds it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FaultFinding {
    /// The recording's file name.
    pub recording: String,
    /// `contact-fault`, `out-of-range` or `clipped`.
    pub kind: String,
    /// The channel: a contact fault's segment voltage (`v1_V`), the
    /// sensor's column otherwise.
    pub channel: String,
    /// Where the first stretch starts, s (the recording's time).
    pub from_s: f64,
    /// Where the last stretch ends, s.
    pub to_s: f64,
    /// Stretches (one for a contact fault; the out-of-range stretches, or
    /// the clipped runs, of this channel in this recording).
    pub stretches: usize,
    /// Their total duration, s.
    pub total_s: f64,
    /// What was seen and what the fit did with it, in words.
    pub detail: String,
}

/// Every fault of `session`: each contact fault alone, out-of-range
/// stretches and clipped runs gathered per recording and channel.
pub fn findings(session: &Session) -> Vec<FaultFinding> {
    let mut out = Vec::new();
    for r in &session.recordings {
        // (kind, channel) -> its stretches (rows), in the order found.
        let mut gathered: BTreeMap<(&str, String), Vec<Stretch>> = BTreeMap::new();
        for f in &r.faults {
            match f.kind {
                FaultKind::Contact { .. } => out.push(contact(r, f)),
                FaultKind::OutOfRange => gathered
                    .entry(("out-of-range", f.channel.name()))
                    .or_default()
                    .push((f.rows.clone(), f64::NAN)),
                FaultKind::Clipped { at, .. } => gathered
                    .entry(("clipped", f.channel.name()))
                    .or_default()
                    .push((f.rows.clone(), at)),
            }
        }
        for ((kind, channel), stretches) in gathered {
            out.push(gathered_finding(r, kind, channel, &stretches));
        }
    }
    out
}

/// The time at `row`, s; past the last row, one sample after it.
fn time_at(r: &SessionRecording, row: usize) -> f64 {
    let t = &r.rec.t_s;
    match t.get(row) {
        Some(&x) => x,
        None => t.last().map_or(0.0, |&x| x + r.dt_s),
    }
}

fn contact(r: &SessionRecording, f: &crate::session::Fault) -> FaultFinding {
    let FaultKind::Contact {
        segment,
        before_v,
        after_v,
        from_rest,
        current_offset_a,
        current_band_a,
    } = f.kind
    else {
        unreachable!("a contact fault");
    };
    let (from_s, to_s) = (time_at(r, f.rows.start), time_at(r, f.rows.end));
    let (v, i) = (
        format!("v{}_V", segment + 1),
        Channel::Current(segment).name(),
    );
    let until = if f.rows.end >= r.rec.t_s.len() {
        format!("to the recording's end ({to_s:.3} s)")
    } else {
        format!("until {to_s:.3} s")
    };
    let fit = if from_rest {
        format!(
            "the strip stayed at rest, so the model is driven at {before_v:.4} V there, and the stretch is left out of the fit"
        )
    } else {
        format!(
            "what the strip saw after it is unknown, so the recording from {from_s:.3} s on is left out of the fit"
        )
    };
    FaultFinding {
        recording: r.name.clone(),
        kind: f.kind.name().to_string(),
        channel: v.clone(),
        from_s,
        to_s,
        stretches: 1,
        total_s: to_s - from_s,
        detail: format!(
            "{}: contact fault on segment {}: {v} goes from {before_v:.4} V to {after_v:.4} V at {from_s:.3} s, but {i} stays within its rest band ({:.2e} ± {:.2e} A) {until}, {:.3} s with no current where the change must push one through the series resistance: the voltage did not reach the strip; {fit}",
            r.name,
            segment + 1,
            current_offset_a,
            current_band_a,
            to_s - from_s,
        ),
    }
}

fn gathered_finding(
    r: &SessionRecording,
    kind: &str,
    channel: String,
    stretches: &[Stretch],
) -> FaultFinding {
    let from_s = time_at(r, stretches[0].0.start);
    let to_s = time_at(r, stretches[stretches.len() - 1].0.end);
    let total_s: f64 = stretches
        .iter()
        .map(|(rows, _)| time_at(r, rows.end) - time_at(r, rows.start))
        .sum();
    let n = stretches.len();
    let plural = if n == 1 { "" } else { "es" };
    let detail = if kind == "out-of-range" {
        format!(
            "{}: {channel} out of range (empty fields, {} samples or more in a row) in {n} stretch{plural}, {total_s:.3} s in all, from {from_s:.3} s to {to_s:.3} s: the sensor had no reading there, and nothing there is fitted",
            r.name,
            crate::session::faults::MISSED_SAMPLES,
        )
    } else {
        let mut at: Vec<f64> = stretches.iter().map(|&(_, a)| a).collect();
        at.sort_by(f64::total_cmp);
        at.dedup();
        let at: Vec<String> = at.iter().map(|a| format!("{a}")).collect();
        let shortest = stretches.iter().map(|(rows, _)| rows.len()).min();
        format!(
            "{}: {channel} clipped: held at its extreme ({}) in {n} run{} of {} samples or more, {total_s:.3} s in all, from {from_s:.3} s to {to_s:.3} s, flatter than its rest's noise allows: the sensor saturated, and those samples are left out of the fit",
            r.name,
            at.join(" and "),
            if n == 1 { "" } else { "s" },
            shortest.unwrap_or(0),
        )
    };
    FaultFinding {
        recording: r.name.clone(),
        kind: kind.to_string(),
        channel,
        from_s,
        to_s,
        stretches: n,
        total_s,
        detail,
    }
}
