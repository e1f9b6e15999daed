//! A seeded sweep of off-class sessions and the confusion matrix of what
//! `finrs diagnose` names against what each session holds.
//!
//! Each session draws its own off-class strip (always damped and soft,
//! relaxing or creeping) and hides, by the scenario's turn, nothing, one
//! departure, a pair of them, or a bench imperfection, on the full
//! protocol or on the board's alone (blocked runs, no camera). The
//! diagnosis runs as a user runs it, the `finrs` binary on the session's
//! directory, and its verdict is scored with [`crate::expect`].

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use rand::SeedableRng;

use crate::bench::{Bench, IMPERFECTIONS};
use crate::expect::{
    expected, expected_lab, expected_literature, Expected, Protocol, Score, BENCH_COLOURED,
    BENCH_HUM,
};
use crate::lab::{first_mode_hz, LabBench, LabProtocol, DRIFT, LAB_ARTEFACTS, LAB_RATE_HZ};
use crate::lab_session::{write_lab, Layout};
use crate::sample::{Hidden, Sample, CATALOGUE, OFF_CLASS_DEPARTURES, SEGMENT_VARIATION};
use crate::session::{board_protocol, short_protocol, write, Run, Sensors};
use crate::trivial::{Trivial, TRIVIAL};

/// Which lab-like session a scenario is ([`crate::lab`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabKind {
    /// The off-class strip on the short protocol, every lab artefact.
    Bench,
    /// The ideal strip (the baseline's own class) on the short protocol,
    /// a perfect bench but for drift: the strip's curl and the sensors'
    /// zeros.
    DriftOnly,
    /// The off-class strip drawn as a lab's, on the lab protocol (one
    /// segment, steps held for minutes, 100 rows/s, a laser), every lab
    /// artefact.
    Protocol,
}

/// One session of a sweep.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scenario {
    /// Seed of every draw of the session.
    pub seed: u64,
    /// Departures hidden on the off-class base.
    pub hidden: Vec<&'static str>,
    /// Bench imperfections.
    pub bench: Vec<&'static str>,
    /// Recorded by the board alone.
    pub board: bool,
    /// On the lab-like bench, which session (`None`: the off-class
    /// sweep's).
    pub lab: Option<LabKind>,
    /// Lab artefacts left out (e.g. `readback`, for a reader that refuses
    /// a DAQ's rests); the others are drawn as they would be with it.
    pub lab_without: Vec<String>,
    /// The baseline's own strip with nothing hidden on a perfect bench
    /// ([`plan_null`]): a right diagnosis is `none`.
    pub null: bool,
    /// The literature strip ([`crate::literature`], [`plan_literature`]).
    pub literature: bool,
    /// Parts of the literature strip's base left out
    /// ([`crate::literature::Literature::without`]): an ablation.
    pub literature_without: Vec<String>,
}

impl Scenario {
    /// The matrix row the session counts in: what was hidden, or `base`
    /// for the off-class strip alone; `board:` in front for the board's
    /// protocol, `lab:` on the lab bench, `lab-protocol:` on the lab's
    /// protocol; `lab:ideal-drift` for the ideal strip with drift alone.
    pub fn row(&self) -> String {
        let mut parts: Vec<&str> = self.hidden.clone();
        parts.extend(self.bench.iter().copied());
        let what = if self.null {
            "null".to_string()
        } else if parts.is_empty() {
            "base".to_string()
        } else {
            parts.join("+")
        };
        if self.literature {
            let board = if self.board { "board:" } else { "" };
            return format!("lit:{board}{what}");
        }
        match self.lab {
            Some(LabKind::DriftOnly) => return "lab:ideal-drift".to_string(),
            Some(LabKind::Bench) => return format!("lab:{what}"),
            Some(LabKind::Protocol) => return format!("lab-protocol:{what}"),
            None => {}
        }
        if self.board {
            format!("board:{what}")
        } else {
            what
        }
    }

    /// The lab artefacts the scenario's bench has.
    fn lab_artefacts(&self) -> Vec<&'static str> {
        let all: &[&'static str] = match self.lab {
            None => &[],
            Some(LabKind::DriftOnly) => &DRIFT,
            Some(_) => &LAB_ARTEFACTS,
        };
        all.iter()
            .copied()
            .filter(|a| !self.lab_without.iter().any(|w| w == a))
            .collect()
    }
}

/// Holds of the sweep's sessions, as a fraction of the full protocol's
/// (the hidden-effect tests' length).
pub const HOLD_SCALE: f64 = 0.6;

