//! The recordings a plan may propose: each a protocol step within the
//! drive limit, named for what it would show.
//!
//! Each is one recording a bench can make in a minute or less: a long
//! hold (the relaxation's slow pole, a creep, drying), a chirp across the
//! first mode (damping, stiffness, added mass), each segment alone and
//! neighbours driven against each other (segment variation, crosstalk),
//! the largest and a small step (electrochemical nonlinearity), the
//! fixture the session lacks, and the first drive again at the session's
//! end (drying).

use finrs_drive::MAX_FREQUENCY_HZ;

use crate::analysis::fit::modal::model_first_hz;
use crate::model::predict::ModelSpec;
use crate::protocol::Step;
use crate::recording::{Fixture, SAFE_VOLTAGE_LIMIT_V};
use crate::session::Session;

/// Opening rest of every proposal, s: the fit reads each sensor's noise
/// from at least 1 s at 0 V.
pub const REST_S: f64 = 1.5;

/// A recording the plan may propose, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The recording as a protocol holds it.
    pub step: Step,
    /// What it is for, in a few words.
    pub purpose: String,
    /// Pause after the session's last recording before this one, s (0:
    /// none); drying is read on the session's clock.
    pub later_s: f64,
}

impl Candidate {
    /// Bench time of the recording itself, s (pauses not counted).
    pub fn duration_s(&self) -> f64 {
        self.step.rest_s + self.step.hold_s + self.step.off_s
    }
}

/// Pause before the repeat of the first drive, s: drying of a few percent
/// an hour shows over minutes, not seconds.
pub const REPEAT_AFTER_S: f64 = 600.0;

