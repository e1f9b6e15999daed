//! `rig-coverage`: fits each session of a seeded sweep with the `finrs`
//! binary and counts how often each 95 % interval holds the truth
//! (`finrs_rig::coverage`).
//!
//! - On the off-class rig, whose strip shares the fitted knobs, the truth
//!   is the rig's own value, and each session is fitted twice: with the
//!   structure the strip truly has and with the baseline alone.
//! - On the literature strip (`--literature`), no knob has a value in the
//!   strip, so each session is fitted with its true structure beside its
//!   twin (the same session with every measurement error `--twin-noise`
//!   times as large), and the twin's estimates are the truths: the
//!   misspecified model's pseudo-true values, every knob scored.
//!
//! Each fit's wall time is kept too: with `--jobs 1` the fit has the
//! machine's cores to itself, the benchmark of #12's 10 s a session.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use finrs_rig::coverage::{markdown, median, pseudo_truth, score, tally, Scored};
use finrs_rig::runner::{each_session, SweepArgs};
use finrs_rig::sweep::{plan_of, structure_of, truth_of, write_scenario, write_twin, Scenario};

/// Fits rig sessions with their true structure (and the off-class rig's
/// with the baseline too), and scores each fitted interval against the
/// rig's value or the twin's estimate.
#[derive(Parser)]
#[command(version)]
struct Cli {
    #[command(flatten)]
    run: SweepArgs,
    /// Directory for the table (coverage.md), every scored interval
    /// (coverage.csv), each fit's wall time (fit-seconds.csv) and JSON
    /// (fits/seed-N-STRUCTURE.json, the twin's seed-N-STRUCTURE-twin.json).
    #[arg(long)]
    out: PathBuf,
    /// The literature sweep's sessions (`sweep::plan_literature`), scored
    /// against their twins' fits.
    #[arg(long)]
    literature: bool,
    /// The null sweep's sessions (with `--literature`, the literature
    /// strip's base alone).
    #[arg(long)]
    null: bool,
    /// The twin's measurement errors over the session's: small enough that
    /// the twin's own scatter is a few percent of an interval, large
    /// enough that its rests still set the fit's weights by noise.
    #[arg(long, default_value_t = 0.05)]
    twin_noise: f64,
    /// Only task K of N's share of the sessions, `K/N` (a job array's
    /// task; as `rig-sweep --shard`): its fits kept in OUT/fits, no table
    /// written. A fit kept there (its JSON and its `.seconds`) is not run
    /// again by a later run on the same OUT without --fresh.
    #[arg(long)]
    shard: Option<finrs_rig::runner::Shard>,
    /// Fit nothing: every fit must be kept in OUT/fits, else the run stops
    /// naming the sessions without one (a merge of shards that all
    /// finished).
    #[arg(long, conflicts_with_all = ["shard", "fresh"])]
    kept_only: bool,
    /// Fit every session again, even those with fits kept in OUT/fits by
    /// an earlier run (of another `finrs`, say).
    #[arg(long)]
    fresh: bool,
}

/// The structures a session can be fitted with: the one its strip truly
/// has, and the baseline alone.
const STRUCTURES: [&str; 2] = ["true", "baseline"];

/// The structures `s` is fitted with: the literature strip's with its
/// true one only (each beside its twin), the off-class rig's with both.
fn structures(s: &Scenario) -> &'static [&'static str] {
    if s.literature {
        &STRUCTURES[..1]
    } else {
        &STRUCTURES
    }
}

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
    Ok((read_json(json)?, seconds))
}

/// A fit's JSON as `finrs fit --json` wrote it.
fn read_json(json: &Path) -> anyhow::Result<serde_json::Value> {
    let text = std::fs::read_to_string(json).with_context(|| json.display().to_string())?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", json.display()))
}

/// The wall time beside a fit's JSON, written after it: a fit
/// interrupted while writing has none, and is not taken as kept.
fn seconds_path(json: &Path) -> PathBuf {
    json.with_extension("seconds")
}

/// Whether an earlier run kept the fit `json` (and --fresh does not ask
/// for it again).
fn is_kept(cli: &Cli, json: &Path) -> bool {
    !cli.fresh && seconds_path(json).is_file()
}

/// The fit kept in `json` by an earlier run, or one of `dir` run now and
/// kept.
fn fit_or_kept(
    cli: &Cli,
    dir: &Path,
    effects: &[&str],
    json: &Path,
) -> anyhow::Result<(serde_json::Value, f64)> {
    if is_kept(cli, json) {
        let read = || -> anyhow::Result<(serde_json::Value, f64)> {
            let value = read_json(json)?;
            let seconds = std::fs::read_to_string(seconds_path(json))?
                .trim()
                .parse()?;
            Ok((value, seconds))
        };
        return read()
            .with_context(|| format!("kept fit {} unreadable (run with --fresh)", json.display()));
    }
    let (value, seconds) = fit(cli, dir, effects, json)?;
    std::fs::write(seconds_path(json), format!("{seconds}\n"))
        .with_context(|| json.display().to_string())?;
    Ok((value, seconds))
}

