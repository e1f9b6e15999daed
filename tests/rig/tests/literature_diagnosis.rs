//! The diagnosis on the literature strip (`finrs_rig::literature`): where
//! one effect's evidence lies in one kind of recording, a session of the
//! literature sweep's plan. The sweep (`rig-sweep --literature`, seeds from
//! 50 000) carries the statistics; the seed here is chosen by its drawn
//! strength, before it was diagnosed, from seeds no sweep had run.

use finrs_rig::expect::names_given;
use finrs_rig::literature::plausible;
use finrs_rig::score;
use finrs_rig::sweep::{diagnose_dir, plan_literature, strengths_of, strip_of, write_scenario};

/// Crosstalk shows apart from the beam's form only where a segment is
/// driven alone: driven together, the literature strip's blocked runs
/// pull `κ` below zero whatever the strip hides (docs/rig.md). The first
/// session of the plan from seed 700 that hides crosstalk alone at twice
/// its plausible strength or more: named, from its lone drives, with the
/// fraction within half of the rig's and no wrong name beside it.
#[test]
fn crosstalk_on_the_literature_strip_is_named_from_its_lone_drives() {
    let crosstalk = "segment-crosstalk";
    let s = plan_literature(700, 400)
        .into_iter()
        .filter(|s| s.hidden == [crosstalk])
        .find(|s| {
            strengths_of(s)
                .unwrap()
                .iter()
                .any(|(n, x)| *n == crosstalk && *x >= 2.0 * plausible(crosstalk))
        })
        .expect("a crosstalk session at twice the plausible strength");
    let kappa = strip_of(&s).unwrap().1.crosstalk.unwrap();
    let dir = std::env::temp_dir().join(format!(
        "finrs-literature-xt-{}-{}",
        s.seed,
        std::process::id()
    ));
    let expected = write_scenario(&s, &dir).unwrap();
    let d = diagnose_dir(&dir).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let v = &d.verdict;
    let names = names_given(&v.causes, v.rest.bench.iter().map(|b| &b.what));
    eprintln!("seed {}: κ {kappa:.3}, names {names:?}", s.seed);
    let scored = score(&expected, &v.verdict, &names);
    assert!(scored.wrong.is_empty(), "{scored:?}\n{v:#?}");
    assert!(v.causes.iter().any(|c| c == crosstalk), "{v:#?}");
    let lone = v
        .candidates
        .iter()
        .find(|c| c.lone_drives)
        .expect("judged on the lone drives");
    assert!(lone.passed && lone.name == crosstalk, "{lone:?}");
    // Reported beside the final fit's own, its covariance row with it.
    let said = v.params.get("crosstalk").copied().unwrap();
    assert!((said / kappa - 1.0).abs() < 0.5, "{said} for {kappa}");
    let est = &d.final_fit.estimates;
    assert_eq!(d.final_fit.value_covariance.nrows(), est.len());
    assert!(est.last().is_some_and(|e| e.low < said && said < e.high));
    assert!((d.final_fit.spec.ext.crosstalk - said).abs() < 1e-12);
}