/// The candidates for `session` whose model is `spec`.
pub fn candidates(session: &Session, spec: &ModelSpec) -> Vec<Candidate> {
    let recs = &session.recordings;
    let segments = recs.first().map_or(1, |r| r.rec.meta.segments);
    let has = |f: Fixture| recs.iter().any(|r| r.rec.meta.fixture == f);
    // The camera shows the free strip; a session without free runs (the
    // board alone) proposes blocked ones, which its load cell reads.
    let fixture = if has(Fixture::Free) {
        Fixture::Free
    } else {
        Fixture::Blocked
    };
    let largest_v = recs
        .iter()
        .flat_map(|r| r.rec.v_v.as_flat().iter().map(|v| v.abs()))
        .fold(0.0f64, f64::max);
    // The session's own largest drive, at least 1 V, never past the limit.
    let level_v = round_v(largest_v.clamp(1.0, SAFE_VOLTAGE_LIMIT_V));
    let step = |name: String, fixture: Fixture, wave: String, hold_s: f64, off_s: f64| Step {
        name,
        fixture,
        wave,
        rest_s: REST_S,
        hold_s,
        off_s,
        tare: fixture == Fixture::Blocked,
        prompt: None,
        notes: None,
    };
    let mut out = Vec::new();
    let mut push = |step: Step, purpose: &str, later_s: f64| {
        out.push(Candidate {
            step,
            purpose: purpose.to_string(),
            later_s,
        })
    };
    let tag = fixture.name();

    push(
        step(
            format!("{tag}_long_hold_{level_v:.1}V"),
            fixture,
            format!("step:{level_v}"),
            20.0,
            10.0,
        ),
        "a 20 s hold and 10 s after: the relaxation's slow pole, creep and drying",
        0.0,
    );
    if let Some(f1_hz) = model_first_hz(spec, fixture) {
        // An octave either side, within what the firmware's generator
        // sweeps: a held strip's first mode can lie above it, and then
        // the chirp ends at the limit, below the mode.
        let top_hz = f64::from(MAX_FREQUENCY_HZ);
        let hi = round_hz((2.0 * f1_hz).min(top_hz));
        let lo = round_hz((0.5 * f1_hz).min(0.25 * hi));
        let amplitude_v = round_v(0.5 * level_v);
        let reach = if 2.0 * f1_hz > top_hz {
            format!(", the sweep ending at the generator's {top_hz} Hz")
        } else {
            String::new()
        };
        push(
            step(
                format!("{tag}_chirp_first_mode"),
                fixture,
                format!("chirp:{amplitude_v},{lo},{hi}"),
                8.0,
                2.0,
            ),
            &format!("a chirp across the first mode (model: {f1_hz:.1} Hz{reach}): damping, stiffness and added mass"),
            0.0,
        );
    }
    if segments > 1 {
        for k in 0..segments {
            let levels: Vec<String> = (0..segments)
                .map(|j| {
                    if j == k {
                        format!("{level_v}")
                    } else {
                        "0".into()
                    }
                })
                .collect();
            push(
                step(
                    format!("{tag}_seg{}_alone", k + 1),
                    fixture,
                    format!("step:{}", levels.join(",")),
                    4.0,
                    3.0,
                ),
                &format!(
                    "segment {} alone: its own R1, C and moment, and what reaches its neighbours",
                    k + 1
                ),
                0.0,
            );
        }
        for k in 0..segments - 1 {
            let levels: Vec<String> = (0..segments)
                .map(|j| match j {
                    _ if j == k => format!("{level_v}"),
                    _ if j == k + 1 => format!("-{level_v}"),
                    _ => "0".into(),
                })
                .collect();
            push(
                step(
                    format!("{tag}_seg{}_against_seg{}", k + 1, k + 2),
                    fixture,
                    format!("step:{}", levels.join(",")),
                    4.0,
                    3.0,
                ),
                &format!(
                    "segments {} and {} driven against each other: crosstalk cancels nothing there",
                    k + 1,
                    k + 2
                ),
                0.0,
            );
        }
    }
    let top_v = SAFE_VOLTAGE_LIMIT_V;
    if largest_v < top_v {
        push(
            step(format!("{tag}_step_{top_v:.1}V"), fixture, format!("step:{top_v}"), 4.0, 3.0),
            "a step at the drive limit: the charge's and the leak's departure from linear grow with the voltage",
            0.0,
        );
    }
    push(
        step(
            format!("{tag}_step_0.5V"),
            fixture,
            "step:0.5".into(),
            4.0,
            3.0,
        ),
        "a small step: the linear reference the large ones depart from",
        0.0,
    );
    let other = match fixture {
        Fixture::Free => Fixture::Blocked,
        Fixture::Blocked => Fixture::Free,
    };
    if !has(other) {
        push(
            step(
                format!("{}_step_{level_v:.1}V", other.name()),
                other,
                format!("step:{level_v}"),
                4.0,
                3.0,
            ),
            match other {
                Fixture::Free => {
                    "a free run (a camera on the tip): the arc of a large deflection, the free mode"
                }
                Fixture::Blocked => {
                    "a blocked run (the tip on the load cell): the moment itself, and the held mode"
                }
            },
            0.0,
        );
    }
    push(
        step(
            format!("{tag}_repeat_later_{level_v:.1}V"),
            fixture,
            format!("step:{level_v}"),
            4.0,
            3.0,
        ),
        "the same step again ten minutes after the session: drying over the session's clock",
        REPEAT_AFTER_S,
    );
    out
}