/// The sweep's scenarios for seeds `first..first + count`, in turn: the
/// base alone, each departure alone, each imperfection alone, pairs of
/// departures, and a board-only session, so that every row fills as the
/// count grows.
pub fn plan(first: u64, count: usize) -> Vec<Scenario> {
    let mut turns: Vec<(Vec<&'static str>, Vec<&'static str>, bool)> =
        vec![(vec![], vec![], false)];
    turns.extend(
        OFF_CLASS_DEPARTURES
            .iter()
            .map(|&d| (vec![d], vec![], false)),
    );
    turns.extend(IMPERFECTIONS.iter().map(|&b| (vec![], vec![b], false)));
    turns.push((vec![], vec!["hum", "coloured-noise"], false));
    turns.push((vec!["dehydration", "segment-variation"], vec![], false));
    turns.push((vec!["large-deflection", "segment-crosstalk"], vec![], false));
    turns.push((vec![], vec![], true));
    turns.push((vec!["back-relaxation"], vec!["hum"], true));
    (0..count)
        .map(|i| {
            let (hidden, bench, board) = turns[i % turns.len()].clone();
            Scenario {
                seed: first + i as u64,
                hidden,
                bench,
                board,
                ..Scenario::default()
            }
        })
        .collect()
}

/// The null sweep's scenarios for seeds `first..first + count` (#49): the
/// baseline's own strip (its class, drawn per seed) with nothing hidden,
/// on a perfect bench and the sweep's short protocol. Every catalogue
/// name given is a false one: the share of sessions with one is the
/// search's family-wise false-name rate.
pub fn plan_null(first: u64, count: usize) -> Vec<Scenario> {
    (0..count)
        .map(|i| Scenario {
            seed: first + i as u64,
            null: true,
            ..Scenario::default()
        })
        .collect()
}

