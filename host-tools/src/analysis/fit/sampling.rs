//! When the bench read its currents: at each row's instant after the row's
//! voltage was applied (a DAQ beside a drive, the rig, the model's own
//! convention), or before it (the finrs board: it samples at the start of
//! a period, then applies the period's voltage). The strip's series
//! resistance passes a change of voltage to the current at once, so the
//! current steps in the row of the voltage's change, or in the next one:
//! the session's own data say which. A bench property, not a model
//! effect: the fit then predicts the currents under the voltage they were
//! read under.

use crate::recording::Channel;
use crate::session::Session;

/// What the currents' steps say.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// The currents were read before each row's voltage was applied.
    pub before_update: bool,
    /// The share of the current's jump at a corner of the voltage that
    /// shows one row late: about 0 read after, about 1 read before.
    pub late_share: f64,
    /// Rows with a corner of the voltage (a change of its step) that the
    /// estimate used.
    pub changes: usize,
}

impl Sampling {
    /// The model's convention, for a session with no evidence.
    pub const AFTER: Sampling = Sampling {
        before_update: false,
        late_share: 0.0,
        changes: 0,
    };
}

impl std::fmt::Display for Sampling {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let when = if self.before_update {
            "before each row's voltage was applied (a bench property; the currents are predicted under the row before's)"
        } else {
            "after each row's voltage was applied"
        };
        write!(
            f,
            "currents read {when}: {:.2} of their jump at a corner of the voltage shows a row late, over {} corners",
            self.late_share, self.changes
        )
    }
}

/// The least-squares split of the currents' second differences `Δ²i_k`
/// between the voltage's in the same row `Δ²V_k` and in the row before
/// `Δ²V_{k−1}`: `Δ²i_k ≈ β₀ Δ²V_k + β₁ Δ²V_{k−1}`, over every segment's
/// current in every recording; the late share is `β₁/(β₀ + β₁)`. Second
/// differences, not first: the capacitor's part of the current is smooth
/// (its second difference is `dt/τ` of the voltage's at a corner), and a
/// slew-limited ramp's equal steps, which would make the voltage's steps in
/// one row and the next alike, leave only its corners. A share above one
/// half is read as "before". Too little evidence (fewer than two corners,
/// or no positive feedthrough at all) keeps the model's convention.
pub fn detect(session: &Session) -> Sampling {
    let (mut s00, mut s01, mut s11, mut t0, mut t1) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut changes = 0;
    for r in &session.recordings {
        // The drive the strip saw: across a contact fault the current
        // answers the contact's closing, not the voltage read.
        let v = &r.drive().v_v;
        for (ch, values) in &r.rec.channels {
            let Channel::Current(seg) = *ch else {
                continue;
            };
            let d2 = |x: [f64; 3]| x[2] - 2.0 * x[1] + x[0];
            for k in 3..values.len() {
                let (Some(i0), Some(i1), Some(i2)) = (values[k - 2], values[k - 1], values[k])
                else {
                    continue;
                };
                let at = |row: usize| v[row][seg];
                let dv0 = d2([at(k - 2), at(k - 1), at(k)]);
                let dv1 = d2([at(k - 3), at(k - 2), at(k - 1)]);
                if dv0 == 0.0 && dv1 == 0.0 {
                    continue;
                }
                if dv0 != 0.0 {
                    changes += 1;
                }
                let di = d2([i0, i1, i2]);
                s00 += dv0 * dv0;
                s01 += dv0 * dv1;
                s11 += dv1 * dv1;
                t0 += di * dv0;
                t1 += di * dv1;
            }
        }
    }
    let det = s00 * s11 - s01 * s01;
    if changes < 2 || det <= 1e-12 * s00 * s11 {
        return Sampling {
            changes,
            ..Sampling::AFTER
        };
    }
    let b0 = (t0 * s11 - t1 * s01) / det;
    let b1 = (t1 * s00 - t0 * s01) / det;
    if (b0 + b1).is_nan() || b0 + b1 <= 0.0 {
        return Sampling {
            changes,
            ..Sampling::AFTER
        };
    }
    let late_share = b1 / (b0 + b1);
    Sampling {
        before_update: late_share > 0.5,
        late_share,
        changes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::predict::{predict_currents, ModelSpec};
    use crate::model::synth::{drive_recording_shaped, limits, Drive};
    use crate::recording::Fixture;
    use crate::session::SessionRecording;
    use crate::wave::{Wave, WaveOptions};

    /// A blocked session of a slewed 2 V step and a 3 Hz sine (the
    /// firmware's generator and limiter), its currents from the model read
    /// `before` or after each row's update, rounded to a 0.25 mA count as
    /// the board's shunts.
    fn session(before: bool) -> Session {
        let dt_s = 1e-3;
        let mut spec = ModelSpec::baseline(model_core::Params::baseline_air_example());
        spec.sensors_before_update = before;
        let recordings = ["step:2", "sine:2,3,0"]
            .iter()
            .map(|wave| {
                let drive = Drive {
                    segments: 3,
                    fixture: Fixture::Blocked,
                    rest_s: 1.0,
                    duration_s: 2.0,
                    off_s: 1.0,
                    rate_hz: 1000.0,
                };
                let mut rec = drive_recording_shaped(
                    &Wave::parse(wave).unwrap(),
                    &drive,
                    &WaveOptions::steady(2.0),
                    Some(limits(4.0, 200.0).unwrap()),
                )
                .unwrap();
                let currents = predict_currents(&rec, &spec, dt_s, 0.0).unwrap();
                for (seg, c) in currents.into_iter().enumerate() {
                    let counted = c
                        .iter()
                        .map(|i| Some((i / 2.5e-4).round() * 2.5e-4))
                        .collect();
                    rec.channels.push((Channel::Current(seg), counted));
                }
                SessionRecording {
                    name: format!("{wave}.csv"),
                    rec,
                    dt_s,
                    t_start_s: Some(0.0),
                    rest_rows: 1000,
                    rests: vec![Default::default(); 3],
                    faults: Vec::new(),
                    strip_drive: None,
                }
            })
            .collect();
        Session {
            dir: "synthetic".into(),
            recordings,
        }
    }

    #[test]
    fn the_currents_steps_tell_when_they_were_read() {
        let before = detect(&session(true));
        assert!(
            before.before_update && before.late_share > 0.9,
            "{before:?}"
        );
        let after = detect(&session(false));
        assert!(!after.before_update && after.late_share < 0.1, "{after:?}");
        assert!(after.changes > 10);
    }

    #[test]
    fn no_change_of_voltage_keeps_the_convention() {
        let mut s = session(true);
        for r in &mut s.recordings {
            for k in 0..r.rec.t_s.len() {
                for seg in 0..3 {
                    r.rec.v_v[k][seg] = 0.0;
                }
            }
        }
        assert_eq!(detect(&s), Sampling::AFTER);
    }
}
