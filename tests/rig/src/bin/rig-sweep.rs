//! `rig-sweep`: diagnoses a seeded sweep of off-class rig sessions with the
//! `finrs` binary and writes the confusion matrix (Markdown, CSV, PNG).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::Context;
use clap::Parser;
use finrs::session::Session;
use finrs_rig::expect::{names_given, score, Expected};
use finrs_rig::runner::{each_session, SweepArgs};
use finrs_rig::sweep::{
    csv, expected_of, markdown, plan_lab, plan_of, write_scenario, Outcome, Scenario,
};
use finrs_rig::trivial::TRIVIAL;

/// Writes and diagnoses off-class rig sessions, one seed each, and counts
/// what the diagnosis names against what each session holds.
#[derive(Parser)]
#[command(version)]
struct Cli {
    #[command(flatten)]
    run: SweepArgs,
    /// Directory for the matrix (sweep.md, sweep.csv, sweep.png), each
    /// session's result (results/seed-N.json: a sweep run again resumes
    /// from them) and, with --keep, the sessions.
    #[arg(long)]
    out: PathBuf,
    /// Keep each session's directory and verdict.
    #[arg(long)]
    keep: bool,
    /// Diagnose every session again, even those with a result in
    /// OUT/results from an earlier (interrupted) run.
    #[arg(long)]
    fresh: bool,
    /// Only these seeds of the sweep (each keeps its row in the whole
    /// sweep's plan), e.g. to look again at the sessions it got wrong.
    #[arg(long, value_delimiter = ',')]
    only: Vec<u64>,
    /// The lab sweep (`sweep::plan_lab`, docs/rig.md "A lab-like bench"):
    /// the off-class strip on the lab bench, alone or with one departure,
    /// on the short protocol or the lab's own, and the ideal strip with
    /// drift alone (seeds from 20 000 are its own).
    #[arg(long)]
    lab: bool,
    /// Lab artefacts left out of every lab session, comma-separated (e.g.
    /// `readback`, for a reader that refuses a DAQ's rests).
    #[arg(long, value_delimiter = ',', requires = "lab")]
    lab_without: Vec<String>,
    /// The null sweep (`sweep::plan_null`): the baseline's own strip with
    /// nothing hidden, on a perfect bench: the share of sessions given a
    /// catalogue name is the search's family-wise false-name rate.
    #[arg(long, conflicts_with = "lab")]
    null: bool,
    /// The literature sweep (`sweep::plan_literature`, docs/rig.md "A
    /// strip from the literature"): electrodes as resistive lines,
    /// electrolysis, a viscoelastic spectrum, drying by water content,
    /// geometry measured a few percent off; each departure from below the
    /// diagnosis's detectable strength to above its plausible one.
    /// With `--null`: the literature strip's base alone, in air, on a
    /// perfect bench (`sweep::plan_literature_null`).
    #[arg(long, conflicts_with = "lab")]
    literature: bool,
    /// Parts of the literature strip's base left out, comma-separated
    /// (`line`, `spectrum`, `ruler`; `finrs_rig::literature::BASE_PARTS`),
    /// every draw as with them: an ablation that tells which part a
    /// sweep's false names come from. Give the sweep an OUT of its own.
    #[arg(long, value_delimiter = ',', requires = "literature")]
    literature_without: Vec<String>,
    /// Only task K of N's share of the sweep, `K/N` (a job array's task,
    /// e.g. `$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`): the sessions
    /// at places K, K + N, ... of the plan. A shard keeps its results in
    /// OUT/results and writes no matrix; the same command without
    /// --shard (and with --kept-only) then merges them (docs/rig.md, "On
    /// a cluster").
    #[arg(long)]
    shard: Option<finrs_rig::runner::Shard>,
    /// Diagnose nothing: every session must have a kept result in
    /// OUT/results, else the sweep stops naming the seeds without one
    /// (a merge of shards that all finished).
    #[arg(long, conflicts_with_all = ["fresh", "shard"])]
    kept_only: bool,
}

/// What `finrs diagnose` said of one session, as kept in OUT/results so
/// that an interrupted sweep resumes where it stopped.
struct Said {
    verdict: String,
    causes: Vec<String>,
    gain_percent: f64,
    seconds: f64,
    /// Each trivial diagnoser's verdict word and names, in [`TRIVIAL`]'s
    /// order (`None` in a result kept before they were scored).
    trivial: Option<Vec<Guess>>,
}

/// A trivial diagnoser's verdict word and names.
type Guess = (String, Vec<String>);

/// Where the scenario's session is written (and kept with --keep).
fn session_dir(cli: &Cli, s: &Scenario) -> PathBuf {
    cli.out.join(format!("session-{}", s.seed))
}

fn result_path(cli: &Cli, s: &Scenario) -> PathBuf {
    cli.out
        .join("results")
        .join(format!("seed-{}.json", s.seed))
}