/// The literature sweep's scenarios for seeds `first..first + count`
/// (#49): the literature strip ([`crate::literature`]) alone, with each
/// departure alone, with pairs, and on the board's protocol, in turn; the
/// strip in water or not drawn apart from the rest (three sessions in
/// ten, from the seed's own stream), so that the metadata's `medium` says
/// nothing of what else is hidden.
pub fn plan_literature(first: u64, count: usize) -> Vec<Scenario> {
    let departures: Vec<&'static str> = OFF_CLASS_DEPARTURES
        .iter()
        .copied()
        .filter(|d| *d != "hydrodynamic-loading")
        .collect();
    let mut turns: Vec<(Vec<&'static str>, bool)> = vec![(vec![], false)];
    turns.extend(departures.iter().map(|&d| (vec![d], false)));
    turns.push((vec!["dehydration", "electrochemical-nonlinearity"], false));
    turns.push((vec!["back-relaxation", SEGMENT_VARIATION], false));
    turns.push((vec!["segment-crosstalk", "large-deflection"], false));
    turns.push((vec![], true));
    turns.push((vec!["electrochemical-nonlinearity"], true));
    (0..count)
        .map(|i| {
            let seed = first + i as u64;
            let (mut hidden, board) = turns[i % turns.len()].clone();
            if in_water(seed) {
                hidden.push("hydrodynamic-loading");
            }
            Scenario {
                seed,
                hidden,
                board,
                literature: true,
                ..Scenario::default()
            }
        })
        .collect()
}

/// The literature null sweep's scenarios (#49): the literature strip's
/// base (its electrode lines, spectrum and measured geometry) in air with
/// no departure, on a perfect bench and a drawn protocol. Its damping and
/// stiffness are the base's; any other catalogue name is a false one.
pub fn plan_literature_null(first: u64, count: usize) -> Vec<Scenario> {
    (0..count)
        .map(|i| Scenario {
            seed: first + i as u64,
            null: true,
            literature: true,
            ..Scenario::default()
        })
        .collect()
}

/// The scenarios of the sweep the binaries' `--literature` and `--null`
/// flags choose (the lab's apart): the off-class sweep ([`plan`]), its
/// null ([`plan_null`]), the literature sweep ([`plan_literature`]) or
/// its null ([`plan_literature_null`]).
pub fn plan_of(literature: bool, null: bool, first: u64, count: usize) -> Vec<Scenario> {
    match (literature, null) {
        (true, true) => plan_literature_null(first, count),
        (true, false) => plan_literature(first, count),
        (false, true) => plan_null(first, count),
        (false, false) => plan(first, count),
    }
}

/// Whether the literature sweep's session `seed` is in water: three in
/// ten, from a stream of the seed's own apart from its draws.
fn in_water(seed: u64) -> bool {
    use rand::Rng;
    rand::rngs::StdRng::seed_from_u64(seed ^ 0x5741_5445_525f_6d65).gen_bool(0.3)
}

/// Session time a protocol of `runs` spans, s: its recordings and the
/// pauses between them.
pub fn span_s(runs: &[Run]) -> f64 {
    let data: f64 = runs.iter().map(|r| r.rest_s + r.hold_s + r.off_s).sum();
    data + crate::session::PAUSE_S * runs.len().saturating_sub(1) as f64
}

/// The runs of the scenario's session when it is not on the lab's
/// protocol: the literature sweep's drawn per session from a stream of
/// the seed's own ([`crate::protocols`]).
pub fn runs_of(s: &Scenario) -> Vec<Run> {
    if s.literature {
        let mut rng = rand::rngs::StdRng::seed_from_u64(s.seed ^ 0x5052_4f54_4f43_4f4c);
        crate::protocols::draw(s.board, &mut rng)
    } else if s.board {
        board_protocol(HOLD_SCALE)
    } else {
        short_protocol(HOLD_SCALE)
    }
}

/// The seeds of the lab sweep ([`plan_lab`]) start here: above the
/// off-class sweep's.
pub const LAB_FIRST_SEED: u64 = 20_000;

/// The lab sweep's scenarios for seeds `first..first + count`, in turn
/// (docs/rig.md, "A lab-like bench"): the off-class strip on the lab
/// bench alone and with one catalogue departure, on the short protocol
/// or the lab's own, and the ideal strip with drift alone.
pub fn plan_lab(first: u64, count: usize) -> Vec<Scenario> {
    use LabKind::{Bench as B, DriftOnly as D, Protocol as P};
    let turns: [(LabKind, &[&'static str]); 14] = [
        (B, &[]),
        (D, &[]),
        (P, &[]),
        (B, &["dehydration"]),
        (B, &["back-relaxation"]),
        (P, &["dehydration"]),
        (B, &["large-deflection"]),
        (D, &[]),
        (B, &[SEGMENT_VARIATION]),
        (B, &["electrochemical-nonlinearity"]),
        (P, &["back-relaxation"]),
        (B, &["segment-crosstalk"]),
        (P, &["electrochemical-nonlinearity"]),
        (B, &["hydrodynamic-loading"]),
    ];
    (0..count)
        .map(|i| {
            let (lab, hidden) = turns[i % turns.len()];
            Scenario {
                seed: first + i as u64,
                hidden: hidden.to_vec(),
                lab: Some(lab),
                ..Scenario::default()
            }
        })
        .collect()
}

/// Everything a scenario's seed draws, in the order the rig draws it.
struct Draws {
    sample: Sample,
    hidden: Hidden,
    sensors: Sensors,
    bench: Bench,
    lab: LabBench,
    /// The lab protocol's runs and laser, on its lab strip.
    lab_protocol: Option<LabProtocol>,
    rng: rand::rngs::StdRng,
}

fn draw(s: &Scenario) -> anyhow::Result<Draws> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(s.seed);
    let ideal = !s.literature && (s.null || s.lab == Some(LabKind::DriftOnly));
    let mut sample = if ideal {
        Sample::draw(&mut rng)
    } else {
        Sample::draw_off_class(&mut rng)
    };
    let hidden = if s.literature {
        crate::literature::Literature::draw(&s.hidden, &sample, span_s(&runs_of(s)), &mut rng)
            .and_then(|mut h| {
                if let Some(lit) = h.literature.as_mut() {
                    lit.without(&s.literature_without)?;
                }
                Ok(h)
            })
    } else if ideal {
        anyhow::ensure!(
            s.hidden.is_empty() && s.bench.is_empty(),
            "the drift-only and null sessions hide nothing (but drift)"
        );
        Hidden::draw(&[], &mut rng)
    } else {
        Hidden::draw_off_class(&s.hidden, &mut rng)
    }
    .map_err(anyhow::Error::msg)?;
    let sensors = Sensors::draw(&mut rng);
    let bench = Bench::draw(&s.bench, &mut rng).map_err(anyhow::Error::msg)?;
    let (lab, lab_protocol) = match s.lab {
        None => (LabBench::default(), None),
        Some(kind) => {
            let lab = LabBench::draw(&s.lab_artefacts(), &mut rng).map_err(anyhow::Error::msg)?;
            let p = (kind == LabKind::Protocol)
                .then(|| LabProtocol::draw(&mut sample, &hidden, &mut rng));
            (lab, p)
        }
    };
    Ok(Draws {
        sample,
        hidden,
        sensors,
        bench,
        lab,
        lab_protocol,
        rng,
    })
}

fn protocol(s: &Scenario, d: &Draws) -> Protocol {
    if d.lab_protocol.is_some() {
        // Free runs, a laser across at 100 rows/s: the first mode is seen
        // ringing only below a quarter of that.
        let ringing = first_mode_hz(&d.sample, &d.hidden, 1) < LAB_RATE_HZ / 4.0;
        return Protocol {
            free: true,
            blocked: false,
            session_start: true,
            along: false,
            ringing,
        };
    }
    Protocol {
        free: !s.board,
        blocked: true,
        // The rig writes every recording's start into its notes.
        session_start: true,
        along: !s.board,
        ringing: true,
    }
}

fn expected_draws(s: &Scenario, d: &Draws) -> Expected {
    if s.literature {
        expected_literature(&d.sample, &d.hidden, &d.bench, protocol(s, d))
    } else if s.lab.is_some() {
        expected_lab(&d.hidden, &d.bench, &d.lab, protocol(s, d))
    } else {
        expected(&d.hidden, &d.bench, protocol(s, d))
    }
}

/// What a right diagnosis of the scenario's session names, without
/// writing the session (the same draws as [`write_scenario`]).
pub fn expected_of(s: &Scenario) -> anyhow::Result<Expected> {
    let d = draw(s)?;
    Ok(expected_draws(s, &d))
}

/// The rig's true values behind the scenario's session, for the knobs
/// that mean the same in the fitted model ([`crate::coverage::truth`]).
pub fn truth_of(s: &Scenario) -> anyhow::Result<BTreeMap<String, f64>> {
    let d = draw(s)?;
    Ok(crate::coverage::truth(&d.sample, &d.hidden))
}

/// The catalogue effects the scenario's strip has, visible or not: the
/// model structure that is right for it.
pub fn structure_of(s: &Scenario) -> anyhow::Result<Vec<&'static str>> {
    let e = expected_of(s)?;
    Ok(e.required
        .into_iter()
        .chain(e.allowed)
        .filter(|n| CATALOGUE.contains(n) || *n == SEGMENT_VARIATION)
        .collect())
}

/// The strengths of what the scenario's strip hides
/// ([`crate::literature::strengths`]).
pub fn strengths_of(s: &Scenario) -> anyhow::Result<crate::literature::Strengths> {
    let d = draw(s)?;
    Ok(crate::literature::strengths(&d.sample, &d.hidden))
}

/// The scenario's strip as its session draws it (its sample and what it
/// hides), for runs beyond the session (`rig-motion`).
pub fn strip_of(s: &Scenario) -> anyhow::Result<(Sample, Hidden)> {
    let d = draw(s)?;
    Ok((d.sample, d.hidden))
}

/// Diagnoses the session in `dir` with the library, around the seed's
/// laminate fitted to the session's geometry, as `finrs diagnose` does:
/// the tests' way to the whole result (the final fit beside the verdict).
pub fn diagnose_dir(dir: &Path) -> anyhow::Result<finrs::analysis::diagnose::Diagnosis> {
    let session = finrs::session::Session::read(dir)?;
    let fixed = finrs::model::params::ModelFile::main_m_2006().spec_for(&session.geometry())?;
    Ok(finrs::analysis::diagnose::diagnose(
        &session,
        fixed,
        &|_| {},
    )?)
}

/// Writes the scenario's session into `dir` and says what a right
/// diagnosis of it names.
pub fn write_scenario(s: &Scenario, dir: &Path) -> anyhow::Result<Expected> {
    write_drawn(s, dir, draw(s)?)
}

/// Writes the scenario's twin into `dir`: the same session with every
/// measurement error `noise_scale` times as large ([`Sensors::scaled`]).
/// The fit of a twin whose errors are shrunk is the fitted model's
/// pseudo-true value on this strip and protocol, what the fit would give
/// on endless data: where the strip is not the model, the truth its
/// intervals can be scored against (`rig-coverage`). Refused on the lab's
/// bench, whose artefacts are not all the sensors'.
pub fn write_twin(s: &Scenario, dir: &Path, noise_scale: f64) -> anyhow::Result<Expected> {
    anyhow::ensure!(
        s.lab.is_none(),
        "seed {}: a lab session has no twin (its artefacts are not the sensors' alone)",
        s.seed
    );
    anyhow::ensure!(
        noise_scale > 0.0 && noise_scale.is_finite(),
        "the twin's noise scale must be a positive number, got {noise_scale}"
    );
    let mut d = draw(s)?;
    d.sensors = d.sensors.scaled(noise_scale);
    write_drawn(s, dir, d)
}

fn write_drawn(s: &Scenario, dir: &Path, mut d: Draws) -> anyhow::Result<Expected> {
    let runs: Vec<Run> = match &d.lab_protocol {
        Some(p) => p.runs.clone(),
        None => runs_of(s),
    };
    let label = format!("SWEEP-{}", s.seed);
    if s.lab.is_none() {
        write(
            dir, &d.sample, &d.hidden, &d.sensors, &d.bench, &runs, &label, &mut d.rng,
        )?;
    } else {
        let layout = d
            .lab_protocol
            .as_ref()
            .map_or_else(Layout::camera, |p| Layout::laser(p.laser));
        write_lab(
            dir, &d.sample, &d.hidden, &d.sensors, &d.bench, &d.lab, &runs, &layout, &label,
            &mut d.rng,
        )?;
    }
    Ok(expected_draws(s, &d))
}

/// One diagnosed session.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The session.
    pub scenario: Scenario,
    /// What a right diagnosis names.
    pub expected: Expected,
    /// `none`, `explained` or `unexplained`, or `failed: …` when the
    /// diagnosis did not run through.
    pub verdict: String,
    /// Names given.
    pub causes: Vec<String>,
    /// Held-out gain, percent.
    pub gain_percent: f64,
    /// The verdict against the expectation.
    pub score: Score,
    /// Wall time of the diagnosis, s.
    pub seconds: f64,
    /// Each trivial diagnoser's verdict on the same session, scored
    /// ([`crate::trivial`]).
    pub trivial: Vec<(Trivial, Score)>,
}

