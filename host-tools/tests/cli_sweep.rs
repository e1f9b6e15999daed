//! A sweep of the `finrs` command line for panics: every subcommand run as
//! a user could run it, over generated arguments and small generated files
//! (recordings, sessions, parameter files, byte dumps, a lab's exports
//! as XLSX, CSV and TSV with their import mappings), valid-looking and
//! broken. Whatever the input, the process must end within a time bound
//! with success or a clear error: never a panic (exit code 101, `panicked`),
//! never killed by a signal (abort, stack overflow), never silent on failure.
//!
//! Cases per sweep: `PROPTEST_CASES` (default [`DEFAULT_CASES`], which keeps
//! the whole file under a minute on a laptop); run it longer by hand with
//! e.g. `PROPTEST_CASES=2000 cargo test --release -p finrs --test cli_sweep`.
//!
//! `FINRS_SWEEP_OUTCOMES=FILE` appends each case's command, exit code, time
//! and first error line to FILE, to see what the generators reach.
//!
//! Commands that talk to a probe always name one that cannot exist
//! (`--probe ffff:fffe` or a selector that does not parse): a board on the
//! developer's desk must never be flashed, stopped or sent a wave by a test.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use finrs_frames::{
    encode_dropped, encode_fault, encode_sample, Dropped, Fault, FaultCode, Sample,
};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use rand::{Rng, SeedableRng};

/// Cases per sweep when `PROPTEST_CASES` is not set.
const DEFAULT_CASES: u32 = 16;
/// Longest a case may run (`FINRS_SWEEP_TIME_BOUND_S` to change it): the
/// generated inputs are small (a diagnosis of them takes at most seconds of
/// CPU), so anything near this is a hang, not work, even on a busy machine.
const TIME_BOUND: Duration = Duration::from_secs(120);

fn time_bound() -> Duration {
    std::env::var("FINRS_SWEEP_TIME_BOUND_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .map_or(TIME_BOUND, Duration::from_secs_f64)
}
/// A probe selector no board has.
const NO_SUCH_PROBE: &str = "ffff:fffe";

fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(DEFAULT_CASES);
    ProptestConfig {
        cases,
        // Each case is a process or several; shrinking them all is slow and
        // the failure message already holds the command and its files.
        max_shrink_iters: 8,
        ..ProptestConfig::default()
    }
}

/// A fresh folder for one case, removed unless the case failed.
struct CaseDir(PathBuf, std::cell::Cell<bool>);

impl CaseDir {
    fn new() -> CaseDir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "finrs-sweep-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        CaseDir(dir, std::cell::Cell::new(false))
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn arg(&self, name: &str) -> String {
        self.path(name).display().to_string()
    }

    fn write(&self, name: &str, bytes: &[u8]) -> String {
        let p = self.path(name);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::write(&p, bytes).unwrap();
        p.display().to_string()
    }
}

impl Drop for CaseDir {
    fn drop(&mut self) {
        if !self.1.get() && !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Runs `finrs args` in `dir` and checks how it ended.
fn run_finrs(dir: &CaseDir, args: &[String]) -> Result<(), TestCaseError> {
    let out = std::fs::File::create(dir.path("stdout.txt")).unwrap();
    let err = std::fs::File::create(dir.path("stderr.txt")).unwrap();
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .args(args)
        .current_dir(&dir.0)
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .env("RUST_BACKTRACE", "1")
        .spawn()
        .unwrap();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if started.elapsed() > time_bound() {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = std::fs::read_to_string(dir.path("stderr.txt")).unwrap_or_default();
    // Kept for whoever reads the failure; removed again if the case passes.
    dir.1.set(true);
    let what = || {
        let mut s = format!("finrs {}", shell_words(args));
        let _ = write!(
            s,
            "\n(case files kept in {})\nstderr:\n{stderr}",
            dir.0.display()
        );
        s
    };
    if let Ok(log) = std::env::var("FINRS_SWEEP_OUTCOMES") {
        // What the cases reached, for a person tuning the generators.
        let first = stderr.lines().find(|l| l.contains("error")).unwrap_or("");
        let line = format!(
            "{}\t{:?}\t{:.2}\t{}\n",
            args.first().map_or("", String::as_str),
            status.and_then(|s| s.code()),
            started.elapsed().as_secs_f64(),
            first
        );
        use std::io::Write as _;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(log)
            .unwrap();
        f.write_all(line.as_bytes()).unwrap();
    }
    let Some(status) = status else {
        return Err(TestCaseError::fail(format!(
            "still running after {:?}: {}",
            time_bound(),
            what()
        )));
    };
    prop_assert!(
        status.code() != Some(101) && !stderr.contains("panicked"),
        "panicked: {}",
        what()
    );
    prop_assert!(
        status.code().is_some(),
        "killed by a signal ({status}): {}",
        what()
    );
    if !status.success() {
        // clap's usage text (no subcommand given) counts as saying why.
        prop_assert!(
            stderr.contains("error") || stderr.contains("Usage:"),
            "failed ({status}) without an error message: {}",
            what()
        );
        // Outputs' folders are made before a run (see `out_path`'s missing
        // folder): a run that fails removes those it left empty.
        let made = dir.path("missing");
        prop_assert!(
            !holds_an_empty_folder(&made),
            "failed and left an empty folder under {}: {}",
            made.display(),
            what()
        );
    }
    dir.1.set(false);
    Ok(())
}

/// Whether `dir` is, or holds, an empty folder.
fn holds_an_empty_folder(dir: &std::path::Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    let mut empty = true;
    for entry in entries.flatten() {
        empty = false;
        if holds_an_empty_folder(&entry.path()) {
            return true;
        }
    }
    empty
}

fn shell_words(args: &[String]) -> String {
    args.iter()
        .map(|a| format!("{a:?}"))
        .collect::<Vec<_>>()
        .join(" ")
}

// ---------------------------------------------------------------- values

/// Numbers as a user might type them, and as nobody should.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-5.0f64..5.0).prop_map(|v| format!("{v}")),
        2 => (0u32..12).prop_map(|v| v.to_string()),
        3 => prop::sample::select(vec![
            "0", "-0", "-1", "1e-300", "1e300", "-1e300", "NaN", "nan", "inf", "-inf",
            "1e400", "", "abc", "18446744073709551616", "4294967295", "4294967296",
            "0x10", "1,2", "0.5", "2", "1000",
        ])
        .prop_map(String::from),
    ]
}

/// A wave as `finrs wave` and `simulate --wave` take it.
fn wave_spec() -> impl Strategy<Value = String> {
    let kind = prop::sample::select(vec![
        "step",
        "sine",
        "standing",
        "chirp",
        "pulses",
        "held",
        "motion-step",
        "force",
        "square",
        "",
        "STEP",
    ]);
    prop_oneof![
        4 => (kind, prop::collection::vec(number(), 0..5))
            .prop_map(|(k, v)| format!("{k}:{}", v.join(","))),
        1 => prop::sample::select(vec![
            "step:1", "sine:2.5,1,120", "standing:1,0.5", "chirp:2,0.1,20",
            "pulses:2.5,0.2,0.2", "step:0,2.5,0", "held:1,0.1,inf,0.3", "motion-step:0.001",
            "step", ":", "sine:", "",
        ])
        .prop_map(String::from),
    ]
}

/// Options given as `--name=VALUE` (so that clap takes `-1` as a value,
/// not a flag), each at most once, maybe none.
fn options(names: &'static [&'static str]) -> impl Strategy<Value = Vec<String>> {
    (
        prop::sample::subsequence(names, 0..=names.len().min(4)),
        prop::collection::vec(number(), 4),
    )
        .prop_map(|(names, values)| {
            names
                .into_iter()
                .zip(values)
                .map(|(n, v)| format!("{n}={v}"))
                .collect()
        })
}