/// The kept result of the scenario's session, if an earlier run wrote one
/// for the same row (a different first seed gives a seed another row).
fn kept(cli: &Cli, s: &Scenario) -> anyhow::Result<Option<Said>> {
    let path = result_path(cli, s);
    if cli.fresh || !path.is_file() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    if v["row"].as_str() != Some(s.row().as_str()) {
        return Ok(None);
    }
    let (verdict, causes, gain_percent) =
        verdict_of(&v).with_context(|| format!("{}: not a kept result", path.display()))?;
    let seconds = v["seconds"].as_f64().unwrap_or(f64::NAN);
    let trivial = v["trivial"].as_array().and_then(|a| {
        let guesses: Vec<Guess> = a
            .iter()
            .filter_map(|g| verdict_of(g).ok().map(|(v, c, _)| (v, c)))
            .collect();
        let names = a.iter().map(|g| g["name"].as_str());
        let same = names.eq(TRIVIAL.iter().map(|t| Some(t.name())));
        (same && guesses.len() == TRIVIAL.len()).then_some(guesses)
    });
    Ok(Some(Said {
        verdict,
        causes,
        gain_percent,
        seconds,
        trivial,
    }))
}

/// Keeps a result: written to a temporary name and renamed, so that an
/// interrupted write never leaves half a file to resume from.
fn keep_result(cli: &Cli, s: &Scenario, said: &Said) -> anyhow::Result<()> {
    let path = result_path(cli, s);
    let tmp = path.with_extension("json.tmp");
    let v = serde_json::json!({
        "seed": s.seed,
        "row": s.row(),
        "verdict": said.verdict,
        "causes": said.causes,
        "gain_percent": if said.gain_percent.is_finite() { Some(said.gain_percent) } else { None },
        "seconds": said.seconds,
        "trivial": said.trivial.as_ref().map(|g| {
            TRIVIAL
                .iter()
                .zip(g)
                .map(|(t, (verdict, causes))| {
                    serde_json::json!({ "name": t.name(), "verdict": verdict, "causes": causes })
                })
                .collect::<Vec<_>>()
        }),
    });
    std::fs::write(&tmp, serde_json::to_string_pretty(&v)?)
        .with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("renaming to {}", path.display()))
}

/// The verdict's words and names from `finrs diagnose --json`.
fn read_verdict(path: &Path) -> anyhow::Result<(String, Vec<String>, f64)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    verdict_of(&v)
}

/// The verdict word, the names (catalogue names, then bench findings as
/// `bench:` names) and the held-out gain of a verdict (or of a kept
/// result, which holds the names already merged).
fn verdict_of(v: &serde_json::Value) -> anyhow::Result<(String, Vec<String>, f64)> {
    let verdict = v["verdict"].as_str().context("no `verdict`")?.to_string();
    let causes: Vec<String> = v["causes"]
        .as_array()
        .context("no `causes`")?
        .iter()
        .filter_map(|c| c.as_str().map(str::to_string))
        .collect();
    let found = v["rest"]["bench"].as_array().into_iter().flatten();
    let causes = names_given(&causes, found.filter_map(|b| b["what"].as_str()));
    let gain = v["gain_percent"].as_f64().unwrap_or(f64::NAN);
    Ok((verdict, causes, gain))
}

/// Each trivial diagnoser's verdict on the session in `dir`; where the
/// session cannot be read (nor diagnosed), `failed`.
fn guesses(dir: &Path) -> Vec<Guess> {
    match Session::read(dir) {
        Ok(session) => TRIVIAL.iter().map(|t| t.diagnose(&session)).collect(),
        Err(e) => TRIVIAL
            .iter()
            .map(|_| (format!("failed: {e}"), Vec::new()))
            .collect(),
    }
}

/// The scenario's outcome: its kept result, or a diagnosis run now. A
/// result kept before the trivial diagnosers were scored gets them now
/// (the session written again: the same seed writes the same session).
fn one(cli: &Cli, s: &Scenario) -> anyhow::Result<Outcome> {
    let (expected, mut said) = match kept(cli, s)? {
        Some(said) => (expected_of(s)?, said),
        None => diagnose_one(cli, s)?,
    };
    if said.trivial.is_none() {
        let dir = session_dir(cli, s);
        write_scenario(s, &dir)?;
        said.trivial = Some(guesses(&dir));
        if !cli.keep {
            std::fs::remove_dir_all(&dir).ok();
        }
        keep_result(cli, s, &said)?;
    }
    let trivial = TRIVIAL
        .iter()
        .zip(said.trivial.iter().flatten())
        .map(|(&t, (verdict, causes))| (t, score(&expected, verdict, causes)))
        .collect();
    let score = score(&expected, &said.verdict, &said.causes);
    Ok(Outcome {
        scenario: s.clone(),
        expected,
        verdict: said.verdict,
        causes: said.causes,
        gain_percent: said.gain_percent,
        score,
        seconds: said.seconds,
        trivial,
    })
}

