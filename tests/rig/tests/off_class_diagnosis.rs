//! The diagnosis on the off-class rig (a damped strip, softer than the
//! laminate, relaxing or creeping): a few sessions on the short protocol,
//! each scored against what a right diagnosis says
//! (`tests/rig/src/expect.rs`, written from the contract before any
//! tuning). The sweep (`scripts/rig-sweep`, seeds from 10 000) carries the
//! statistics; these seeds (500 on) were fixed before they were run, and
//! no other seed was tried in their place.

use finrs::analysis::diagnose::Verdict;
use finrs_rig::expect::names_given;
use finrs_rig::sweep::{diagnose_dir, write_scenario, Scenario};
use finrs_rig::{score, Expected};

/// Writes the scenario's session, diagnoses it with the library, and
/// returns what was expected and the names given (catalogue names, then
/// bench findings as `bench:` names, as the sweep counts them).
fn run(
    hidden: &[&'static str],
    bench: &[&'static str],
    seed: u64,
) -> (Expected, Verdict, Vec<String>) {
    let s = Scenario {
        seed,
        hidden: hidden.to_vec(),
        bench: bench.to_vec(),
        board: false,
        ..Scenario::default()
    };
    let dir = std::env::temp_dir().join(format!("finrs-off-class-{seed}-{}", std::process::id()));
    let expected = write_scenario(&s, &dir).unwrap();
    let v = diagnose_dir(&dir).unwrap().verdict;
    std::fs::remove_dir_all(&dir).ok();
    let names = names_given(&v.causes, v.rest.bench.iter().map(|b| &b.what));
    eprintln!(
        "{} (seed {seed}): verdict {}, names {names:?}, expected {expected:?}",
        s.row(),
        v.verdict
    );
    (expected, v, names)
}

/// The names are right: every required name, no wrong one. The verdict
/// word is not asserted here: on these sessions the held-out residuals
/// stay above the noise floor (`unexplained`). The rig damps each mode by
/// its own ratio, which the model's Rayleigh damping matches at two modes
/// at most: a cause, not yet shown to be the only one. The sweep counts
/// the word.
fn assert_named_right(hidden: &[&'static str], bench: &[&'static str], seed: u64) {
    let (expected, v, names) = run(hidden, bench, seed);
    let s = score(&expected, &v.verdict, &names);
    assert!(s.missed.is_empty() && s.wrong.is_empty(), "{s:?}\n{v:#?}");
}

#[test]
fn the_off_class_base_is_named_damped_and_where_free_runs_show_it_soft() {
    assert_named_right(&[], &[], 500);
}

#[test]
fn large_deflection_on_the_off_class_base_is_named_beside_it() {
    assert_named_right(&["large-deflection"], &[], 501);
}

#[test]
fn coloured_noise_on_the_off_class_base_is_the_bench_not_a_model_effect() {
    assert_named_right(&[], &["coloured-noise"], 502);
}

/// A drying strip that is also damped and soft: its fading moment must not
/// be taken up by the damping and the stiffness that join first. (This
/// seed is named right with or without the refit of the joined model from
/// the data's start; sweep seeds 10022 and 10039 were not without it.)
#[test]
fn dehydration_on_the_off_class_base_is_named_beside_it() {
    assert_named_right(&["dehydration"], &[], 503);
}
