//! The command line's shape: every command, its options and their help,
//! and how an option becomes a library value. Refusals of a value name the
//! flag here; the library names only its own fields.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::bail;
use clap::{Args, Parser, Subcommand, ValueEnum};
use finrs::recording::Geometry;
use finrs::recording::Medium;

/// Tools for segmented IPMC fins.
#[derive(Parser)]
#[command(name = "finrs", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
    /// Predict what the model does for a recording's drive, or for a wave.
    Simulate(SimulateArgs),
    /// Print a parameter file (one of the seed's presets) to edit.
    Params {
        /// Which of the seed's parameter sets: main_m_2006 (Appendix B
        /// main.m, the 13 mm calibration) or table_4_2_2006 (Table 4-2).
        #[arg(long, default_value = "main_m_2006")]
        preset: String,
    },
    /// Fit the model's free parameters jointly over a session's recordings.
    Fit(FitArgs),
    /// Find what the baseline gets wrong in a session and name the cause.
    Diagnose(DiagnoseArgs),
    /// Propose the recordings that would let a session show the effects it
    /// cannot show now, ranked by the information they add.
    Plan(PlanArgs),
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
    /// Merge a camera's tracked dots into a free recording from the board.
    MergeCamera(MergeCameraArgs),
    /// Make a lab's own exports (XLSX, CSV, TSV) ipmc-bench/1 recordings,
    /// by a mapping of their columns (docs/import.md).
    Import(ImportArgs),
    /// Record a whole session from the board by a protocol, through one
    /// link.
    Bench {
        /// What to do.
        #[command(subcommand)]
        what: BenchWhat,
    },
    /// Send a fitted model to the running firmware, which then shapes
    /// motion waves with it (`finrs wave motion:TIP_AMP_M,HZ,LAG_DEG`).
    Tune(TuneArgs),
    /// Measure the board's sensors (shunt zeros, load-cell scale) and store
    /// the calibration in its flash; or show or set it.
    Calibrate {
        /// What to calibrate.
        #[command(subcommand)]
        what: CalibrateWhat,
    },
}

/// `finrs tune`.
#[derive(Args)]
pub struct TuneArgs {
    /// The fitted parameter file (`finrs fit`'s, or `finrs params`'s).
    pub params: PathBuf,
    /// A recording of the strip (the session's the fit came from), for its
    /// length, width and thickness.
    #[arg(long)]
    pub geometry_from: PathBuf,
    /// Wait this long for the board's answer, s.
    #[arg(long, default_value_t = 10.0)]
    pub timeout_s: f64,
    #[command(flatten)]
    pub send: SendArgs,
}

/// `finrs merge-camera`.
#[derive(Args)]
pub struct MergeCameraArgs {
    /// The DAQ's free recording (from `finrs bench run` or `finrs log`).
    #[arg(long)]
    pub daq: PathBuf,
    /// The tracker's CSV: frame, time_s (or --fps), dot (1.., tip, sync),
    /// x_px, y_px.
    #[arg(long)]
    pub track: PathBuf,
    /// The merged recording to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Image scale at the strip's plane, m per pixel.
    #[arg(long)]
    pub m_per_px: f64,
    /// The camera's frame rate, for a track without time_s, frames/s.
    #[arg(long)]
    pub fps: Option<f64>,
    /// The image's x runs from the tip toward the clamp.
    #[arg(long)]
    pub flip_x: bool,
    /// The image's y runs opposite to the strip's positive bending (as in
    /// most image coordinates, y down).
    #[arg(long)]
    pub flip_y: bool,
    /// The sync event's camera time, s, if the track has no `sync` row.
    #[arg(long)]
    pub sync_time_s: Option<f64>,
}

