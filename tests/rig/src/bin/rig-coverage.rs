//! `rig-coverage`: fits each session of a seeded off-class sweep with the
//! `finrs` binary, once with the structure the strip truly has and once
//! with the baseline alone, and counts how often each 95 % interval holds
//! the rig's true value (`finrs_rig::coverage`).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::Context;
use clap::Parser;
use finrs_rig::coverage::{markdown, score, tally, Scored};
use finrs_rig::runner::{each_session, SweepArgs};
use finrs_rig::sweep::{plan, structure_of, truth_of, write_scenario, Scenario};

/// Fits off-class rig sessions with their true structure and with the
/// baseline, and scores each fitted interval against the rig's value.
#[derive(Parser)]
#[command(version)]
struct Cli {
    #[command(flatten)]
    run: SweepArgs,
    /// Directory for the table (coverage.md), every scored interval
    /// (coverage.csv) and each fit's JSON (fits/seed-N-STRUCTURE.json).
    #[arg(long)]
    out: PathBuf,
}

/// The two structures each session is fitted with.
const STRUCTURES: [&str; 2] = ["true", "baseline"];

/// Fits `dir` with `effects` into `json`.
fn fit(cli: &Cli, dir: &Path, effects: &[&str], json: &Path) -> anyhow::Result<serde_json::Value> {
    let mut cmd = Command::new(&cli.run.finrs);
    cmd.arg("fit").arg(dir).arg("--json").arg(json);
    if !effects.is_empty() {
        cmd.arg("--effects").arg(effects.join(","));
    }
    let run = cmd
        .output()
        .with_context(|| format!("running {}", cli.run.finrs.display()))?;
    anyhow::ensure!(
        run.status.success(),
        "finrs fit {} --effects {}: {}",
        dir.display(),
        effects.join(","),
        String::from_utf8_lossy(&run.stderr).trim()
    );
    let text = std::fs::read_to_string(json).with_context(|| json.display().to_string())?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", json.display()))
}

/// The session's scored intervals under each of [`STRUCTURES`].
fn one(cli: &Cli, s: &Scenario) -> anyhow::Result<[Vec<Scored>; 2]> {
    let dir = cli.out.join(format!("session-{}", s.seed));
    write_scenario(s, &dir)?;
    let truth = truth_of(s)?;
    let structure = structure_of(s)?;
    let mut out = [Vec::new(), Vec::new()];
    for (k, label) in STRUCTURES.iter().enumerate() {
        let effects: &[&str] = if k == 0 { &structure } else { &[] };
        let json = cli
            .out
            .join("fits")
            .join(format!("seed-{}-{label}.json", s.seed));
        out[k] = score(&fit(cli, &dir, effects, &json)?, &truth)?;
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(out)
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    cli.run.check()?;
    std::fs::create_dir_all(cli.out.join("fits"))?;
    let scenarios = plan(cli.run.first_seed, cli.run.sessions);
    let results: Vec<(Scenario, [Vec<Scored>; 2])> = each_session(&scenarios, cli.run.jobs, |s| {
        let scored = one(&cli, s)?;
        let missed: Vec<&str> = scored[0]
            .iter()
            .filter(|x| !x.covered())
            .map(|x| x.knob.as_str())
            .collect();
        eprintln!(
            "seed {:>6} {:<45} true structure misses: {}",
            s.seed,
            s.row(),
            if missed.is_empty() {
                "-".to_string()
            } else {
                missed.join(",")
            }
        );
        Ok((s.clone(), scored))
    });
    let mut csv = String::from("seed,row,structure,knob,truth,value,low,high,covered\n");
    for (s, scored) in &results {
        for (label, list) in STRUCTURES.iter().zip(scored) {
            for x in list {
                csv.push_str(&format!(
                    "{},{},{label},{},{:e},{:e},{:e},{:e},{}\n",
                    s.seed,
                    s.row(),
                    x.knob,
                    x.truth,
                    x.value,
                    x.low,
                    x.high,
                    x.covered()
                ));
            }
        }
    }
    let tallies: Vec<(&str, _)> = STRUCTURES
        .iter()
        .enumerate()
        .map(|(k, &label)| (label, tally(results.iter().map(|(_, s)| s[k].as_slice()))))
        .collect();
    let md = format!(
        "{} sessions from seed {}; `true`: fitted with the catalogue effects the strip has, `baseline`: with none.\n\n{}",
        results.len(),
        cli.run.first_seed,
        markdown(&tallies)
    );
    std::fs::write(cli.out.join("coverage.md"), &md)?;
    std::fs::write(cli.out.join("coverage.csv"), csv)?;
    println!("{md}");
    Ok(())
}
