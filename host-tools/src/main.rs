//! The `finrs` command line: a thin layer over the `finrs` library.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand, ValueEnum};
use finrs::fit::{Effect, Fitter};
use finrs::params::{Geometry, ModelFile};
use finrs::recording::{Fixture, Recording};
use finrs::session::Session;
use finrs::simulate::simulate;
use finrs::wave::Wave;
use finrs::{plot, synth};
use indicatif::{ProgressBar, ProgressStyle};

/// Tools for segmented IPMC fins.
#[derive(Parser)]
#[command(name = "finrs", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Predict what the model does for a recording's drive, or for a wave.
    Simulate(SimulateArgs),
    /// Print a parameter file (the `thesis_2006` preset) to edit.
    Params,
    /// Fit the model's free parameters jointly over a session's recordings.
    Fit(FitArgs),
    /// Find what the baseline gets wrong in a session and name the cause.
    Diagnose(DiagnoseArgs),
    /// Set the seed's own measurements beside the baseline and the extended model.
    SeedCheck {
        /// Also write the check as JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

#[derive(clap::Args)]
struct DiagnoseArgs {
    /// Folder of recordings of one sample (ipmc-bench/1).
    session: PathBuf,
    /// Where to write the verdict (JSON).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Folder for the human report (REPORT.md and plots).
    #[arg(long)]
    report: Option<PathBuf>,
}

#[derive(clap::Args)]
struct FitArgs {
    /// Folder of recordings of one sample (ipmc-bench/1).
    session: PathBuf,
    /// Effects to add to the baseline, comma separated (e.g. damping,large-deflection).
    #[arg(long, value_delimiter = ',')]
    effects: Vec<String>,
    /// Where to write the fitted parameters (TOML, as `simulate --params` reads).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum FixtureArg {
    Free,
    Blocked,
}

#[derive(clap::Args)]
struct SimulateArgs {
    /// Recording whose voltage columns drive the model (ipmc-bench/1).
    #[arg(long, conflicts_with = "wave", required_unless_present = "wave")]
    input: Option<PathBuf>,
    /// A wave instead of a recording: step:V[,V..], sine:AMP,HZ,LAG_DEG,
    /// chirp:AMP,HZ0,HZ1 or pulses:AMP,ON_S,OFF_S.
    #[arg(long)]
    wave: Option<String>,
    /// Segments, with --wave.
    #[arg(long, default_value_t = 3)]
    segments: usize,
    /// Fixture, with --wave.
    #[arg(long, value_enum, default_value_t = FixtureArg::Free)]
    fixture: FixtureArg,
    /// Rest at 0 V before the wave, s.
    #[arg(long, default_value_t = 1.0)]
    rest_s: f64,
    /// Duration of the wave, s.
    #[arg(long, default_value_t = 10.0)]
    duration_s: f64,
    /// Rest at 0 V after the wave, s.
    #[arg(long, default_value_t = 0.0)]
    off_s: f64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    rate_hz: f64,
    /// Parameter file (TOML); default: the thesis_2006 preset.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Finite elements per segment (1, 2 or 4).
    #[arg(long, default_value_t = 1)]
    elements: usize,
    /// Where to write the simulated recording (CSV).
    #[arg(long)]
    out: PathBuf,
    /// Also write a PNG plot here.
    #[arg(long)]
    plot: Option<PathBuf>,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Simulate(args) => run_simulate(args),
        Command::Fit(args) => run_fit(args),
        Command::Diagnose(args) => run_diagnose(args),
        Command::SeedCheck { json } => run_seed_check(json),
        Command::Params => {
            print!("{}", ModelFile::thesis_2006().to_toml());
            Ok(())
        }
    }
}

fn run_simulate(args: SimulateArgs) -> anyhow::Result<()> {
    let model = match &args.params {
        Some(p) => ModelFile::read(p)?,
        None => ModelFile::thesis_2006(),
    };
    let (name, input) = match (&args.input, &args.wave) {
        (Some(path), _) => (path.display().to_string(), Recording::read(path)?),
        (None, Some(spec)) => {
            let wave = Wave::parse(spec).map_err(anyhow::Error::msg)?;
            let fixture = match args.fixture {
                FixtureArg::Free => Fixture::Free,
                FixtureArg::Blocked => Fixture::Blocked,
            };
            let drive = synth::Drive {
                segments: args.segments,
                fixture,
                rest_s: args.rest_s,
                duration_s: args.duration_s,
                off_s: args.off_s,
                rate_hz: args.rate_hz,
            };
            (spec.clone(), synth::drive_recording(&wave, &drive)?)
        }
        (None, None) => bail!("give --input REC.csv or --wave SPEC"),
    };
    let geometry = Geometry {
        length_m: input.meta.length_m,
        width_m: input.meta.width_m,
        thickness_m: input.meta.thickness_m,
    };
    let spec = model.spec_for(&geometry).with_context(|| name.clone())?;

    let bar = ProgressBar::new(input.t_s.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message("simulating");
    let sim = simulate(&name, &input, &spec, args.elements, &mut |n| {
        bar.set_position(n)
    })?;
    bar.finish_and_clear();

    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    }
    sim.write(&args.out)?;
    eprintln!("wrote {} ({} rows)", args.out.display(), sim.t_s.len());
    if let Some(png) = &args.plot {
        let measured = args.input.as_ref().map(|_| &input);
        plot::plot(png, &format!("finrs simulate: {name}"), measured, &sim)
            .with_context(|| png.display().to_string())?;
        eprintln!("wrote {}", png.display());
    }
    Ok(())
}

