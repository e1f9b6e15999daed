//! `rig-motion`: #16's feed-forward on the off-class rig's strips. For each
//! session of the seeded sweep (`rig-sweep`'s plan): the session written,
//! diagnosed (`finrs diagnose`) and fitted twice (`finrs fit --out`): the
//! baseline alone, and with the effects the diagnosis named (less those
//! the board's shaper cannot invert: the electrochemical cubics, the large
//! deflection's arc). Then the rig's own strip, from the session's end on
//! (drying goes on), driven 60 s by a travelling motion at 1 Hz, 60° a
//! segment, three times: the plain wave the nominal model (the example
//! session's strip) shapes for it, and the waves the board's shaper makes
//! from each fit (the same code: `finrs_controller`'s shaper, and where
//! the fit dries, its tracker following the drying law once a period, as
//! the controller does for `motion-ff:`). The tip
//! (true, no camera) by lock-in over each 5 s against the motion asked.
//! The amplitude asked: 5 mm, or 80 % of what the diagnosed fit says 4 V
//! reach, the smaller; a wave that needs more than 4 V for it is not
//! driven.
//!
//! Writes OUT/motion.csv (per session and drive: first, worst and last
//! window's amplitude error, worst phase error) and OUT/motion.md.
//!
//! Not here: the gain tracker, which needs the strip stepped in the
//! controller's loop; the rig runs a whole drive at once.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::Context;
use clap::Parser;
use finrs::model::motion::record;
use finrs::model::params::{ModelFile, Relaxation};
use finrs::model::predict::ModelSpec;
use finrs::recording::{Recording, Voltages};
use finrs_controller::shaper::{ShapeRefused, Shaper, ELEMENTS};
use finrs_controller::tracker::Tracker;
use finrs_drive::{Envelope, Generator};
use finrs_frames::Motion;
use finrs_rig::runner::{each_session, SweepArgs};
use finrs_rig::strip::{run, MESH};
use finrs_rig::sweep::{plan, strip_of, write_scenario, Scenario};
use finrs_rig::Tip;

/// Drives the off-class rig's strips with motions fed forward from their
/// fits, and with the nominal model's plain waves.
#[derive(Parser)]
#[command(version)]
struct Cli {
    #[command(flatten)]
    run: SweepArgs,
    /// Directory for motion.csv and motion.md.
    #[arg(long)]
    out: PathBuf,
}

const HZ: f64 = 1.0;
const LAG_DEG: f64 = 60.0;
const HOLD_S: f64 = 60.0;
const REST_S: f64 = 1.0;
const RATE_HZ: f64 = 1000.0;
const WINDOW_S: f64 = 5.0;
const WANTED_M: f64 = 5e-3;
const LIMIT_V: f32 = 4.0;

/// One drive's errors per window: amplitude (a fraction), phase, degrees.
type Windows = Vec<(f64, f64)>;

/// What the board's shaper cannot invert (no single-sine response).
const NOT_INVERTIBLE: [&str; 2] = ["electrochemical-nonlinearity", "large-deflection"];

/// The three drives, in the order of [`Outcome::drives`].
const DRIVES: [&str; 3] = ["nominal", "baseline fit", "diagnosed fit"];

/// What one session gave.
struct Outcome {
    scenario: Scenario,
    asked_m: f64,
    /// The effects the diagnosed fit has.
    effects: Vec<String>,
    /// Each of [`DRIVES`], `None` where it needs more than 4 V.
    drives: [Option<Windows>; 3],
}

/// The example session's strip: `main.m` with the example's relaxation
/// network (as the virtual bench's tests take it).
fn nominal() -> ModelFile {
    let mut f = ModelFile::main_m_2006();
    let p = model_core::Params::baseline_air_example();
    f.relaxation = Relaxation {
        a_nm_per_c: p.a_nm_per_c,
        b_nm_per_c_s: p.b_nm_per_c_s,
        p_per_s: p.p_per_s,
    };
    f
}