/// The columns of the matrix: the catalogue (the ideal rig's names and
/// `segment-variation`), then `none` and `unexplained` (the verdict words),
/// then the bench findings.
pub fn columns() -> Vec<&'static str> {
    CATALOGUE
        .iter()
        .copied()
        .chain([
            SEGMENT_VARIATION,
            "none",
            "unexplained",
            BENCH_HUM,
            BENCH_COLOURED,
        ])
        .collect()
}

/// One row of the matrix.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// Sessions in the row.
    pub sessions: usize,
    /// Per column, sessions whose verdict gave it.
    pub named: BTreeMap<&'static str, usize>,
    /// Sessions whose every required name was given.
    pub detected: usize,
    /// Sessions with at least one wrong name.
    pub false_named: usize,
    /// Sessions scored right (every required name, no wrong one, a
    /// fitting verdict word).
    pub right: usize,
    /// Held-out gains, percent.
    pub gains: Vec<f64>,
}

/// The confusion matrix, row by row in first-seen order.
pub fn matrix(outcomes: &[Outcome]) -> Vec<(String, Row)> {
    let mut rows: Vec<(String, Row)> = Vec::new();
    for o in outcomes {
        let key = o.scenario.row();
        let at = match rows.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None => {
                rows.push((key, Row::default()));
                rows.len() - 1
            }
        };
        let row = &mut rows[at].1;
        row.sessions += 1;
        for c in columns() {
            let given = o.causes.iter().any(|x| x == c) || o.verdict == c;
            if given {
                *row.named.entry(c).or_default() += 1;
            }
        }
        row.detected += usize::from(o.score.missed.is_empty());
        row.false_named += usize::from(!o.score.wrong.is_empty());
        row.right += usize::from(o.score.is_right());
        row.gains.push(o.gain_percent);
    }
    rows
}