// ---------------------------------------------------------- recordings

/// How a generated recording's voltages go.
#[derive(Clone, Copy, Debug)]
enum Drive {
    AllZero,
    /// Rest of `rest_rows`, then a step.
    Step {
        rest_rows: usize,
        level_v: f64,
    },
    /// Rest, then random voltages within the safe range.
    Noise {
        rest_rows: usize,
    },
    /// Rest, then a value no valid file holds.
    Odd {
        rest_rows: usize,
        token: &'static str,
    },
}

/// What happens to the file after it is written well.
#[derive(Clone, Copy, Debug)]
enum Damage {
    None,
    Truncate(f64),
    FlipBytes(u64),
    RandomBytes(usize),
}

/// A recording to generate: the choices proptest sees; row values come
/// from `seed`.
#[derive(Clone, Debug)]
struct RecSpec {
    segments: usize,
    /// Replaces the `segments` value in the metadata when set.
    segments_token: Option<String>,
    blocked: bool,
    water: bool,
    /// Length, width, thickness: a usual strip or odd tokens.
    geometry: [String; 3],
    dots: usize,
    currents: bool,
    /// Measured channels: the camera (free) or the load cell (blocked).
    measured: bool,
    rows: usize,
    dt_s: f64,
    drive: Drive,
    /// Notes with a session start time.
    session_start: Option<String>,
    /// Odd values in measured fields: empty, NaN, huge.
    odd_fields: bool,
    damage: Damage,
    seed: u64,
}

fn geometry_token(usual: &'static str) -> impl Strategy<Value = String> {
    prop_oneof![
        6 => Just(usual.to_string()),
        1 => number(),
    ]
}

fn drive() -> impl Strategy<Value = Drive> {
    let rest = prop_oneof![
        Just(0usize),
        Just(500),
        Just(1000),
        Just(1001),
        0usize..1500
    ];
    prop_oneof![
        1 => Just(Drive::AllZero),
        4 => (rest.clone(), -4.0f64..4.0).prop_map(|(rest_rows, level_v)| Drive::Step { rest_rows, level_v }),
        2 => rest.clone().prop_map(|rest_rows| Drive::Noise { rest_rows }),
        1 => (rest, prop::sample::select(vec!["NaN", "inf", "1e300", "4.0001", "-4", "1e-300", "", "x"]))
            .prop_map(|(rest_rows, token)| Drive::Odd { rest_rows, token }),
    ]
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        12 => Just(Damage::None),
        1 => (0.0f64..1.0).prop_map(Damage::Truncate),
        1 => any::<u64>().prop_map(Damage::FlipBytes),
        1 => (0usize..2000).prop_map(Damage::RandomBytes),
    ]
}

/// A recording a session accepts: at least 1 s at rest, then a drive of
/// up to 1.5 s, mostly at 100 rows/s to keep a diagnosis of it to seconds.
fn valid_rec_spec() -> impl Strategy<Value = RecSpec> {
    let rate = prop_oneof![3 => Just(100usize), 1 => Just(1000usize)];
    let timing = rate.prop_flat_map(|per_s| {
        (
            Just(per_s),
            per_s..per_s + per_s / 10,
            per_s / 10..per_s * 3 / 2,
        )
    });
    let drive = prop_oneof![
        4 => (-4.0f64..4.0).prop_map(|level_v| Drive::Step { rest_rows: 0, level_v }),
        2 => Just(Drive::Noise { rest_rows: 0 }),
        1 => Just(Drive::AllZero),
    ];
    (
        // Mostly one segment: a diagnosis of three costs twenty times more.
        (
            prop_oneof![4 => Just(1usize), 1 => 2usize..=3],
            any::<bool>(),
            prop::bool::weighted(0.2),
            0usize..4,
        ),
        (
            any::<bool>(),
            prop::bool::weighted(0.9),
            timing,
            drive,
            prop::option::weighted(
                0.5,
                prop::sample::select(vec!["0", "12.5", "600", "-5", "1e9"]).prop_map(String::from),
            ),
            any::<u64>(),
        ),
    )
        .prop_map(
            |(
                (segments, blocked, water, dots),
                (currents, measured, (per_s, rest_rows, drive_rows), drive, session_start, seed),
            )| RecSpec {
                segments,
                segments_token: None,
                blocked,
                water,
                geometry: ["0.05".into(), "0.01".into(), "0.0003".into()],
                dots,
                currents,
                measured,
                rows: rest_rows + drive_rows,
                dt_s: 1.0 / per_s as f64,
                drive: match drive {
                    Drive::Step { level_v, .. } => Drive::Step { rest_rows, level_v },
                    Drive::Noise { .. } => Drive::Noise { rest_rows },
                    d => d,
                },
                session_start,
                odd_fields: false,
                damage: Damage::None,
                seed,
            },
        )
}

