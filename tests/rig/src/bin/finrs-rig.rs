//! `finrs-rig`: writes a synthetic session with hidden effects.

use std::path::PathBuf;

use clap::Parser;
use rand::SeedableRng;

/// Writes a session of the example's protocol from a strip drawn at random,
/// with the named effects hidden at random strengths.
#[derive(Parser)]
#[command(version)]
struct Cli {
    /// Effects to hide, comma-separated catalogue names (or `mains-pickup`);
    /// empty: none.
    #[arg(long, default_value = "")]
    hide: String,
    /// Draw the off-class strip (always damped and soft, relaxing or
    /// creeping, lagged crosstalk) instead of the baseline's own class.
    #[arg(long)]
    off_class: bool,
    /// Bench imperfections, comma-separated: hum, coloured-noise,
    /// compliant-load-cell, camera-exposure; empty: a perfect bench.
    #[arg(long, default_value = "")]
    bench: String,
    /// Seed of every random draw (sample, strengths, noise).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scale every hold by this and shorten the rests (the tests' and the
    /// shipped example's sessions use 0.6); without it, the full protocol.
    #[arg(long)]
    short: Option<f64>,
    /// Record every run blocked, without a camera, as the board alone does
    /// (holds scaled as --short, 1 if not given).
    #[arg(long)]
    board: bool,
    /// The lab-like bench (docs/rig.md, "A lab-like bench"): these of its
    /// artefacts, comma-separated (curl, zero-drift, dropouts,
    /// quantisation, readback, contact-faults, carry-over, asymmetry), or
    /// `all` (the default when the flag is given without a list); `drift`
    /// is curl and zero-drift.
    #[arg(long, num_args = 0..=1, default_missing_value = "all")]
    lab: Option<String>,
    /// Lab artefacts to leave out of --lab (or of --lab-protocol's),
    /// comma-separated: e.g. `readback`, whose rests a reader that wants
    /// exact 0 V refuses. The others are drawn as they would be with it.
    #[arg(long, default_value = "")]
    lab_without: String,
    /// The lab protocol: a strip drawn as a lab's (20-40 x 4-10 x
    /// 0.2-0.6 mm, one segment), five steps of 1-3 V held 1-6 min (about
    /// 20 min of data), 100 rows/s, a laser at one point, currents; on
    /// the lab bench (every artefact unless --lab names some).
    #[arg(long, conflicts_with_all = ["short", "board"])]
    lab_protocol: bool,
    /// Session directory to write.
    #[arg(long)]
    out: PathBuf,
}

/// The comma list's names, blanks dropped.
fn list(text: &str) -> Vec<&str> {
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect()
}

/// The protocol's runs: the board's, the short one or the full one.
fn runs(cli: &Cli, scale: Option<f64>) -> Vec<finrs_rig::Run> {
    match (cli.board, scale) {
        (true, scale) => finrs_rig::board_protocol(scale.unwrap_or(1.0)),
        (false, Some(scale)) => finrs_rig::short_protocol(scale),
        (false, None) => finrs_rig::protocol(),
    }
}

/// The session on the lab-like bench: its artefacts drawn after
/// everything else, so that the strip and sensors are those the same seed
/// draws without it; the lab protocol's strip is drawn last.
fn lab(
    cli: &Cli,
    mut sample: finrs_rig::Sample,
    hidden: finrs_rig::Hidden,
    sensors: finrs_rig::Sensors,
    bench: finrs_rig::Bench,
    label: &str,
    rng: &mut rand::rngs::StdRng,
) -> anyhow::Result<()> {
    let asked = cli.lab.as_deref().unwrap_or("all");
    let mut names: Vec<&str> = Vec::new();
    for n in list(asked) {
        match n {
            "all" => names.extend(finrs_rig::LAB_ARTEFACTS),
            "drift" => names.extend(finrs_rig::DRIFT),
            n => names.push(n),
        }
    }
    let without = list(&cli.lab_without);
    if let Some(w) = without
        .iter()
        .find(|w| !finrs_rig::LAB_ARTEFACTS.contains(w))
    {
        anyhow::bail!(
            "--lab-without `{w}`: the lab bench has {:?}",
            finrs_rig::LAB_ARTEFACTS
        );
    }
    names.retain(|n| !without.contains(n));
    let lab = finrs_rig::LabBench::draw(&names, rng).map_err(anyhow::Error::msg)?;
    let (runs, layout) = if cli.lab_protocol {
        let p = finrs_rig::LabProtocol::draw(&mut sample, &hidden, rng);
        (p.runs, finrs_rig::Layout::laser(p.laser))
    } else {
        let scale = match cli.short {
            Some(scale) if scale.is_finite() && scale > 0.0 => Some(scale),
            Some(scale) => anyhow::bail!("--short must be a positive factor, got {scale}"),
            None => None,
        };
        (runs(cli, scale), finrs_rig::Layout::camera())
    };
    let written = finrs_rig::write_lab(
        &cli.out, &sample, &hidden, &sensors, &bench, &lab, &runs, &layout, label, rng,
    )?;
    println!("{sample:#?}\n{hidden:#?}\n{sensors:#?}\n{bench:#?}\n{lab:#?}\n{layout:#?}");
    for (i, f) in written.faults.iter().enumerate() {
        if let Some(f) = f {
            println!("recording {}: contact open {f:?}", i + 1);
        }
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let names = list(&cli.hide);
    let mut rng = rand::rngs::StdRng::seed_from_u64(cli.seed);
    let (sample, hidden) = if cli.off_class {
        let sample = finrs_rig::Sample::draw_off_class(&mut rng);
        let hidden = finrs_rig::Hidden::draw_off_class(&names, &mut rng);
        (sample, hidden.map_err(anyhow::Error::msg)?)
    } else {
        let sample = finrs_rig::Sample::draw(&mut rng);
        let hidden = finrs_rig::Hidden::draw(&names, &mut rng);
        (sample, hidden.map_err(anyhow::Error::msg)?)
    };
    let sensors = finrs_rig::Sensors::draw(&mut rng);
    let bench = finrs_rig::Bench::draw(&list(&cli.bench), &mut rng).map_err(anyhow::Error::msg)?;
    let label = format!("RIG-{}", cli.seed);
    if cli.lab.is_some() || cli.lab_protocol || !cli.lab_without.is_empty() {
        return lab(&cli, sample, hidden, sensors, bench, &label, &mut rng);
    }
    let scale = match cli.short {
        Some(scale) if scale.is_finite() && scale > 0.0 => Some(scale),
        Some(scale) => anyhow::bail!("--short must be a positive factor, got {scale}"),
        None => None,
    };
    let runs = runs(&cli, scale);
    finrs_rig::write_session(
        &cli.out, &sample, &hidden, &sensors, &bench, &runs, &label, &mut rng,
    )?;
    println!("{sample:#?}\n{hidden:#?}\n{sensors:#?}\n{bench:#?}");
    Ok(())
}
