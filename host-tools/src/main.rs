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
    /// Record the firmware's force stream (RTT up channel 1) through a probe,
    /// or from a raw byte dump with --from-bytes.
    Log(LogArgs),
    /// Flash an ELF, reset and run it, print its defmt log and record its
    /// force stream.
    Run(RunArgs),
    /// Send a new wave to the running firmware (RTT down channel 0).
    Wave(WaveArgs),
    /// Ask the firmware to measure the load cell's zero again.
    Tare(SendArgs),
    /// Bring every output to 0 V through the slew limit.
    Stop(SendArgs),
    /// Lower the firmware's voltage limit to V volts (a raise is refused).
    Limit {
        /// The new limit on |V|, V (above 0, at most 4).
        max_abs_v: f64,
        #[command(flatten)]
        send: SendArgs,
    },
    /// Clear a latched fault (outputs stay at 0 V until the next wave).
    ClearFault(SendArgs),
}

#[derive(clap::Args)]
struct SendArgs {
    /// The running firmware's ELF, for its `_SEGGER_RTT` (default: scan RAM).
    #[arg(long)]
    elf: Option<PathBuf>,
    #[command(flatten)]
    probe: ProbeArgs,
}

#[derive(clap::Args)]
struct WaveArgs {
    /// step:V[,V..], sine:AMP,HZ,LAG_DEG, chirp:AMP,HZ0,HZ1,
    /// pulses:AMP,ON_S,OFF_S or standing:AMP,HZ.
    wave: String,
    /// Segments of the fin (the firmware's N).
    #[arg(long, default_value_t = 3)]
    segments: usize,
    /// Constant added to a sine: or standing: wave, V.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    offset_v: f64,
    /// Time to full amplitude, s.
    #[arg(long, default_value_t = 1.0)]
    ramp_in_s: f64,
    /// Time at full amplitude, s (default: for ever).
    #[arg(long, default_value_t = f64::INFINITY)]
    hold_s: f64,
    /// Time from full amplitude to zero, s.
    #[arg(long, default_value_t = 0.0)]
    ramp_out_s: f64,
    /// Length of one chirp: sweep, s.
    #[arg(long, default_value_t = 10.0)]
    sweep_s: f64,
    #[command(flatten)]
    send: SendArgs,
}

#[derive(clap::Args)]
struct ProbeArgs {
    /// probe-rs chip name.
    #[arg(long, default_value = finrs::probe::DEFAULT_CHIP)]
    chip: String,
    /// Debug probe as VID:PID[:SERIAL] (hex), when more than one is attached.
    #[arg(long)]
    probe: Option<String>,
    /// Longest wait for the probe search, the attach and each later probe call (reset, RTT read or write), s.
    #[arg(long, default_value_t = 5.0)]
    probe_timeout_s: f64,
}

impl ProbeArgs {
    fn options(&self) -> anyhow::Result<finrs::probe::ProbeOptions> {
        Ok(finrs::probe::ProbeOptions {
            chip: self.chip.clone(),
            probe: self.probe.clone(),
            timeout: timeout("--probe-timeout-s", self.probe_timeout_s)?,
            flash_timeout: finrs::probe::DEFAULT_FLASH_TIMEOUT,
        })
    }
}

