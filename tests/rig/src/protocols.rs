//! Protocols drawn per session (#49): a lab does not record the example
//! session's ten runs in its order, so the literature sweep draws each
//! session's own: steps on all segments or one, sines, chirps, pulse
//! trains, blocked steps and sines, with amplitudes, frequencies, holds
//! and rests of their own, in a shuffled order.
//!
//! What every drawn session keeps, so that each catalogue effect can be
//! seen at all: two blocked runs or more (the load cell pins `EI` against
//! the free runs), and on the full protocol a free step of 3 V or more,
//! a free step on one segment alone, and a free sine or chirp.

use finrs::recording::Fixture;
use rand::seq::SliceRandom;
use rand::Rng;

use crate::session::Run;

/// Recordings of a drawn session, at least and at most.
pub const RECORDINGS: (usize, usize) = (7, 11);

/// Draws a session's runs; `board`: every run blocked (the board records
/// alone, no camera).
pub fn draw(board: bool, rng: &mut impl Rng) -> Vec<Run> {
    let count = rng.gen_range(RECORDINGS.0..=RECORDINGS.1);
    let mut kinds: Vec<Kind> = if board {
        vec![Kind::BlockedStep, Kind::BlockedStep]
    } else {
        vec![
            Kind::BlockedStep,
            Kind::BlockedStep,
            Kind::LargeStep,
            Kind::OneSegment,
            if rng.gen_bool(0.5) {
                Kind::Sine
            } else {
                Kind::Chirp
            },
        ]
    };
    while kinds.len() < count {
        kinds.push(if board {
            *[Kind::BlockedStep, Kind::BlockedSine]
                .choose(rng)
                .unwrap_or(&Kind::BlockedStep)
        } else {
            *Kind::ALL.choose(rng).unwrap_or(&Kind::Step)
        });
    }
    kinds.shuffle(rng);
    kinds
        .into_iter()
        .enumerate()
        .map(|(i, k)| k.run(i + 1, rng))
        .collect()
}

/// What a drawn run does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// A free step on every segment.
    Step,
    /// A free step of 3 V or more on every segment.
    LargeStep,
    /// A free step on one segment.
    OneSegment,
    /// A free travelling sine.
    Sine,
    /// A free chirp, every segment in phase.
    Chirp,
    /// A free pulse train.
    Pulses,
    /// A blocked step.
    BlockedStep,
    /// A blocked travelling sine.
    BlockedSine,
}

impl Kind {
    const ALL: [Kind; 8] = [
        Kind::Step,
        Kind::LargeStep,
        Kind::OneSegment,
        Kind::Sine,
        Kind::Chirp,
        Kind::Pulses,
        Kind::BlockedStep,
        Kind::BlockedSine,
    ];

