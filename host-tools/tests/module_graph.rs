//! The library's import graph has no circle and every import goes to a
//! lower layer: `scripts/module-graph` run over `src/`, and over a small
//! tree with a circle to show the check can fail.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/module-graph")
}

fn run(src: &Path) -> Output {
    Command::new("python3")
        .arg(script())
        .arg(src)
        .output()
        .expect("python3 runs scripts/module-graph")
}

#[test]
fn the_library_has_no_circle_and_no_upward_import() {
    let o = run(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    // Not vacuous: the graph has the layers' edges.
    let edges = String::from_utf8_lossy(&o.stdout);
    assert!(
        edges.contains("analysis::fit::fitter -> model::predict"),
        "{edges}"
    );
    assert!(edges.contains("session -> recording"), "{edges}");
}

/// A tree with `session` and `model` importing each other, and `recording`
/// importing `session`: both rules are broken, and named.
#[test]
fn a_circle_and_an_upward_import_fail_the_check() {
    let dir = std::env::temp_dir().join(format!("finrs-module-graph-{}", std::process::id()));
    let write = |file: &str, text: &str| {
        let path = dir.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    };
    write(
        "lib.rs",
        "pub mod model;\npub mod recording;\npub mod session;\n",
    );
    write("recording/mod.rs", "mod data;\npub use data::Recording;\n");
    write(
        "recording/data.rs",
        "pub struct Recording;\nfn f() -> crate::session::Session { todo!() }\n",
    );
    write(
        "session.rs",
        "use crate::model::{predict::run, Spec};\npub struct Session;\n",
    );
    write("model/mod.rs", "pub mod predict;\npub use predict::Spec;\n");
    write(
        "model/predict.rs",
        "// crate::analysis::x in a comment is no import\nuse crate::session::Session;\npub struct Spec;\npub fn run() {}\n",
    );
    let o = run(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cycle between modules: model::predict, session"),
        "{err}"
    );
    assert!(
        err.contains("recording::data (layer 0) imports session, a higher layer (1)"),
        "{err}"
    );
    assert!(
        err.contains("session (layer 1) imports model::predict, a higher layer (2)"),
        "{err}"
    );
    assert!(!err.contains("analysis"), "{err}");
}
