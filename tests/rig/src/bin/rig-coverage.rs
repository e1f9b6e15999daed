//! `rig-coverage`: fits each session of a seeded off-class sweep with the
//! `finrs` binary, once with the structure the strip truly has and once
//! with the baseline alone, and counts how often each 95 % interval holds
//! the rig's true value (`finrs_rig::coverage`). Each fit's wall time is
//! kept too: with `--jobs 1` the fit has the machine's cores to itself,
//! the benchmark of #12's 10 s a session.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use finrs_rig::coverage::{markdown, median, score, tally, Scored};
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
    /// (coverage.csv), each fit's wall time (fit-seconds.csv) and JSON
    /// (fits/seed-N-STRUCTURE.json).
    #[arg(long)]
    out: PathBuf,
}

/// The two structures each session is fitted with.
const STRUCTURES: [&str; 2] = ["true", "baseline"];

/// Fits `dir` with `effects` into `json`; the fit's JSON and its wall
/// time, s.
fn fit(
    cli: &Cli,
    dir: &Path,
    effects: &[&str],
    json: &Path,
) -> anyhow::Result<(serde_json::Value, f64)> {
    let mut cmd = Command::new(&cli.run.finrs);
    cmd.arg("fit").arg(dir).arg("--json").arg(json);
    if !effects.is_empty() {
        cmd.arg("--effects").arg(effects.join(","));
    }
    let start = Instant::now();
    let run = cmd
        .output()
        .with_context(|| format!("running {}", cli.run.finrs.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    anyhow::ensure!(
        run.status.success(),
        "finrs fit {} --effects {}: {}",
        dir.display(),
        effects.join(","),
        String::from_utf8_lossy(&run.stderr).trim()
    );
    let text = std::fs::read_to_string(json).with_context(|| json.display().to_string())?;
    let value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", json.display()))?;
    Ok((value, seconds))
}

/// The session's scored intervals and fit times, s, under each of
/// [`STRUCTURES`].
type Fitted = ([Vec<Scored>; 2], [f64; 2]);

/// The session's scored intervals and fit times.
fn one(cli: &Cli, s: &Scenario) -> anyhow::Result<Fitted> {
    let dir = cli.out.join(format!("session-{}", s.seed));
    write_scenario(s, &dir)?;
    let truth = truth_of(s)?;
    let structure = structure_of(s)?;
    let mut out = [Vec::new(), Vec::new()];
    let mut seconds = [0.0; 2];
    for (k, label) in STRUCTURES.iter().enumerate() {
        let effects: &[&str] = if k == 0 { &structure } else { &[] };
        let json = cli
            .out
            .join("fits")
            .join(format!("seed-{}-{label}.json", s.seed));
        let (value, t) = fit(cli, &dir, effects, &json)?;
        out[k] = score(&value, &truth)?;
        seconds[k] = t;
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok((out, seconds))
}

/// The fits' wall times under each structure: median, the slowest and how
/// many took over #12's 10 s.
fn times(results: &[(Scenario, Fitted)]) -> String {
    let mut out = String::from(
        "\n`finrs fit` wall time (s; one session at a time has both cores with `--jobs 1`):\n\n| structure | fits | median | slowest (seed) | over 10 s |\n|---|---|---|---|---|\n",
    );
    for (k, label) in STRUCTURES.iter().enumerate() {
        let mut t: Vec<(f64, u64)> = results.iter().map(|(s, f)| (f.1[k], s.seed)).collect();
        t.sort_by(|a, b| a.0.total_cmp(&b.0));
        let Some(&(max, slowest)) = t.last() else {
            continue;
        };
        let n = t.len();
        let median = median(&t.iter().map(|x| x.0).collect::<Vec<_>>());
        let over = t.iter().filter(|x| x.0 > 10.0).count();
        out.push_str(&format!(
            "| {label} | {n} | {median:.1} | {max:.1} ({slowest}) | {over} |\n"
        ));
    }
    out
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    cli.run.check()?;
    std::fs::create_dir_all(cli.out.join("fits"))?;
    let scenarios = plan(cli.run.first_seed, cli.run.sessions);
    let results: Vec<(Scenario, Fitted)> = each_session(&scenarios, cli.run.jobs, |s| {
        let (scored, seconds) = one(&cli, s)?;
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
        Ok((s.clone(), (scored, seconds)))
    });
    let mut csv = String::from("seed,row,structure,knob,truth,value,low,high,covered\n");
    let mut fit_csv = String::from("seed,row,structure,seconds\n");
    for (s, (scored, seconds)) in &results {
        for (label, t) in STRUCTURES.iter().zip(seconds) {
            fit_csv.push_str(&format!("{},{},{label},{t:.2}\n", s.seed, s.row()));
        }
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
        .map(|(k, &label)| {
            let scored = results.iter().map(|(_, f)| f.0[k].as_slice());
            (label, tally(scored))
        })
        .collect();
    let md = format!(
        "{} sessions from seed {}; `true`: fitted with the catalogue effects the strip has, `baseline`: with none.\n\n{}{}",
        results.len(),
        cli.run.first_seed,
        markdown(&tallies),
        times(&results)
    );
    std::fs::write(cli.out.join("coverage.md"), &md)?;
    std::fs::write(cli.out.join("coverage.csv"), csv)?;
    std::fs::write(cli.out.join("fit-seconds.csv"), fit_csv)?;
    println!("{md}");
    Ok(())
}
