//! `finrs diagnose`, `fit` and `seed-check` as users run them: an output
//! they cannot write fails at once, naming the path, instead of after the
//! run (minutes long for a diagnosis).

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

/// The shipped example session, a valid input.
fn example_session() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session")
}

/// A fresh folder holding a regular file `blocker`, under which nothing can
/// be created.
fn blocker(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("finrs-diag-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("blocker");
    std::fs::write(&file, "a file, not a folder\n").unwrap();
    file
}

/// Runs `finrs diagnose SESSION extra…`, which must fail within 5 s
/// (a diagnosis of the example takes far longer); returns its stderr.
fn fails_fast(extra: &[&str]) -> String {
    let started = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .arg("diagnose")
        .arg(example_session())
        .args(extra)
        .output()
        .unwrap();
    let took = started.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "diagnose succeeded: {stderr}");
    assert!(
        took < Duration::from_secs(5),
        "failed only after {took:?}: {stderr}"
    );
    stderr
}

#[test]
fn an_unwritable_json_output_fails_before_the_run_naming_the_path() {
    let file = blocker("json");
    let json = file.join("verdict.json");
    let stderr = fails_fast(&["--json", json.to_str().unwrap()]);
    assert!(
        stderr.starts_with(&format!(
            "error: cannot create the folder {}: ",
            file.display()
        )),
        "{stderr}"
    );
    std::fs::remove_dir_all(file.parent().unwrap()).unwrap();
}

#[test]
fn an_unwritable_report_folder_fails_before_the_run_naming_the_path() {
    let file = blocker("report");
    let stderr = fails_fast(&["--report", file.to_str().unwrap()]);
    assert!(
        stderr.starts_with(&format!(
            "error: cannot create the folder {}: ",
            file.display()
        )),
        "{stderr}"
    );
    std::fs::remove_dir_all(file.parent().unwrap()).unwrap();
}

#[test]
fn the_check_leaves_no_output_behind_when_the_run_then_fails() {
    let file = blocker("leftover");
    let dir = file.parent().unwrap();
    let old = dir.join("old.json");
    std::fs::write(&old, "old\n").unwrap();
    let new = dir.join("new").join("verdict.json");
    for json in [&old, &new] {
        // A session that does not exist fails after the outputs are checked.
        let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
            .arg("diagnose")
            .arg(dir.join("no-such-session"))
            .arg("--json")
            .arg(json)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains("no-such-session"), "{stderr}");
    }
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "old\n");
    assert!(!new.exists(), "the check left {} behind", new.display());
    std::fs::remove_dir_all(dir).unwrap();
}

/// Runs `finrs args…`, which must fail before its run: nothing on stdout,
/// where each prints its result; returns its stderr.
fn refused_before_the_run(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "succeeded: {stderr}");
    assert!(
        out.stdout.is_empty(),
        "ran before failing: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    stderr
}

#[test]
fn an_unwritable_fit_output_fails_before_the_fit_naming_the_path() {
    let file = blocker("fit");
    let toml = file.join("params.toml");
    let session = example_session();
    let stderr = refused_before_the_run(&[
        "fit",
        session.to_str().unwrap(),
        "--out",
        toml.to_str().unwrap(),
    ]);
    assert!(
        stderr.starts_with(&format!(
            "error: cannot create the folder {}: ",
            file.display()
        )),
        "{stderr}"
    );
    std::fs::remove_dir_all(file.parent().unwrap()).unwrap();
}

#[test]
fn an_unwritable_seed_check_output_fails_before_the_check_naming_the_path() {
    let file = blocker("seed");
    let json = file.join("seed.json");
    let stderr = refused_before_the_run(&["seed-check", "--json", json.to_str().unwrap()]);
    assert!(
        stderr.starts_with(&format!(
            "error: cannot create the folder {}: ",
            file.display()
        )),
        "{stderr}"
    );
    std::fs::remove_dir_all(file.parent().unwrap()).unwrap();
}