fn run_fit(args: FitArgs) -> anyhow::Result<()> {
    let effects = args
        .effects
        .iter()
        .map(|name| {
            Effect::parse(name).with_context(|| {
                let known: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
                format!(
                    "--effects: unknown effect {name:?}; known: {}",
                    known.join(", ")
                )
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let session = Session::read(&args.session)?;
    let fixed = ModelFile::thesis_2006().spec_for(&session.geometry())?;
    let fitter = Fitter::new(&session);
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let bar = spinner("fitting");
    let started = std::time::Instant::now();
    let fit = fitter.fit(&all, &effects, None, fixed)?;
    bar.finish_and_clear();
    print!("{}", finrs::fit::report::text(&fit, fitter.targets()));
    eprintln!(
        "fitted {} recordings in {:.1} s ({} model evaluations, {})",
        all.len(),
        started.elapsed().as_secs_f64(),
        fit.evaluations,
        fit.termination
    );
    if let Some(out) = &args.out {
        let file = ModelFile::from_fit(&fit.spec, &effects);
        std::fs::write(out, file.to_toml()).with_context(|| out.display().to_string())?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}

fn spinner(msg: &'static str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("static template"),
    );
    bar.set_message(msg);
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

fn run_diagnose(args: DiagnoseArgs) -> anyhow::Result<()> {
    let session = Session::read(&args.session)?;
    let fixed = ModelFile::thesis_2006().spec_for(&session.geometry())?;
    let bar = spinner("diagnosing");
    let started = std::time::Instant::now();
    let d = finrs::diagnose::diagnose(&session, fixed, &|msg| bar.set_message(msg.to_string()))?;
    bar.finish_and_clear();
    let v = &d.verdict;
    println!(
        "verdict: {}; causes: {}",
        v.verdict,
        if v.causes.is_empty() {
            "none".to_string()
        } else {
            v.causes.join(", ")
        }
    );
    println!(
        "held-out NRMSE {:.4} (baseline) -> {:.4} (final): {:.1} % gain; held-out RSS/m {:.3} -> {:.3}",
        v.baseline.holdout_nrmse,
        v.extended.holdout_nrmse,
        v.gain_percent,
        v.baseline.holdout_rss_per_residual,
        v.extended.holdout_rss_per_residual
    );
    for c in &v.candidates {
        println!(
            "  round {} {:<30} dBIC {:>12.1}  held-out gain {:>7.2} %  {}",
            c.round + 1,
            c.name,
            c.delta_bic,
            c.holdout_gain_percent,
            if c.passed { "passed" } else { "-" }
        );
    }
    eprintln!("diagnosed in {:.1} s", started.elapsed().as_secs_f64());
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(v)?;
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).with_context(|| parent.display().to_string())?;
        }
        std::fs::write(path, text + "\n").with_context(|| path.display().to_string())?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(dir) = &args.report {
        finrs::diagnose::report::write(dir, &session, &d)
            .with_context(|| dir.display().to_string())?;
        eprintln!("wrote {}", dir.join("REPORT.md").display());
    }
    Ok(())
}

fn run_seed_check(json: Option<PathBuf>) -> anyhow::Result<()> {
    let c = finrs::seed_check::seed_check()?;
    println!(
        "{:<44} {:>12} {:>12} {:>12}  extension",
        "the seed's fact", "measured", "baseline", "extended"
    );
    for r in &c.rows {
        println!(
            "{:<44} {:>12.4e} {:>12.4e} {:>12.4e}  {} ({})",
            r.quantity, r.measured, r.baseline, r.extended, r.effect, r.unit
        );
    }
    for e in &c.explanations {
        println!("\n{e}");
    }
    if let Some(path) = json {
        std::fs::write(&path, serde_json::to_string_pretty(&c)? + "\n")
            .with_context(|| path.display().to_string())?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