/// Mostly recordings a session accepts, else anything.
fn rec_spec() -> impl Strategy<Value = RecSpec> {
    prop_oneof![3 => valid_rec_spec(), 2 => any_rec_spec()]
}

fn any_rec_spec() -> impl Strategy<Value = RecSpec> {
    let rows = prop_oneof![
        Just(0usize),
        Just(1),
        Just(2),
        Just(3),
        Just(999),
        Just(1000),
        Just(1001),
        0usize..2500,
    ];
    let dt = prop_oneof![
        8 => Just(1e-3),
        1 => Just(1e-2),
        1 => prop::sample::select(vec![0.0, 1e-9, 0.5, 1e300, -1e-3]),
    ];
    (
        (
            prop_oneof![6 => 1usize..=3, 1 => 0usize..=9],
            prop::option::weighted(0.1, number()),
            any::<bool>(),
            any::<bool>(),
            [
                geometry_token("0.05"),
                geometry_token("0.01"),
                geometry_token("0.0003"),
            ],
            0usize..4,
        ),
        (
            any::<bool>(),
            prop::bool::weighted(0.8),
            rows,
            dt,
            drive(),
            prop::option::weighted(0.3, number()),
            prop::bool::weighted(0.15),
            damage(),
            any::<u64>(),
        ),
    )
        .prop_map(
            |(
                (segments, segments_token, blocked, water, geometry, dots),
                (currents, measured, rows, dt_s, drive, session_start, odd_fields, damage, seed),
            )| RecSpec {
                segments,
                segments_token,
                blocked,
                water,
                geometry,
                dots,
                currents,
                measured,
                rows,
                dt_s,
                drive,
                session_start,
                odd_fields,
                damage,
                seed,
            },
        )
}

impl RecSpec {
    fn render(&self) -> Vec<u8> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(self.seed);
        if let Damage::RandomBytes(n) = self.damage {
            return (0..n).map(|_| rng.gen()).collect();
        }
        let n = self.segments;
        let mut s = String::new();
        s += "# format = \"ipmc-bench/1\"\n";
        match &self.segments_token {
            Some(t) => writeln!(s, "# segments = {t}").unwrap(),
            None => writeln!(s, "# segments = {n}").unwrap(),
        }
        let [l, w, t] = &self.geometry;
        writeln!(s, "# length_m = {l}\n# width_m = {w}\n# thickness_m = {t}").unwrap();
        let fixture = if self.blocked { "blocked" } else { "free" };
        let medium = if self.water { "water" } else { "air" };
        writeln!(s, "# fixture = \"{fixture}\"\n# medium = \"{medium}\"").unwrap();
        let dots = if self.blocked { 0 } else { self.dots };
        if dots > 0 {
            let pos: Vec<String> = (1..=dots).map(|j| format!("0.0{j}")).collect();
            writeln!(s, "# dots_s_m = [{}]", pos.join(", ")).unwrap();
        }
        if let Some(t0) = &self.session_start {
            writeln!(s, "# notes = \"t_session_start_s = {t0}; generated\"").unwrap();
        }
        let mut header = vec!["t_s".to_string()];
        header.extend((1..=n).map(|k| format!("v{k}_V")));
        if self.currents {
            header.extend((1..=n).map(|k| format!("i{k}_A")));
        }
        let camera = self.measured && !self.blocked;
        if camera {
            header.extend(["tip_y_m".to_string(), "tip_x_m".to_string()]);
            for j in 1..=dots {
                header.extend([format!("dot{j}_y_m"), format!("dot{j}_x_m")]);
            }
        }
        if self.measured && self.blocked {
            header.push("force_N".to_string());
        }
        s += &header.join(",");
        s += "\n";
        let odd = |rng: &mut rand::rngs::StdRng| -> String {
            ["", "NaN", "1e300", "-1e300", "inf", "0"][rng.gen_range(0..6)].to_string()
        };
        for i in 0..self.rows {
            let t = i as f64 * self.dt_s;
            write!(s, "{t}").unwrap();
            for _ in 0..n {
                let v = match self.drive {
                    Drive::AllZero => "0".to_string(),
                    Drive::Step { rest_rows, level_v } => {
                        if i < rest_rows {
                            "0".into()
                        } else {
                            format!("{level_v}")
                        }
                    }
                    Drive::Noise { rest_rows } => {
                        if i < rest_rows {
                            "0".into()
                        } else {
                            format!("{}", rng.gen_range(-4.0..4.0))
                        }
                    }
                    Drive::Odd { rest_rows, token } => {
                        if i < rest_rows {
                            "0".into()
                        } else if rng.gen_bool(0.1) {
                            token.into()
                        } else {
                            "1".into()
                        }
                    }
                };
                write!(s, ",{v}").unwrap();
            }
            let value = |rng: &mut rand::rngs::StdRng, scale: f64| -> String {
                if self.odd_fields && rng.gen_bool(0.05) {
                    odd(rng)
                } else {
                    format!("{}", rng.gen_range(-1.0..1.0) * scale)
                }
            };
            if self.currents {
                for _ in 0..n {
                    let v = value(&mut rng, 1e-3);
                    write!(s, ",{v}").unwrap();
                }
            }
            if camera {
                // 30 camera frames/s, aligned to rows.
                let every = ((1.0 / (30.0 * self.dt_s)).round() as usize).max(1);
                let frame = i % every == 0;
                for _ in 0..2 + 2 * dots {
                    let v = if frame {
                        value(&mut rng, 1e-4)
                    } else {
                        String::new()
                    };
                    write!(s, ",{v}").unwrap();
                }
            }
            if self.measured && self.blocked {
                let v = value(&mut rng, 1e-4);
                write!(s, ",{v}").unwrap();
            }
            s += "\n";
        }
        let mut bytes = s.into_bytes();
        match self.damage {
            Damage::Truncate(f) => bytes.truncate((bytes.len() as f64 * f) as usize),
            Damage::FlipBytes(seed) => {
                let mut r = rand::rngs::StdRng::seed_from_u64(seed);
                for _ in 0..r.gen_range(1..8) {
                    if !bytes.is_empty() {
                        let i = r.gen_range(0..bytes.len());
                        bytes[i] = r.gen();
                    }
                }
            }
            Damage::None | Damage::RandomBytes(_) => {}
        }
        bytes
    }
}

