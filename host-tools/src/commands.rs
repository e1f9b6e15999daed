//! One function per command: calls the library, shows progress, writes
//! the files asked for. Progress bars and Ctrl-C live here, not in the
//! library.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context};
use finrs::analysis::fit::{Effect, Fitter};
use finrs::link::capture::{self, CaptureError, Firmware, Monitor};
use finrs::link::probe::ProbeError;
use finrs::model::motion;
use finrs::model::params::{ModelFile, Preset};
use finrs::model::simulate::write_prediction;
use finrs::model::synth::{self, DriveError};
use finrs::plot;
use finrs::recording::Geometry;
use finrs::recording::{Fixture, Recording};
use finrs::session::Session;
use finrs::wave::{Wave, WaveError, WaveKind, WaveOptions};
use finrs_drive::MAX_SEGMENTS;
use indicatif::{ProgressBar, ProgressStyle};

use crate::cli::{
    timeout, DiagnoseArgs, FirmwareWaveArgs, FitArgs, FixtureArg, LogArgs, PlanArgs, RunArgs,
    SendArgs, SimWaveArgs, SimulateArgs, WaveArgs,
};
use crate::new_folders::{check_writable, create_parent, NewFolders};
use crate::stages::Stages;

/// `finrs simulate`.
pub fn simulate(args: SimulateArgs) -> anyhow::Result<()> {
    let model = match &args.params {
        Some(p) => ModelFile::read(p)?,
        None => ModelFile::main_m_2006(),
    };
    // What a motion asks (of the tip, or the load cell), to draw beside
    // the model's.
    let mut asked = None;
    // clap refuses the wave's options with --input, and requires one of
    // --input and --wave.
    let (name, input) = match (&args.input, &args.wave) {
        // Measured channels are only drawn, never simulated.
        (Some(path), _) if args.plot.is_some() => {
            (path.display().to_string(), Recording::read(path)?)
        }
        (Some(path), _) => (path.display().to_string(), Recording::read_drive(path)?),
        (None, Some(spec)) => {
            let (rec, wanted) = wave_recording(spec, &args.drive, &model, args.session_s)?;
            asked = wanted;
            (spec.clone(), rec)
        }
        (None, None) => bail!("give --input REC.csv or --wave SPEC"),
    };
    let spec = model
        .spec_for(&input.meta.geometry())
        .with_context(|| name.clone())?;

    let bar = ProgressBar::new(input.t_s.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows ({eta})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message("simulating");
    let elements = sim_elements(&args, &model);
    let mut made = create_parent(&args.out)?;
    // A picture that cannot be written fails before the simulation.
    if let Some(png) = &args.plot {
        made.add(check_writable(png)?);
    }
    // Written as it is computed; kept whole only to be drawn.
    let kept = write_prediction(
        &name,
        &input,
        &spec,
        elements,
        (&args.out, args.plot.is_some()),
        &mut |n| bar.set_position(n),
    )?;
    bar.finish_and_clear();
    eprintln!("wrote {} ({} rows)", args.out.display(), input.t_s.len());
    if let (Some(png), Some(sim)) = (&args.plot, kept) {
        let measured = args.input.as_ref().map(|_| &input);
        // Plotting needs the prediction as a recording of its own.
        let sim = sim.to_recording();
        let title = format!("finrs simulate: {name}");
        match asked {
            // A motion: what was asked beside what the model does.
            Some((channel, values)) => {
                let asked = Recording {
                    meta: sim.meta.clone(),
                    t_s: sim.t_s.clone(),
                    v_v: sim.v_v.clone(),
                    channels: vec![(channel, values)],
                };
                plot::plot_models(png, &title, None, &[("model", &sim), ("asked", &asked)])
            }
            None => plot::plot(png, &title, measured, &sim),
        }
        .with_context(|| png.display().to_string())?;
        eprintln!("wrote {}", png.display());
        std::mem::forget(sim);
    }
    made.keep();
    // The process ends here: the system takes the recording's memory back
    // at exit, quicker than freeing it piece by piece.
    std::mem::forget(input);
    Ok(())
}

/// The elements per segment `simulate` runs: a fitted file predicts what
/// its fit saw on the fit's own mesh.
fn sim_elements(args: &SimulateArgs, model: &ModelFile) -> usize {
    args.elements
        .or(model.mesh.map(|m| m.elements_per_segment))
        .unwrap_or(1)
}

/// The drive of `simulate --wave`, with `simulate`'s defaults; a motion
/// turned into each segment's sine by `model` as the board's shaper does
/// it (on the seed's geometry, which the wave's recording has), with the
/// tip it asks at each row while the wave is held.
fn wave_recording(
    spec: &str,
    args: &SimWaveArgs,
    model: &ModelFile,
    session_s: Option<f64>,
) -> anyhow::Result<(Recording, Option<motion::Asked>)> {
    let wave = Wave::parse(spec)?;
    let fixture = match args.fixture.unwrap_or(FixtureArg::Free) {
        FixtureArg::Free => Fixture::Free,
        FixtureArg::Blocked => Fixture::Blocked,
    };
    let duration_s = args.duration_s.unwrap_or(10.0);
    let drive = synth::Drive {
        segments: args.shape.segments.unwrap_or(3),
        fixture,
        rest_s: args.rest_s.unwrap_or(1.0),
        duration_s,
        off_s: args.off_s.unwrap_or(0.0),
        rate_hz: args.rate_hz.unwrap_or(1000.0),
    };
    let limits = match (args.limit_v, args.slew_v_per_s) {
        (Some(v), Some(slew)) => Some(synth::limits(v, slew).map_err(drive_flags)?),
        _ => None,
    };
    // Held until the ramp out ends the wave at --duration-s.
    let options = WaveOptions {
        offset_v: args.shape.offset_v.unwrap_or(0.0),
        ramp_in_s: args.shape.ramp_in_s.unwrap_or(0.0),
        ramp_out_s: args.shape.ramp_out_s.unwrap_or(0.0),
        ..WaveOptions::steady(args.shape.sweep_s.unwrap_or(duration_s))
    };
    let (shaped, shaped_options) = match wave.kind() {
        WaveKind::Motion { .. } | WaveKind::MotionStep { .. } | WaveKind::Force { .. } => {
            let spec = model.spec_for(&Geometry::THESIS_2006)?;
            let (shaped, shaped_options) = motion::shaped(
                &wave,
                &spec,
                drive.segments,
                drive.rate_hz,
                session_s,
                &options,
            )?;
            eprintln!("{} is {}", wave.text(), shaped.text());
            (shaped, shaped_options)
        }
        _ => (wave.clone(), options),
    };
    let rec = synth::drive_recording_shaped(&shaped, &drive, &shaped_options, limits)
        .map_err(drive_flags)?;
    // Asked once the ramp-in (a step's rise) is over.
    let start_s = drive.start_row() as f64 / drive.rate_hz;
    let hold_s = (
        start_s + options.ramp_in_s,
        start_s + duration_s - options.ramp_out_s,
    );
    let asked = motion::asked(&wave, &rec.t_s, start_s, hold_s);
    Ok((rec, asked))
}

/// The flag that sets a field of the library's options: `rest_s` is
/// `--rest-s`.
fn flag(field: &str) -> String {
    format!("--{}", field.replace('_', "-"))
}

/// A refused drive, told with the flags that set it.
fn drive_flags(e: DriveError) -> anyhow::Error {
    match e {
        DriveError::Negative { field, value } => {
            anyhow!("{} must be zero or positive, got {value}", flag(field))
        }
        DriveError::NotPositive { field, value } => {
            anyhow!("{} must be positive, got {value}", flag(field))
        }
        DriveError::RateNotWhole(rate_hz) => anyhow!(
            "--rate-hz must be a whole number of Hz up to {} (the generator counts ticks), got {rate_hz}",
            u32::MAX
        ),
        DriveError::RampsTooLong {
            ramp_in_s,
            ramp_out_s,
            duration_s,
        } => anyhow!(
            "--ramp-in-s + --ramp-out-s must not exceed --duration-s: {ramp_in_s} + {ramp_out_s} > {duration_s}"
        ),
        DriveError::Limits { field, value, rule } => anyhow!("{} {value}: {rule}", flag(field)),
        DriveError::Wave(e) => wave_flags(e),
        other => other.into(),
    }
}

/// A refused wave, told with the flags that set it.
fn wave_flags(e: WaveError) -> anyhow::Error {
    match e {
        WaveError::Segments(n) => anyhow!("--segments must be 1..={MAX_SEGMENTS}, got {n}"),
        WaveError::Offset { wave } => {
            anyhow!("--offset-v applies to sine: and standing: waves only, not `{wave}`")
        }
        other => other.into(),
    }
}

/// `finrs params`.
pub fn params(preset: &str) -> anyhow::Result<()> {
    let Some(preset) = Preset::parse(preset) else {
        let known: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
        bail!(
            "--preset: unknown preset {preset:?}; known: {}",
            known.join(", ")
        );
    };
    print!("{}", ModelFile::preset(preset).to_toml());
    Ok(())
}

/// `finrs fit`.
pub fn fit(args: FitArgs) -> anyhow::Result<()> {
    let effects = parse_effects(&args.effects)?;
    // An output that cannot be written fails before the fit, not after.
    let mut made = NewFolders::default();
    for out in args.out.iter().chain(&args.json) {
        made.add(check_writable(out)?);
    }
    let session = Session::read(&args.session)?;
    let fixed = ModelFile::main_m_2006().spec_for(&session.geometry())?;
    let fitter = Fitter::new(&session);
    let all: Vec<usize> = (0..session.recordings.len()).collect();
    let bar = spinner("fitting, with each mode's own damping");
    let started = Instant::now();
    // The intervals carry how far the estimates lean on the damping law.
    let fit = fitter.fit_with_form_check(&all, &effects, fixed)?;
    bar.finish_and_clear();
    print!(
        "{}",
        finrs::analysis::fit::report::text(&fit, fitter.targets())
    );
    eprintln!(
        "fitted {} recordings in {:.1} s with each mode's own damping beside \
         ({} model evaluations, {})",
        all.len(),
        started.elapsed().as_secs_f64(),
        fit.evaluations,
        fit.termination,
    );
    if let Some(out) = &args.out {
        let file = fit.model_file();
        std::fs::write(out, file.to_toml()).with_context(|| out.display().to_string())?;
        eprintln!("wrote {}", out.display());
    }
    if let Some(json) = &args.json {
        write_json(
            json,
            &finrs::analysis::fit::report::FitSummary::new(&fit, fitter.targets()),
        )?;
    }
    made.keep();
    Ok(())
}

/// `finrs diagnose`.
pub fn diagnose(args: DiagnoseArgs) -> anyhow::Result<()> {
    // The run takes minutes: an output that cannot be written fails now.
    let mut made = NewFolders::default();
    if let Some(path) = &args.json {
        made.add(check_writable(path)?);
    }
    if let Some(dir) = &args.report {
        made.add(check_writable(&dir.join("REPORT.md"))?);
    }
    let session = Session::read(&args.session)?;
    let fixed = ModelFile::main_m_2006().spec_for(&session.geometry())?;
    let bar = spinner("diagnosing");
    let stages = Stages::new();
    let d = finrs::analysis::diagnose::diagnose(&session, fixed, &|msg| {
        stages.begin(msg);
        bar.set_message(msg.to_string())
    })?;
    bar.finish_and_clear();
    print!("{}", d.verdict);
    eprintln!(
        "diagnosed in {:.1} s ({})",
        stages.total().as_secs_f64(),
        stages.summary()
    );
    if let Some(path) = &args.json {
        write_json(path, &d.verdict)?;
    }
    if let Some(dir) = &args.report {
        finrs::analysis::diagnose::report::write(dir, &session, &d)?;
        eprintln!("wrote {}", dir.join("REPORT.md").display());
    }
    made.keep();
    Ok(())
}

/// `finrs plan`.
pub fn plan(args: PlanArgs) -> anyhow::Result<()> {
    if !(args.budget_s.is_finite() && args.budget_s > 0.0) {
        bail!(
            "--budget-s: {} must be a positive number of seconds",
            args.budget_s
        );
    }
    let effects = parse_effects(&args.effects)?;
    let mut made = NewFolders::default();
    for out in args.out.iter().chain(&args.json) {
        made.add(check_writable(out)?);
    }
    let session = Session::read(&args.session)?;
    let fixed = ModelFile::main_m_2006().spec_for(&session.geometry())?;
    let bar = spinner("planning");
    let stages = Stages::new();
    let plan = finrs::analysis::plan::plan(&session, fixed, &effects, args.budget_s, &|msg| {
        stages.begin(msg);
        bar.set_message(msg.to_string())
    })?;
    bar.finish_and_clear();
    print!("{plan}");
    eprintln!(
        "planned in {:.1} s ({})",
        stages.total().as_secs_f64(),
        stages.summary()
    );
    if let Some(path) = &args.json {
        write_json(path, &plan)?;
    }
    if let Some(out) = &args.out {
        match plan.protocol(&session) {
            Some(p) => {
                std::fs::write(out, p.to_toml()).with_context(|| out.display().to_string())?;
                eprintln!("wrote {} (finrs bench run reads it)", out.display());
            }
            None => eprintln!("nothing chosen: {} not written", out.display()),
        }
    }
    made.keep();
    Ok(())
}

/// `--effects` names as the library's effects; an unknown one is refused
/// with the names known.
fn parse_effects(names: &[String]) -> anyhow::Result<Vec<Effect>> {
    names
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
        .collect()
}

/// `finrs seed-check`.
pub fn seed_check(json: Option<PathBuf>) -> anyhow::Result<()> {
    let made = match &json {
        Some(path) => check_writable(path)?,
        None => NewFolders::default(),
    };
    let c = finrs::analysis::seed_check::seed_check()?;
    print!("{c}");
    if let Some(path) = json {
        write_json(&path, &c)?;
    }
    made.keep();
    Ok(())
}

/// `finrs log`.
pub fn log(args: LogArgs) -> anyhow::Result<()> {
    let report = match &args.from_bytes {
        Some(path) => {
            let opts = args
                .record
                .options(format!("the byte dump {}", path.display()))?;
            capture::from_bytes(path, &opts).map_err(capture_flags)?
        }
        None => {
            let probe = args.probe.options()?;
            let opts = args.record.options(format!(
                "RTT up channel {} on {}",
                finrs::link::probe::FORCE_UP_CHANNEL,
                probe.chip
            ))?;
            record(&probe, &Firmware::Running(args.elf.clone()), &opts, None)?
        }
    };
    eprint!("{report}");
    Ok(())
}

/// `finrs run`.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    // Refused here, before any probe is looked for.
    let start = match &args.wave {
        Some(spec) => Some(firmware_wave(spec, &args.shaping)?),
        None => match args.shaping.given() {
            Some(flag) => bail!("{flag} shapes a wave: give it with --wave"),
            None => None,
        },
    };
    let mut probe = args.probe.options()?;
    probe.flash_timeout = timeout("--flash-timeout-s", args.flash_timeout_s)?;
    let opts = args.record.options(format!(
        "RTT up channel {} on {} running {}",
        finrs::link::probe::FORCE_UP_CHANNEL,
        probe.chip,
        args.elf.display()
    ))?;
    eprint!(
        "{}",
        record(
            &probe,
            &Firmware::Flash(args.elf.clone()),
            &opts,
            start.as_ref()
        )?
    );
    Ok(())
}