/// Writes the scenario's session, diagnoses it with the `finrs` binary
/// and keeps the result.
fn diagnose_one(cli: &Cli, s: &Scenario) -> anyhow::Result<(Expected, Said)> {
    let dir = session_dir(cli, s);
    let expected = write_scenario(s, &dir)?;
    let trivial = Some(guesses(&dir));
    let json = dir.join("verdict.json");
    let start = Instant::now();
    let run = Command::new(&cli.run.finrs)
        .arg("diagnose")
        .arg(&dir)
        .arg("--json")
        .arg(&json)
        .output()
        .with_context(|| format!("running {}", cli.run.finrs.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    // A diagnosis killed by a signal (the sweep interrupted) is not a
    // result: nothing is kept, and a resumed sweep runs it again.
    anyhow::ensure!(
        run.status.code().is_some(),
        "{} was stopped by a signal ({})",
        cli.run.finrs.display(),
        run.status
    );
    let (verdict, causes, gain_percent) = if run.status.success() {
        read_verdict(&json)?
    } else {
        let why = String::from_utf8_lossy(&run.stderr);
        (
            format!("failed: {}", why.trim().lines().last().unwrap_or("")),
            Vec::new(),
            f64::NAN,
        )
    };
    if !cli.keep {
        std::fs::remove_dir_all(&dir).ok();
    }
    let said = Said {
        verdict,
        causes,
        gain_percent,
        seconds,
        trivial,
    };
    keep_result(cli, s, &said)?;
    Ok((expected, said))
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    cli.run.check()?;
    std::fs::create_dir_all(cli.out.join("results"))?;
    if let Some(w) = cli
        .lab_without
        .iter()
        .find(|w| !finrs_rig::LAB_ARTEFACTS.contains(&w.as_str()))
    {
        anyhow::bail!(
            "--lab-without `{w}`: the lab bench has {:?}",
            finrs_rig::LAB_ARTEFACTS
        );
    }
    if let Some(w) = cli
        .literature_without
        .iter()
        .find(|w| !finrs_rig::literature::BASE_PARTS.contains(&w.as_str()))
    {
        anyhow::bail!(
            "--literature-without `{w}`: the literature strip's base has {:?}",
            finrs_rig::literature::BASE_PARTS
        );
    }
    let mut scenarios = if cli.lab && !cli.null && !cli.literature {
        let mut p = plan_lab(cli.run.first_seed, cli.run.sessions);
        for s in &mut p {
            s.lab_without = cli.lab_without.clone();
        }
        p
    } else {
        let mut p = plan_of(
            cli.literature,
            cli.null,
            cli.run.first_seed,
            cli.run.sessions,
        );
        for s in &mut p {
            s.literature_without = cli.literature_without.clone();
        }
        p
    };
    if let Some(s) = cli
        .only
        .iter()
        .find(|&&s| !scenarios.iter().any(|x| x.seed == s))
    {
        anyhow::bail!(
            "--only {s}: not a seed of this sweep ({} to {})",
            cli.run.first_seed,
            cli.run.first_seed + cli.run.sessions as u64 - 1
        );
    }
    if !cli.only.is_empty() {
        scenarios.retain(|x| cli.only.contains(&x.seed));
    }
    if let Some(shard) = cli.shard {
        scenarios = shard.take(scenarios);
    }
    if cli.kept_only {
        let missing: Vec<u64> = scenarios
            .iter()
            .filter(|s| !matches!(kept(&cli, s), Ok(Some(_))))
            .map(|s| s.seed)
            .collect();
        anyhow::ensure!(
            missing.is_empty(),
            "--kept-only: {} of {} sessions have no kept result of their row in {}: seeds {:?}{}",
            missing.len(),
            scenarios.len(),
            cli.out.join("results").display(),
            &missing[..missing.len().min(20)],
            if missing.len() > 20 { " and more" } else { "" }
        );
    }
    let outcomes: Vec<Outcome> = each_session(&scenarios, cli.run.jobs, |s| {
        let o = one(&cli, s)?;
        eprintln!(
            "seed {:>6} {:<45} {:<12} {:<50} {} ({:.0} s)",
            o.scenario.seed,
            o.scenario.row(),
            o.verdict,
            o.causes.join(","),
            if o.score.is_right() { "right" } else { "WRONG" },
            o.seconds
        );
        Ok(o)
    });
    if let Some(shard) = cli.shard {
        let kept_in = cli.out.join("results");
        println!(
            "{}",
            shard.summary(outcomes.len(), scenarios.len(), &kept_in)
        );
        return Ok(());
    }
    let md = markdown(&outcomes);
    std::fs::write(cli.out.join("sweep.md"), &md)?;
    std::fs::write(cli.out.join("sweep.csv"), csv(&outcomes))?;
    finrs_rig::heatmap::draw(&outcomes, &cli.out.join("sweep.png"))?;
    println!("{md}");
    Ok(())
}