/// A session folder: one to four recordings. Half the sessions are of
/// accepted recordings of one sample (two of each fixture when there are
/// four, as a diagnosis holds them out), so that fit and diagnosis run.
fn session() -> impl Strategy<Value = Vec<RecSpec>> {
    let mixed = (
        rec_spec(),
        prop::collection::vec(rec_spec(), 0..4),
        prop::bool::weighted(0.7),
    )
        .prop_map(|(first, rest, same_sample)| {
            let mut all = vec![first.clone()];
            for mut r in rest {
                if same_sample {
                    same_sample_as(&mut r, &first);
                }
                all.push(r);
            }
            all
        });
    let accepted = prop::collection::vec(valid_rec_spec(), 2..=4).prop_map(|mut all| {
        let first = all[0].clone();
        let n = all.len();
        for (i, r) in all.iter_mut().enumerate() {
            same_sample_as(r, &first);
            r.blocked = if n == 4 { i % 2 == 1 } else { first.blocked };
        }
        all
    });
    prop_oneof![mixed, accepted]
}

fn same_sample_as(r: &mut RecSpec, first: &RecSpec) {
    r.segments = first.segments;
    r.segments_token = first.segments_token.clone();
    r.geometry = first.geometry.clone();
    r.water = first.water;
}

fn write_session(dir: &CaseDir, recs: &[RecSpec]) -> String {
    for (i, r) in recs.iter().enumerate() {
        dir.write(&format!("session/{:02}_rec.csv", i + 1), &r.render());
    }
    dir.arg("session")
}

// ------------------------------------------------------- other files

/// A parameter file: the preset, maybe with `[beam]` and `[extensions]`,
/// some values replaced by odd ones; or bytes.
#[derive(Clone, Debug)]
struct ParamsSpec {
    beam: bool,
    extensions: bool,
    /// (line index, replacement value).
    replace: Vec<(usize, String)>,
    drop_line: Option<usize>,
    random_bytes: Option<u64>,
}

fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => number().prop_filter("TOML floats", |s| s.parse::<f64>().is_ok()),
        2 => prop::sample::select(vec![
            "nan", "inf", "-inf", "1e308", "-1e308", "0.0", "-0.0", "1e-320", "true",
            "false", "\"x\"", "", "1", "[1.0]", "1e9", "-1.0",
        ])
        .prop_map(String::from),
    ]
}

fn params_spec() -> impl Strategy<Value = ParamsSpec> {
    (
        any::<bool>(),
        any::<bool>(),
        prop::collection::vec((0usize..40, toml_value()), 0..4),
        prop::option::weighted(0.1, 0usize..40),
        prop::option::weighted(0.05, any::<u64>()),
    )
        .prop_map(
            |(beam, extensions, replace, drop_line, random_bytes)| ParamsSpec {
                beam,
                extensions,
                replace,
                drop_line,
                random_bytes,
            },
        )
}

impl ParamsSpec {
    fn render(&self) -> Vec<u8> {
        if let Some(seed) = self.random_bytes {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            return (0..rng.gen_range(0..500)).map(|_| rng.gen()).collect();
        }
        let mut text = finrs::model::params::ModelFile::main_m_2006().to_toml();
        if self.beam {
            text += "\n[beam]\nei_nm2 = 1e-4\nmass_per_length_kg_per_m = 0.01\n";
        }
        if self.extensions {
            text += "\n[extensions]\ndamping_mass_per_s = 1.0\ndamping_stiffness_s = 1e-4\n\
                     added_mass_kg_per_m = 0.0\ndrag_n_s_per_m2 = 0.0\ncharge_cubic_per_v2 = 0.01\n\
                     leak_cubic_per_v2 = 0.01\ncrosstalk = 0.1\nback_relaxation = true\n\
                     large_deflection = true\ndehydration_per_s = 0.001\ndehydration_curvature = 1.0\n";
        }
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let assignments: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].contains(" = "))
            .collect();
        for (k, value) in &self.replace {
            let i = assignments[k % assignments.len()];
            let key = lines[i].split(" = ").next().unwrap().to_string();
            lines[i] = format!("{key} = {value}");
        }
        if let Some(k) = self.drop_line {
            lines.remove(k % lines.len());
        }
        (lines.join("\n") + "\n").into_bytes()
    }
}

/// A byte dump of the force stream: frames with odd values, maybe damaged.
fn byte_dump(seed: u64, frames: usize, damage: Damage) -> Vec<u8> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut buf = [0u8; finrs_frames::MAX_FRAME_LEN];
    let odd = [
        0.0f32,
        1.0,
        -4.0,
        4.5,
        f32::NAN,
        f32::INFINITY,
        1e30,
        -1e-30,
    ];
    let mut seq = 0u32;
    for _ in 0..frames {
        // Mostly in order, sometimes a jump, a repeat or a wrap.
        seq = match rng.gen_range(0..10) {
            0 => rng.gen(),
            1 => seq,
            _ => seq.wrapping_add(1),
        };
        let t_us = seq.wrapping_mul(1000);
        let f = |rng: &mut rand::rngs::StdRng| -> f32 {
            if rng.gen_bool(0.2) {
                odd[rng.gen_range(0..odd.len())]
            } else {
                rng.gen_range(-0.01..0.01)
            }
        };
        let n = match rng.gen_range(0..12) {
            0 => encode_dropped(
                &Dropped {
                    first_seq: seq,
                    count: rng.gen(),
                },
                &mut buf,
            ),
            1 => encode_fault(
                &Fault {
                    seq,
                    t_us,
                    code: FaultCode::from_u8(rng.gen_range(1..5)).unwrap(),
                    segment: if rng.gen() {
                        Some(rng.gen_range(0..8))
                    } else {
                        None
                    },
                },
                &mut buf,
            ),
            2 => {
                let s: Sample<1> = Sample {
                    seq,
                    t_us,
                    force_n: f(&mut rng),
                    flags: finrs_frames::SampleFlags::default(),
                    voltages_v: [f(&mut rng)],
                    currents_a: [f(&mut rng)],
                };
                encode_sample(&s, &mut buf)
            }
            _ => {
                let s: Sample<3> = Sample {
                    seq,
                    t_us,
                    force_n: f(&mut rng),
                    flags: finrs_frames::SampleFlags::default(),
                    voltages_v: [f(&mut rng), f(&mut rng), f(&mut rng)],
                    currents_a: [f(&mut rng), f(&mut rng), f(&mut rng)],
                };
                encode_sample(&s, &mut buf)
            }
        }
        .unwrap();
        out.extend_from_slice(&buf[..n]);
    }
    match damage {
        Damage::None => {}
        Damage::Truncate(f) => out.truncate((out.len() as f64 * f) as usize),
        Damage::FlipBytes(_) => {
            for _ in 0..rng.gen_range(1..8) {
                if !out.is_empty() {
                    let i = rng.gen_range(0..out.len());
                    out[i] = rng.gen();
                }
            }
        }
        Damage::RandomBytes(n) => out = (0..n).map(|_| rng.gen()).collect(),
    }
    out
}