/// `finrs import`.
#[derive(Args)]
pub struct ImportArgs {
    /// The lab's exports: XLSX workbooks, CSV or TSV files, or folders of
    /// them (taken in name order).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The mapping of the exports' columns to ipmc-bench/1 (TOML,
    /// finrs-import/1).
    #[arg(long)]
    pub mapping: PathBuf,
    /// Where to write: a folder, a recording per export
    /// (FOLDER/<export's name>.csv); or a .csv file for one export.
    #[arg(long)]
    pub out: PathBuf,
}

/// `finrs bench`'s commands.
#[derive(Subcommand)]
pub enum BenchWhat {
    /// Run a protocol (a TOML list of recordings, `finrs-protocol/1`)
    /// against the running firmware and write the session, a file per
    /// recording as it ends.
    Run(BenchRunArgs),
    /// Record the running firmware while showing force, currents and what
    /// was lost, with keys to send a wave, stop, tare, lower the limit and
    /// mark events.
    Live(BenchLiveArgs),
}

/// `finrs bench live`.
#[derive(Args)]
pub struct BenchLiveArgs {
    /// The running firmware's ELF: its `_SEGGER_RTT` and defmt table.
    #[arg(long, conflicts_with = "from_bytes")]
    pub elf: Option<PathBuf>,
    /// Play a raw byte dump of the up channel instead of a probe (a
    /// journal, a QEMU run); keys that command are refused.
    #[arg(long)]
    pub from_bytes: Option<PathBuf>,
    /// The virtual bench: run this firmware (built with `--features
    /// qemu-serial`) in QEMU at the pace of real time, the model as the
    /// strip (blocked), instead of a board.
    #[arg(long, value_name = "ELF", conflicts_with_all = ["elf", "from_bytes"])]
    pub qemu: Option<PathBuf>,
    #[command(flatten)]
    pub probe: ProbeArgs,
    #[command(flatten)]
    pub record: RecordArgs,
}

/// `finrs bench run`.
#[derive(Args)]
pub struct BenchRunArgs {
    /// The protocol file.
    pub protocol: PathBuf,
    /// The session's folder (its recordings must not exist yet).
    #[arg(long)]
    pub out: PathBuf,
    /// The running firmware's ELF, for its `_SEGGER_RTT` (default: scan RAM).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    /// The virtual bench: run this firmware (built with `--features
    /// qemu-serial`) in QEMU, the model as the strip, instead of a board;
    /// the operator's prompts are shown, not waited for.
    #[arg(long, value_name = "ELF", conflicts_with = "elf")]
    pub qemu: Option<PathBuf>,
    /// Wait this long for the board's answers, s (default: 10 for a board,
    /// 60 for `--qemu`, whose emulated board shares the host's cores and
    /// can take seconds to invert a model when they are busy).
    #[arg(long)]
    pub timeout_s: Option<f64>,
    /// Run `finrs diagnose` on the session once it is recorded.
    #[arg(long)]
    pub diagnose: bool,
    #[command(flatten)]
    pub probe: ProbeArgs,
}

/// `finrs calibrate`'s steps.
#[derive(Subcommand)]
pub enum CalibrateWhat {
    /// Print the calibration in force and where it came from, and the
    /// model the board holds.
    Show(SendArgs),
    /// Stop the outputs, wait at 0 V and measure each shunt's zero.
    Shunts {
        #[command(flatten)]
        window: CalibrateWindowArgs,
        #[command(flatten)]
        send: SendArgs,
    },
    /// Measure the load cell's scale with a reference mass (asks, on the
    /// terminal, to unload and then to load the cell).
    LoadCell {
        /// The reference mass, g.
        #[arg(long)]
        mass_g: f64,
        /// Local gravity, m/s² (standard gravity by default).
        #[arg(long, default_value_t = finrs::link::calibrate::STANDARD_GRAVITY_M_PER_S2)]
        g_m_per_s2: f64,
        /// The way the mass pushes, in the board's force convention.
        #[arg(long, value_enum, default_value = "positive")]
        direction: LoadDirection,
        #[command(flatten)]
        window: CalibrateWindowArgs,
        #[command(flatten)]
        send: SendArgs,
    },
    /// Set values directly (the others are kept).
    Set {
        /// Load-cell scale, N per ADC count.
        #[arg(long, allow_negative_numbers = true)]
        newtons_per_count: Option<f64>,
        /// Each segment's shunt zero, counts, comma-separated from segment 1.
        #[arg(long, value_delimiter = ',')]
        zero_counts: Option<Vec<u16>>,
        /// Wait this long for the board's answer, s.
        #[arg(long, default_value_t = 10.0)]
        timeout_s: f64,
        #[command(flatten)]
        send: SendArgs,
    },
}

