//! `finrs plan` on a session the board alone could record: the example
//! session's two blocked steps. What such a session cannot show is said
//! (large deflection needs a camera on a free run), the proposals are
//! ranked by what they add, the chosen ones fit the budget, and the
//! protocol written for them is one `finrs bench run` reads, within the
//! drive limit.

use std::path::{Path, PathBuf};
use std::process::Command;

use finrs::protocol::Protocol;
use finrs::recording::SAFE_VOLTAGE_LIMIT_V;

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/rig-session")
}

#[test]
fn a_board_only_session_is_planned_into_a_protocol_the_bench_runs() {
    let dir = std::env::temp_dir().join(format!("finrs-plan-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let session = dir.join("session");
    std::fs::create_dir_all(&session).unwrap();
    for name in ["09_blocked_step_2.0V.csv", "10_blocked_step_4.0V.csv"] {
        std::fs::copy(example().join(name), session.join(name)).unwrap();
    }
    let (toml, json) = (dir.join("plan.toml"), dir.join("plan.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .arg("plan")
        .arg(&session)
        .args(["--budget-s", "30"])
        .arg("--out")
        .arg(&toml)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    eprintln!("{stdout}");

    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // Blocked runs only: the arc of a large deflection needs a free tip.
    let advice = plan["advice"].as_array().unwrap();
    assert!(
        advice
            .iter()
            .any(|a| a["effect"] == "large-deflection"
                && a["change"].as_str().unwrap().contains("free")),
        "{advice:?}"
    );
    assert!(stdout.contains("large-deflection") && stdout.contains("not testable here"));

    // Ranked: what an addition makes testable first, then its bits.
    let proposals = plan["proposals"].as_array().unwrap();
    assert!(proposals.len() >= 8, "{proposals:?}");
    let key = |p: &serde_json::Value| {
        (
            p["newly_detectable"].as_array().unwrap().len(),
            p["bits"].as_f64().unwrap(),
        )
    };
    for w in proposals.windows(2) {
        let (a, b) = (key(&w[0]), key(&w[1]));
        assert!(
            a.0 > b.0 || (a.0 == b.0 && a.1 >= b.1),
            "{a:?} before {b:?}"
        );
    }
    // Something is worth recording, and it is chosen within the budget.
    let chosen: Vec<&str> = plan["chosen"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert!(!chosen.is_empty(), "{stdout}");
    // The best proposal that fits the budget alone comes first (the
    // best of all may not: a 31.5 s hold against 30 s).
    let first_fitting = proposals
        .iter()
        .find(|p| p["duration_s"].as_f64().unwrap() <= 30.0 && p["refused"].is_null())
        .unwrap();
    assert_eq!(chosen[0], first_fitting["name"].as_str().unwrap());
    let spent: f64 = proposals
        .iter()
        .filter(|p| chosen.contains(&p["name"].as_str().unwrap()))
        .map(|p| p["duration_s"].as_f64().unwrap())
        .sum();
    assert!(spent <= 30.0, "{spent}");

    // The protocol holds the chosen recordings, in order, for the bench.
    let protocol = Protocol::read(&toml).unwrap();
    let names: Vec<&str> = protocol
        .recordings
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(names, chosen);
    assert_eq!(protocol.geometry.length_m, 0.05);
    for step in &protocol.recordings {
        let levels = step
            .wave
            .split_once(':')
            .unwrap()
            .1
            .split(',')
            .map(|v| v.parse::<f64>().unwrap());
        let amplitude = if step.wave.starts_with("step:") {
            levels.fold(0.0f64, |m, v| m.max(v.abs()))
        } else {
            levels.take(1).fold(0.0, |_, v: f64| v.abs())
        };
        assert!(amplitude <= SAFE_VOLTAGE_LIMIT_V, "{}", step.wave);
        assert!(step.rest_s >= 1.0);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
