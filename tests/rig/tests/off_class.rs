//! The off-class rig's forms, each against what it claims: the base strip's
//! draws, a damping ratio per mode, segments that differ, crosstalk through
//! a lag, a load cell that gives, and the board-only protocol. Short runs
//! of the rig's own strip, no diagnosis.

use finrs::recording::Voltages;
use finrs_rig::beam::Beam;
use finrs_rig::strip::{run, Truth, BLOCKED_MESH, MESH};
use finrs_rig::{
    board_protocol, Hidden, Sample, SegmentFactors, Tip, OFF_CLASS_DEPARTURES, SEGMENT_VARIATION,
};
use rand::SeedableRng;

fn rng(seed: u64) -> rand::rngs::StdRng {
    rand::rngs::StdRng::seed_from_u64(seed)
}

/// `rest_s` at 0 V, then `volts` on the segments for `hold_s`, at 1 kHz.
fn step(volts: [f64; 3], rest_s: f64, hold_s: f64) -> Voltages {
    let rest = (rest_s * 1000.0) as usize;
    let hold = (hold_s * 1000.0) as usize;
    Voltages::from_rows(
        3,
        (0..rest + hold).map(|r| if r < rest { [0.0; 3] } else { volts }),
    )
}

fn held(sample: &Sample, hidden: &Hidden, tip: Tip, volts: &Voltages) -> Truth {
    let camera = vec![false; volts.len()];
    run(
        sample,
        hidden,
        BLOCKED_MESH,
        tip,
        volts,
        1e-3,
        0.0,
        &camera,
        &[],
    )
}