/// Per structure fitted: its label, the scored intervals and the fit's
/// wall time, s.
type Fitted = Vec<(&'static str, Vec<Scored>, f64)>;

/// The session's scored intervals and fit times.
fn one(cli: &Cli, s: &Scenario) -> anyhow::Result<Fitted> {
    let dir = cli.out.join(format!("session-{}", s.seed));
    let twin_dir = cli.out.join(format!("twin-{}", s.seed));
    let json = |label: &str, twin: &str| {
        cli.out
            .join("fits")
            .join(format!("seed-{}-{label}{twin}.json", s.seed))
    };
    let twins: &[&str] = if s.literature { &["", "-twin"] } else { &[""] };
    // The sessions are written only when some fit must run.
    let all_kept = structures(s)
        .iter()
        .all(|&label| twins.iter().all(|twin| is_kept(cli, &json(label, twin))));
    if !all_kept {
        anyhow::ensure!(
            !cli.kept_only,
            "--kept-only: seed {}'s fits are not all kept in {}",
            s.seed,
            cli.out.join("fits").display()
        );
        write_scenario(s, &dir)?;
        if s.literature {
            write_twin(s, &twin_dir, cli.twin_noise)?;
        }
    }
    let structure = structure_of(s)?;
    // The off-class rig's own values, the same for every structure.
    let rig_truth = if s.literature {
        None
    } else {
        Some(truth_of(s)?)
    };
    let mut out = Vec::new();
    for &label in structures(s) {
        let effects: &[&str] = if label == STRUCTURES[0] {
            &structure
        } else {
            &[]
        };
        let (value, t) = fit_or_kept(cli, &dir, effects, &json(label, ""))?;
        let scored = match &rig_truth {
            Some(truth) => score(&value, truth)?,
            None => {
                let (twin, _) = fit_or_kept(cli, &twin_dir, effects, &json(label, "-twin"))?;
                score(&value, &pseudo_truth(&twin)?)?
            }
        };
        out.push((label, scored, t));
    }
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&twin_dir).ok();
    Ok(out)
}

/// The fits' wall times under each structure: median, the slowest and how
/// many took over #12's 10 s.
fn times(results: &[(Scenario, Fitted)]) -> String {
    let mut out = String::from(
        "\n`finrs fit` wall time (s; one session at a time has both cores with `--jobs 1`; the twins' fits not counted):\n\n| structure | fits | median | slowest (seed) | over 10 s |\n|---|---|---|---|---|\n",
    );
    for label in STRUCTURES {
        let mut t: Vec<(f64, u64)> = results
            .iter()
            .flat_map(|(s, f)| f.iter().filter(|x| x.0 == label).map(|x| (x.2, s.seed)))
            .collect();
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
    let mut scenarios = plan_of(
        cli.literature,
        cli.null,
        cli.run.first_seed,
        cli.run.sessions,
    );
    if let Some(shard) = cli.shard {
        scenarios = shard.take(scenarios);
    }
    let results: Vec<(Scenario, Fitted)> = each_session(&scenarios, cli.run.jobs, |s| {
        let fitted = one(&cli, s)?;
        let missed: Vec<&str> = fitted[0]
            .1
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
        Ok((s.clone(), fitted))
    });
    anyhow::ensure!(
        !cli.kept_only || results.len() == scenarios.len(),
        "--kept-only: {} of {} sessions have no kept fits (named above)",
        scenarios.len() - results.len(),
        scenarios.len()
    );
    if let Some(shard) = cli.shard {
        let kept_in = cli.out.join("fits");
        println!(
            "{}",
            shard.summary(results.len(), scenarios.len(), &kept_in)
        );
        return Ok(());
    }
    let mut csv = String::from("seed,row,structure,knob,truth,value,low,high,covered\n");
    let mut fit_csv = String::from("seed,row,structure,seconds\n");
    for (s, fitted) in &results {
        for (label, list, t) in fitted {
            fit_csv.push_str(&format!("{},{},{label},{t:.2}\n", s.seed, s.row()));
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
        .into_iter()
        .map(|label| {
            let scored = results
                .iter()
                .flat_map(|(_, f)| f.iter().filter(|x| x.0 == label).map(|x| x.1.as_slice()));
            (label, tally(scored))
        })
        .filter(|(_, t)| !t.is_empty())
        .collect();
    let truths = if cli.literature {
        format!(
            "the truths are each session's twin's estimates (its measurement errors {} times the session's), the fitted model's pseudo-true values on that strip and protocol",
            cli.twin_noise
        )
    } else {
        "the truths are the rig's own values of the knobs that mean the same in the rig".to_string()
    };
    let md = format!(
        "{} of {} sessions from seed {} (a session whose fit failed is named on stderr); `true`: fitted with the catalogue effects the strip has, `baseline`: with none; {truths}.\n\n{}{}",
        results.len(),
        scenarios.len(),
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