/// The session's recordings, its geometry and segments, and its end on
/// the session's clock, s.
fn session_facts(dir: &Path) -> anyhow::Result<(finrs::recording::Geometry, usize, f64)> {
    let mut end_s: f64 = 0.0;
    let mut facts = None;
    for entry in std::fs::read_dir(dir).with_context(|| dir.display().to_string())? {
        let path = entry?.path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        let rec = Recording::read(&path).with_context(|| path.display().to_string())?;
        let start = rec.meta.t_session_start_s.unwrap_or(0.0);
        end_s = end_s.max(start + rec.t_s.last().copied().unwrap_or(0.0));
        facts.get_or_insert((rec.meta.geometry(), rec.v_v.segments()));
    }
    let (geometry, segments) = facts.context("no recording in the session")?;
    Ok((geometry, segments, end_s))
}

/// The rig's segments, the board's build for them.
const N: usize = 3;

/// The board's shaper for the rig's segments.
type BoardShaper = Shaper<N, ELEMENTS, { model_core::state_len(N, ELEMENTS) }>;

/// The board's shaper holding `spec`'s model.
fn shaper(spec: &ModelSpec) -> anyhow::Result<BoardShaper> {
    let mut shaper = Shaper::new();
    shaper
        .install(Shaper::check(&record(spec), 1.0 / RATE_HZ).map_err(|e| anyhow::anyhow!("{e}"))?);
    Ok(shaper)
}

/// The motion asked, `asked_m` at the tip.
fn motion(asked_m: f64) -> Motion {
    Motion::Travelling {
        tip_amp_m: asked_m as f32,
        frequency_hz: HZ as f32,
        lag_deg_per_segment: LAG_DEG as f32,
    }
}

/// The voltages the board drives for `motion(asked_m)` with `shaper`'s
/// model from `t_session_s` on, `rows` samples: the shaper's program, and
/// where the model dries, its correction once a period (the tracker fed
/// no current: `motion-ff:`). `None` where the motion needs more than 4 V.
fn board_drive(
    shaper: &BoardShaper,
    asked_m: f64,
    t_session_s: f64,
    rows: u64,
) -> anyhow::Result<Option<Vec<[f64; N]>>> {
    let shaped = match shaper.program(
        &motion(asked_m),
        Envelope::STEADY,
        LIMIT_V,
        t_session_s as f32,
    ) {
        Ok(s) => s,
        Err(ShapeRefused::Unreachable { .. }) => return Ok(None),
        Err(e) => anyhow::bail!("{e}"),
    };
    let steady = shaped.envelope;
    let mut generator =
        Generator::<N>::new(shaped.program, steady).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut tracker = shaped
        .target
        .drying
        .map(|_| Tracker::new(shaped.target, RATE_HZ as u32));
    let mut out = Vec::with_capacity(rows as usize);
    for tick in 0..rows {
        let v = generator.voltages_at_tick_v(tick, RATE_HZ as u32);
        out.push(v.map(f64::from));
        let Some(t) = tracker.as_mut() else { continue };
        if let Some(c) = t.feed(&v, &[0.0; N], 0.0) {
            let (program, _) = t.program(&c, LIMIT_V);
            generator = Generator::new(program, steady).map_err(|e| anyhow::anyhow!("{e}"))?;
        }
    }
    Ok(Some(out))
}

/// The tip amplitude the limit lets `shaper`'s model reach, m, if 5 mm is
/// beyond it.
fn reachable_m(shaper: &BoardShaper, t_session_s: f64) -> anyhow::Result<Option<f64>> {
    match shaper.program(
        &motion(WANTED_M),
        Envelope::STEADY,
        LIMIT_V,
        t_session_s as f32,
    ) {
        Ok(_) => Ok(None),
        Err(ShapeRefused::Unreachable { reachable_m, .. }) => Ok(Some(f64::from(reachable_m))),
        Err(e) => anyhow::bail!("{e}"),
    }
}