/// How `finrs calibrate` averages.
#[derive(Args)]
pub struct CalibrateWindowArgs {
    /// Averaging window, s (of the board's clock).
    #[arg(long, default_value_t = 2.0)]
    pub average_s: f64,
    /// Time at 0 V before the shunts are averaged, s.
    #[arg(long, default_value_t = 1.0)]
    pub settle_s: f64,
    /// Wait this long for the board's answers, s.
    #[arg(long, default_value_t = 30.0)]
    pub timeout_s: f64,
    /// Measure and print, but store nothing.
    #[arg(long)]
    pub dry_run: bool,
}

impl CalibrateWindowArgs {
    /// The library's options, or the flag that is wrong.
    pub fn options(&self) -> anyhow::Result<finrs::link::calibrate::CalibrateOptions> {
        for (flag, v) in [
            ("--average-s", self.average_s),
            ("--settle-s", self.settle_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                bail!("{flag} {v}: must be a positive number of seconds");
            }
        }
        Ok(finrs::link::calibrate::CalibrateOptions {
            timeout: timeout("--timeout-s", self.timeout_s)?,
            settle_s: self.settle_s,
            average_s: self.average_s,
        })
    }
}

/// Which way a reference load pushes.
#[derive(Clone, Copy, ValueEnum)]
pub enum LoadDirection {
    /// The way the board reads as positive force.
    Positive,
    /// The other way.
    Negative,
}

/// How a wave is shaped beyond its text: `finrs wave` and
/// `finrs simulate --wave` share these. Each is an `Option` so that each
/// command applies its own default, and `simulate` can refuse them with
/// `--input`.
#[derive(Args)]
pub struct ShapeArgs {
    /// Segments of the fin (the firmware's N; default 3).
    #[arg(long)]
    pub segments: Option<usize>,
    /// Constant added to a sine: or standing: wave, V (default 0).
    #[arg(long, allow_negative_numbers = true)]
    pub offset_v: Option<f64>,
    /// Raised-cosine ramp to full amplitude, s (default: 1 for `wave`; 0
    /// for `simulate`, within its --duration-s).
    #[arg(long)]
    pub ramp_in_s: Option<f64>,
    /// Raised-cosine ramp from full amplitude to zero, s (default 0; for
    /// `simulate` within its --duration-s).
    #[arg(long)]
    pub ramp_out_s: Option<f64>,
    /// Length of one chirp: sweep, s (default: 10 for `wave`; --duration-s
    /// for `simulate`).
    #[arg(long)]
    pub sweep_s: Option<f64>,
}

/// The probe and the firmware a command is sent to.
#[derive(Args)]
pub struct SendArgs {
    /// The running firmware's ELF, for its `_SEGGER_RTT` (default: scan RAM).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    #[command(flatten)]
    pub probe: ProbeArgs,
}

/// A wave for the firmware as `finrs wave` and `finrs run --wave` shape it.
#[derive(Args)]
pub struct FirmwareWaveArgs {
    #[command(flatten)]
    pub shape: ShapeArgs,
    /// Time at full amplitude, s (default: for ever).
    #[arg(long, default_value_t = f64::INFINITY)]
    pub hold_s: f64,
}

