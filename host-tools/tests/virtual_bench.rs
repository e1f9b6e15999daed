//! The whole bench chain on the virtual bench, as a user runs it: the
//! firmware built for QEMU with `qemu-serial` (its waves, limiter, frames
//! and commands, the model core as the strip, a camera around it), `finrs
//! bench run --qemu` on the example protocol, `finrs merge-camera` on each
//! free recording's track, then `finrs fit` and `finrs diagnose`.
//!
//! What it checks: every recording whole (no sample lost, no fault), the
//! blocked ones with a force and the free ones with the camera's columns
//! once merged; the merged tip equal to the model's own simulation of the
//! recorded drive (`finrs simulate` with the plant's parameters) to within
//! the virtual camera's tracking noise, which only holds if the waves, the
//! world's fixture switching, the camera's clock and the merge's alignment
//! are all right; the fit finding that the board reads its currents before
//! each period's voltage; and the diagnosis naming what the plant hides:
//! nothing, `damping` on a plant built with `plant-damping`, and nothing
//! on a creeping one (`plant-creep`: creep is the baseline's).

use std::path::{Path, PathBuf};
use std::process::Command;

use finrs::recording::{Channel, Fixture, Recording};
use finrs_firmware_support::world::CAMERA_NOISE_M;

mod common;

fn finrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_finrs"))
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The QEMU firmware with the serial link and `features`, built from
/// `firmware/` (its `.cargo/config.toml`: target, linker) into
/// `target/qemu-bench`, this file's own target folder (`scripts/test`
/// runs the other crates' QEMU tests, which build into `target/qemu`,
/// beside this one), and copied aside: the tests build in turn into one
/// place and run at once.
fn build_firmware(features: &str) -> PathBuf {
    static BUILD: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let target_dir = workspace().join("target/qemu-bench");
    let status = Command::new(cargo)
        .current_dir(workspace().join("firmware"))
        .args(["build", "--release", "--locked", "-p", "finrs-firmware"])
        .args(["--no-default-features", "--features", features])
        .arg("--target-dir")
        .arg(&target_dir)
        .env_remove("FINRS_SEGMENTS")
        .env_remove("FINRS_DAC_SEGMENTS")
        .status()
        .expect("cargo runs");
    assert!(
        status.success(),
        "building the QEMU firmware failed (target, flip-link installed? run scripts/setup)"
    );
    let release = target_dir.join("thumbv7em-none-eabihf/release");
    let copy = release.join(format!("finrs-firmware-{}", features.replace(',', "-")));
    std::fs::copy(release.join("finrs-firmware"), &copy).expect("the ELF copies");
    copy
}

fn run_ok(mut c: Command, what: &str) -> String {
    let out = c.output().expect("finrs runs");
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{what} failed:\n{stderr}");
    stderr
}

/// What the chain gave: the diagnosis's JSON and `finrs fit`'s output.
struct Chain {
    verdict: serde_json::Value,
    fit_log: String,
}