/// Volts to 0.1 V, as an operator types them.
fn round_v(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

/// Hertz to two significant digits' worth (0.1 Hz below 10 Hz, 1 Hz above).
fn round_hz(hz: f64) -> f64 {
    if hz < 10.0 {
        (hz * 10.0).round() / 10.0
    } else {
        hz.round()
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::model::params::ModelFile;
    use crate::model::synth::{drive_recording_shaped, Drive};
    use crate::protocol::Protocol;
    use crate::recording::Recording;
    use crate::wave::{Wave, WaveOptions};

    fn example() -> Session {
        Session::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session"))
            .unwrap()
    }

    fn spec(session: &Session) -> ModelSpec {
        ModelFile::main_m_2006()
            .spec_for(&session.geometry())
            .unwrap()
    }

    /// The candidates as a protocol, read back, and each one's drive as
    /// the firmware's generator makes it: its largest voltage.
    fn checked(session: &Session) -> Vec<(Candidate, f64)> {
        let all = candidates(session, &spec(session));
        let p = Protocol {
            sample: None,
            medium: session.recordings[0].rec.meta.medium,
            geometry: session.geometry(),
            dots_s_m: None,
            model: None,
            recordings: all.iter().map(|c| c.step.clone()).collect(),
        };
        // Unique names, waves the protocol accepts.
        assert_eq!(Protocol::parse("plan.toml", &p.to_toml()).unwrap(), p);
        all.into_iter()
            .map(|c| {
                let s = &c.step;
                let drive = Drive {
                    segments: session.recordings[0].rec.meta.segments,
                    fixture: s.fixture,
                    rest_s: s.rest_s,
                    duration_s: s.hold_s,
                    off_s: s.off_s,
                    rate_hz: 1000.0,
                };
                let options = WaveOptions {
                    hold_s: s.hold_s,
                    ..WaveOptions::steady(s.hold_s)
                };
                let rec =
                    drive_recording_shaped(&Wave::parse(&s.wave).unwrap(), &drive, &options, None)
                        .unwrap_or_else(|e| panic!("{}: {e}", s.name));
                let peak = rec.v_v.as_flat().iter().fold(0.0f64, |m, v| m.max(v.abs()));
                (c, peak)
            })
            .collect()
    }

    #[test]
    fn every_candidate_is_a_protocol_step_the_generator_runs_within_the_limit() {
        let session = example();
        let all = checked(&session);
        for (c, peak) in &all {
            assert!(*peak <= SAFE_VOLTAGE_LIMIT_V, "{}: {peak} V", c.step.name);
            assert!(*peak > 0.0, "{}", c.step.name);
            assert!(c.step.rest_s >= 1.0, "the fit reads the noise at rest");
        }
        let names: Vec<&str> = all.iter().map(|(c, _)| c.step.name.as_str()).collect();
        // Three segments: each alone and two pairs against each other.
        assert!(names.contains(&"free_seg3_alone"), "{names:?}");
        assert!(names.contains(&"free_seg2_against_seg3"), "{names:?}");
        // The example has blocked runs and reached 4 V: no other fixture,
        // no step to the limit.
        assert!(
            !names.iter().any(|n| n.starts_with("blocked_")),
            "{names:?}"
        );
        assert!(!names.contains(&"free_step_4.0V"), "{names:?}");
    }

    #[test]
    fn a_board_only_session_gets_blocked_runs_a_free_one_and_a_chirp_below_the_generators_limit() {
        let mut session = example();
        session
            .recordings
            .retain(|r| r.rec.meta.fixture == Fixture::Blocked);
        let all = checked(&session);
        let chirp = all
            .iter()
            .find(|(c, _)| c.step.name == "blocked_chirp_first_mode")
            .expect("a chirp");
        // The held strip's first mode lies above what the generator sweeps.
        assert!(chirp.0.step.wave.ends_with(",100"), "{}", chirp.0.step.wave);
        assert!(all.iter().any(|(c, _)| c.step.fixture == Fixture::Free));
    }

    #[test]
    fn a_strip_of_one_segment_gets_no_segment_drives() {
        let mut text = String::from(
            "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V,i1_A\n",
        );
        for i in 0..2500 {
            let v = if i < 1200 { 0.0 } else { 2.0 };
            text += &format!("{},{v},0\n", i as f64 * 1e-3);
        }
        let rec = Recording::parse("one.csv", &text).unwrap();
        let session = Session {
            dir: "one".into(),
            recordings: vec![Session::prepare(Path::new("one.csv"), rec).unwrap()],
        };
        let all = checked(&session);
        assert!(all.iter().all(|(c, _)| !c.step.name.contains("seg")));
        // The session's largest drive, 2 V, and the limit above it.
        assert!(all.iter().any(|(c, _)| c.step.wave == "step:2"));
        assert!(all.iter().any(|(c, _)| c.step.wave == "step:4"));
    }
}