// ------------------------------------------------------- lab exports

/// What a generated export's mapped cell is spoiled with.
#[derive(Clone, Copy, Debug)]
enum Spoil {
    Text(&'static str),
    Number(f64),
    Blank,
    /// A formula whose cached result is an error (a workbook's only).
    DivZero,
    /// A TRUE/FALSE cell (a workbook's only).
    Boolean,
}

/// A lab's export to generate: columns `t (ms)`, `V1 (V)`, `I1 (mA)`,
/// `d (mm)` (a laser's distance) and an unmapped `note`, then spoiled.
#[derive(Clone, Debug)]
struct ExportSpec {
    /// `xlsx`, `csv`, `tsv` or an extension nobody reads.
    extension: &'static str,
    rows: usize,
    decimal_comma: bool,
    /// A mapped column's header renamed (0: time, 1..=3 the channels).
    renamed: Option<usize>,
    /// The voltage's header given to the unmapped column too.
    duplicated: bool,
    /// A workbook with its sheet left empty.
    empty_sheet: bool,
    /// Merged cells: first row, first column, rows, columns (0-based).
    merged: Option<(u32, u16, u32, u16)>,
    /// Cells spoiled: data row, column (0..5), with what.
    spoiled: Vec<(usize, usize, Spoil)>,
    /// A data row left blank.
    blank_row: Option<usize>,
    random_bytes: Option<usize>,
    seed: u64,
}

/// A generated export's cell: a number, spoiled, or empty.
type ExportCell = Option<Result<f64, Spoil>>;

fn spoil() -> impl Strategy<Value = Spoil> {
    prop_oneof![
        4 => prop::sample::select(vec![
            "abc", "Inf", "-inf", "NaN", "1,5", "1.5.5", "#N/A", " ", "2e400", "0x10", "−1",
        ])
        .prop_map(Spoil::Text),
        3 => prop::sample::select(vec![-99.9999, 4.5, -4.0001, 1e308, -1e308, 0.0, -0.0, 1e-320])
            .prop_map(Spoil::Number),
        2 => Just(Spoil::Blank),
        1 => Just(Spoil::DivZero),
        1 => Just(Spoil::Boolean),
    ]
}

fn export_spec() -> impl Strategy<Value = ExportSpec> {
    (
        (
            prop::sample::select(vec!["xlsx", "xlsx", "xlsx", "csv", "csv", "tsv", "dat"]),
            prop_oneof![Just(0usize), Just(1), Just(2), 0usize..300],
            any::<bool>(),
            prop::option::weighted(0.15, 0usize..4),
            prop::bool::weighted(0.1),
            prop::bool::weighted(0.05),
        ),
        (
            prop::option::weighted(0.15, (0u32..40, 0u16..6, 0u32..3, 0u16..3)),
            prop::collection::vec((0usize..300, 0usize..5, spoil()), 0..3),
            prop::option::weighted(0.1, 0usize..300),
            prop::option::weighted(0.05, 0usize..3000),
            any::<u64>(),
        ),
    )
        .prop_map(
            |(
                (extension, rows, decimal_comma, renamed, duplicated, empty_sheet),
                (merged, spoiled, blank_row, random_bytes, seed),
            )| ExportSpec {
                extension,
                rows,
                decimal_comma,
                renamed,
                duplicated,
                empty_sheet,
                merged,
                spoiled,
                blank_row,
                random_bytes,
                seed,
            },
        )
}

impl ExportSpec {
    /// The header and the data rows, unspoiled numbers as `f64`.
    fn cells(&self) -> (Vec<String>, Vec<Vec<ExportCell>>) {
        let mut header: Vec<String> = ["t (ms)", "V1 (V)", "I1 (mA)", "d (mm)", "note"]
            .map(String::from)
            .into();
        if let Some(c) = self.renamed {
            header[c] += " renamed";
        }
        if self.duplicated {
            header[4] = header[1].clone();
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(self.seed);
        let mut rows: Vec<Vec<ExportCell>> = (0..self.rows)
            .map(|i| {
                let on = i >= 100;
                vec![
                    Some(Ok(i as f64 * 10.0)),
                    Some(Ok(if on { 2.0 } else { 0.0007 })),
                    Some(Ok((rng.gen_range(-200.0..200.0f64)).round() / 10.0)),
                    Some(Ok(if rng.gen_bool(0.05) {
                        -99.9999
                    } else {
                        30.0 + rng.gen_range(-0.01..0.01)
                    })),
                    rng.gen_bool(0.1).then_some(Ok(1.0)),
                ]
            })
            .collect();
        for &(r, c, spoil) in &self.spoiled {
            if let Some(row) = rows.get_mut(r) {
                row[c] = Some(Err(spoil));
            }
        }
        if let Some(row) = self.blank_row.and_then(|r| rows.get_mut(r)) {
            row.iter_mut().for_each(|c| *c = None);
        }
        (header, rows)
    }

    fn render(&self, path: &std::path::Path) {
        if let Some(n) = self.random_bytes {
            let mut rng = rand::rngs::StdRng::seed_from_u64(self.seed);
            let bytes: Vec<u8> = (0..n).map(|_| rng.gen()).collect();
            std::fs::write(path, bytes).unwrap();
            return;
        }
        let (header, rows) = self.cells();
        if self.extension == "xlsx" {
            let mut book = rust_xlsxwriter::Workbook::new();
            let ws = book.add_worksheet();
            if !self.empty_sheet {
                for (c, h) in header.iter().enumerate() {
                    ws.write_string(0, c as u16, h).unwrap();
                }
                for (r, row) in rows.iter().enumerate() {
                    for (c, cell) in row.iter().enumerate() {
                        let (r, c) = (r as u32 + 1, c as u16);
                        match cell {
                            None | Some(Err(Spoil::Blank)) => {}
                            Some(Ok(x)) | Some(Err(Spoil::Number(x))) => {
                                ws.write_number(r, c, *x).unwrap();
                            }
                            Some(Err(Spoil::Text(t))) => {
                                ws.write_string(r, c, *t).unwrap();
                            }
                            Some(Err(Spoil::DivZero)) => {
                                let f = rust_xlsxwriter::Formula::new("=1/0").set_result("#DIV/0!");
                                ws.write_formula(r, c, f).unwrap();
                            }
                            Some(Err(Spoil::Boolean)) => {
                                ws.write_boolean(r, c, true).unwrap();
                            }
                        }
                    }
                }
                if let Some((r, c, dr, dc)) = self.merged {
                    let f = rust_xlsxwriter::Format::new();
                    // One cell is no block: rust_xlsxwriter refuses it.
                    let _ = ws.merge_range(r, c, r + dr, c + dc.max(u16::from(dr == 0)), "", &f);
                }
            }
            book.save(path).unwrap();
            return;
        }
        let sep = match (self.extension, self.decimal_comma) {
            ("tsv", _) => "\t",
            (_, true) => ";",
            _ => ",",
        };
        let number = |x: f64| {
            let s = format!("{x}");
            if self.decimal_comma {
                s.replace('.', ",")
            } else {
                s
            }
        };
        let mut text = header.join(sep) + "\n";
        for row in &rows {
            let fields: Vec<String> = row
                .iter()
                .map(|cell| match cell {
                    None | Some(Err(Spoil::Blank)) => String::new(),
                    Some(Ok(x)) | Some(Err(Spoil::Number(x))) => number(*x),
                    Some(Err(Spoil::Text(t))) => t.to_string(),
                    Some(Err(Spoil::DivZero)) => "#DIV/0!".to_string(),
                    Some(Err(Spoil::Boolean)) => "TRUE".to_string(),
                })
                .collect();
            text += &fields.join(sep);
            text += "\n";
        }
        std::fs::write(path, text).unwrap();
    }
}

/// A mapping of [`ExportSpec`]'s columns to generate, then spoil.
#[derive(Clone, Debug)]
struct ImportMappingSpec {
    /// The time from a rate instead of the `t (ms)` column.
    rate: bool,
    /// Values put in place of others: an assignment's index, the value.
    replace: Vec<(usize, String)>,
    /// A key nobody knows, in a table.
    unknown_key: Option<usize>,
    drop_line: Option<usize>,
    random_bytes: Option<u64>,
}

fn import_mapping_spec() -> impl Strategy<Value = ImportMappingSpec> {
    (
        any::<bool>(),
        // Mostly a mapping that holds, so that the exports are read.
        prop_oneof![
            3 => Just(Vec::new()),
            1 => prop::collection::vec((0usize..40, toml_value()), 1..3),
        ],
        prop::option::weighted(0.1, 0usize..6),
        prop::option::weighted(0.1, 0usize..40),
        prop::option::weighted(0.03, any::<u64>()),
    )
        .prop_map(
            |(rate, replace, unknown_key, drop_line, random_bytes)| ImportMappingSpec {
                rate,
                replace,
                unknown_key,
                drop_line,
                random_bytes,
            },
        )
}

impl ImportMappingSpec {
    fn render(&self, export: &ExportSpec) -> Vec<u8> {
        if let Some(seed) = self.random_bytes {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            return (0..rng.gen_range(0..500)).map(|_| rng.gen()).collect();
        }
        let time = if self.rate {
            "rate_hz = 100.0".to_string()
        } else {
            "column = \"t (ms)\"\nscale = 0.001".to_string()
        };
        let source = match (export.extension, export.decimal_comma) {
            ("tsv", comma) => format!("decimal_comma = {comma}"),
            ("csv" | "dat", true) => "delimiter = \";\"\ndecimal_comma = true".to_string(),
            ("dat", false) => "delimiter = \",\"".to_string(),
            _ => "header_row = 1".to_string(),
        };
        let text = format!(
            "format = \"finrs-import/1\"\n[source]\n{source}\n[time]\n{time}\n\
             [[channel]]\nto = \"v1_V\"\ncolumn = \"V1 (V)\"\n\
             [[channel]]\nto = \"i1_A\"\ncolumn = \"I1 (mA)\"\nscale = 0.001\n\
             [[channel]]\nto = \"tip_y_m\"\nletter = \"D\"\nscale = 0.001\nsign = -1\n\
             zero = \"opening\"\nopening_s = 0.5\nout_of_range = [-99.9999]\nvalid = [0.0, 60.0]\n\
             [metadata]\nsegments = 1\nlength_m = 0.03\nwidth_m = 0.005\nthickness_m = 0.0002\n\
             fixture = \"free\"\nmedium = \"air\"\n\
             [files.\"export.{}\"]\nt_session_start_s = 12.5\n",
            export.extension
        );
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let assignments: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].contains(" = "))
            .collect();
        for (k, value) in &self.replace {
            let i = assignments[k % assignments.len()];
            let key = lines[i].split(" = ").next().unwrap().to_string();
            lines[i] = format!("{key} = {value}");
        }
        if let Some(k) = self.unknown_key {
            let tables: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].starts_with('['))
                .collect();
            lines.insert(tables[k % tables.len()] + 1, "units = \"mm\"".to_string());
        }
        if let Some(k) = self.drop_line {
            lines.remove(k % lines.len());
        }
        (lines.join("\n") + "\n").into_bytes()
    }
}

