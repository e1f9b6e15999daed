//! The rig hides an effect (or none) in a session, at a random strength in
//! a randomly drawn strip; `finrs diagnose` must name it without seeing
//! the seed. Over the whole catalogue, over pairs, and for an effect
//! outside it, which must come out `unexplained` and not as a wrong cause.
//!
//! Seeds are fixed so that CI is repeatable; `FINRS_RIG_SEED=n` draws
//! other strips and strengths (`scripts/rig-sweep-ideal` runs many).

use finrs::analysis::diagnose::Verdict;
use finrs_rig::sweep::diagnose_dir;
use finrs_rig::{
    short_protocol, write_session, Bench, Hidden, Sample, Sensors, CATALOGUE, OUTSIDE,
    SEGMENT_VARIATION,
};
use rand::{Rng, SeedableRng};

fn seed(default: u64) -> u64 {
    std::env::var("FINRS_RIG_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .map_or(default, |s| s.wrapping_mul(1000).wrapping_add(default))
}

/// Writes a rig session hiding `names`, diagnoses it, and reports.
fn hide(names: &[&str], default_seed: u64) -> Verdict {
    let seed = seed(default_seed);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let sample = Sample::draw(&mut rng);
    let hidden = Hidden::draw(names, &mut rng).unwrap();
    let sensors = Sensors::draw(&mut rng);
    let label = format!("{}-{seed}", names.join("+"));
    let dir = std::env::temp_dir().join(format!("finrs-rig-{label}-{}", std::process::id()));
    write_session(
        &dir,
        &sample,
        &hidden,
        &sensors,
        &Bench::default(),
        &short_protocol(0.6),
        &label,
        &mut rng,
    )
    .unwrap();
    let v = diagnose_dir(&dir).unwrap().verdict;
    std::fs::remove_dir_all(&dir).ok();
    // docs/rig.md's table quotes these lines (`-- --nocapture`).
    eprintln!(
        "hidden {names:?} (seed {seed}): verdict {}, causes {:?}, held-out NRMSE {:.4} -> {:.4} ({:.1} % gain), RSS/m {:.3} -> {:.3}\n  {hidden:?}",
        v.verdict,
        v.causes,
        v.baseline.holdout_nrmse,
        v.extended.holdout_nrmse,
        v.gain_percent,
        v.baseline.holdout_rss_per_residual,
        v.extended.holdout_rss_per_residual
    );
    v
}

/// The effect is named, alone, and the extended model gains on held-out data.
fn named(effect: &str, seed: u64) -> Verdict {
    let v = hide(&[effect], seed);
    assert_eq!(v.causes, [effect], "{v:#?}");
    assert_ne!(v.verdict, "none");
    assert!(v.gain_percent > 0.0, "{v:#?}");
    v
}

#[test]
fn nothing_hidden_is_none() {
    let v = hide(&[], 101);
    assert_eq!(v.verdict, "none", "{v:#?}");
    assert!(v.causes.is_empty());
    assert!(
        v.analyses.immovable.is_empty(),
        "{:?}",
        v.analyses.immovable
    );
}

#[test]
fn large_deflection() {
    let v = named("large-deflection", 102);
    // The baseline cannot move the camera's along-the-strip channels.
    assert!(
        v.analyses.immovable.iter().any(|c| c.ends_with("tip_x_m")),
        "{:?}",
        v.analyses.immovable
    );
    // The baseline's tip residual follows the drive (far beyond the white
    // band); the arc kinematics take most of that dependence away.
    let tip = v
        .residual_tests
        .iter()
        .filter(|t| t.channel == "tip_y_m")
        .max_by(|a, b| {
            a.baseline_input_correlation
                .total_cmp(&b.baseline_input_correlation)
        })
        .expect("a held-out tip channel");
    assert!(
        tip.baseline_input_correlation > 2.0 * tip.input_band
            && tip.final_input_correlation < 0.5 * tip.baseline_input_correlation,
        "{tip:?}"
    );
}

#[test]
fn beam_stiffness() {
    named("beam-stiffness", 103);
}

#[test]
fn damping() {
    named("damping", 104);
}

#[test]
fn hydrodynamic_loading() {
    named("hydrodynamic-loading", 105);
}

#[test]
fn electrochemical_nonlinearity() {
    named("electrochemical-nonlinearity", 106);
}

#[test]
fn back_relaxation() {
    named("back-relaxation", 107);
}

#[test]
fn dehydration() {
    let v = named("dehydration", 108);
    // The strip answers the baseline less and less over the session.
    let trend = v
        .analyses
        .trend
        .as_ref()
        .expect("start times are in the notes");
    assert!(trend.spearman < -0.5, "{trend:?}");
}

#[test]
fn segment_crosstalk() {
    named("segment-crosstalk", 109);
}

/// Segments 2 and 3 depart from segment 1 by 5 to 15 % in each of `R1`,
/// `C` and `K` (hand-cut electrodes, uneven plating).
#[test]
fn segment_variation() {
    named(SEGMENT_VARIATION, 114);
}

#[test]
fn a_pair_is_named_both() {
    for (pair, seed) in [
        (["damping", "large-deflection"], 110),
        (["dehydration", "segment-crosstalk"], 111),
    ] {
        let v = hide(&pair, seed);
        let mut got = v.causes.clone();
        got.sort();
        let mut want: Vec<String> = pair.iter().map(|s| s.to_string()).collect();
        want.sort();
        assert_eq!(got, want, "{v:#?}");
        // Each cause was checked after the search, beside the other, and
        // stayed: the last check naming it passed.
        for cause in &v.causes {
            let last = v
                .candidates
                .iter()
                .rev()
                .find(|c| c.backward && c.name.split('+').any(|n| n == cause));
            assert!(last.is_some_and(|c| c.passed), "{cause}: {v:#?}");
        }
    }
}

/// Mains pickup is outside the catalogue: a bench imperfection
/// (docs/FORMAT.md). The opening rests show it, so the diagnosis reports
/// it as the bench, on the DAQ channels that carry it (currents and load
/// cell), and names nothing.
#[test]
fn mains_pickup_is_reported_as_the_bench_and_named_nothing() {
    let v = hide(&[OUTSIDE], 112);
    assert!(v.causes.is_empty(), "named a wrong cause: {v:#?}");
    assert!(v.verdict == "none" || v.verdict == "unexplained", "{v:#?}");
    let hum: Vec<&str> = v
        .rest
        .bench
        .iter()
        .filter(|b| b.what == "mains-hum" && b.mains_hz == Some(50.0))
        .map(|b| b.channel.as_str())
        .collect();
    assert_eq!(hum, ["i1_A", "i2_A", "i3_A", "force_N"], "{:#?}", v.rest);
}

/// One draw from the catalogue and `none`; the effect comes from the seed.
#[test]
fn a_random_draw_is_named() {
    let seed = seed(113);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0x5eed);
    let pick = rng.gen_range(0..=CATALOGUE.len());
    match CATALOGUE.get(pick) {
        Some(effect) => {
            named(effect, seed);
        }
        None => {
            let v = hide(&[], seed);
            assert_eq!(v.verdict, "none", "{v:#?}");
        }
    }
}