/// A bound given in seconds on the command line.
fn timeout(flag: &str, s: f64) -> anyhow::Result<std::time::Duration> {
    match std::time::Duration::try_from_secs_f64(s) {
        Ok(d) if s > 0.0 => Ok(d),
        _ => bail!("{flag} must be a positive number of seconds, got {s:?}"),
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum MediumArg {
    Air,
    Water,
}

#[derive(clap::Args)]
struct RecordArgs {
    /// Where to write the recording (CSV, ipmc-bench/1, fixture "blocked").
    #[arg(long)]
    out: PathBuf,
    /// Stop after this long, s (default: until Ctrl-C; the file is written either way).
    #[arg(long = "duration-s", visible_alias = "duration")]
    duration_s: Option<f64>,
    /// Free length of the strip, m (default: the seed's 50 mm strip).
    #[arg(long)]
    length_m: Option<f64>,
    /// Width of the strip, m.
    #[arg(long)]
    width_m: Option<f64>,
    /// Thickness of the strip, m.
    #[arg(long)]
    thickness_m: Option<f64>,
    /// What surrounds the strip.
    #[arg(long, value_enum, default_value_t = MediumArg::Air)]
    medium: MediumArg,
    /// Sample id, for the metadata.
    #[arg(long)]
    sample: Option<String>,
}

impl RecordArgs {
    fn options(&self, source: String) -> anyhow::Result<finrs::capture::CaptureOptions> {
        let g = Geometry::THESIS_2006;
        let geometry = Geometry {
            length_m: self.length_m.unwrap_or(g.length_m),
            width_m: self.width_m.unwrap_or(g.width_m),
            thickness_m: self.thickness_m.unwrap_or(g.thickness_m),
        };
        for (name, v) in [
            ("--length-m", geometry.length_m),
            ("--width-m", geometry.width_m),
            ("--thickness-m", geometry.thickness_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                bail!("{name} must be a positive length in metres, got {v}");
            }
        }
        Ok(finrs::capture::CaptureOptions {
            out: self.out.clone(),
            duration_s: self.duration_s,
            setup: finrs::stream::Setup {
                geometry,
                medium: match self.medium {
                    MediumArg::Air => finrs::recording::Medium::Air,
                    MediumArg::Water => finrs::recording::Medium::Water,
                },
                sample: self.sample.clone(),
                source,
            },
        })
    }
}

#[derive(clap::Args)]
struct LogArgs {
    /// The running firmware's ELF: its `_SEGGER_RTT` symbol and defmt table.
    #[arg(long, conflicts_with = "from_bytes")]
    elf: Option<PathBuf>,
    /// Read a raw byte dump of the up channel instead of a probe (`-`: stdin).
    #[arg(long)]
    from_bytes: Option<PathBuf>,
    #[command(flatten)]
    probe: ProbeArgs,
    #[command(flatten)]
    record: RecordArgs,
}

#[derive(clap::Args)]
struct RunArgs {
    /// The firmware to flash (ELF with `_SEGGER_RTT` and a defmt table).
    elf: PathBuf,
    #[command(flatten)]
    probe: ProbeArgs,
    /// Longest wait for flashing the ELF, s.
    #[arg(long, default_value_t = finrs::probe::DEFAULT_FLASH_TIMEOUT.as_secs_f64())]
    flash_timeout_s: f64,
    #[command(flatten)]
    record: RecordArgs,
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
    /// standing:AMP,HZ, chirp:AMP,HZ0,HZ1 or pulses:AMP,ON_S,OFF_S (as
    /// `finrs wave`, evaluated by the firmware's generator).
    #[arg(long)]
    wave: Option<String>,
    // The options below shape a --wave only; they are `Option`s, defaults
    // applied in `run_simulate`, so that one given with --input is refused
    // instead of silently ignored.
    /// Segments, with --wave (default 3).
    #[arg(long)]
    segments: Option<usize>,
    /// Fixture, with --wave (default free).
    #[arg(long, value_enum)]
    fixture: Option<FixtureArg>,
    /// Rest at 0 V before the wave, s (default 1).
    #[arg(long)]
    rest_s: Option<f64>,
    /// Duration of the wave, s (default 10).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Rest at 0 V after the wave, s (default 0).
    #[arg(long)]
    off_s: Option<f64>,
    /// Sample rate, Hz, with --wave (whole: the generator's tick rate;
    /// default 1000).
    #[arg(long)]
    rate_hz: Option<f64>,
    /// Constant added to a sine: or standing: wave, V (default 0).
    #[arg(long, allow_negative_numbers = true)]
    offset_v: Option<f64>,
    /// Raised-cosine ramp in, s, within --duration-s (default 0).
    #[arg(long)]
    ramp_in_s: Option<f64>,
    /// Raised-cosine ramp out, s, within --duration-s (default 0).
    #[arg(long)]
    ramp_out_s: Option<f64>,
    /// Length of one chirp: sweep, s (default: --duration-s).
    #[arg(long)]
    sweep_s: Option<f64>,
    /// Pass the wave through the firmware's limiter at this voltage limit,
    /// V (with --slew-v-per-s).
    #[arg(long, requires = "slew_v_per_s")]
    limit_v: Option<f64>,
    /// The limiter's slew limit, V/s (with --limit-v).
    #[arg(long, requires = "limit_v")]
    slew_v_per_s: Option<f64>,
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
            eprintln!("error: {}", chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, `: `-separated as `{:#}` prints them, but a
/// cause the message before it already ends with is said once.
fn chain(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.ends_with(&cause) {
            text += ": ";
            text += &cause;
        }
    }
    text
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Simulate(args) => run_simulate(args),
        Command::Fit(args) => run_fit(args),
        Command::Diagnose(args) => run_diagnose(args),
        Command::SeedCheck { json } => run_seed_check(json),
        Command::Log(args) => run_log(args),
        Command::Run(args) => run_run(args),
        Command::Wave(args) => {
            let req = finrs::command::WaveRequest {
                spec: args.wave.clone(),
                segments: args.segments,
                offset_v: args.offset_v,
                ramp_in_s: args.ramp_in_s,
                hold_s: args.hold_s,
                ramp_out_s: args.ramp_out_s,
                sweep_s: args.sweep_s,
            };
            // Refused here, before any probe is looked for.
            let command = finrs::command::wave_command(&req).map_err(anyhow::Error::msg)?;
            send(&args.send, &command)
        }
        Command::Tare(args) => send(&args, &finrs_frames::Command::Tare),
        Command::Stop(args) => send(&args, &finrs_frames::Command::Stop),
        Command::ClearFault(args) => send(&args, &finrs_frames::Command::ClearFault),
        Command::Limit {
            max_abs_v,
            send: args,
        } => {
            let command = finrs::command::limit_command(max_abs_v).map_err(anyhow::Error::msg)?;
            send(&args, &command)
        }
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
        (Some(path), _) => {
            // A recording brings its own segments, fixture, timing and
            // voltages: these options would be silently ignored.
            for (option, given) in [
                ("--segments", args.segments.is_some()),
                ("--fixture", args.fixture.is_some()),
                ("--rest-s", args.rest_s.is_some()),
                ("--duration-s", args.duration_s.is_some()),
                ("--off-s", args.off_s.is_some()),
                ("--rate-hz", args.rate_hz.is_some()),
                ("--offset-v", args.offset_v.is_some()),
                ("--ramp-in-s", args.ramp_in_s.is_some()),
                ("--ramp-out-s", args.ramp_out_s.is_some()),
                ("--sweep-s", args.sweep_s.is_some()),
                ("--limit-v", args.limit_v.is_some()),
            ] {
                if given {
                    bail!("{option} describes a --wave; it does not apply to --input (the recording gives it)");
                }
            }
            (path.display().to_string(), Recording::read(path)?)
        }
        (None, Some(spec)) => {
            let wave = Wave::parse(spec).map_err(anyhow::Error::msg)?;
            let fixture = match args.fixture.unwrap_or(FixtureArg::Free) {
                FixtureArg::Free => Fixture::Free,
                FixtureArg::Blocked => Fixture::Blocked,
            };
            let drive = synth::Drive {
                segments: args.segments.unwrap_or(3),
                fixture,
                rest_s: args.rest_s.unwrap_or(1.0),
                duration_s: args.duration_s.unwrap_or(10.0),
                off_s: args.off_s.unwrap_or(0.0),
                rate_hz: args.rate_hz.unwrap_or(1000.0),
            };
            let limits = match (args.limit_v, args.slew_v_per_s) {
                (Some(v), Some(slew)) => Some(synth::limits(v, slew)?),
                _ => None,
            };
            let shaping = synth::Shaping {
                offset_v: args.offset_v.unwrap_or(0.0),
                ramp_in_s: args.ramp_in_s.unwrap_or(0.0),
                ramp_out_s: args.ramp_out_s.unwrap_or(0.0),
                sweep_s: args.sweep_s,
                limits,
            };
            (
                spec.clone(),
                synth::drive_recording_shaped(&wave, &drive, &shaping)?,
            )
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

fn run_log(args: LogArgs) -> anyhow::Result<()> {
    let report = match &args.from_bytes {
        Some(path) => {
            let opts = args
                .record
                .options(format!("the byte dump {}", path.display()))?;
            finrs::capture::from_bytes(path, &opts)?
        }
        None => {
            let probe = args.probe.options()?;
            let opts = args.record.options(format!(
                "RTT up channel {} on {}",
                finrs::probe::FORCE_UP_CHANNEL,
                probe.chip
            ))?;
            let firmware = finrs::capture::Firmware::Running(args.elf.clone());
            finrs::capture::from_probe(&probe, &firmware, &opts)?
        }
    };
    eprint!("{report}");
    Ok(())
}

fn run_run(args: RunArgs) -> anyhow::Result<()> {
    let mut probe = args.probe.options()?;
    probe.flash_timeout = timeout("--flash-timeout-s", args.flash_timeout_s)?;
    let opts = args.record.options(format!(
        "RTT up channel {} on {} running {}",
        finrs::probe::FORCE_UP_CHANNEL,
        probe.chip,
        args.elf.display()
    ))?;
    let firmware = finrs::capture::Firmware::Flash(args.elf.clone());
    eprint!("{}", finrs::capture::from_probe(&probe, &firmware, &opts)?);
    Ok(())
}

fn send(args: &SendArgs, command: &finrs_frames::Command) -> anyhow::Result<()> {
    let probe = args.probe.options()?;
    let bytes = finrs::command::encode(command);
    finrs::probe::send(&probe, args.elf.as_deref(), &bytes)?;
    eprintln!("sent {command:?}");
    Ok(())
}