/// Connects through the probe, asks the firmware for its Info frame (so
/// that the recording's notes say which firmware and set-up made it), sends
/// `start` (a wave) if given, then records until Ctrl-C or the duration,
/// with a live status line. Returns the report.
fn record(
    probe: &finrs::link::probe::ProbeOptions,
    firmware: &Firmware,
    opts: &capture::CaptureOptions,
    start: Option<&finrs_frames::Command>,
) -> anyhow::Result<String> {
    let status = StatusLine::new();
    let mut connected = capture::connect(probe, firmware, &status).map_err(capture_flags)?;
    let commands = std::iter::once(&finrs_frames::Command::RequestInfo).chain(start);
    for command in commands {
        let bytes = finrs::link::command::encode(command);
        finrs::link::probe::write_all(
            &mut connected.link,
            finrs::link::probe::COMMAND_DOWN_CHANNEL,
            &bytes,
            probe.timeout,
        )
        .map_err(probe_flags)?;
    }
    if let Some(command) = start {
        eprintln!("sent {command:?}");
    }
    // Armed only now: until here Ctrl-C ends the process as usual.
    let stop = interrupted()?;
    capture::capture(
        &mut connected.link,
        connected.table.as_ref(),
        &stop,
        opts,
        &status,
    )
    .map_err(capture_flags)
}

