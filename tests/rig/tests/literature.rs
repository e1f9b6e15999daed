//! The literature strip's forms (`finrs_rig::literature`), each against
//! what it claims: electrolysis only above its onset, a resistive electrode
//! that makes the tip lag, a viscoelastic strip that rings down and is
//! stiffer to a quick load, drying that takes the moment, and metadata
//! measured a few percent off. Short runs of the rig's strip, no
//! diagnosis.

use std::path::PathBuf;

use finrs::recording::{Channel, Recording, Voltages};
use finrs_rig::literature::{Drying, Literature};
use finrs_rig::strip::{run, Truth, BLOCKED_MESH, MESH};
use finrs_rig::sweep::{plan_literature, strengths_of, strip_of, write_scenario, write_twin};
use finrs_rig::{Hidden, Sample, Tip};
use rand::SeedableRng;

fn rng(seed: u64) -> rand::rngs::StdRng {
    rand::rngs::StdRng::seed_from_u64(seed)
}

/// `rest_s` at 0 V, then `volts` on every segment for `hold_s`, at 1 kHz.
fn step(volts: f64, rest_s: f64, hold_s: f64) -> Voltages {
    let rest = (rest_s * 1000.0) as usize;
    let hold = (hold_s * 1000.0) as usize;
    Voltages::from_rows(
        3,
        (0..rest + hold).map(|r| if r < rest { [0.0; 3] } else { [volts; 3] }),
    )
}

/// A literature strip with its base physics and nothing else.
fn base(seed: u64) -> (Sample, Hidden) {
    let mut r = rng(seed);
    let sample = Sample::draw_off_class(&mut r);
    let hidden = Literature::draw(&[], &sample, 150.0, &mut r).unwrap();
    (sample, hidden)
}

fn blocked(sample: &Sample, hidden: &Hidden, volts: &Voltages) -> Truth {
    let camera = vec![false; volts.len()];
    run(
        sample,
        hidden,
        BLOCKED_MESH,
        Tip::Pinned,
        volts,
        1e-3,
        0.0,
        &camera,
        &[],
    )
}

/// The free strip's point at arc length `s_m`, `(along, across)` from
/// where it rests, at every row.
fn free_point(
    sample: &Sample,
    hidden: &Hidden,
    volts: &Voltages,
    t0_s: f64,
    s_m: f64,
) -> Vec<(f64, f64)> {
    let camera = vec![true; volts.len()];
    let t = run(
        sample,
        hidden,
        MESH,
        Tip::Free,
        volts,
        1e-3,
        t0_s,
        &camera,
        &[s_m],
    );
    t.points_m.into_iter().next().expect("one point asked for")
}

fn free_tip(sample: &Sample, hidden: &Hidden, volts: &Voltages, t0_s: f64) -> Vec<f64> {
    free_point(sample, hidden, volts, t0_s, 0.05)
        .iter()
        .map(|p| p.1)
        .collect()
}

fn last_current(t: &Truth) -> f64 {
    *t.currents_a[0].last().unwrap()
}

#[test]
fn electrolysis_raises_the_steady_current_only_above_its_onset() {
    let (sample, mut hidden) = base(1);
    let plain = hidden.clone();
    let extra = 1.0;
    hidden.literature.as_mut().unwrap().reaction =
        Some(Literature::reaction_for(&sample, extra, 1.23, 0.06));
    // Below the onset the double layer never reaches it: the same current.
    let low = step(1.0, 0.1, 3.0);
    let (a, b) = (
        last_current(&blocked(&sample, &plain, &low)),
        last_current(&blocked(&sample, &hidden, &low)),
    );
    assert!((b / a - 1.0).abs() < 1e-6, "{b} against {a} at 1 V");
    // At 3 V the steady current is the drawn multiple of the linear
    // leak's (stated on the lumped strip; the line's sheet shifts it a
    // little).
    let high = step(3.0, 0.1, 3.0);
    let (a, b) = (
        last_current(&blocked(&sample, &plain, &high)),
        last_current(&blocked(&sample, &hidden, &high)),
    );
    assert!(
        (b / a - (1.0 + extra)).abs() < 0.1,
        "{:.3} times the linear leak's at 3 V, drawn {}",
        b / a,
        1.0 + extra
    );
}

#[test]
fn a_resistive_electrode_makes_the_tip_lag() {
    let (sample, hidden) = base(2);
    let mut tight = hidden.clone();
    tight.literature.as_mut().unwrap().sheet_over_r1 = 0.01;
    let mut loose = hidden.clone();
    loose.literature.as_mut().unwrap().sheet_over_r1 = 2.0;
    let v = step(2.0, 0.05, 0.03);
    let early = |h: &Hidden| {
        let t = blocked(&sample, h, &v);
        t.force_n[60]
    };
    // 10 ms into the step: the far cells of the loose electrode are still
    // charging, and the force (all of the strip's moment) lags.
    let (f_tight, f_loose) = (early(&tight), early(&loose));
    assert!(
        f_loose.abs() < 0.9 * f_tight.abs(),
        "{f_loose} against {f_tight}"
    );
}

