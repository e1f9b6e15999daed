//! `finrs fit` recovers a sample's parameters, which differ from the
//! seed's, from a session it has not seen, starting from the data alone.

mod common;

use finrs::analysis::fit::{Effect, FitResult, Fitter, Knob, Space};
use finrs::model::params::ModelFile;
use finrs::model::predict::ModelSpec;
use finrs::recording::Geometry;
use finrs::session::Session;
use model_core::Params;

fn sample() -> ModelSpec {
    ModelSpec::baseline(Params {
        r1_ohm: 230.0,
        r2_ohm: 520.0,
        c_f: 1.6e-4,
        // K = 4.1 N·m/C, z = 0.06/s: a relaxation (z < p), which the fit
        // reaches from main.m's pure lag (a = 0) through z = p.
        a_nm_per_c: 4.1,
        b_nm_per_c_s: 4.1 * 0.06,
        p_per_s: 0.14,
        ..Params::main_m_2006()
    })
}

/// Writes the short session of `truth` (noise seeded by `seed`), reads it
/// back and fits it with `effects`, from the data alone; with the
/// session's geometry.
fn fit_session(
    label: &str,
    truth: &ModelSpec,
    seed: u64,
    effects: &[Effect],
) -> (FitResult, Geometry) {
    let dir = std::env::temp_dir().join(format!("finrs-fit-{label}-{}", std::process::id()));
    common::write_session(&dir, truth, &common::short_protocol(), seed);
    let session = Session::read(&dir).unwrap();
    let fixed = ModelFile::main_m_2006()
        .spec_for(&session.geometry())
        .unwrap();
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let fit = Fitter::new(&session)
        .fit(&all, effects, None, fixed)
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    (fit, session.geometry())
}

#[test]
fn baseline_fit_recovers_the_sample_within_its_intervals() {
    let truth = sample();
    let (fit, geometry) = fit_session("base", &truth, 11, &[]);

    // At the noise floor: weighted RSS per residual near 1 (the camera's
    // whole pixels add a little to its noise).
    let per = fit.score.rss / fit.score.m as f64;
    assert!(per < 1.15, "RSS/m = {per}");
    for e in &fit.estimates {
        let want = match e.knob {
            Knob::R1 => truth.params.r1_ohm,
            Knob::R2 => truth.params.r2_ohm,
            Knob::C => truth.params.c_f,
            Knob::A => truth.params.a_nm_per_c,
            Knob::B => truth.params.b_nm_per_c_s,
            Knob::P => truth.params.p_per_s,
            other => panic!("baseline fitted {other:?}"),
        };
        // The 95 % interval, widened by half for the rounding of the data.
        let half = 0.75 * (e.high - e.low);
        assert!(
            (e.value - want).abs() <= half,
            "{}: {} [{}, {}], truth {want}",
            e.knob.name(),
            e.value,
            e.low,
            e.high
        );
        assert!(
            e.high - e.low < 0.2 * want.abs(),
            "{} interval too wide",
            e.knob.name()
        );
    }
    // What is written is what simulate reads back.
    let file = fit.model_file();
    let back = ModelFile::parse("fit.toml", &file.to_toml()).unwrap();
    assert_eq!(back.spec_for(&geometry).unwrap(), fit.spec);
}

#[test]
fn noise_levels_are_read_off_the_rests() {
    let dir = std::env::temp_dir().join(format!("finrs-noise-{}", std::process::id()));
    common::write_session(&dir, &sample(), &common::short_protocol()[..1], 3);
    let session = Session::read(&dir).unwrap();
    let fitter = Fitter::new(&session);
    std::fs::remove_dir_all(&dir).ok();
    for (sensor, sigma) in &fitter.targets().sigma {
        let want = match sensor {
            finrs::analysis::fit::Sensor::Current => common::CURRENT_NOISE_A,
            // Noise plus whole pixels: sqrt(σ² + q²/12).
            _ => (common::CAMERA_NOISE_M.powi(2) + common::PIXEL_M.powi(2) / 12.0).sqrt(),
        };
        assert!(
            (sigma / want - 1.0).abs() < 0.3,
            "{sensor:?}: {sigma} vs {want}"
        );
    }
}

/// `segment-variation` is fittable: on a sample whose segments 2 and 3
/// differ from segment 1 in `R1`, `C` and `K`, the fit with the effect
/// recovers every deviation within its interval, from all-alike at the
/// start (each segment's current and the single-segment recording are the
/// evidence).
#[test]
fn segment_variation_fit_recovers_each_segments_deviations() {
    let mut truth = sample();
    let var = &mut truth.ext.segment_variation;
    (var.r1_deviation[1], var.c_deviation[1], var.k_deviation[1]) = (0.12, -0.08, 0.1);
    (var.r1_deviation[2], var.c_deviation[2], var.k_deviation[2]) = (-0.1, 0.14, -0.12);
    let (fit, geometry) = fit_session("var", &truth, 12, &[Effect::SegmentVariation]);

    let per = fit.score.rss / fit.score.m as f64;
    assert!(per < 1.15, "RSS/m = {per}");
    let mut seen = 0;
    for e in fit
        .estimates
        .iter()
        .filter(|e| e.knob.is_segment_deviation())
    {
        let want = Space::value(e.knob, &truth);
        let half = 0.75 * (e.high - e.low);
        assert!(
            (e.value - want).abs() <= half && half < 0.05,
            "{}: {} [{}, {}], truth {want}",
            e.knob.name(),
            e.value,
            e.low,
            e.high
        );
        seen += 1;
    }
    assert_eq!(
        seen, 6,
        "two segments past the reference, three values each"
    );
    let file = fit.model_file();
    let back = ModelFile::parse("fit.toml", &file.to_toml()).unwrap();
    assert_eq!(back.spec_for(&geometry).unwrap(), fit.spec);
}