fn free_tip(sample: &Sample, hidden: &Hidden, volts: &Voltages) -> Vec<f64> {
    let camera = vec![true; volts.len()];
    let t = run(
        sample,
        hidden,
        MESH,
        Tip::Free,
        volts,
        1e-3,
        0.0,
        &camera,
        &[0.05],
    );
    t.points_m[0].iter().map(|p| p.1).collect()
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

#[test]
fn the_off_class_base_is_damped_soft_and_relaxes_or_creeps() {
    let mut creeps = 0;
    for seed in 0..200 {
        let mut r = rng(seed);
        let s = Sample::draw_off_class(&mut r);
        let h = Hidden::draw_off_class(&[], &mut r).unwrap();
        let zp = s.z_per_s / s.p_per_s;
        assert!((0.5..2.5).contains(&zp), "z/p {zp}");
        creeps += usize::from(zp > 1.0);
        let ei = h.ei_factor.unwrap();
        assert!((0.15..1.0).contains(&ei), "EI factor {ei}");
        for k in 0..20 {
            let z = h.damping_of_mode(k);
            assert!((0.02..0.1).contains(&z), "mode {k}: {z}");
        }
        assert!(h.crosstalk.is_none() && h.segment_factors.is_none());
    }
    // z/p uniform on 0.5..2.5: three draws in four creep.
    assert!((120..180).contains(&creeps), "{creeps} of 200 creep");
}

#[test]
fn the_off_class_rig_refuses_what_its_base_always_has() {
    for name in ["damping", "beam-stiffness", "wobble"] {
        let e = Hidden::draw_off_class(&[name], &mut rng(1)).unwrap_err();
        assert!(e.contains(&format!("`{name}`")), "{e}");
    }
    for name in OFF_CLASS_DEPARTURES {
        Hidden::draw_off_class(&[name], &mut rng(1)).unwrap();
    }
    let h = Hidden::draw_off_class(&["segment-crosstalk"], &mut rng(1)).unwrap();
    let lag = h.crosstalk_lag_s.expect("off-class crosstalk is lagged");
    assert!((0.01..0.03).contains(&lag), "{lag}");
}

#[test]
fn a_ratio_per_mode_is_the_single_ratio_when_they_agree_and_damps_the_ringing() {
    let s = Sample::draw(&mut rng(5));
    let v = step([2.0; 3], 0.05, 1.0);
    let uniform = Hidden {
        damping_ratio: Some(0.05),
        ..Hidden::default()
    };
    let per_mode = Hidden {
        modal_damping: Some(vec![0.05; 4]),
        ..Hidden::default()
    };
    assert_eq!(free_tip(&s, &uniform, &v), free_tip(&s, &per_mode, &v));
    // The ringing about the creeping mean, over the last half second:
    // undamped it keeps its amplitude, at ζ = 0.05 on ~27 Hz it is gone.
    let ringing = |h: &Hidden| {
        let tip = free_tip(&s, h, &v);
        let tail = &tip[tip.len() - 500..];
        let m = mean(tail);
        tail.iter().map(|x| (x - m).abs()).fold(0.0, f64::max)
    };
    let undamped = ringing(&Hidden::default());
    let damped = ringing(&per_mode);
    assert!(damped < 0.05 * undamped, "{damped} vs {undamped}");
}

#[test]
fn segment_variation_scales_each_segments_r1_and_moment() {
    let s = Sample::draw(&mut rng(5));
    let f = SegmentFactors {
        r1: 1.12,
        c: 0.9,
        k: 1.1,
    };
    let h = Hidden {
        segment_factors: Some(vec![SegmentFactors::ONE, f, SegmentFactors::ONE]),
        ..Hidden::default()
    };
    let v = step([0.0, 2.0, 0.0], 0.01, 0.5);
    let (base, varied) = (
        held(&s, &Hidden::default(), Tip::Pinned, &v),
        held(&s, &h, Tip::Pinned, &v),
    );
    // The current's jump at the step: V/R1 + V/R2.
    let jump = |t: &Truth| t.currents_a[1][10];
    let want = 2.0 / (s.r1_ohm * 1.12) + 2.0 / s.r2_ohm;
    assert!(
        (jump(&varied) - want).abs() < 1e-9,
        "{} vs {want}",
        jump(&varied)
    );
    assert!((jump(&base) - (2.0 / s.r1_ohm + 2.0 / s.r2_ohm)).abs() < 1e-9);
    // The untouched segments carry no current either way.
    assert!(varied.currents_a[0].iter().all(|&i| i == 0.0));
    // Same charge history aside, the force scales with K at the very first
    // instants, where the charge is the current's integral (R1 only sets
    // it): compare late, when C has charged: q ∝ C, force ∝ K·C.
    let late = |t: &Truth| mean(&t.force_n[400..]);
    let ratio = late(&varied) / late(&base);
    assert!((ratio - 1.1 * 0.9).abs() < 0.03, "force ratio {ratio}");
}

#[test]
fn lagged_crosstalk_reaches_the_neighbours_late_and_in_full() {
    let s = Sample::draw(&mut rng(5));
    let damped = |lag: Option<f64>| Hidden {
        crosstalk: Some(0.3),
        crosstalk_lag_s: lag,
        damping_ratio: Some(0.1),
        ..Hidden::default()
    };
    let v = step([2.0, 0.0, 0.0], 0.01, 2.0);
    let now = held(&s, &damped(None), Tip::Pinned, &v).force_n;
    let late = held(&s, &damped(Some(0.03)), Tip::Pinned, &v).force_n;
    // 20 ms after the step the lagged neighbour has passed on less; after
    // 60 lag times the same.
    let at = |f: &[f64], row: usize| f[row];
    assert!(
        at(&late, 30) < at(&now, 30) - 1e-6,
        "{} vs {}",
        at(&late, 30),
        at(&now, 30)
    );
    let end = now.len() - 1;
    let rel = (at(&late, end) - at(&now, end)).abs() / at(&now, end).abs();
    assert!(rel < 1e-3, "{rel}");
}

#[test]
fn a_load_cell_that_gives_lowers_the_held_mode_and_reads_the_same_static_force() {
    let s = Sample::draw(&mut rng(5));
    let (ei, mass) = (s.laminate_ei_nm2(), s.mass_kg_per_m());
    let beam = |tip| Beam::new(s.length_m, 3, 4, ei, mass, tip);
    let pinned_hz = beam(Tip::Pinned).omega[0] / (2.0 * std::f64::consts::PI);
    let free_hz = beam(Tip::Free).omega[0] / (2.0 * std::f64::consts::PI);
    assert!(
        (100.0..130.0).contains(&pinned_hz) && free_hz < 35.0,
        "{pinned_hz} {free_hz}"
    );
    let target = 0.55 * pinned_hz;
    let k = Beam::spring_for_first_mode(s.length_m, 3, 4, ei, mass, target).unwrap();
    let got = beam(Tip::Spring(k)).omega[0] / (2.0 * std::f64::consts::PI);
    assert!((got - target).abs() < 1e-6 * target, "{got} vs {target}");
    assert!(Beam::spring_for_first_mode(s.length_m, 3, 4, ei, mass, 1.1 * pinned_hz).is_none());
    // Damped and settled, the spring and the pin carry the same force
    // (the strip's static moment is taken up at the tip either way, the
    // spring's small give aside).
    let h = Hidden {
        damping_ratio: Some(0.1),
        ..Hidden::default()
    };
    let v = step([2.0; 3], 0.01, 1.0);
    let pin = held(&s, &h, Tip::Pinned, &v).force_n;
    let stiff = held(&s, &h, Tip::Spring(1e4 * k), &v).force_n;
    let soft = held(&s, &h, Tip::Spring(k), &v).force_n;
    let settled = |f: &[f64]| mean(&f[800..]);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(
        rel(settled(&stiff), settled(&pin)) < 1e-3,
        "{} {}",
        settled(&stiff),
        settled(&pin)
    );
    assert!(settled(&soft) > 0.0 && settled(&soft) < settled(&pin));
}

#[test]
fn the_board_protocol_holds_every_run_on_the_load_cell() {
    let runs = board_protocol(0.6);
    assert_eq!(runs.len(), 10);
    for r in &runs {
        assert_eq!(r.fixture, finrs::recording::Fixture::Blocked, "{}", r.name);
        assert!(!r.name.contains("free") && !r.description.contains("free"));
    }
    assert!(SEGMENT_VARIATION == "segment-variation");
}

#[test]
fn a_resumed_sweep_scores_a_kept_result_against_the_same_expectation() {
    // The sweep rebuilds the expectation of a kept result from the seed
    // alone; it must be the one written beside the session.
    use finrs_rig::sweep::{expected_of, write_scenario, Scenario};
    let s = Scenario {
        seed: 31,
        hidden: vec![SEGMENT_VARIATION],
        bench: vec!["hum"],
        board: true,
        ..Scenario::default()
    };
    let dir = std::env::temp_dir().join(format!("finrs-rig-resume-{}", std::process::id()));
    let written = write_scenario(&s, &dir).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(expected_of(&s).unwrap(), written);
    assert!(
        written.required.contains(&SEGMENT_VARIATION)
            || written.allowed.contains(&SEGMENT_VARIATION)
    );
}

#[test]
fn the_last_dot_is_the_tips_mark_read_once_by_the_camera() {
    use finrs::recording::{Channel, Recording};
    use finrs_rig::sweep::{write_scenario, Scenario};
    let s = Scenario {
        seed: 32,
        hidden: vec![],
        bench: vec![],
        board: false,
        ..Scenario::default()
    };
    let dir = std::env::temp_dir().join(format!("finrs-rig-tipmark-{}", std::process::id()));
    write_scenario(&s, &dir).unwrap();
    let mut free = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        let rec = Recording::read(&path).unwrap();
        let Some(tip_y) = rec.channel(Channel::TipY) else {
            continue;
        };
        free += 1;
        let last = rec.meta.dots_s_m.as_ref().unwrap().len() - 1;
        assert_eq!(
            Some(tip_y),
            rec.channel(Channel::DotY(last)),
            "{}",
            path.display()
        );
        assert_eq!(
            rec.channel(Channel::TipX),
            rec.channel(Channel::DotX(last)),
            "{}",
            path.display()
        );
        // The other dots are looked at on their own.
        assert_ne!(Some(tip_y), rec.channel(Channel::DotY(last - 1)));
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(free >= 3, "only {free} free recordings");
}