impl FirmwareWaveArgs {
    /// The wave's shaping with the firmware's defaults: no offset, 1 s ramp
    /// in, no ramp out, 10 s sweeps.
    pub fn options(&self) -> finrs::wave::WaveOptions {
        let s = &self.shape;
        finrs::wave::WaveOptions {
            offset_v: s.offset_v.unwrap_or(0.0),
            ramp_in_s: s.ramp_in_s.unwrap_or(1.0),
            hold_s: self.hold_s,
            ramp_out_s: s.ramp_out_s.unwrap_or(0.0),
            sweep_s: s.sweep_s.unwrap_or(10.0),
        }
    }

    /// The flag of a shaping option given, if any (for a command that
    /// takes them only with a wave).
    pub fn given(&self) -> Option<&'static str> {
        let s = &self.shape;
        [
            (s.segments.is_some(), "--segments"),
            (s.offset_v.is_some(), "--offset-v"),
            (s.ramp_in_s.is_some(), "--ramp-in-s"),
            (s.ramp_out_s.is_some(), "--ramp-out-s"),
            (s.sweep_s.is_some(), "--sweep-s"),
            (self.hold_s != f64::INFINITY, "--hold-s"),
        ]
        .into_iter()
        .find_map(|(given, flag)| given.then_some(flag))
    }
}

/// `finrs wave`.
#[derive(Args)]
pub struct WaveArgs {
    /// step:V[,V..], sine:AMP,HZ,LAG_DEG, chirp:AMP,HZ0,HZ1,
    /// pulses:AMP,ON_S,OFF_S, standing:AMP,HZ or
    /// harmonic:HZ,AMP,PHASE_DEG[,AMP,PHASE_DEG..] (each segment its own
    /// sine), motion:TIP_AMP_M,HZ,LAG_DEG (shaped by the board's model and
    /// held by its gain tracker) or motion-ff:TIP_AMP_M,HZ,LAG_DEG (fed
    /// forward only).
    pub wave: String,
    /// For a motion: when it starts on the clock of the model's drying law
    /// (the session's, from its first recording), s; needed when the
    /// model the board holds dries.
    #[arg(long)]
    pub session_s: Option<f64>,
    #[command(flatten)]
    pub shaping: FirmwareWaveArgs,
    #[command(flatten)]
    pub send: SendArgs,
}

/// Which debug probe and chip, and how long to wait for them.
#[derive(Args)]
pub struct ProbeArgs {
    /// probe-rs chip name.
    #[arg(long, default_value = finrs::link::probe::DEFAULT_CHIP)]
    pub chip: String,
    /// Debug probe as VID:PID[:SERIAL] (hex), when more than one is attached.
    #[arg(long)]
    pub probe: Option<String>,
    /// Longest wait for the probe search, the attach and each later probe call (reset, RTT read or write), s.
    #[arg(long, default_value_t = 5.0)]
    pub probe_timeout_s: f64,
    /// SWD clock to ask the probe for, kHz (default: the probe's own);
    /// RTT's throughput follows it.
    #[arg(long)]
    pub speed_khz: Option<u32>,
}

impl ProbeArgs {
    /// The library's probe options.
    pub fn options(&self) -> anyhow::Result<finrs::link::probe::ProbeOptions> {
        if let Some(p) = &self.probe {
            // Checked now, so the refusal names the flag.
            finrs::link::probe::parse_selector(p)
                .map_err(|e| anyhow::anyhow!("--probe {:#}", anyhow::Error::new(e)))?;
        }
        Ok(finrs::link::probe::ProbeOptions {
            chip: self.chip.clone(),
            probe: self.probe.clone(),
            timeout: timeout("--probe-timeout-s", self.probe_timeout_s)?,
            flash_timeout: finrs::link::probe::DEFAULT_FLASH_TIMEOUT,
            speed_khz: match self.speed_khz {
                Some(0) => anyhow::bail!("--speed-khz must be above 0"),
                other => other,
            },
        })
    }
}

