//! `finrs calibrate`: connects through the probe, runs the library's
//! measurement ([`finrs::link::calibrate`]), prints what it found, and
//! stores it unless `--dry-run`; the prompts for the reference load are
//! asked here, on the terminal. And `finrs tune`, which sends the board
//! its model.

use anyhow::bail;
use finrs::link::calibrate::{self, CalibrateOptions};
use finrs::link::capture::{self, Connected, Firmware};
use finrs_frames::{Calibration, Info, MAX_SEGMENTS};

use crate::cli::{timeout, CalibrateWhat, LoadDirection, SendArgs, TuneArgs};
use crate::commands::{capture_flags, prompt, StatusLine};

/// `finrs calibrate ...`.
pub fn run(what: CalibrateWhat) -> anyhow::Result<()> {
    match what {
        CalibrateWhat::Show(send) => {
            let opts = CalibrateOptions::default();
            let mut c = connect(&send)?;
            let info = calibrate::read_info(&mut c.link, &opts)?;
            println!("{}", describe(&info.calibration, &info));
            match info.model_crc {
                Some(crc) => println!("model {crc:04x} in use for motion waves (finrs tune)"),
                None => println!("no model: motion waves are refused (finrs tune FIT.toml)"),
            }
            Ok(())
        }
        CalibrateWhat::Shunts { window, send } => {
            let opts = window.options()?;
            let mut c = connect(&send)?;
            eprintln!("stopping the outputs; measuring the shunts at 0 V");
            let z = calibrate::measure_shunt_zeros(&mut c.link, &opts)?;
            for (k, (amps, se_counts)) in z.offsets.iter().enumerate() {
                println!(
                    "segment {}: {:+.3} mA at 0 V (±{:.2} counts); zero {} -> {} counts",
                    k + 1,
                    amps * 1e3,
                    se_counts,
                    z.before.calibration.current_zero_counts[k],
                    z.calibration.current_zero_counts[k]
                );
            }
            store(&mut c, &opts, &z.calibration, window.dry_run)
        }
        CalibrateWhat::LoadCell {
            mass_g,
            g_m_per_s2,
            direction,
            window,
            send,
        } => {
            if !(mass_g.is_finite() && mass_g > 0.0) {
                bail!("--mass-g {mass_g}: must be a positive mass in grams");
            }
            if !(g_m_per_s2.is_finite() && (9.7..=9.9).contains(&g_m_per_s2)) {
                bail!("--g-m-per-s2 {g_m_per_s2}: must be within 9.7..=9.9 (the Earth's surface)");
            }
            let sign = match direction {
                LoadDirection::Positive => 1.0,
                LoadDirection::Negative => -1.0,
            };
            let reference_n = sign * mass_g * 1e-3 * g_m_per_s2;
            let opts = window.options()?;
            let mut c = connect(&send)?;
            let s = calibrate::measure_load_cell(&mut c.link, &opts, reference_n, &mut prompt)?;
            println!(
                "reference {:.4e} N read as {:.4e} N (±{:.1e}) at the old scale; scale {:e} -> {:e} N/count",
                s.reference_n,
                s.delta_n.mean,
                s.delta_n.se,
                s.before.calibration.newtons_per_count,
                s.calibration.newtons_per_count
            );
            store(&mut c, &opts, &s.calibration, window.dry_run)
        }
        CalibrateWhat::Set {
            newtons_per_count,
            zero_counts,
            timeout_s,
            send,
        } => {
            let opts = CalibrateOptions {
                timeout: timeout("--timeout-s", timeout_s)?,
                ..CalibrateOptions::default()
            };
            if newtons_per_count.is_none() && zero_counts.is_none() {
                bail!("nothing to set: give --newtons-per-count and/or --zero-counts");
            }
            if let Some(z) = &zero_counts {
                if z.len() > MAX_SEGMENTS {
                    bail!("--zero-counts: {} values, at most {MAX_SEGMENTS}", z.len());
                }
            }
            let mut c = connect(&send)?;
            let info = calibrate::read_info(&mut c.link, &opts)?;
            let mut new = info.calibration;
            if let Some(v) = newtons_per_count {
                new.newtons_per_count = v as f32;
            }
            if let Some(z) = zero_counts {
                if z.len() != usize::from(info.segments) {
                    bail!(
                        "--zero-counts: {} values for a board of {} segments",
                        z.len(),
                        info.segments
                    );
                }
                new.current_zero_counts[..z.len()].copy_from_slice(&z);
            }
            store(&mut c, &opts, &new, false)
        }
    }
}

/// `finrs tune`: the fit's model for the strip's geometry, checked by the
/// board's own shaper for the board's segments and sample rate, sent, and
/// confirmed by the Info that names it.
pub fn tune(args: TuneArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    use finrs::model::motion::{board_check, record};
    use finrs::model::params::ModelFile;
    use finrs::recording::Recording;

    let opts = CalibrateOptions {
        timeout: timeout("--timeout-s", args.timeout_s)?,
        ..CalibrateOptions::default()
    };
    let model = ModelFile::read(&args.params)?;
    let geometry = Recording::read_drive(&args.geometry_from)?.meta.geometry();
    let spec = model
        .spec_for(&geometry)
        .with_context(|| args.params.display().to_string())?;
    let r = record(&spec);
    let mut c = connect(&args.send)?;
    let info = calibrate::read_info(&mut c.link, &opts)?;
    board_check(&r, usize::from(info.segments), f64::from(info.sample_hz))
        .with_context(|| format!("{}: the board would refuse it", args.params.display()))?;
    let info = calibrate::apply_model(&mut c.link, &opts, &r)?;
    println!(
        "board: model {:04x} from {} (a strip {} m long) in use for motion waves; \
         the board stores it in flash (its log says whether the write succeeded)",
        info.model_crc.unwrap_or_default(),
        args.params.display(),
        geometry.length_m
    );
    Ok(())
}

fn connect(send: &SendArgs) -> anyhow::Result<Connected> {
    let probe = send.probe.options()?;
    let status = StatusLine::new();
    capture::connect(&probe, &Firmware::Running(send.elf.clone()), &status).map_err(capture_flags)
}

/// Sends `new` and prints the board's answer, or only says what would be
/// sent.
fn store(
    c: &mut Connected,
    opts: &CalibrateOptions,
    new: &Calibration,
    dry_run: bool,
) -> anyhow::Result<()> {
    if dry_run {
        println!("--dry-run: nothing stored");
        return Ok(());
    }
    let info = calibrate::apply(&mut c.link, opts, new)?;
    println!("board: {}", describe(&info.calibration, &info));
    if info.calibration_origin != finrs_frames::CalibrationOrigin::Stored {
        bail!("the board uses the calibration but could not store it in flash (its defmt log says why): it is lost at the next reset");
    }
    Ok(())
}

fn describe(c: &Calibration, info: &Info) -> String {
    calibrate::describe(c, info.calibration_origin, info.segments)
}