    fn run(self, index: usize, rng: &mut impl Rng) -> Run {
        // Volts to the DAQ's millivolt, frequencies to the centihertz: as
        // a lab writes them.
        let v = |rng: &mut dyn rand::RngCore, lo: f64, hi: f64| {
            (rng.gen_range(lo..hi) * 1000.0).round() / 1000.0
        };
        let hz = |rng: &mut dyn rand::RngCore, lo: f64, hi: f64| {
            (rng.gen_range(f64::ln(lo)..f64::ln(hi)).exp() * 100.0).round() / 100.0
        };
        let (wave, fixture, what) = match self {
            Kind::Step => {
                let a = v(rng, 0.5, 3.0);
                (
                    format!("step:{a}"),
                    Fixture::Free,
                    format!("step {a} V on all segments"),
                )
            }
            Kind::LargeStep => {
                let a = v(rng, 3.0, 4.0);
                (
                    format!("step:{a}"),
                    Fixture::Free,
                    format!("step {a} V on all segments"),
                )
            }
            Kind::OneSegment => {
                let a = v(rng, 1.5, 3.5);
                let on = rng.gen_range(0..crate::sample::SEGMENTS);
                let levels: Vec<String> = (0..crate::sample::SEGMENTS)
                    .map(|i| {
                        if i == on {
                            a.to_string()
                        } else {
                            "0".to_string()
                        }
                    })
                    .collect();
                (
                    format!("step:{}", levels.join(",")),
                    Fixture::Free,
                    format!("step {a} V on segment {} only", on + 1),
                )
            }
            Kind::Sine | Kind::BlockedSine => {
                let (a, f) = (v(rng, 0.8, 2.5), hz(rng, 0.2, 5.0));
                let lag = [0, 60, 90, 120][rng.gen_range(0..4)];
                let fixture = if self == Kind::Sine {
                    Fixture::Free
                } else {
                    Fixture::Blocked
                };
                (
                    format!("sine:{a},{f},{lag}"),
                    fixture,
                    format!("travelling sine {f} Hz, {a} V, {lag} deg lag per segment"),
                )
            }
            Kind::Chirp => {
                let (a, f0, f1) = (v(rng, 1.0, 2.5), hz(rng, 0.05, 0.3), hz(rng, 8.0, 25.0));
                (
                    format!("chirp:{a},{f0},{f1}"),
                    Fixture::Free,
                    format!("logarithmic chirp {f0} to {f1} Hz, {a} V, all segments in phase"),
                )
            }
            Kind::Pulses => {
                let (a, on, off) = (v(rng, 1.0, 3.0), v(rng, 0.2, 1.0), v(rng, 0.2, 1.0));
                (
                    format!("pulses:{a},{on},{off}"),
                    Fixture::Free,
                    format!("pulses {a} V, {on} s on, {off} s off"),
                )
            }
            Kind::BlockedStep => {
                let a = v(rng, 1.0, 4.0);
                (
                    format!("step:{a}"),
                    Fixture::Blocked,
                    format!("step {a} V on all segments"),
                )
            }
        };
        let held = if fixture == Fixture::Blocked {
            "blocked"
        } else {
            "free"
        };
        let hold_s = match self {
            // A chirp needs its sweep's length to reach its end.
            Kind::Chirp => v(rng, 5.0, 8.0),
            _ => v(rng, 2.0, 5.0),
        };
        let kind = format!("{self:?}").to_lowercase();
        Run {
            name: format!("{index:02}_{held}_{kind}"),
            wave,
            fixture,
            rest_s: v(rng, 1.0, 2.5),
            hold_s,
            off_s: v(rng, 1.5, 4.0),
            description: format!("{held} {what}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn every_drawn_session_keeps_what_each_effect_needs_and_parses() {
        for seed in 0..200 {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let board = seed % 5 == 0;
            let runs = draw(board, &mut rng);
            assert!((RECORDINGS.0..=RECORDINGS.1).contains(&runs.len()));
            let blocked = runs
                .iter()
                .filter(|r| r.fixture == Fixture::Blocked)
                .count();
            assert!(blocked >= 2, "seed {seed}: {blocked} blocked");
            for r in &runs {
                finrs::wave::Wave::parse(&r.wave).unwrap();
                assert!(r.rest_s >= 1.0 && r.hold_s >= 2.0, "{r:?}");
            }
            if board {
                assert_eq!(blocked, runs.len());
            } else {
                let has = |k: &str| runs.iter().any(|r| r.name.ends_with(k));
                assert!(has("largestep") && has("onesegment"));
                assert!(has("free_sine") || has("chirp"));
            }
        }
        // Sessions differ from seed to seed.
        let a = draw(false, &mut rand::rngs::StdRng::seed_from_u64(1));
        let b = draw(false, &mut rand::rngs::StdRng::seed_from_u64(2));
        assert_ne!(
            a.iter().map(|r| &r.wave).collect::<Vec<_>>(),
            b.iter().map(|r| &r.wave).collect::<Vec<_>>()
        );
    }
}