/// A refused capture, told with the flags that set it.
pub(crate) fn capture_flags(e: CaptureError) -> anyhow::Error {
    match e {
        CaptureError::Probe(e) => probe_flags(e),
        other => other.into(),
    }
}

/// A probe that cannot be chosen, told with the flag that chooses it.
pub(crate) fn probe_flags(e: ProbeError) -> anyhow::Error {
    match e {
        ProbeError::ManyProbes { count, found } => {
            anyhow!("{count} debug probes found: {found}; choose one with --probe VID:PID[:SERIAL]")
        }
        ProbeError::NoProbe {
            selector: Some(selector),
            seen,
        } => ProbeError::NoProbe {
            selector: Some(format!("--probe {selector}")),
            seen,
        }
        .into(),
        other => other.into(),
    }
}

/// A flag that Ctrl-C sets (the handler is installed once per process).
/// A second Ctrl-C exits at once, for when the loop cannot see the flag
/// soon enough (each probe call is bounded, but by seconds).
fn interrupted() -> anyhow::Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            eprintln!("second Ctrl-C: exiting without writing the recording");
            std::process::exit(130);
        }
    })
    .context("cannot install the Ctrl-C handler")?;
    Ok(flag)
}

/// The recording's status on one terminal line, log lines above it.
pub(crate) struct StatusLine(ProgressBar);

