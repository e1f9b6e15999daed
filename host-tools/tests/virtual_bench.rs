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
/// `target/qemu`, the QEMU tests' own target folder (this `cargo test`
/// holds the workspace's), and copied aside: the tests build in turn into
/// one place and run at once.
fn build_firmware(features: &str) -> PathBuf {
    static BUILD: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let target_dir = workspace().join("target/qemu");
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

    let mut run = finrs();
    run.args(["bench", "run"])
        .arg(workspace().join("examples/bench/protocol.toml"))
        .arg("--qemu")
        .arg(&elf)
        .arg("--out")
        .arg(&session);
    let log = run_ok(run, "finrs bench run --qemu");
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
                let track = session.join("tracks").join(&name);
                let mut merge = finrs();
                merge
                    .arg("merge-camera")
                    .arg("--daq")
                    .arg(path)
                    .arg("--track")
                    .arg(&track)
                    .args(["--m-per-px", "5e-5"])
                    .arg("--out")
                    .arg(path);
                run_ok(merge, "finrs merge-camera");
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
    let dir = std::env::temp_dir().join(format!("finrs-virtual-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("live.csv");
    let mut pty = common::pty::Pty::spawn(&format!(
        "{} bench live --qemu {} --out {}",
        env!("CARGO_BIN_EXE_finrs"),
        elf.display(),
        out.display()
    ));
    pty.keys(b"", 3000);
    pty.keys(b"w", 500);
    pty.keys(b"step:1\r", 3000);
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
    assert!(held > 500, "{held} rows at 1 V of {}", rec.t_s.len());
    let _ = std::fs::remove_dir_all(&dir);
}