/// A dot at the tip (`dots_s_m` ends at `length_m`) is the tip's own
/// measurement: the fit counts the tip once, not as two sensors.
#[test]
fn the_tip_and_a_dot_at_the_tip_are_fitted_once() {
    let dir = std::env::temp_dir().join(format!("finrs-fit-tip-once-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let name = "04_free_chirp.csv";
    std::fs::copy(common::baseline_air_dir().join(name), dir.join(name)).unwrap();
    let session = Session::read(&dir).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let meta = &session.recordings[0].rec.meta;
    let dots = meta.dots_s_m.clone().unwrap();
    assert_eq!(
        *dots.last().unwrap(),
        meta.length_m,
        "the data's last dot is at the tip"
    );
    let fitter = Fitter::new(&session);
    let names: Vec<String> = fitter.targets().recordings[0]
        .targets
        .iter()
        .map(|t| t.channel.name())
        .collect();
    for kept in ["tip_y_m", "tip_x_m", "dot4_y_m", "dot4_x_m"] {
        assert!(names.iter().any(|n| n == kept), "{kept} missing: {names:?}");
    }
    for dropped in ["dot5_y_m", "dot5_x_m"] {
        assert!(
            !names.iter().any(|n| n == dropped),
            "{dropped} fitted: {names:?}"
        );
    }
}

/// A fit that starts with no DC moment (`b = 0`, where an earlier fit on a
/// misfitting structure can leave it) climbs back to the strip's. On a
/// logarithmic scale `b/p → 0` had a vanishing gradient, and a soft
/// strip's stiffness fit that started there kept `b = 0` and the tip at
/// 4.5× its noise.
#[test]
fn a_fit_started_at_zero_dc_moment_leaves_it() {
    let truth = sample();
    let dir = std::env::temp_dir().join(format!("finrs-fit-b0-{}", std::process::id()));
    common::write_session(&dir, &truth, &common::short_protocol(), 12);
    let session = Session::read(&dir).unwrap();
    let fixed = ModelFile::main_m_2006()
        .spec_for(&session.geometry())
        .unwrap();
    let mut start = truth;
    start.params.b_nm_per_c_s = 0.0;
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let fit = Fitter::new(&session)
        .fit(&all, &[], Some(&start), fixed)
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let b = fit.spec.params.b_nm_per_c_s;
    let want = truth.params.b_nm_per_c_s;
    assert!((b - want).abs() < 0.05 * want, "b = {b}, truth {want}");
    let per = fit.score.rss / fit.score.m as f64;
    assert!(per < 1.15, "RSS/m = {per}");
}

#[test]
fn fit_json_holds_what_the_text_prints_for_a_program_to_read() {
    let truth = sample();
    let dir = std::env::temp_dir().join(format!("finrs-fit-json-{}", std::process::id()));
    common::write_session(&dir, &truth, &common::short_protocol(), 12);
    let json = dir.join("fit.json");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_finrs"))
        .arg("fit")
        .arg(&dir)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["effects"].as_array().unwrap().len(), 0);
    let estimates = v["estimates"].as_array().unwrap();
    let knobs: Vec<&str> = estimates
        .iter()
        .map(|e| e["knob"].as_str().unwrap())
        .collect();
    assert_eq!(
        knobs,
        [
            "r1_ohm",
            "r2_ohm",
            "c_f",
            "a_nm_per_c",
            "b_nm_per_c_s",
            "p_per_s"
        ]
    );
    for e in estimates {
        let (value, low, high) = (
            e["value"].as_f64().unwrap(),
            e["low"].as_f64().unwrap(),
            e["high"].as_f64().unwrap(),
        );
        assert!(low <= value && value <= high, "{e}");
        // The text's line for the knob, to its printed digits.
        let line = format!("{:<26} {:>12.5e}", e["knob"].as_str().unwrap(), value);
        assert!(stdout.contains(&line), "{line:?} not in\n{stdout}");
    }
    // R1 is read from the currents alone: its interval holds the truth.
    let r1 = &estimates[0];
    assert!(r1["low"].as_f64().unwrap() <= truth.params.r1_ohm);
    assert!(r1["high"].as_f64().unwrap() >= truth.params.r1_ohm);
    assert!(v["noise"]["currents"].as_f64().unwrap() > 0.0);
    let per = v["rss_per_residual"].as_f64().unwrap();
    assert!(per > 0.5 && per < 1.5, "{per}");
    assert!(!v["channels"].as_array().unwrap().is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

/// A fitted file says the mesh its fit simulated on, and `simulate` with
/// that file uses it: the same prediction as asking for it, not the
/// seed's one element per segment.
#[test]
fn a_fitted_file_simulates_on_its_fits_mesh() {
    use std::ffi::OsString;
    let truth = sample();
    let dir = std::env::temp_dir().join(format!("finrs-fit-mesh-{}", std::process::id()));
    common::write_session(&dir, &truth, &common::short_protocol(), 13);
    let finrs = |args: &[OsString]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_finrs"))
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let toml = dir.join("fit.toml");
    finrs(&[
        "fit".into(),
        dir.clone().into(),
        "--out".into(),
        toml.clone().into(),
    ]);
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(text.contains("[mesh]\nelements_per_segment = 4"), "{text}");
    let input = common::recordings_in(&dir).pop().unwrap();
    let simulate = |name: &str, elements: Option<&str>| {
        let out = dir.join(name);
        let mut args: Vec<OsString> = vec![
            "simulate".into(),
            "--input".into(),
            input.clone().into(),
            "--params".into(),
            toml.clone().into(),
            "--out".into(),
            out.clone().into(),
        ];
        if let Some(e) = elements {
            args.push("--elements".into());
            args.push(e.into());
        }
        finrs(&args);
        std::fs::read_to_string(&out).unwrap()
    };
    let own = simulate("own.csv", None);
    let four = simulate("four.csv", Some("4"));
    let one = simulate("one.csv", Some("1"));
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        own.contains("(4 element(s) per segment)"),
        "{}",
        &own[..400]
    );
    assert_ne!(own, one);
    assert_eq!(own, four);
}

/// The check of the damping law's form (`Fitter::fit_with_form_check`). A
/// sample whose modes each have their own damping ratio (the form the
/// check fits) is fitted with the law (`damping`: one `ζ₀` and `β` for all
/// modes); every interval then spans the check's, which the sample's own
/// form gives: the relaxation's `a`, `b`, `p` and `EI` inside them, where
/// the law's own intervals miss `b` and `p` (its first run: `b` 0.2547 in
/// [0.2487, 0.2608] against 0.246, then [0.2445, 0.2608]). The seed (21)
/// was fixed before the test was first run.
#[test]
fn intervals_carry_the_damping_laws_form() {
    let mut truth = sample();
    truth.params.ei_nm2 *= 0.5;
    let modal = &mut truth.ext.modal_damping;
    modal.free.fill(0.03);
    modal.blocked = [0.08, 0.02, 0.06, 0.04, 0.04, 0.04, 0.04, 0.04];
    let dir = std::env::temp_dir().join(format!("finrs-fit-form-{}", std::process::id()));
    common::write_session(&dir, &truth, &common::short_protocol(), 21);
    let session = Session::read(&dir).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let fixed = ModelFile::main_m_2006()
        .spec_for(&session.geometry())
        .unwrap();
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let fitter = Fitter::new(&session);
    let effects = [Effect::Damping, Effect::BeamStiffness];
    let law = fitter.fit_from_either_start(&all, &effects, fixed).unwrap();
    let checked = fitter.fit_with_form_check(&all, &effects, fixed).unwrap();
    let form = checked.form.as_ref().unwrap();
    // The sample's form fits better than the law.
    assert!(form.cost_each_mode < form.cost_law, "{form:?}");
    for (e, before) in checked.estimates.iter().zip(&law.estimates) {
        assert_eq!(e.value, before.value, "the estimate is the law's");
        assert!(e.low <= before.low && e.high >= before.high);
        let want = Space::value(e.knob, &truth);
        if matches!(e.knob, Knob::A | Knob::B | Knob::P | Knob::Ei) {
            eprintln!(
                "{}: {} [{}, {}] (law's [{}, {}]), truth {want}",
                e.knob.name(),
                e.value,
                e.low,
                e.high,
                before.low,
                before.high
            );
            assert!(
                e.low <= want && want <= e.high,
                "{}: [{}, {}], truth {want}",
                e.knob.name(),
                e.low,
                e.high
            );
        }
    }
    // Without the check the law's intervals miss: what it is for.
    let misses = law
        .estimates
        .iter()
        .filter(|e| matches!(e.knob, Knob::B | Knob::P))
        .filter(|e| {
            let want = Space::value(e.knob, &truth);
            want < e.low || want > e.high
        })
        .count();
    assert!(misses > 0, "the law's intervals hold b and p here");
    // The check finds the modes' own ratios it can see.
    let ratio = |k: Knob| form.each_mode.iter().find(|e| e.knob == k).unwrap();
    for (knob, want) in [(Knob::FreeMode(0), 0.03), (Knob::BlockedMode(0), 0.08)] {
        let e = ratio(knob);
        assert!(
            e.low <= want && want <= e.high,
            "{}: {} [{}, {}], truth {want}",
            knob.name(),
            e.value,
            e.low,
            e.high
        );
    }
}