/// A bound given in seconds on the command line.
pub fn timeout(flag: &str, s: f64) -> anyhow::Result<Duration> {
    match Duration::try_from_secs_f64(s) {
        Ok(d) if s > 0.0 => Ok(d),
        _ => bail!("{flag} must be a positive number of seconds, got {s:?}"),
    }
}

/// What surrounds the strip.
#[derive(Clone, Copy, ValueEnum)]
pub enum MediumArg {
    /// Air.
    Air,
    /// Water.
    Water,
}

/// Where a recording from the firmware goes, and the strip it comes from.
#[derive(Args)]
pub struct RecordArgs {
    /// Where to write the recording (CSV, ipmc-bench/1, fixture "blocked").
    #[arg(long)]
    pub out: PathBuf,
    /// Stop after this long, s (default: until Ctrl-C; the file is written either way).
    #[arg(long = "duration-s", visible_alias = "duration")]
    pub duration_s: Option<f64>,
    /// Free length of the strip, m (default: the seed's 50 mm strip).
    #[arg(long)]
    pub length_m: Option<f64>,
    /// Width of the strip, m.
    #[arg(long)]
    pub width_m: Option<f64>,
    /// Thickness of the strip, m.
    #[arg(long)]
    pub thickness_m: Option<f64>,
    /// What surrounds the strip.
    #[arg(long, value_enum, default_value_t = MediumArg::Air)]
    pub medium: MediumArg,
    /// Sample id, for the metadata.
    #[arg(long)]
    pub sample: Option<String>,
}

impl RecordArgs {
    /// The library's capture options; `source` says where the bytes come from.
    pub fn options(&self, source: String) -> anyhow::Result<finrs::link::capture::CaptureOptions> {
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
        if let Some(d) = self.duration_s {
            if !(d.is_finite() && d > 0.0) {
                bail!("--duration-s must be a positive number of seconds, got {d}");
            }
        }
        Ok(finrs::link::capture::CaptureOptions {
            out: self.out.clone(),
            duration_s: self.duration_s,
            setup: finrs::link::stream::Setup {
                geometry,
                medium: match self.medium {
                    MediumArg::Air => Medium::Air,
                    MediumArg::Water => Medium::Water,
                },
                sample: self.sample.clone(),
                source,
            },
        })
    }
}

/// `finrs log`.
#[derive(Args)]
pub struct LogArgs {
    /// The running firmware's ELF: its `_SEGGER_RTT` symbol and defmt table.
    #[arg(long, conflicts_with = "from_bytes")]
    pub elf: Option<PathBuf>,
    /// Read a raw byte dump of the up channel instead of a probe (`-`: stdin).
    #[arg(long)]
    pub from_bytes: Option<PathBuf>,
    #[command(flatten)]
    pub probe: ProbeArgs,
    #[command(flatten)]
    pub record: RecordArgs,
}

/// `finrs run`.
#[derive(Args)]
pub struct RunArgs {
    /// The firmware to flash (ELF with `_SEGGER_RTT` and a defmt table).
    pub elf: PathBuf,
    #[command(flatten)]
    pub probe: ProbeArgs,
    /// Longest wait for flashing the ELF, s.
    #[arg(long, default_value_t = finrs::link::probe::DEFAULT_FLASH_TIMEOUT.as_secs_f64())]
    pub flash_timeout_s: f64,
    #[command(flatten)]
    pub record: RecordArgs,
    /// A wave to start once the firmware runs, as `finrs wave` takes it
    /// (the firmware boots stopped and drives nothing until asked).
    #[arg(long)]
    pub wave: Option<String>,
    #[command(flatten)]
    pub shaping: FirmwareWaveArgs,
}