#[test]
fn a_viscoelastic_strip_rings_down_by_its_spectrum_alone() {
    let (sample, hidden) = base(3);
    assert!(hidden.modal_damping.is_none() && hidden.damping_ratio.is_none());
    let y = free_tip(&sample, &hidden, &step(2.0, 0.0, 1.5), 0.0);
    // The swing about a running mean over the first and the last 100 ms.
    let swing = |from: usize| {
        let w = &y[from..from + 100];
        let m = w.iter().sum::<f64>() / w.len() as f64;
        w.iter().map(|x| (x - m).abs()).fold(0.0, f64::max)
    };
    assert!(
        swing(1400) < 0.2 * swing(0),
        "{} against {}",
        swing(1400),
        swing(0)
    );
}

#[test]
fn drying_takes_the_moment_and_the_charge_with_the_water() {
    let (sample, mut hidden) = base(4);
    hidden.literature.as_mut().unwrap().drying = Some(Drying {
        loss: 0.2,
        tau_s: 100.0,
        span_s: 300.0,
    });
    let v = step(1.0, 0.0, 2.0);
    let early = free_tip(&sample, &hidden, &v, 0.0);
    let late = free_tip(&sample, &hidden, &v, 300.0);
    // Moment per volt as w²: 0.64 of the wet strip's, the current's
    // charge as w.
    let ratio = late.last().unwrap() / early.last().unwrap();
    assert!((ratio - 0.64).abs() < 0.05, "{ratio}");
}

#[test]
fn a_literature_session_is_measured_with_a_ruler_and_a_balance() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("finrs-literature-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let s = plan_literature(50_000, 14)
        .into_iter()
        .find(|s| s.hidden.contains(&"electrochemical-nonlinearity"))
        .unwrap();
    write_scenario(&s, &dir).unwrap();
    let (sample, hidden) = strip_of(&s).unwrap();
    let lit = hidden.literature.as_ref().unwrap();
    // The session's own drawn protocol: its first free recording.
    let runs = finrs_rig::sweep::runs_of(&s);
    let first = runs.iter().find(|r| r.name.contains("_free_")).unwrap();
    let rec = Recording::read(&dir.join(format!("{}.csv", first.name))).unwrap();
    let off = |said: f64, truth: f64| said / truth - 1.0;
    let (l, w, t) = (
        off(rec.meta.length_m, sample.length_m),
        off(rec.meta.width_m, sample.width_m),
        off(rec.meta.thickness_m, sample.thickness_m()),
    );
    assert!(l.abs() <= 0.01 && w.abs() <= 0.02 && t.abs() <= 0.04);
    assert!(l != 0.0 && w != 0.0 && t != 0.0, "{l} {w} {t}");
    assert!(
        (1.0 + l - lit.measured[0]).abs() < 1e-9,
        "{l} {:?}",
        lit.measured
    );
    // The tip's dot is where the ruler puts the tip.
    let dots = rec.meta.dots_s_m.clone().unwrap();
    assert_eq!(*dots.last().unwrap(), rec.meta.length_m);
    assert!(rec.channels.iter().any(|(c, _)| *c == Channel::TipY));
    // Its strength is stated, in the diagnosis's unit.
    let st = strengths_of(&s).unwrap();
    assert!(st
        .iter()
        .any(|(n, x)| *n == "electrochemical-nonlinearity" && *x > 0.0));
    std::fs::remove_dir_all(&dir).ok();
}

/// The standard deviation of segment 1's current over the first
/// recording's opening rest, A.
fn rest_spread_a(dir: &std::path::Path, name: &str) -> f64 {
    let rec = Recording::read(&dir.join(format!("{name}.csv"))).unwrap();
    let current = rec.channel(Channel::Current(0)).unwrap();
    let rest: Vec<f64> = (0..rec.t_s.len())
        .take_while(|&r| rec.v_v.row(r).is_some_and(|v| v.iter().all(|v| *v == 0.0)))
        .filter_map(|r| current[r])
        .collect();
    assert!(rest.len() > 100, "{} rest rows", rest.len());
    let mean = rest.iter().sum::<f64>() / rest.len() as f64;
    (rest.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / rest.len() as f64).sqrt()
}

