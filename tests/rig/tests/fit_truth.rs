//! `finrs fit` with the structure an off-class strip truly has, against
//! the rig's values. The coverage over many sessions is measured by
//! `scripts/rig-coverage` (seeds from 10 000); this seed (504) was fixed
//! before it was run, and no other seed was tried in its place.

use finrs::analysis::fit::{profile_cost, Effect, Fitter};
use finrs::model::params::ModelFile;
use finrs::session::Session;
use finrs_rig::sweep::{structure_of, truth_of, write_scenario, Scenario};

/// A large deflection on the damped, soft base: from the data's own start
/// the fit of this structure took `EI` to a tenth of the truth on the
/// sweep's three such strips (10001, 10018, 10035); started also where the
/// measured mode rings, as the diagnosis starts it, the fit keeps
/// whichever ends lower. This seed is fitted right from either start (its
/// run printed the same `EI`, 8.0564e-5 against 8.0575e-5): the sweep's
/// seeds are the evidence for the second start, and no test uses them.
#[test]
fn a_large_deflection_fit_finds_the_strips_stiffness_and_circuit() {
    let s = Scenario {
        seed: 504,
        hidden: vec!["large-deflection"],
        bench: vec![],
        board: false,
        ..Scenario::default()
    };
    let dir = std::env::temp_dir().join(format!("finrs-fit-truth-{}", std::process::id()));
    write_scenario(&s, &dir).unwrap();
    let session = Session::read(&dir).unwrap();
    let fixed = ModelFile::main_m_2006()
        .spec_for(&session.geometry())
        .unwrap();
    let effects: Vec<Effect> = structure_of(&s)
        .unwrap()
        .iter()
        .map(|n| Effect::parse(n).unwrap())
        .collect();
    assert!(effects.contains(&Effect::LargeDeflection), "{effects:?}");
    let fitter = Fitter::new(&session);
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let from_data = fitter.fit(&all, &effects, None, fixed).unwrap();
    let either = fitter.fit_from_either_start(&all, &effects, fixed).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    // The lower of the two by the cost both descents minimised, to the
    // last digits two descents to the same point can differ in (the race
    // keeps either where the ends differ by less than a millionth; with
    // the drift's projection this seed's two ends differ by 1e-11).
    let (kept, data) = (profile_cost(&either.score), profile_cost(&from_data.score));
    assert!(kept <= data * (1.0 + 1e-9), "{kept} against {data}");
    let truth = truth_of(&s).unwrap();
    let off = |knob: &str, value: f64| (value - truth[knob]).abs() / truth[knob];
    let p = &either.spec.params;
    eprintln!(
        "EI {:.4e} (truth {:.4e}; from the data's start {:.4e}), RSS/m {:.3} ({:.3})",
        p.ei_nm2,
        truth["ei_nm2"],
        from_data.spec.params.ei_nm2,
        either.score.rss / either.score.m as f64,
        from_data.score.rss / from_data.score.m as f64
    );
    assert!(off("ei_nm2", p.ei_nm2) < 0.1, "EI {}", p.ei_nm2);
    // The currents alone fit the circuit, whatever the beam does.
    assert!(off("r1_ohm", p.r1_ohm) < 0.01, "R1 {}", p.r1_ohm);
    assert!(off("r2_ohm", p.r2_ohm) < 0.01, "R2 {}", p.r2_ohm);
    assert!(off("c_f", p.c_f) < 0.01, "C {}", p.c_f);
}
