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
    /// Seed of every random draw (sample, strengths, noise).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scale every hold by this and shorten the rests (the tests' and the
    /// shipped example's sessions use 0.6); without it, the full protocol.
    #[arg(long)]
    short: Option<f64>,
    /// Session directory to write.
    #[arg(long)]
    out: PathBuf,
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let names: Vec<&str> = cli
        .hide
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(cli.seed);
    let sample = finrs_rig::Sample::draw(&mut rng);
    let hidden = finrs_rig::Hidden::draw(&names, &mut rng).map_err(anyhow::Error::msg)?;
    let sensors = finrs_rig::Sensors::draw(&mut rng);
    let label = format!("RIG-{}", cli.seed);
    let runs = match cli.short {
        Some(scale) if scale.is_finite() && scale > 0.0 => finrs_rig::short_protocol(scale),
        Some(scale) => anyhow::bail!("--short must be a positive factor, got {scale}"),
        None => finrs_rig::protocol(),
    };
    finrs_rig::write_session(
        &cli.out, &sample, &hidden, &sensors, &runs, &label, &mut rng,
    )?;
    println!("{sample:#?}\n{hidden:#?}\n{sensors:#?}");
    Ok(())
}