#[test]
fn a_twin_is_the_session_with_its_measurement_errors_scaled() {
    let root: PathBuf = std::env::temp_dir().join(format!("finrs-twin-{}", std::process::id()));
    std::fs::remove_dir_all(&root).ok();
    let s = &finrs_rig::sweep::plan_literature_null(60_000, 1)[0];
    let (session, same, small) = (root.join("session"), root.join("same"), root.join("small"));
    write_scenario(s, &session).unwrap();
    // At scale 1 the twin draws everything as the session did: the same
    // bytes, so a smaller scale changes the errors and nothing else.
    write_twin(s, &same, 1.0).unwrap();
    write_twin(s, &small, 0.1).unwrap();
    let runs = finrs_rig::sweep::runs_of(s);
    for r in &runs {
        let file = format!("{}.csv", r.name);
        assert_eq!(
            std::fs::read(session.join(&file)).unwrap(),
            std::fs::read(same.join(&file)).unwrap(),
            "{file}"
        );
    }
    let ratio = rest_spread_a(&small, &runs[0].name) / rest_spread_a(&session, &runs[0].name);
    assert!((0.08..0.12).contains(&ratio), "rest spread ratio {ratio}");
    // Nothing else is scaled: the metadata's geometry is the same.
    let meta = |d: &std::path::Path| {
        Recording::read(&d.join(format!("{}.csv", runs[0].name)))
            .unwrap()
            .meta
    };
    assert_eq!(meta(&session).thickness_m, meta(&small).thickness_m);
    let err = write_twin(s, &root.join("zero"), 0.0).unwrap_err();
    assert!(err.to_string().contains("noise scale"), "{err}");
    std::fs::remove_dir_all(&root).ok();
}

#[test]
fn a_back_relaxing_strip_ends_bent_the_other_way() {
    // The catalogue's back-relaxation (FORMAT.md): held, the strip ends
    // bent against its first bend. Drawn in the probe's unit, every draw
    // is one (a branch of β ≤ 1 only relaxes part way: the baseline).
    for seed in 0..4 {
        let mut r = rng(100 + seed);
        let sample = Sample::draw_off_class(&mut r);
        let hidden = Literature::draw(&["back-relaxation"], &sample, 150.0, &mut r).unwrap();
        let s = finrs_rig::literature::strengths(&sample, &hidden)
            .into_iter()
            .find(|(n, _)| *n == "back-relaxation")
            .unwrap()
            .1;
        assert!((0.02..=1.0).contains(&s), "{s}");
        let t = blocked(&sample, &hidden, &step(1.0, 0.0, 90.0));
        let (first, last) = (t.force_n[100], *t.force_n.last().unwrap());
        assert!(
            first * last < 0.0,
            "seed {seed}: {last} N at 90 s after {first} N at 0.1 s (strength {s})"
        );
    }
}

/// The tip's ring after a step of `volts` on every segment held 1.5 s:
/// the mean spacing of the first four peaks of its distance from where it
/// comes to rest, s (1 kHz rows).
fn ring_period_s(sample: &Sample, hidden: &Hidden, volts: f64) -> f64 {
    let v = step(volts, 0.1, 1.5);
    let tip = free_point(sample, hidden, &v, 0.0, sample.length_m);
    let rest = tip[tip.len() - 10];
    let d: Vec<f64> = tip
        .iter()
        .map(|p| (p.0 - rest.0).hypot(p.1 - rest.1))
        .collect();
    // Peaks of the distance from rest are the swing's turning points, each
    // half a period apart; the first is the step's own overshoot.
    let floor = 1e-3 * d[100..].iter().fold(0.0, |a, &b| f64::max(a, b));
    let peaks: Vec<usize> = (101..v.len() - 1)
        .filter(|&i| d[i] > d[i - 1] && d[i] >= d[i + 1] && d[i] > floor)
        .take(4)
        .collect();
    assert_eq!(
        peaks.len(),
        4,
        "{volts} V: the ring has died before four turns"
    );
    2.0 * (peaks[3] - peaks[0]) as f64 / 3.0 * 1e-3
}

/// The free strip of large rotation rings faster at a large swing than
/// at a small one (the cantilever's first mode hardens); on the linear
/// beam, its slope field drawn as an arc afterwards, the period is the
/// same at every swing (seed 10: 64.7 ms at 4 V against 76.0 ms at 0.2 V;
/// with the rotation taken out, 76.0 ms at both).
#[test]
fn a_strip_of_large_rotation_rings_at_a_period_of_its_own_swing() {
    for seed in [10, 17] {
        let (sample, mut hidden) = base(seed);
        hidden.arcs = true;
        let small = ring_period_s(&sample, &hidden, 0.2);
        let large = ring_period_s(&sample, &hidden, 4.0);
        assert!(
            large < 0.93 * small,
            "seed {seed}: {:.1} ms at 4 V against {:.1} ms at 0.2 V",
            large * 1e3,
            small * 1e3
        );
    }
}