/// The rig strip of `s` at rest for `REST_S`, then driven by `wave` (a
/// row a sample) from `t_session_s` on: the tip's errors against
/// `asked_m · sin(2π HZ τ)`, τ from the wave's start, per window.
fn drive(
    s: &Scenario,
    wave: &[[f64; N]],
    t_session_s: f64,
    asked_m: f64,
) -> anyhow::Result<Windows> {
    let (sample, hidden) = strip_of(s)?;
    let rest = (REST_S * RATE_HZ) as u64;
    let rows = rest + wave.len() as u64;
    let mut volts = Voltages::with_capacity(N, rows as usize);
    for _ in 0..rest {
        volts.push(&[0.0; N]);
    }
    for v in wave {
        volts.push(v);
    }
    let camera = vec![true; rows as usize];
    let truth = run(
        &sample,
        &hidden,
        MESH,
        Tip::Free,
        &volts,
        1.0 / RATE_HZ,
        t_session_s - REST_S,
        &camera,
        &[sample.length_m],
    );
    let tip = truth.points_m.last().context("the rig tracks the tip")?;
    let omega = 2.0 * std::f64::consts::PI * HZ;
    let windows = (HOLD_S / WINDOW_S).round() as usize;
    // Row r holds the tip after the drive of row r − 1: at τ = (r − rest)/rate.
    Ok((0..windows)
        .map(|w| {
            let (from, to) = (w as f64 * WINDOW_S, (w + 1) as f64 * WINDOW_S);
            let (mut sn, mut cs, mut n) = (0.0, 0.0, 0.0);
            for (r, &(_, y)) in tip.iter().enumerate().skip(rest as usize) {
                let tau = (r as u64 - rest) as f64 / RATE_HZ;
                if (from..to).contains(&tau) {
                    sn += y * (omega * tau).sin();
                    cs += y * (omega * tau).cos();
                    n += 1.0;
                }
            }
            let (sn, cs) = (2.0 * sn / n, 2.0 * cs / n);
            (sn.hypot(cs) / asked_m - 1.0, cs.atan2(sn).to_degrees())
        })
        .collect())
}

/// Runs the `finrs` binary with the arguments `args` adds, which must
/// succeed.
fn finrs(cli: &Cli, args: impl FnOnce(&mut Command)) -> anyhow::Result<()> {
    let mut cmd = Command::new(&cli.run.finrs);
    args(&mut cmd);
    let out = cmd
        .output()
        .with_context(|| format!("running {}", cli.run.finrs.display()))?;
    anyhow::ensure!(
        out.status.success(),
        "{:?}: {}",
        cmd,
        String::from_utf8_lossy(&out.stderr).trim()
    );
    Ok(())
}

/// `finrs fit DIR [--effects E] --out PATH`, read back.
fn fit(cli: &Cli, dir: &Path, effects: &[String], path: &Path) -> anyhow::Result<ModelFile> {
    finrs(cli, |c| {
        c.arg("fit").arg(dir);
        if !effects.is_empty() {
            c.arg("--effects").arg(effects.join(","));
        }
        c.arg("--out").arg(path);
    })?;
    Ok(ModelFile::read(path)?)
}

/// The causes `finrs diagnose` names for the session in `dir`.
fn diagnosed(cli: &Cli, dir: &Path, json: &Path) -> anyhow::Result<Vec<String>> {
    finrs(cli, |c| {
        c.arg("diagnose").arg(dir).arg("--json").arg(json);
    })?;
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json)?)?;
    Ok(v["causes"]
        .as_array()
        .context("no `causes`")?
        .iter()
        .filter_map(|c| c.as_str().map(str::to_string))
        .collect())
}

fn one(cli: &Cli, s: &Scenario) -> anyhow::Result<Outcome> {
    let dir = cli.out.join(format!("session-{}", s.seed));
    write_scenario(s, &dir)?;
    let fits = cli.out.join("fits");
    let (geometry, segments, end_s) = session_facts(&dir)?;
    let causes = diagnosed(
        cli,
        &dir,
        &fits.join(format!("seed-{}-verdict.json", s.seed)),
    )?;
    let effects: Vec<String> = causes
        .into_iter()
        .filter(|c| !NOT_INVERTIBLE.contains(&c.as_str()))
        .collect();
    let baseline = fit(
        cli,
        &dir,
        &[],
        &fits.join(format!("seed-{}-baseline.toml", s.seed)),
    )?;
    let diagnosed = fit(
        cli,
        &dir,
        &effects,
        &fits.join(format!("seed-{}-diagnosed.toml", s.seed)),
    )?;
    std::fs::remove_dir_all(&dir).ok();
    anyhow::ensure!(
        segments == N,
        "{segments} segments: the rig's board has {N}"
    );
    // Each model checked and built once, as the board holds it.
    let shapers = [
        shaper(&nominal().spec_for(&geometry)?)?,
        shaper(&baseline.spec_for(&geometry)?)?,
        shaper(&diagnosed.spec_for(&geometry)?)?,
    ];
    // The motion starts at the session's end (after a second's rest).
    let t_start_s = end_s + REST_S;
    let asked_m = reachable_m(&shapers[2], t_start_s)?.map_or(WANTED_M, |r| 0.8 * r);
    let rows = (HOLD_S * RATE_HZ) as u64;
    let mut drives = [None, None, None];
    for (d, shaper) in drives.iter_mut().zip(&shapers) {
        *d = match board_drive(shaper, asked_m, t_start_s, rows)? {
            Some(wave) => Some(drive(s, &wave, t_start_s, asked_m)?),
            None => None,
        };
    }
    Ok(Outcome {
        scenario: s.clone(),
        asked_m,
        effects,
        drives,
    })
}