/// Where a command is told to write: a fresh file, a folder, a missing
/// folder's file, a file that cannot be written.
fn out_path(dir: &CaseDir, kind: u8, name: &str) -> String {
    match kind % 6 {
        0 => dir.arg(&format!("missing/dir/{name}")),
        1 => dir.arg("session"),
        2 => "/dev/full".to_string(),
        3 => "/proc/finrs-sweep-cannot-write".to_string(),
        _ => dir.arg(name),
    }
}

// ------------------------------------------------------------- sweeps

proptest! {
    #![proptest_config(config())]

    #[test]
    fn simulate_input(rec in rec_spec(), params in prop::option::of(params_spec()),
                      elements in prop::sample::select(vec!["1", "2", "4", "0", "3", "100", "-1", "x"]),
                      plot in prop::option::of(any::<u8>()), out_kind in any::<u8>(),
                      stray in options(&["--segments", "--rate-hz", "--limit-v", "--duration-s"])) {
        let dir = CaseDir::new();
        let input = dir.write("in.csv", &rec.render());
        let mut args = vec!["simulate".into(), "--input".into(), input, format!("--elements={elements}")];
        args.extend(["--out".into(), out_path(&dir, out_kind, "sim.csv")]);
        if let Some(p) = params {
            args.extend(["--params".into(), dir.write("params.toml", &p.render())]);
        }
        if let Some(kind) = plot {
            args.extend(["--plot".into(), out_path(&dir, kind, "sim.png")]);
        }
        // Wave options with --input must be refused, not ignored.
        if rec.seed % 8 == 0 {
            args.extend(stray);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn simulate_wave(spec in wave_spec(),
                     opts in options(&["--segments", "--rest-s", "--duration-s", "--off-s", "--rate-hz",
                                       "--offset-v", "--ramp-in-s", "--ramp-out-s", "--sweep-s",
                                       "--elements"]),
                     limits in prop::option::weighted(0.3, (number(), number())),
                     fixture in prop::sample::select(vec!["", "free", "blocked", "clamped"]),
                     plot in any::<bool>()) {
        let dir = CaseDir::new();
        let mut args = vec!["simulate".into(), "--wave".into(), spec, "--out".into(), dir.arg("sim.csv")];
        // Keep the drive small: long runs are work, not bugs.
        if !opts.iter().any(|o| o.starts_with("--duration-s=")) {
            args.extend(["--duration-s".into(), "0.5".into()]);
        }
        args.extend(opts);
        if let Some((v, slew)) = limits {
            args.extend(["--limit-v".into(), v, "--slew-v-per-s".into(), slew]);
        }
        if !fixture.is_empty() {
            args.extend(["--fixture".into(), fixture.into()]);
        }
        if plot {
            args.extend(["--plot".into(), dir.arg("sim.png")]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn fit(recs in session(),
           effects in prop::option::weighted(0.4, prop::collection::vec(prop::sample::select(vec![
               "damping", "large-deflection", "dehydration", "beam-stiffness", "segment-crosstalk",
               "back-relaxation", "electrochemical-nonlinearity", "hydrodynamic-loading",
               "segment-variation", "", "none", "Damping"]), 0..3)),
           out in prop::option::of(any::<u8>())) {
        let dir = CaseDir::new();
        let session = write_session(&dir, &recs);
        let mut args = vec!["fit".into(), session];
        if let Some(e) = effects {
            args.extend(["--effects".into(), e.join(",")]);
        }
        if let Some(kind) = out {
            args.extend(["--out".into(), out_path(&dir, kind, "fit.toml")]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn plan(recs in session(),
            effects in prop::option::weighted(0.3, prop::collection::vec(prop::sample::select(vec![
                "damping", "beam-stiffness", "dehydration", "", "bogus"]), 0..2)),
            budget in prop::option::weighted(0.5, number()),
            out in prop::option::of(any::<u8>()),
            json in prop::option::of(any::<u8>())) {
        let dir = CaseDir::new();
        let session = write_session(&dir, &recs);
        let mut args = vec!["plan".into(), session];
        if let Some(e) = effects {
            args.extend(["--effects".into(), e.join(",")]);
        }
        if let Some(b) = budget {
            args.push(format!("--budget-s={b}"));
        }
        if let Some(kind) = out {
            args.extend(["--out".into(), out_path(&dir, kind, "plan.toml")]);
        }
        if let Some(kind) = json {
            args.extend(["--json".into(), out_path(&dir, kind, "plan.json")]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn diagnose(recs in session(), json in prop::option::of(any::<u8>()), report in prop::option::of(any::<u8>())) {
        let dir = CaseDir::new();
        let session = write_session(&dir, &recs);
        let mut args = vec!["diagnose".into(), session];
        if let Some(kind) = json {
            args.extend(["--json".into(), out_path(&dir, kind, "verdict.json")]);
        }
        if let Some(kind) = report {
            args.extend(["--report".into(), out_path(&dir, kind, "report")]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn log_from_bytes(seed in any::<u64>(), frames in prop_oneof![Just(0usize), Just(1), 0usize..3000],
                      damage in damage(), stdin in prop::bool::weighted(0.1),
                      opts in options(&["--duration-s", "--length-m", "--width-m", "--thickness-m"]),
                      medium in prop::sample::select(vec!["", "air", "water", "oil"]),
                      out_kind in any::<u8>()) {
        let dir = CaseDir::new();
        let dump = if stdin { "-".to_string() } else { dir.write("dump.bin", &byte_dump(seed, frames, damage)) };
        let mut args = vec!["log".into(), "--from-bytes".into(), dump, "--out".into(), out_path(&dir, out_kind, "log.csv")];
        args.extend(opts);
        if !medium.is_empty() {
            args.extend(["--medium".into(), medium.into()]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn probe_commands(which in 0u8..7, spec in wave_spec(), value in number(),
                      opts in options(&["--segments", "--offset-v", "--ramp-in-s", "--hold-s", "--ramp-out-s",
                                        "--sweep-s", "--probe-timeout-s", "--flash-timeout-s", "--duration-s"]),
                      probe in prop::sample::select(vec![NO_SUCH_PROBE, "zz", "", ":", "0483", "ffff:fffe:NOPE", "1:2:3:4"]),
                      chip in prop::option::weighted(0.2, prop::sample::select(vec!["", "NoSuchChip", "STM32F446RETx"])),
                      elf in prop::option::weighted(0.5, prop::collection::vec(any::<u8>(), 0..256))) {
        let dir = CaseDir::new();
        let elf_path = elf.map(|b| dir.write("fw.elf", &b));
        let mut args: Vec<String> = match which {
            0 => vec!["wave".into(), spec],
            1 => vec!["limit".into()],
            2 => vec!["tare".into()],
            3 => vec!["stop".into()],
            4 => vec!["clear-fault".into()],
            5 => vec!["log".into(), "--out".into(), dir.arg("log.csv")],
            _ => vec![
                "run".into(),
                elf_path.clone().unwrap_or_else(|| dir.arg("missing.elf")),
                "--out".into(),
                dir.arg("run.csv"),
            ],
        };
        // Only options the command takes, so that the probe path is reached.
        let takes = |o: &str| match which {
            0 => !matches!(o, "--flash-timeout-s" | "--duration-s"),
            5 => matches!(o, "--probe-timeout-s" | "--duration-s"),
            6 => matches!(o, "--probe-timeout-s" | "--flash-timeout-s" | "--duration-s"),
            _ => o == "--probe-timeout-s",
        };
        args.extend(opts.into_iter().filter(|o| takes(o.split('=').next().unwrap_or(""))));
        if which != 6 {
            if let Some(elf) = elf_path {
                args.extend(["--elf".into(), elf]);
            }
        }
        if let Some(chip) = chip {
            args.extend(["--chip".into(), chip.into()]);
        }
        // Always a selector, and never one a real probe answers to.
        args.extend(["--probe".into(), probe.into()]);
        if which == 1 {
            // After `--`, so that a negative value reaches the command.
            args.extend(["--".into(), value]);
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn anything(tokens in prop::collection::vec(prop_oneof![
                    3 => prop::sample::select(vec![
                        "simulate", "params", "fit", "diagnose", "plan", "seed-check", "help", "--help", "-h",
                        "--version", "--input", "--wave", "--out", "--params", "--json", "--report",
                        "--effects", "--elements", "--segments", "--plot", "--budget-s", "--", "-", "bogus",
                    ]).prop_map(String::from),
                    1 => number(),
                    1 => wave_spec(),
                ], 0..6),
                first in prop::sample::select(vec!["simulate", "params", "fit", "diagnose", "plan", "seed-check", "", "help"])) {
        let dir = CaseDir::new();
        // Paths the tokens may name land in the case folder.
        dir.write("session/01.csv", b"t_s,v1_V\n0,0\n");
        let mut args = Vec::new();
        if !first.is_empty() {
            args.push(first.to_string());
        }
        for t in tokens {
            match t.as_str() {
                "--out" | "--json" | "--plot" => args.extend([t, dir.arg("out")]),
                "--report" | "--input" | "--params" => args.extend([t, dir.arg("session/01.csv")]),
                _ => args.push(t),
            }
        }
        run_finrs(&dir, &args)?;
    }

    #[test]
    fn import(exports in prop::collection::vec(export_spec(), 1..3), mapping in import_mapping_spec(),
              folder in prop::bool::weighted(0.2), out_kind in any::<u8>()) {
        let dir = CaseDir::new();
        let mut args = vec!["import".to_string()];
        for (k, e) in exports.iter().enumerate() {
            // The first export is the one the mapping's [files] names.
            let name = match k {
                0 => format!("exports/export.{}", e.extension),
                _ => format!("exports/export{k}.{}", e.extension),
            };
            std::fs::create_dir_all(dir.path("exports")).unwrap();
            e.render(&dir.path(&name));
            if !folder {
                args.push(dir.arg(&name));
            }
        }
        if folder {
            args.push(dir.arg("exports"));
        }
        let toml = dir.write("lab.toml", &mapping.render(&exports[0]));
        let out = match out_kind % 8 {
            6 => dir.arg("missing/dir/one.csv"),
            7 => dir.arg("exports"),
            k => out_path(&dir, k, "out"),
        };
        args.extend(["--mapping".into(), toml, "--out".into(), out.clone()]);
        run_finrs(&dir, &args)?;
        // A refusal names what it refuses: an export, the mapping or the
        // output.
        let stderr = std::fs::read_to_string(dir.path("stderr.txt")).unwrap_or_default();
        if let Some(error) = stderr.lines().find(|l| l.starts_with("error:")) {
            prop_assert!(
                error.contains("export") || error.contains("lab.toml") || error.contains(&out)
                    || error.contains("/dev/full") || error.contains("/proc"),
                "an error naming nothing: {error}\n{}", shell_words(&args)
            );
        }
    }

    #[test]
    fn seed_check(json in prop::option::of(any::<u8>())) {
        let dir = CaseDir::new();
        let mut args = vec!["seed-check".to_string()];
        if let Some(kind) = json {
            args.extend(["--json".into(), out_path(&dir, kind, "seed.json")]);
        }
        run_finrs(&dir, &args)?;
    }
}

// ------------------------------------------------------- regressions

/// A free, one-segment recording of `rows` rows at 1 kHz, all at 0 V, with
/// the camera's tip at rest on every 33rd row.
fn all_zero_recording(rows: usize) -> String {
    let mut text = String::from(
        "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n\
         # thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V,tip_y_m\n",
    );
    for i in 0..rows {
        let cam = if i % 33 == 0 { "0" } else { "" };
        writeln!(text, "{},0,{cam}", i as f64 * 1e-3).unwrap();
    }
    text
}

/// The known bug of issue #15: a session whose recording is all 0 V and
/// shorter than 1 s panicked (index out of bounds) in `fit` and `diagnose`.
#[test]
fn all_zero_session_shorter_than_1_s_is_refused_by_name() {
    let dir = CaseDir::new();
    let text = all_zero_recording(500);
    let file = dir.write("session/zero.csv", text.as_bytes());
    for command in ["fit", "diagnose", "plan"] {
        let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
            .args([command, &dir.arg("session")])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{command}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "{file}: the recording is 0.500 s long (500 data rows), all at rest"
            )) && stderr.contains("at least 1 s at rest"),
            "{command}: {stderr}"
        );
    }
}

/// A session nobody drove says nothing of the model: the fit refuses it
/// instead of printing its starting point as an estimate.
#[test]
fn undriven_session_is_refused_by_the_fit() {
    let dir = CaseDir::new();
    let text = all_zero_recording(1500);
    dir.write("session/a.csv", text.as_bytes());
    dir.write("session/b.csv", text.as_bytes());
    for command in ["fit", "diagnose", "plan"] {
        let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
            .args([command, &dir.arg("session")])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{command}: {stderr}");
        assert!(stderr.contains("drives a segment"), "{command}: {stderr}");
    }
}

/// An error whose message already ends with its cause says the cause once
/// (it printed `…, got 3: elements per segment must be …, got 3`).
#[test]
fn a_cause_is_said_once() {
    let dir = CaseDir::new();
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .args(["simulate", "--wave", "step:1", "--elements=3", "--out"])
        .arg(dir.path("sim.csv"))
        .output()
        .unwrap();
    assert_eq!(
        String::from_utf8_lossy(&out.stderr),
        "error: step:1: elements per segment must be one of [1, 2, 4], got 3\n"
    );
}