/// The median of the finite values of `x`, NaN when none.
fn median(x: &[f64]) -> f64 {
    let finite = x.iter().copied().filter(|g| g.is_finite()).collect();
    finrs::analysis::median::median(finite).unwrap_or(f64::NAN)
}

/// The matrix as Markdown: shares of the row's sessions naming each
/// column, then detection, false-name and right rates and the median gain.
pub fn markdown(outcomes: &[Outcome]) -> String {
    let rows = matrix(outcomes);
    let mut out = String::new();
    let short = |c: &str| {
        match c {
            "large-deflection" => "LD",
            "beam-stiffness" => "EI",
            "damping" => "damp",
            "hydrodynamic-loading" => "hydro",
            "electrochemical-nonlinearity" => "echem",
            "back-relaxation" => "back",
            "dehydration" => "dry",
            "segment-crosstalk" => "xtalk",
            "segment-variation" => "var",
            other => other,
        }
        .to_string()
    };
    let columns = columns();
    let _ = write!(out, "| hidden | n |");
    for &c in &columns {
        let _ = write!(out, " {} |", short(c));
    }
    let _ = writeln!(out, " detected | false name | right | gain % |");
    let _ = write!(out, "|---|---|");
    for _ in &columns {
        let _ = write!(out, "---|");
    }
    let _ = writeln!(out, "---|---|---|---|");
    let pct = |k: usize, n: usize| format!("{:.0}", 100.0 * k as f64 / n.max(1) as f64);
    let mut totals = (0, 0, 0, 0);
    for (key, r) in &rows {
        let _ = write!(out, "| {key} | {} |", r.sessions);
        for &c in &columns {
            let k = r.named.get(c).copied().unwrap_or(0);
            let _ = write!(
                out,
                " {} |",
                if k == 0 {
                    String::new()
                } else {
                    pct(k, r.sessions)
                }
            );
        }
        let _ = writeln!(
            out,
            " {} | {} | {} | {:.1} |",
            pct(r.detected, r.sessions),
            pct(r.false_named, r.sessions),
            pct(r.right, r.sessions),
            median(&r.gains)
        );
        totals.0 += r.sessions;
        totals.1 += r.detected;
        totals.2 += r.false_named;
        totals.3 += r.right;
    }
    let _ = writeln!(
        out,
        "\nAll {} sessions: detected {} %, a false name in {} %, right {} %.",
        totals.0,
        pct(totals.1, totals.0),
        pct(totals.2, totals.0),
        pct(totals.3, totals.0)
    );
    let _ = writeln!(out, "\n{}", right_apart(outcomes));
    let _ = writeln!(out, "\n{}", trivial_scores(outcomes));
    if outcomes.iter().any(|o| o.scenario.literature) {
        let _ = writeln!(out, "\n{}", power(outcomes));
    }
    let _ = writeln!(
        out,
        "\nCells: percent of the row's sessions whose verdict gives the column. \
         Detected: every required name given. False name: a name for something \
         the session does not have. Right: detected, no false name and a fitting \
         verdict word (src/expect.rs says what each session requires)."
    );
    out
}