/// `finrs diagnose`.
#[derive(Args)]
pub struct DiagnoseArgs {
    /// Folder of recordings of one sample (ipmc-bench/1).
    pub session: PathBuf,
    /// Where to write the verdict (JSON).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Folder for the human report (REPORT.md and plots).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// `finrs plan`.
#[derive(Args)]
pub struct PlanArgs {
    /// Folder of recordings of one sample (ipmc-bench/1).
    pub session: PathBuf,
    /// Effects the model already has beyond the baseline, comma separated
    /// (what `finrs diagnose` named, e.g. damping,beam-stiffness).
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Recording time the plan may spend, s.
    #[arg(long, default_value_t = 60.0)]
    pub budget_s: f64,
    /// Where to write the chosen recordings as a protocol for `finrs bench run`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Where to write the plan as JSON: every proposal with its gain per effect.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// `finrs fit`.
#[derive(Args)]
pub struct FitArgs {
    /// Folder of recordings of one sample (ipmc-bench/1).
    pub session: PathBuf,
    /// Effects to add to the baseline, comma separated (e.g. damping,large-deflection).
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Where to write the fitted parameters (TOML, as `simulate --params` reads).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Where to write the fit as JSON: every parameter with its 95 %
    /// interval, the noise per sensor, the information criteria and the
    /// fit per channel.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// How the tip is held.
#[derive(Clone, Copy, ValueEnum)]
pub enum FixtureArg {
    /// Tip free.
    Free,
    /// Tip held by the load cell.
    Blocked,
}

/// `finrs simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// Recording whose voltage columns drive the model (ipmc-bench/1).
    // A recording brings its own segments, fixture, timing and voltages:
    // every option that describes a --wave conflicts with it.
    #[arg(
        long,
        conflicts_with_all = [
            "wave", "segments", "offset_v", "ramp_in_s", "ramp_out_s", "sweep_s",
            "fixture", "rest_s", "duration_s", "off_s", "rate_hz", "limit_v", "slew_v_per_s",
        ],
        required_unless_present = "wave"
    )]
    pub input: Option<PathBuf>,
    /// A wave instead of a recording: step:V[,V..], sine:AMP,HZ,LAG_DEG,
    /// standing:AMP,HZ, chirp:AMP,HZ0,HZ1, pulses:AMP,ON_S,OFF_S or
    /// harmonic:HZ,AMP,PHASE_DEG[,AMP,PHASE_DEG..] (as
    /// `finrs wave`, evaluated by the firmware's generator).
    #[arg(long)]
    pub wave: Option<String>,
    /// For a motion whose model dries: when it starts on the session's
    /// clock, s (the board's shaper needs it).
    #[arg(long)]
    pub session_s: Option<f64>,
    #[command(flatten)]
    pub drive: SimWaveArgs,
    /// Parameter file (TOML); default: the main_m_2006 preset.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Finite elements per segment (1, 2 or 4); default: the parameter
    /// file's `[mesh]` (a fit's own), else 1 (the seed's).
    #[arg(long)]
    pub elements: Option<usize>,
    /// Where to write the simulated recording (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write a PNG plot here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// The options of `finrs simulate` that describe a --wave (defaults
/// applied in [`SimWaveArgs::drive`] and [`SimWaveArgs::shaping`]).
#[derive(Args)]
pub struct SimWaveArgs {
    #[command(flatten)]
    pub shape: ShapeArgs,
    /// Fixture, with --wave (default free).
    #[arg(long, value_enum)]
    pub fixture: Option<FixtureArg>,
    /// Rest at 0 V before the wave, s (default 1).
    #[arg(long)]
    pub rest_s: Option<f64>,
    /// Duration of the wave, s (default 10).
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Rest at 0 V after the wave, s (default 0).
    #[arg(long)]
    pub off_s: Option<f64>,
    /// Sample rate, Hz, with --wave (whole: the generator's tick rate;
    /// default 1000).
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Pass the wave through the firmware's limiter at this voltage limit,
    /// V (with --slew-v-per-s).
    #[arg(long, requires = "slew_v_per_s")]
    pub limit_v: Option<f64>,
    /// The limiter's slew limit, V/s (with --limit-v).
    #[arg(long, requires = "limit_v")]
    pub slew_v_per_s: Option<f64>,
}
