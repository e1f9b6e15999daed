//! Trivial diagnosers (#49): verdicts that fit nothing, scored beside
//! `finrs diagnose` on the same sessions, so that a headline says what
//! the diagnosis adds to a guess.
//!
//! Each reports the bench findings of the opening rests as `finrs
//! diagnose` does (`rests::rest_structure`: hum and 1/f noise, a spectrum
//! of the rests and no fit), and one fixed set of names:
//!
//! | diagnoser | verdict | names |
//! |---|---|---|
//! | `none` | `none` | none |
//! | `damped-soft` | `explained` | `damping`, `beam-stiffness`, and `hydrodynamic-loading` where the metadata say water |
//! | `damped-soft-unexplained` | `unexplained` | the same |
//!
//! `damping` and `beam-stiffness` are the contract's expected findings on
//! any real strip (docs/FORMAT.md, notes on the catalogue); water is read
//! off the metadata's `medium`.

use finrs::analysis::diagnose::rests::rest_structure;
use finrs::recording::Medium;
use finrs::session::Session;

use crate::expect::names_given;

/// A diagnoser that fits nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trivial {
    /// `none`, with the rests' bench findings.
    Nothing,
    /// `explained`: a damped, soft strip (in water, loaded by it).
    DampedSoft,
    /// `unexplained` with the same names.
    DampedSoftUnexplained,
}

/// Every trivial diagnoser, in the order the sweep reports them.
pub const TRIVIAL: [Trivial; 3] = [
    Trivial::Nothing,
    Trivial::DampedSoft,
    Trivial::DampedSoftUnexplained,
];

impl Trivial {
    /// The name the sweep's tables give it.
    pub fn name(self) -> &'static str {
        match self {
            Trivial::Nothing => "none",
            Trivial::DampedSoft => "damped-soft",
            Trivial::DampedSoftUnexplained => "damped-soft-unexplained",
        }
    }

    /// Its verdict word and names (catalogue names, then the rests' bench
    /// findings as `bench:` names) for `session`.
    pub fn diagnose(self, session: &Session) -> (String, Vec<String>) {
        let mut causes = Vec::new();
        let verdict = match self {
            Trivial::Nothing => "none",
            Trivial::DampedSoft => "explained",
            Trivial::DampedSoftUnexplained => "unexplained",
        };
        if self != Trivial::Nothing {
            causes.push("damping".to_string());
            causes.push("beam-stiffness".to_string());
            if session
                .recordings
                .iter()
                .any(|r| r.rec.meta.medium == Medium::Water)
            {
                causes.push("hydrodynamic-loading".to_string());
            }
        }
        let rests = rest_structure(session);
        let names = names_given(&causes, rests.bench.iter().map(|b| b.what.as_str()));
        (verdict.to_string(), names)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expect::{expected, score, Protocol};
    use crate::{bench::Bench, sample::Hidden};

    fn example() -> Session {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rig-session");
        Session::read(&dir).unwrap()
    }

    #[test]
    fn the_guesses_name_a_damped_soft_strip_and_score_against_the_contract() {
        let s = example();
        let (v, names) = Trivial::DampedSoft.diagnose(&s);
        assert_eq!(v, "explained");
        assert_eq!(&names[..2], ["damping", "beam-stiffness"]);
        let (v, names) = Trivial::Nothing.diagnose(&s);
        assert_eq!(v, "none");
        assert!(names.iter().all(|n| n.starts_with("bench:")), "{names:?}");
        // On the baseline's own strip, the damped-soft guess names two
        // effects it does not have; the null guess is right.
        let full = Protocol {
            free: true,
            blocked: true,
            session_start: true,
            along: true,
            ringing: true,
        };
        let e = expected(&Hidden::default(), &Bench::default(), full);
        let guess = ["damping".to_string(), "beam-stiffness".to_string()];
        assert_eq!(score(&e, "explained", &guess).wrong, guess);
        assert!(score(&e, "none", &[]).is_right());
    }
}