/// The right verdicts split by their word: those that name every cause
/// and say the model now explains the data (`none` or `explained`), and
/// those right only because `unexplained` was allowed there (#49).
pub fn right_apart(outcomes: &[Outcome]) -> String {
    let n = outcomes.len();
    let right = |word: bool| {
        outcomes
            .iter()
            .filter(|o| o.score.is_right() && (o.verdict == "unexplained") == word)
            .count()
    };
    let (named, unexplained) = (right(false), right(true));
    format!(
        "Right with `none` or `explained`: {named} of {n} ({}); right as an allowed `unexplained`: {unexplained} of {n} ({}).",
        wilson_text(named, n),
        wilson_text(unexplained, n)
    )
}

/// Detection against strength (#49): for each departure with a strength
/// ([`crate::literature::strengths`]), the share of the sessions holding
/// it whose verdict names it, by strength over the diagnosis's plausible
/// one ([`crate::literature::plausible`]), with Wilson's interval; then
/// the effects without a strength; then each name's false-name rate: the
/// share of the sessions that do not hold it (neither required nor
/// allowed) whose verdict gives it.
pub fn power(outcomes: &[Outcome]) -> String {
    use crate::literature::plausible;
    const BINS: [(f64, f64); 4] = [(0.0, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, f64::INFINITY)];
    let named = |o: &Outcome, n: &str| o.causes.iter().any(|c| c == n);
    let mut out = String::from(
        "Detection against strength (strength over the plausible one; named / sessions, Wilson 95 %):\n\n\
         | effect | plausible | < 0.5 | 0.5-1 | 1-2 | >= 2 |\n|---|---|---|---|---|---|\n",
    );
    let strengths: Vec<crate::literature::Strengths> = outcomes
        .iter()
        .map(|o| strengths_of(&o.scenario).unwrap_or_default())
        .collect();
    let names = [
        "damping",
        "electrochemical-nonlinearity",
        "dehydration",
        "back-relaxation",
        "segment-crosstalk",
        SEGMENT_VARIATION,
    ];
    for n in names {
        let mut cells = Vec::new();
        for (lo, hi) in BINS {
            let mut k = 0;
            let mut m = 0;
            for (o, st) in outcomes.iter().zip(&strengths) {
                if let Some((_, x)) = st.iter().find(|(e, _)| *e == n) {
                    let r = x / plausible(n);
                    if (lo..hi).contains(&r) {
                        m += 1;
                        k += usize::from(named(o, n));
                    }
                }
            }
            cells.push(if m == 0 {
                "-".to_string()
            } else {
                let (a, b) = wilson(k, m);
                format!("{k}/{m} ({:.0}-{:.0} %)", 100.0 * a, 100.0 * b)
            });
        }
        let _ = writeln!(out, "| {n} | {} | {} |", plausible(n), cells.join(" | "));
    }
    let _ = writeln!(
        out,
        "\nWithout a strength: named / sessions that require it:"
    );
    for n in [
        "damping",
        "hydrodynamic-loading",
        "large-deflection",
        "beam-stiffness",
    ] {
        let holding: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.expected.required.contains(&n))
            .collect();
        let k = holding.iter().filter(|o| named(o, n)).count();
        let _ = writeln!(
            out,
            "- `{n}`: {k} of {} ({})",
            holding.len(),
            wilson_text(k, holding.len())
        );
    }
    let _ = writeln!(
        out,
        "\nFalse names: sessions naming the effect / sessions without it:"
    );
    for n in CATALOGUE.iter().copied().chain([SEGMENT_VARIATION]) {
        let without: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| !o.expected.required.contains(&n) && !o.expected.allowed.contains(&n))
            .collect();
        let k = without.iter().filter(|o| named(o, n)).count();
        let _ = writeln!(
            out,
            "- `{n}`: {k} of {} ({})",
            without.len(),
            wilson_text(k, without.len())
        );
    }
    out
}

/// Each trivial diagnoser's right count on the same sessions.
pub fn trivial_scores(outcomes: &[Outcome]) -> String {
    let n = outcomes.len();
    let parts: Vec<String> = TRIVIAL
        .iter()
        .map(|&t| {
            let scored = outcomes
                .iter()
                .filter(|o| o.trivial.iter().any(|(x, _)| *x == t))
                .count();
            let right = outcomes
                .iter()
                .filter(|o| o.trivial.iter().any(|(x, s)| *x == t && s.is_right()))
                .count();
            if scored == n {
                format!(
                    "`{}` right in {right} ({})",
                    t.name(),
                    wilson_text(right, n)
                )
            } else {
                format!("`{}` scored on {scored} of {n} only", t.name())
            }
        })
        .collect();
    format!(
        "Trivial diagnosers on the same {n} sessions (src/trivial.rs: no fit, the rests' bench findings): {}.",
        parts.join(", ")
    )
}