/// First, worst and last window's amplitude error (fractions) and the
/// worst phase error, degrees.
fn summary(w: &Windows) -> (f64, f64, f64, f64) {
    let worst = w
        .iter()
        .map(|x| x.0)
        .fold(0.0f64, |m, a| if a.abs() > m.abs() { a } else { m });
    let phase = w
        .iter()
        .map(|x| x.1)
        .fold(0.0f64, |m, p| if p.abs() > m.abs() { p } else { m });
    (w[0].0, worst, w[w.len() - 1].0, phase)
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    cli.run.check()?;
    std::fs::create_dir_all(cli.out.join("fits"))?;
    let scenarios = plan(cli.run.first_seed, cli.run.sessions);
    let outcomes = each_session(&scenarios, cli.run.jobs, |s| {
        let o = one(&cli, s)?;
        let said: Vec<String> = o
            .drives
            .iter()
            .zip(DRIVES)
            .map(|(w, name)| {
                w.as_ref().map_or(format!("{name} beyond 4 V"), |w| {
                    let (_, worst, _, phase) = summary(w);
                    format!("{name} {:+.1} % {phase:+.1}°", 100.0 * worst)
                })
            })
            .collect();
        eprintln!(
            "seed {:>6} {:<40} [{}] asked {:.2} mm: {}",
            s.seed,
            s.row(),
            o.effects.join(","),
            o.asked_m * 1e3,
            said.join(", ")
        );
        Ok(o)
    });
    let mut csv =
        String::from("seed,row,effects,asked_mm,drive,first,worst,last,worst_phase_deg\n");
    let mut md = String::from(
        "Each drive's worst 5 s window of the 60 s: amplitude error, phase error.\n\n| seed | strip | diagnosed effects | asked, mm | nominal wave | baseline fit | diagnosed fit |\n|---|---|---|---|---|---|---|\n",
    );
    let mut within = [0usize; 3];
    for o in &outcomes {
        let mut cells = Vec::new();
        for (k, (w, name)) in o.drives.iter().zip(DRIVES).enumerate() {
            let Some(w) = w else {
                cells.push("beyond 4 V".to_string());
                continue;
            };
            let (a, b, c, d) = summary(w);
            csv.push_str(&format!(
                "{},{},{},{:.4},{name},{a:.5},{b:.5},{c:.5},{d:.3}\n",
                o.scenario.seed,
                o.scenario.row(),
                o.effects.join("+"),
                o.asked_m * 1e3
            ));
            within[k] += usize::from(b.abs() <= 0.05 && d.abs() <= 5.0);
            cells.push(format!("{:+.1} %, {d:+.1}°", 100.0 * b));
        }
        md.push_str(&format!(
            "| {} | {} | {} | {:.2} | {} |\n",
            o.scenario.seed,
            o.scenario.row(),
            if o.effects.is_empty() {
                "-".to_string()
            } else {
                o.effects.join(", ")
            },
            o.asked_m * 1e3,
            cells.join(" | ")
        ));
    }
    md.push_str(&format!(
        "\nWithin 5 % and 5° in every 5 s window, of {}: the nominal wave {}, the baseline fit's {}, the diagnosed fit's {}.\n",
        outcomes.len(),
        within[0],
        within[1],
        within[2]
    ));
    std::fs::write(cli.out.join("motion.csv"), csv)?;
    std::fs::write(cli.out.join("motion.md"), &md)?;
    print!("{md}");
    Ok(())
}