/// The example protocol on the virtual bench built with `features`: each
/// recording checked, each free one merged and its tip checked, then
/// `finrs fit` and `finrs diagnose` on the session.
fn run_chain(features: &str) -> Chain {
    let elf = build_firmware(features);
    let dir = std::env::temp_dir().join(format!(
        "finrs-virtual-bench-{}-{}",
        std::process::id(),
        features.replace(',', "-")
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let session = dir.join("session");

    let log = bench(
        &elf,
        &workspace().join("examples/bench/protocol.toml"),
        &session,
    );
    assert!(log.contains("session"), "{log}");

    let recordings = common::recordings_in(&session);
    assert_eq!(recordings.len(), 10, "{recordings:?}");
    let mut free = 0;
    for path in &recordings {
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let rec = Recording::read(path).unwrap();
        let notes = rec.meta.notes.clone().unwrap_or_default();
        assert!(
            notes.contains("no gaps")
                && notes.contains("no faults")
                && notes.contains("firmware 0.1.0"),
            "{name}: {notes}"
        );
        let has = |ch: Channel| rec.channels.iter().any(|(c, _)| *c == ch);
        match rec.meta.fixture {
            Fixture::Blocked => assert!(has(Channel::Force), "{name}"),
            Fixture::Free => {
                free += 1;
                merge(&session, path);
                if !features.contains("plant-") {
                    check_tip_against_the_model(path, &dir);
                }
            }
        }
    }
    assert_eq!(free, 8);

    let mut fit = finrs();
    fit.arg("fit").arg(&session);
    let out = fit.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fit_log =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);

    let json = dir.join("verdict.json");
    let mut diagnose = finrs();
    diagnose
        .arg("diagnose")
        .arg(&session)
        .arg("--json")
        .arg(&json);
    let log = run_ok(diagnose, "finrs diagnose");
    // One line times the run and each stage, the baseline first.
    let timing = log
        .lines()
        .find(|l| l.starts_with("diagnosed in "))
        .unwrap_or_else(|| panic!("no timing line:\n{log}"));
    assert!(timing.contains(" s (baseline "), "{timing}");
    assert!(timing.contains("; round 1: "), "{timing}");
    let verdict: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    eprintln!(
        "virtual session ({features}): {} {}",
        verdict["verdict"], verdict["causes"]
    );
    let _ = std::fs::remove_dir_all(&dir);
    Chain { verdict, fit_log }
}

#[test]
fn the_example_protocol_on_the_virtual_bench_is_recorded_merged_and_diagnosed() {
    let chain = run_chain("qemu-serial");
    // The bench reads its currents before each period's voltage, and the
    // fit must have found that in the data (else its circuit is off and
    // the mechanics after it).
    assert!(
        chain
            .fit_log
            .contains("currents read before each row's voltage was applied"),
        "{}",
        chain.fit_log
    );
    // The plant hides no effect: none may be named.
    assert_eq!(
        chain.verdict["causes"],
        serde_json::json!([]),
        "the plant hides no effect: {}",
        chain.verdict["verdict"]
    );
}

/// The same chain with a damped plant (`plant-damping`, a 5 % modal
/// damping ratio): the diagnosis must name `damping`, and only that.
#[test]
fn a_damped_plant_on_the_virtual_bench_is_diagnosed_as_damping() {
    let chain = run_chain("qemu-serial,plant-damping");
    assert_eq!(
        chain.verdict["causes"],
        serde_json::json!(["damping"]),
        "{}",
        chain.verdict["verdict"]
    );
}

/// The merged tip against `finrs simulate` of the recording's drive with
/// the plant's parameters (the example session's): the difference is the
/// camera's tracking error, uniform in ±`CAMERA_NOISE_M` (RMS that over
/// √3), and no more.
fn check_tip_against_the_model(path: &Path, dir: &Path) {
    let params = dir.join("plant.toml");
    std::fs::write(&params, common::baseline_air_model().to_toml()).unwrap();
    let sim = dir.join("sim.csv");
    let mut simulate = finrs();
    simulate
        .arg("simulate")
        .arg("--input")
        .arg(path)
        .arg("--params")
        .arg(&params)
        .arg("--out")
        .arg(&sim);
    run_ok(simulate, "finrs simulate");
    let column = |rec: &Recording| {
        rec.channels
            .iter()
            .find(|(c, _)| *c == Channel::TipY)
            .map(|(_, v)| v.clone())
            .unwrap()
    };
    let measured = column(&Recording::read(path).unwrap());
    let model = column(&Recording::read(&sim).unwrap());
    let (mut sum_sq, mut n, mut peak) = (0.0, 0, 0.0f64);
    for (m, s) in measured.iter().zip(&model) {
        if let (Some(m), Some(s)) = (m, s) {
            sum_sq += (m - s) * (m - s);
            n += 1;
            peak = peak.max(s.abs());
        }
    }
    let rms = (sum_sq / f64::from(n)).sqrt();
    let noise_rms = f64::from(CAMERA_NOISE_M) / 3f64.sqrt();
    assert!(n > 100, "{}: {n} camera rows", path.display());
    assert!(
        peak > 50.0 * noise_rms,
        "{}: the tip barely moves ({peak} m)",
        path.display()
    );
    assert!(
        rms < 1.3 * noise_rms,
        "{}: the tip differs from the model's by {rms:e} m RMS; the camera's noise alone is {noise_rms:e} m",
        path.display()
    );
}

/// The same chain with a creeping plant (`plant-creep`: the network's zero
/// above its pole, Table 4-2's `z = 0.24/s`, `p = 0.1/s`): creep is the
/// baseline's, so nothing may be named.
#[test]
fn a_creeping_plant_on_the_virtual_bench_names_nothing() {
    let chain = run_chain("qemu-serial,plant-creep");
    assert_eq!(
        chain.verdict["causes"],
        serde_json::json!([]),
        "{}",
        chain.verdict["verdict"]
    );
}

/// `finrs bench live --qemu` under a pseudo-terminal (util-linux
/// `script`): the live view on the virtual bench, at the pace of real
/// time; a wave typed at its `w` key reaches the firmware in QEMU and
/// drives the strip, `q` ends it, and the recording is whole.
#[test]
fn the_live_view_drives_the_virtual_bench_from_its_keys() {
    use std::time::Duration;
    let elf = build_firmware("qemu-serial");
    let dir = fresh_dir("finrs-virtual-live");
    let out = dir.join("live.csv");
    let mut pty = common::pty::Pty::spawn(&format!(
        "{} bench live --qemu {} --out {}",
        env!("CARGO_BIN_EXE_finrs"),
        elf.display(),
        out.display()
    ));
    // Each key once the view shows the last was taken, and the end once
    // the board has run on for 1.5 s of its own time with the wave: not
    // after fixed waits, since under load QEMU and the view start late
    // and the board's clock runs behind the wall's (a run beside other
    // tests quit before the wave had driven a sample: 0 rows at 1 V).
    let limit = Duration::from_secs(120);
    pty.wait_until("the board's Info frame", limit, |s| s.contains("segments,"));
    pty.keys(b"w", 0);
    pty.wait_until("the wave prompt", limit, |s| s.contains("Esc to cancel"));
    pty.keys(b"step:1\r", 0);
    let sent = pty.wait_until("the wave sent", limit, |s| s.contains("wave step:1"));
    let at_send = samples_shown(&sent).expect("the view shows its samples");
    let last = pty.wait_until("1.5 s of samples after the wave", limit, |s| {
        samples_shown(s).is_some_and(|n| n >= at_send + 1500)
    });
    pty.keys(b"q", 0);
    let (status, screen) = pty.finish(
        Duration::from_secs(30),
        "finrs bench live --qemu did not end on q",
    );
    assert!(status.success(), "{status:?}: {screen}");
    let rec = Recording::read(&out).unwrap();
    let notes = rec.meta.notes.clone().unwrap_or_default();
    assert!(
        notes.contains("no gaps") && notes.contains("firmware 0.1.0"),
        "{notes}"
    );
    // The typed step reached the firmware: every segment at 1 V for a
    // stretch (after the limiter's 5 ms ramp).
    let held = rec
        .v_v
        .rows()
        .filter(|v| v.iter().all(|&x| (x - 1.0).abs() < 1e-6))
        .count();
    let peak_v = rec
        .v_v
        .rows()
        .flatten()
        .fold(0.0f64, |m, &x| m.max(x.abs()));
    assert!(
        held > 500,
        "{held} rows at 1 V of {} (peak {peak_v} V; {at_send} samples shown when the wave was sent); the view before q:\n{last}",
        rec.t_s.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The count of samples the live view's status line shows (`N samples,
/// …`).
fn samples_shown(screen: &str) -> Option<usize> {
    // The line opens with the border: `│1793 samples, …`.
    let line = screen.lines().find(|l| l.contains(" samples, "))?;
    let count = line.trim_start_matches(|c: char| !c.is_ascii_digit());
    count.split(' ').next()?.parse().ok()
}

/// `finrs bench run PROTOCOL --qemu ELF --out OUT`, which must succeed;
/// its log.
fn bench(elf: &Path, protocol: &Path, out: &Path) -> String {
    let mut run = finrs();
    run.args(["bench", "run"])
        .arg(protocol)
        .arg("--qemu")
        .arg(elf)
        .arg("--out")
        .arg(out);
    run_ok(run, "finrs bench run --qemu")
}

/// An empty folder of this test run's, named `name`.
fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `finrs merge-camera` of the free recording `path` of `session`, in
/// place.
fn merge(session: &Path, path: &Path) {
    let mut merge = finrs();
    merge
        .arg("merge-camera")
        .arg("--daq")
        .arg(path)
        .arg("--track")
        .arg(session.join("tracks").join(path.file_name().unwrap()))
        .args(["--m-per-px", "5e-5"])
        .arg("--out")
        .arg(path);
    run_ok(merge, "finrs merge-camera");
}

/// The merged free recording at `path` and its camera's tip column.
fn read_with_tip(path: &Path) -> (Recording, Vec<Option<f64>>) {
    read_with(path, Channel::TipY)
}

/// The recording at `path` and its `channel` (which it must hold).
fn read_with(path: &Path, channel: Channel) -> (Recording, Vec<Option<f64>>) {
    let rec = Recording::read(path).unwrap();
    let values = rec
        .channels
        .iter()
        .find(|(c, _)| *c == channel)
        .map(|(_, v)| v.clone())
        .unwrap_or_else(|| panic!("{}: no {channel:?}", path.display()));
    (rec, values)
}

/// The merged free recording's tip over the last ten periods of its wave
/// at `hz`, by lock-in: its amplitude, m, and its phase less segment 1's
/// recorded voltage's, degrees (the command's latency cancels).
fn tip_response(path: &Path, hz: f64) -> (f64, f64) {
    let (rec, tip) = read_with_tip(path);
    let v1: Vec<f64> = rec.v_v.rows().map(|r| r[0]).collect();
    // The wave's end: the last row driven.
    let last = v1.iter().rposition(|&v| v != 0.0).expect("a driven row");
    let to_s = rec.t_s[last];
    let from_s = to_s - 10.0 / hz;
    // `2/n Σ y e^{−jωt}` over whole periods: the sine's phasor.
    let lock_in = |values: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut re, mut im, mut n) = (0.0, 0.0, 0.0);
        for (t, y) in values.filter(|(t, _)| (from_s..to_s).contains(t)) {
            let w = 2.0 * std::f64::consts::PI * hz * t;
            re += y * w.cos();
            im -= y * w.sin();
            n += 1.0;
        }
        (2.0 * re / n, 2.0 * im / n)
    };
    let y = lock_in(
        &mut rec
            .t_s
            .iter()
            .zip(&tip)
            .filter_map(|(&t, y)| y.map(|y| (t, y))),
    );
    let v = lock_in(&mut rec.t_s.iter().copied().zip(v1.iter().copied()));
    (
        y.0.hypot(y.1),
        (y.1.atan2(y.0) - v.1.atan2(v.0)).to_degrees(),
    )
}

/// `x`, degrees, wrapped to (−180°, 180°].
fn wrapped_deg(x: f64) -> f64 {
    180.0 - (180.0 - x).rem_euclid(360.0)
}

/// The program the board's shaper makes of `motion` with the model of
/// `file` for the virtual bench's strip (the seed's geometry, as its
/// protocols state it): its phase on segment 1, degrees.
fn shaped_phase_deg(file: &finrs::model::params::ModelFile, motion: &finrs_frames::Motion) -> f64 {
    let spec = file
        .spec_for(&finrs::recording::Geometry::THESIS_2006)
        .unwrap();
    let record = finrs::model::motion::record(&spec);
    let steady = finrs_drive::Envelope::STEADY;
    match finrs::model::motion::board_program(&record, 3, 1000.0, motion, steady, 4.0, f32::NAN)
        .unwrap()
        .0
    {
        finrs_drive::Program::Harmonic { phases_deg, .. } => f64::from(phases_deg[0]),
        other => panic!("{other:?}"),
    }
}

/// A protocol of the virtual bench's strip, its model `model` if any.
/// Runs on `elf` a protocol of one recording, `(name, fixture, wave)`
/// held `hold_s` after 1 s of rest, the model file `model` (in `dir`)
/// loaded first: the board's log and the recording's file (its session
/// in `dir/name`).
fn one_recording(
    elf: &Path,
    dir: &Path,
    model: &str,
    (name, fixture, wave): (&str, &str, &str),
    hold_s: f64,
) -> (String, PathBuf) {
    let recording = format!(
        "[[recording]]\nname = \"{name}\"\nfixture = \"{fixture}\"\nwave = \"{wave}\"\n\
         rest_s = 1.0\nhold_s = {hold_s}\noff_s = 0.5\n"
    );
    let protocol = dir.join(format!("{name}.toml"));
    std::fs::write(&protocol, protocol_text(Some(model), &recording)).unwrap();
    let out = dir.join(name);
    let log = bench(elf, &protocol, &out);
    let path = common::recordings_in(&out).pop().expect("one recording");
    (log, path)
}

/// Per-window errors `(amplitude fraction, phase °)` as printed, and the
/// worst amplitude and phase after the first window.
fn shown_and_worst(errors: &[(f64, f64)]) -> (String, (f64, f64)) {
    let shown: Vec<String> = errors
        .iter()
        .map(|(a, p)| format!("{:+.1}% {:+.1}°", 100.0 * a, p))
        .collect();
    let worst = errors[1..].iter().fold((0.0f64, 0.0f64), |m, &(a, p)| {
        (m.0.max(a.abs()), m.1.max(p.abs()))
    });
    (shown.join(", "), worst)
}

fn protocol_text(model: Option<&str>, recordings: &str) -> String {
    let model = model.map_or(String::new(), |m| format!("model = {m:?}\n"));
    format!(
        "format = \"finrs-protocol/1\"\nmedium = \"air\"\nlength_m = 0.05\nwidth_m = 0.01\n\
         thickness_m = 0.0002858\ndots_s_m = [0.025, 0.05]\n{model}\n{recordings}"
    )
}

/// Feed-forward end to end (#16): a protocol that tunes the QEMU firmware
/// with the plant's own model and asks a travelling motion of the free
/// tip. The board's shaper turns it into each segment's sine; the plant's
/// tip, as the virtual camera sees it, moves as asked: by lock-in over the
/// last ten periods, the amplitude within 2 % and the phase (against
/// segment 1's recorded voltage, so that the command's latency cancels)
/// within 2° of the shaped program's.
#[test]
fn a_motion_on_the_virtual_bench_moves_the_plants_tip_as_asked() {
    use finrs_frames::Motion;

    let elf = build_firmware("qemu-serial");
    let dir = fresh_dir("finrs-virtual-motion");
    let plant = common::baseline_air_model();
    std::fs::write(dir.join("plant.toml"), plant.to_toml()).unwrap();
    // The issue's 5 mm at 1 Hz: within 1 V a segment for this plant.
    let (tip_amp_m, hz, lag_deg) = (5e-3, 1.0, 60.0);
    let wave = format!("motion:{tip_amp_m},{hz},{lag_deg}");
    let (log, path) = one_recording(
        &elf,
        &dir,
        "plant.toml",
        ("free_motion", "free", &wave),
        30.0,
    );
    assert!(log.contains("in use on the board"), "{log}");
    merge(&dir.join("free_motion"), &path);
    let (amplitude, phase_deg) = tip_response(&path, hz);
    let motion = Motion::Travelling {
        tip_amp_m: tip_amp_m as f32,
        frequency_hz: hz as f32,
        lag_deg_per_segment: lag_deg as f32,
    };
    // Asked: the tip's phase 0, less segment 1's.
    let off_deg = wrapped_deg(phase_deg + shaped_phase_deg(&plant, &motion));
    eprintln!(
        "motion on the virtual bench: tip {:.4} mm (asked {:.4}), phase off by {off_deg:.2}°",
        amplitude * 1e3,
        tip_amp_m * 1e3
    );
    assert!(
        (amplitude / tip_amp_m - 1.0).abs() < 0.02,
        "tip {amplitude} m"
    );
    assert!(off_deg.abs() < 2.0, "phase off by {off_deg}°");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The fit (TOML) of a strip unlike its nominal model (`plant-variant`:
/// `R1` 15 % up, `C` 10 % and the moment per charge 20 % down): the
/// example protocol recorded from it on the virtual bench, each free
/// recording's camera track merged (as the bench tells a user to), then
/// `finrs fit --out`. Made once for the tests that use it (the first waits
/// for it). Without the camera only the two short blocked steps show the
/// relaxation, and a slow term fitted beside them (the bench's drift)
/// takes part of it (`z/p` fitted 0.71 for the strip's 0.77, and the held
/// step 5.5 % off at 30 s; with the camera 0.75, and 1.4 %).
fn variant_fit() -> &'static str {
    static FIT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    FIT.get_or_init(|| {
        let elf = build_firmware("qemu-serial,plant-variant");
        let dir = fresh_dir("finrs-virtual-variant-fit");
        let session = dir.join("session");
        bench(
            &elf,
            &workspace().join("examples/bench/protocol.toml"),
            &session,
        );
        for path in common::recordings_in(&session) {
            if session
                .join("tracks")
                .join(path.file_name().unwrap())
                .exists()
            {
                merge(&session, &path);
            }
        }
        let mut fit = finrs();
        fit.arg("fit")
            .arg(&session)
            .arg("--out")
            .arg(dir.join("fit.toml"));
        run_ok(fit, "finrs fit");
        let text = std::fs::read_to_string(dir.join("fit.toml")).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        text
    })
}

/// #16's comparison on the `plant-variant` strip, no drying: its fit
/// ([`variant_fit`]), then one protocol that drives the same motion
/// twice: as the plain wave the nominal model shapes (the example
/// session's parameters, sent as `harmonic:`), and as a motion the board
/// shapes with the fit (`model =`), fed forward only (`motion-ff:`). The
/// fit's is within 5 % and 5° (the issue's targets); the nominal wave's
/// misses by the parameter spread.
#[test]
fn feed_forward_from_a_fit_makes_the_motion_a_nominal_wave_misses() {
    use finrs::wave::Wave;
    use finrs_frames::Motion;

    let elf = build_firmware("qemu-serial,plant-variant");
    let dir = fresh_dir("finrs-virtual-variant");
    std::fs::write(dir.join("fit.toml"), variant_fit()).unwrap();
    let fitted = finrs::model::params::ModelFile::read(&dir.join("fit.toml")).unwrap();
    // The nominal model's wave for the motion, and the motion itself.
    let (tip_amp_m, hz, lag_deg) = (5e-3, 1.0, 60.0);
    let text = format!("motion-ff:{tip_amp_m},{hz},{lag_deg}");
    let nominal = common::baseline_air_model();
    let spec = nominal
        .spec_for(&finrs::recording::Geometry::THESIS_2006)
        .unwrap();
    let steady = finrs::wave::WaveOptions::steady(1.0);
    let plain = finrs::model::motion::shaped(
        &Wave::parse(&text).unwrap(),
        &spec,
        3,
        1000.0,
        None,
        &steady,
    )
    .unwrap()
    .0
    .text()
    .to_string();
    let recording = |name: &str, wave: &str| {
        format!(
            "[[recording]]\nname = \"{name}\"\nfixture = \"free\"\nwave = \"{wave}\"\n\
             rest_s = 1.0\nhold_s = 30\noff_s = 0.5\n\n"
        )
    };
    let protocol = dir.join("protocol.toml");
    std::fs::write(
        &protocol,
        protocol_text(
            Some("fit.toml"),
            &(recording("nominal", &plain) + &recording("fitted", &text)),
        ),
    )
    .unwrap();
    let motions = dir.join("motions");
    bench(&elf, &protocol, &motions);
    let paths = common::recordings_in(&motions);
    assert_eq!(paths.len(), 2, "{paths:?}");
    let motion = Motion::Travelling {
        tip_amp_m: tip_amp_m as f32,
        frequency_hz: hz as f32,
        lag_deg_per_segment: lag_deg as f32,
    };
    let mut errors = Vec::new();
    for (path, model) in paths.iter().zip([&nominal, &fitted]) {
        merge(&motions, path);
        let (amplitude, phase_deg) = tip_response(path, hz);
        let off_deg = wrapped_deg(phase_deg + shaped_phase_deg(model, &motion));
        let off = amplitude / tip_amp_m - 1.0;
        eprintln!(
            "{}: tip {:.4} mm (asked {:.4}, {:+.2} %), phase {off_deg:+.2}°",
            path.file_name().unwrap().to_string_lossy(),
            amplitude * 1e3,
            tip_amp_m * 1e3,
            100.0 * off
        );
        errors.push((off.abs(), off_deg.abs()));
    }
    let (nominal_err, fitted_err) = (errors[0], errors[1]);
    assert!(
        fitted_err.0 < 0.05 && fitted_err.1 < 5.0,
        "fitted: {fitted_err:?}"
    );
    assert!(
        nominal_err.0 > 0.10 && nominal_err.0 > 3.0 * fitted_err.0,
        "the nominal wave should miss by the spread: {nominal_err:?} against {fitted_err:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The merged free recording's tip against the motion asked of it,
/// `tip_amp_m · sin(2π hz (t − t₀))` with `t₀` the wave's first driven row
/// (the program's time 0: the tip after its first step holds the sample
/// after it), by lock-in over each `window_s` of the `hold_s` after `t₀`:
/// per window, the amplitude's error (a fraction) and the phase's, degrees.
fn motion_errors(
    path: &Path,
    tip_amp_m: f64,
    hz: f64,
    hold_s: f64,
    window_s: f64,
) -> Vec<(f64, f64)> {
    sine_errors(path, Channel::TipY, tip_amp_m, hz, hold_s, window_s)
}

/// As [`motion_errors`], of the recording's `channel` against `amplitude`.
fn sine_errors(
    path: &Path,
    channel: Channel,
    amplitude: f64,
    hz: f64,
    hold_s: f64,
    window_s: f64,
) -> Vec<(f64, f64)> {
    let omega = 2.0 * std::f64::consts::PI * hz;
    windows(path, channel, hold_s, window_s)
        .into_iter()
        .map(|w| {
            let n = w.len() as f64;
            let s = 2.0
                * w.iter()
                    .map(|(tau, y)| y * (omega * tau).sin())
                    .sum::<f64>()
                / n;
            let c = 2.0
                * w.iter()
                    .map(|(tau, y)| y * (omega * tau).cos())
                    .sum::<f64>()
                / n;
            (s.hypot(c) / amplitude - 1.0, c.atan2(s).to_degrees())
        })
        .collect()
}

/// The recording's `channel` samples `(τ, value)` in each `window_s` of
/// the `hold_s` after the wave's first driven row (`τ` from it).
fn windows(path: &Path, channel: Channel, hold_s: f64, window_s: f64) -> Vec<Vec<(f64, f64)>> {
    let (rec, tip) = read_with(path, channel);
    let first = rec
        .v_v
        .rows()
        .position(|r| r.iter().any(|&v| v != 0.0))
        .expect("a driven row");
    let t0 = rec.t_s[first];
    let windows = (hold_s / window_s).round() as usize;
    (0..windows)
        .map(|w| {
            let (from, to) = (w as f64 * window_s, (w + 1) as f64 * window_s);
            rec.t_s
                .iter()
                .zip(&tip)
                .filter_map(|(&t, y)| Some((t - t0, (*y)?)))
                .filter(|(tau, _)| (from..to).contains(tau))
                .collect()
        })
        .collect()
}

/// `motion-step:` on the `plant-variant` strip (no drying): the fit of
/// [`variant_fit`] on the board, one protocol that steps the tip to 3 mm
/// twice for 30 s: as a plain `step:` of the levels the nominal model
/// holds it with (its static inverse), and as `motion-step:` shaped by
/// the board from the fit (no rise: the fit has an instant moment). The
/// tip's mean over each 5 s window (the first mode's ringing averages
/// out) against 3 mm. Asserted: the fit's step within 5 % in every window
/// after the first (the charging); the plain step off by more than 10 %
/// in every window (the parameter spread, and the relaxation it leaves).
#[test]
fn a_held_step_from_a_fit_holds_the_tip_a_nominal_step_misses() {
    use finrs::wave::Wave;

    let elf = build_firmware("qemu-serial,plant-variant");
    let dir = fresh_dir("finrs-virtual-step");
    std::fs::write(dir.join("fit.toml"), variant_fit()).unwrap();
    let (tip_m, hold_s) = (3e-3, 30.0);
    let nominal = common::baseline_air_model()
        .spec_for(&finrs::recording::Geometry::THESIS_2006)
        .unwrap();
    let (held, _) = finrs::model::motion::shaped(
        &Wave::parse(&format!("motion-step:{tip_m}")).unwrap(),
        &nominal,
        3,
        1000.0,
        None,
        &finrs::wave::WaveOptions::steady(1.0),
    )
    .unwrap();
    let finrs::wave::WaveKind::HeldStep { levels_v, .. } = held.kind() else {
        panic!("{}", held.text())
    };
    let levels: Vec<String> = levels_v.iter().map(|v| v.to_string()).collect();
    let recordings: String = [
        ("nominal_step", format!("step:{}", levels.join(","))),
        ("fitted_held", format!("motion-step:{tip_m}")),
    ]
    .iter()
    .map(|(name, wave)| {
        format!(
            "[[recording]]\nname = \"{name}\"\nfixture = \"free\"\nwave = \"{wave}\"\n\
             rest_s = 1.0\nhold_s = {hold_s}\noff_s = 0.5\n\n"
        )
    })
    .collect();
    let protocol = dir.join("protocol.toml");
    std::fs::write(&protocol, protocol_text(Some("fit.toml"), &recordings)).unwrap();
    let out = dir.join("steps");
    bench(&elf, &protocol, &out);
    let paths = common::recordings_in(&out);
    assert_eq!(paths.len(), 2, "{paths:?}");
    let mut errors = Vec::new();
    for path in &paths {
        merge(&out, path);
        let e: Vec<f64> = windows(path, Channel::TipY, hold_s, 5.0)
            .iter()
            .map(|w| w.iter().map(|(_, y)| y).sum::<f64>() / w.len() as f64 / tip_m - 1.0)
            .collect();
        let shown: Vec<String> = e.iter().map(|a| format!("{:+.1}%", 100.0 * a)).collect();
        eprintln!(
            "{}: mean per 5 s: {}",
            path.file_name().unwrap().to_string_lossy(),
            shown.join(", ")
        );
        errors.push(e);
    }
    let (plain, fitted) = (&errors[0], &errors[1]);
    assert!(
        fitted[1..].iter().all(|a| a.abs() < 0.05),
        "fitted held step: {fitted:?}"
    );
    assert!(
        plain.iter().all(|a| a.abs() > 0.10),
        "the nominal step should miss by the spread: {plain:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// #16's SIL: the strip of [`variant_fit`], fitted wet, then drying
/// from boot (`plant-drying`: every admittance times e^{−t/300 s}, 18 %
/// less after a minute); each from a fresh boot, 60 s of the issue's 5 mm
/// travelling tip wave at 1 Hz: the plain voltage wave the nominal model
/// shapes, the motion fed forward from the fit (`motion-ff:`), and the
/// motion held by the board's gain tracker (`motion:`). The tip by
/// lock-in over each 5 s window. Asserted: tracked, every window after the
/// first (the tracker's estimate needs a few periods) within the issue's
/// 5 % and 5°; the plain wave off by more than 10 % in every window; the
/// feed-forward's worst window off by more than the tracked one's.
#[test]
fn a_tracked_motion_holds_on_a_drying_strip_where_feed_forward_drifts() {
    use finrs::wave::Wave;

    let elf = build_firmware("qemu-serial,plant-variant,plant-drying");
    let dir = fresh_dir("finrs-virtual-drying");
    std::fs::write(dir.join("fit.toml"), variant_fit()).unwrap();
    let (tip_amp_m, hz, lag_deg, hold_s) = (5e-3, 1.0, 60.0, 60.0);
    let motion = format!("{tip_amp_m},{hz},{lag_deg}");
    let nominal = common::baseline_air_model();
    let spec = nominal
        .spec_for(&finrs::recording::Geometry::THESIS_2006)
        .unwrap();
    let plain = finrs::model::motion::shaped(
        &Wave::parse(&format!("motion:{motion}")).unwrap(),
        &spec,
        3,
        1000.0,
        None,
        &finrs::wave::WaveOptions::steady(1.0),
    )
    .unwrap()
    .0
    .text()
    .to_string();
    let mut worst = Vec::new();
    for (name, wave) in [
        ("plain", plain),
        ("feed_forward", format!("motion-ff:{motion}")),
        ("tracked", format!("motion:{motion}")),
    ] {
        let (log, path) = one_recording(&elf, &dir, "fit.toml", (name, "free", &wave), hold_s);
        let out = dir.join(name);
        merge(&out, &path);
        let errors = motion_errors(&path, tip_amp_m, hz, hold_s, 5.0);
        let (shown, worst_after_first) = shown_and_worst(&errors);
        eprintln!("{name}: per 5 s: {shown}");
        // The tracker's reports, once a period after the first.
        let tracking = out.join("tracking").join(path.file_name().unwrap());
        assert_eq!(
            tracking.exists(),
            name == "tracked",
            "{name}: tracking file {}:\n{log}",
            tracking.display()
        );
        if name == "tracked" {
            let csv = std::fs::read_to_string(&tracking).unwrap();
            let last = csv.lines().last().unwrap();
            eprintln!(
                "tracked: {} reports, the last {last}",
                csv.lines().count() - 1
            );
            assert!(csv.lines().count() > 55, "{csv}");
        }
        worst.push((name, errors, worst_after_first));
    }
    let (_, plain_errors, _) = &worst[0];
    let (_, _, ff) = worst[1];
    let (_, _, tracked) = worst[2];
    assert!(
        tracked.0 <= 0.05 && tracked.1 <= 5.0,
        "tracked, worst 5 s window after the first: {tracked:?}"
    );
    assert!(
        plain_errors.iter().all(|(a, _)| a.abs() > 0.10),
        "the plain wave should miss by the spread and the drying: {plain_errors:?}"
    );
    assert!(
        ff.0 > tracked.0,
        "feed-forward {ff:?} against tracked {tracked:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// #16's load cell in blocked runs: the [`variant_fit`] strip drying from
/// boot (`plant-drying`), held by the load cell; 40 s of a 1 mN travelling
/// force wave at 1 Hz, 60° a segment, from fresh boots: fed forward from
/// the fit (`force-ff:`) and held by the board's tracker reading the load
/// cell (`force:`). The force by lock-in over each 5 s window. Asserted:
/// tracked, every window after the first within 5 % and 5°; fed forward,
/// the last window off by more than 8 % (the drying, 12 % in 40 s) and its
/// worst worse than the tracked one's.
#[test]
fn a_force_wave_is_held_by_the_load_cell_on_a_drying_strip() {
    let elf = build_firmware("qemu-serial,plant-variant,plant-drying");
    let dir = fresh_dir("finrs-virtual-force");
    std::fs::write(dir.join("fit.toml"), variant_fit()).unwrap();
    let (force_n, hz, lag_deg, hold_s) = (1e-3, 1.0, 60.0, 40.0);
    let mut worst = Vec::new();
    for (name, wave) in [
        ("feed_forward", format!("force-ff:{force_n},{hz},{lag_deg}")),
        ("tracked", format!("force:{force_n},{hz},{lag_deg}")),
    ] {
        let (_, path) = one_recording(&elf, &dir, "fit.toml", (name, "blocked", &wave), hold_s);
        let errors = sine_errors(&path, Channel::Force, force_n, hz, hold_s, 5.0);
        let (shown, worst_after_first) = shown_and_worst(&errors);
        eprintln!("force {name}: per 5 s: {shown}");
        let tracking = dir
            .join(name)
            .join("tracking")
            .join(path.file_name().unwrap());
        assert_eq!(tracking.exists(), name == "tracked", "{name}");
        worst.push((errors, worst_after_first));
    }
    let (ff_errors, ff) = &worst[0];
    let (_, tracked) = worst[1];
    assert!(
        tracked.0 <= 0.05 && tracked.1 <= 5.0,
        "tracked, worst 5 s window after the first: {tracked:?}"
    );
    assert!(
        ff_errors.last().unwrap().0 < -0.08 && ff.0 > tracked.0,
        "fed forward {ff_errors:?} against tracked {tracked:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