impl StatusLine {
    pub(crate) fn new() -> Self {
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("{spinner} {msg}").expect("static template"));
        StatusLine(bar)
    }
}

impl Monitor for StatusLine {
    fn line(&self, text: &str) {
        // indicatif drops `println` when standard error is not a terminal
        // (a log redirected to a file, CI): the lines matter more there.
        if self.0.is_hidden() {
            eprintln!("{text}");
        } else {
            self.0.println(text);
        }
    }

    fn status(&self, text: &str) {
        self.0.set_message(text.to_string());
        self.0.tick();
    }
}

impl Drop for StatusLine {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// `finrs wave`.
pub fn wave(args: WaveArgs) -> anyhow::Result<()> {
    // Refused here, before any probe is looked for.
    let command = firmware_wave(&args.wave, &args.shaping)?;
    let command = match args.session_s {
        Some(t) => finrs::link::command::at_session_time(command, t),
        None => command,
    };
    send(&args.send, &command)
}

/// The SetWave command for `spec` shaped by `shaping`, checked with the
/// firmware's own rules.
fn firmware_wave(spec: &str, shaping: &FirmwareWaveArgs) -> anyhow::Result<finrs_frames::Command> {
    let segments = shaping.shape.segments.unwrap_or(3);
    finrs::link::command::wave_command(spec, segments, &shaping.options()).map_err(wave_flags)
}

/// `finrs limit`.
pub fn limit(max_abs_v: f64, args: &SendArgs) -> anyhow::Result<()> {
    let command = finrs::link::command::limit_command(max_abs_v)?;
    send(args, &command)
}

/// Sends `command` down the firmware's command channel.
pub fn send(args: &SendArgs, command: &finrs_frames::Command) -> anyhow::Result<()> {
    let probe = args.probe.options()?;
    let bytes = finrs::link::command::encode(command);
    finrs::link::probe::send(&probe, args.elf.as_deref(), &bytes).map_err(probe_flags)?;
    eprintln!("sent {command:?}");
    Ok(())
}

fn spinner(msg: &'static str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("static template"),
    );
    bar.set_message(msg);
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// Writes `value` to `path` as pretty JSON ending in a newline, its folder
/// created, and says so on stderr.
fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    let made = create_parent(path)?;
    std::fs::write(path, serde_json::to_string_pretty(value)? + "\n")
        .with_context(|| path.display().to_string())?;
    made.keep();
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// `finrs merge-camera`.
pub fn merge_camera(args: crate::cli::MergeCameraArgs) -> anyhow::Result<()> {
    use finrs::camera::merge::{merge, MergeOptions};
    use finrs::camera::track::Track;
    let daq = Recording::read(&args.daq)?;
    let track = Track::read(&args.track, args.fps)?;
    let opts = MergeOptions {
        flip_x: args.flip_x,
        flip_y: args.flip_y,
        sync_time_s: args.sync_time_s,
        ..MergeOptions::new(args.m_per_px)
    };
    let m = merge(
        &daq,
        &args.daq.display().to_string(),
        &track,
        &args.track.display().to_string(),
        &opts,
    )?;
    let made = create_parent(&args.out)?;
    m.recording.write(&args.out)?;
    made.keep();
    eprintln!(
        "wrote {}: {} positions placed, {} outside the DAQ's rows; camera clock + {:.4} s = DAQ clock",
        args.out.display(),
        m.placed,
        m.outside,
        m.offset_s
    );
    Ok(())
}

/// Shows `text` and waits for Enter.
pub(crate) fn prompt(text: &str) -> std::io::Result<()> {
    eprint!("{text} ");
    let mut line = String::new();
    let n = std::io::BufRead::read_line(&mut std::io::stdin().lock(), &mut line)?;
    if n == 0 {
        return Err(std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            "stdin closed before Enter",
        ));
    }
    Ok(())
}