/// `k` of `n` as a percentage with Wilson's 95 % interval.
fn wilson_text(k: usize, n: usize) -> String {
    if n == 0 {
        return "no sessions".to_string();
    }
    let (lo, hi) = wilson(k, n);
    format!(
        "{:.0} %, {:.0}–{:.0} %",
        100.0 * k as f64 / n as f64,
        100.0 * lo,
        100.0 * hi
    )
}

/// Wilson's 95 % score interval for `k` successes in `n` trials.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    let z = 1.959_963_984_540_054_f64;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

/// One CSV line per session.
pub fn csv(outcomes: &[Outcome]) -> String {
    let mut out = String::from(
        "seed,row,board,verdict,causes,required,allowed,missed,wrong,right,gain_percent,seconds",
    );
    for t in TRIVIAL {
        let _ = write!(out, ",trivial_{}_right", t.name().replace('-', "_"));
    }
    out.push_str(",strengths\n");
    for o in outcomes {
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{:.2},{:.1}",
            o.scenario.seed,
            o.scenario.row(),
            o.scenario.board,
            o.verdict.replace(',', ";"),
            o.causes.join(";"),
            o.expected.required.join(";"),
            o.expected.allowed.join(";"),
            o.score.missed.join(";"),
            o.score.wrong.join(";"),
            o.score.is_right(),
            o.gain_percent,
            o.seconds
        );
        for t in TRIVIAL {
            let right = o.trivial.iter().find(|(x, _)| *x == t);
            let _ = write!(
                out,
                ",{}",
                right.map_or(String::new(), |(_, s)| s.is_right().to_string())
            );
        }
        // Each departure's strength in the diagnosis's probe unit.
        let strengths: Vec<String> = strengths_of(&o.scenario)
            .unwrap_or_default()
            .iter()
            .map(|(n, x)| format!("{n}={x:.4}"))
            .collect();
        let _ = writeln!(out, ",{}", strengths.join(";"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expect::score;

    fn outcome(hidden: Vec<&'static str>, verdict: &str, causes: &[&str]) -> Outcome {
        let scenario = Scenario {
            seed: 1,
            hidden,
            ..Scenario::default()
        };
        let expected = Expected {
            required: vec!["damping"],
            allowed: vec![],
            unexplained_ok: false,
        };
        let causes: Vec<String> = causes.iter().map(|s| s.to_string()).collect();
        let score = score(&expected, verdict, &causes);
        let null = crate::expect::score(&expected, "none", &[]);
        Outcome {
            scenario,
            expected,
            verdict: verdict.to_string(),
            causes,
            gain_percent: 10.0,
            score,
            seconds: 1.0,
            trivial: vec![(Trivial::Nothing, null)],
        }
    }

    #[test]
    fn the_plan_visits_every_row_and_never_reuses_a_seed() {
        let p = plan(1000, 40);
        let rows: std::collections::BTreeSet<String> = p.iter().map(Scenario::row).collect();
        assert!(rows.contains("base") && rows.contains("board:base"));
        for d in OFF_CLASS_DEPARTURES.iter().chain(&IMPERFECTIONS) {
            assert!(rows.contains(*d), "{d}");
        }
        let seeds: std::collections::BTreeSet<u64> = p.iter().map(|s| s.seed).collect();
        assert_eq!(seeds.len(), p.len());
    }

    #[test]
    fn the_lab_plan_has_each_kind_and_its_rows_say_so() {
        let p = plan_lab(LAB_FIRST_SEED, 14);
        let rows: std::collections::BTreeSet<String> = p.iter().map(Scenario::row).collect();
        for r in [
            "lab:base",
            "lab:ideal-drift",
            "lab-protocol:base",
            "lab:dehydration",
            "lab-protocol:back-relaxation",
        ] {
            assert!(rows.contains(r), "{r}: {rows:?}");
        }
        // Every departure at most one, on the off-class strip; drift alone
        // on the ideal one.
        assert!(p.iter().all(|s| s.hidden.len() <= 1 && s.bench.is_empty()));
        let drift = p
            .iter()
            .find(|s| s.lab == Some(LabKind::DriftOnly))
            .unwrap();
        assert_eq!(drift.lab_artefacts(), DRIFT);
        let e = expected_of(drift).unwrap();
        assert!(e.required.is_empty() && !e.unexplained_ok, "{e:?}");
        let mut s = p[0].clone();
        s.lab_without = vec!["readback".to_string()];
        assert!(!s.lab_artefacts().contains(&"readback"));
        assert_eq!(s.lab_artefacts().len(), LAB_ARTEFACTS.len() - 1);
    }

    #[test]
    fn a_null_session_is_the_baselines_own_strip_and_wants_none() {
        let p = plan_null(40_000, 3);
        assert!(p.iter().all(|s| s.null && s.row() == "null"));
        let e = expected_of(&p[0]).unwrap();
        assert_eq!(e, Expected::default());
        // Its strip is the ideal class's: what the drift-only lab session
        // draws from the same seed.
        let drift = Scenario {
            seed: 40_000,
            lab: Some(LabKind::DriftOnly),
            ..Scenario::default()
        };
        let debug = |s: &Scenario| format!("{:?}", strip_of(s).unwrap());
        assert_eq!(debug(&p[0]), debug(&drift));
    }

    #[test]
    fn the_literature_plan_draws_water_apart_and_power_bins_by_strength() {
        let p = plan_literature(50_000, 140);
        assert!(p
            .iter()
            .all(|s| s.literature && s.row().starts_with("lit:")));
        // Water in about three sessions of ten, whatever else is hidden.
        let wet: Vec<&Scenario> = p
            .iter()
            .filter(|s| s.hidden.contains(&"hydrodynamic-loading"))
            .collect();
        assert!((25..=60).contains(&wet.len()), "{}", wet.len());
        assert!(wet.iter().any(|s| s.hidden.len() == 1));
        assert!(wet.iter().any(|s| s.hidden.len() > 1));
        // Each session its own protocol.
        assert_ne!(
            format!("{:?}", runs_of(&p[0])),
            format!("{:?}", runs_of(&p[14]))
        );
        // Detection lands in the bin of the session's own strength.
        let echem = |s: &Scenario| {
            strengths_of(s)
                .unwrap()
                .into_iter()
                .find(|(n, _)| *n == "electrochemical-nonlinearity")
                .map(|(_, x)| x)
        };
        let s = p
            .iter()
            .find(|s| echem(s).is_some_and(|x| x >= 0.2))
            .unwrap()
            .clone();
        let mut o = outcome(vec![], "unexplained", &["electrochemical-nonlinearity"]);
        o.scenario = s;
        let md = power(&[o]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| electrochemical-nonlinearity |"))
            .unwrap();
        assert!(row.ends_with("| - | - | - | 1/1 (21-100 %) |"), "{row}");
    }

    #[test]
    fn the_matrix_counts_names_and_rates_per_row() {
        let o = [
            outcome(vec![], "explained", &["damping"]),
            outcome(vec![], "explained", &["damping", "dehydration"]),
            outcome(vec![], "none", &[]),
        ];
        let m = matrix(&o);
        assert_eq!(m.len(), 1);
        let (key, r) = &m[0];
        assert_eq!(key, "base");
        assert_eq!(
            (r.sessions, r.detected, r.false_named, r.right),
            (3, 2, 1, 1)
        );
        assert_eq!(r.named.get("damping"), Some(&2));
        assert_eq!(r.named.get("none"), Some(&1));
        let md = markdown(&o);
        assert!(md.contains("| base | 3 |"), "{md}");
        assert!(md.contains("right 33 %"), "{md}");
        // The null guess misses damping in all three; the others were
        // never scored by it.
        assert!(md.contains("`none` right in 0 (0 %, 0–56 %)"), "{md}");
        assert!(md.contains("`damped-soft` scored on 0 of 3 only"), "{md}");
        assert!(md.contains("`explained`: 1 of 3"), "{md}");
        let text = csv(&o);
        assert_eq!(text.lines().count(), 4);
        assert!(text
            .lines()
            .next()
            .unwrap()
            .ends_with("trivial_damped_soft_unexplained_right,strengths"));
        // The base hides no departure: no strength.
        assert!(
            text.lines().nth(1).unwrap().ends_with(",false,,,"),
            "{text}"
        );
    }

    #[test]
    fn wilsons_interval_matches_its_textbook_values() {
        // 0 of 3: upper end 1 - 1/(1 + z²/3) = 0.5615; 10 of 10: 0.7225.
        let (lo, hi) = wilson(0, 3);
        assert!(lo.abs() < 1e-12 && (hi - 0.5615).abs() < 1e-3, "{lo} {hi}");
        let (lo, hi) = wilson(10, 10);
        assert!(
            (lo - 0.7225).abs() < 1e-3 && (hi - 1.0).abs() < 1e-12,
            "{lo} {hi}"
        );
        let (lo, hi) = wilson(116, 120);
        assert!(
            (lo - 0.917).abs() < 2e-3 && (hi - 0.987).abs() < 2e-3,
            "{lo} {hi}"
        );
    }

    #[test]
    fn the_heat_map_is_drawn_with_the_embedded_font() {
        let o = [
            outcome(vec![], "explained", &["damping"]),
            outcome(vec!["segment-variation"], "none", &[]),
        ];
        let path = std::env::temp_dir().join(format!("finrs-heatmap-{}.png", std::process::id()));
        crate::heatmap::draw(&o, &path).unwrap();
        // Labels and shaded cells: far more than an empty PNG's few bytes.
        let bytes = std::fs::metadata(&path).unwrap().len();
        std::fs::remove_file(&path).ok();
        assert!(bytes > 5_000, "{bytes} bytes");
    }
}
