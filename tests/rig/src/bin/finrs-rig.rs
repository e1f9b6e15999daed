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
    let scale = match cli.short {
        Some(scale) if scale.is_finite() && scale > 0.0 => Some(scale),
        Some(scale) => anyhow::bail!("--short must be a positive factor, got {scale}"),
        None => None,
    };
    let runs = match (cli.board, scale) {
        (true, scale) => finrs_rig::board_protocol(scale.unwrap_or(1.0)),
        (false, Some(scale)) => finrs_rig::short_protocol(scale),
        (false, None) => finrs_rig::protocol(),
    };
    finrs_rig::write_session(
        &cli.out, &sample, &hidden, &sensors, &bench, &runs, &label, &mut rng,
    )?;
    println!("{sample:#?}\n{hidden:#?}\n{sensors:#?}\n{bench:#?}");
    Ok(())
}
