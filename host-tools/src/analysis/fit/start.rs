//! Starting values read off the data, so that the fit does not depend on
//! the seed's numbers being close to the sample's.
//!
//! Electrical: at a voltage step from rest the current jumps to
//! `V/R1 + V/R2` and settles to `V/R2` with `τ1 = R1 C`. Mechanical: with
//! the electrics fixed, every deflection and force is proportional to the
//! relaxation network's gain (`a` and `b` together), so the gain follows by
//! linear least squares.

use super::data::SessionTargets;
use super::error::FitError;
use super::space::Space;
use crate::analysis::median::median;
use crate::model::predict::ModelSpec;
use crate::recording::Channel;
use crate::session::Session;

/// Weighted residuals of a model on one recording, target by target.
pub type Residuals<'a> = dyn Fn(usize, &ModelSpec) -> Result<Vec<Vec<f64>>, FitError> + 'a;

/// A starting model for `space` on `recordings` of `session`, whose
/// targets are `targets`; `residuals_of` runs the model on one recording.
pub fn from_data(
    session: &Session,
    targets: &SessionTargets,
    recordings: &[usize],
    space: &Space,
    residuals_of: &Residuals<'_>,
) -> Result<ModelSpec, FitError> {
    let mut spec = space.fixed;
    if let Some((r1, r2, c)) = electrical(session, recordings) {
        spec.params.r1_ohm = r1;
        spec.params.r2_ohm = r2;
        spec.params.c_f = c;
    }
    // The network's gain by linear least squares over the mechanical
    // channels, on the residuals as the fit sees them (drift removed):
    // with the gain doubled, r₂ − r₁ is the model's part and r₂ − 2r₁
    // the data's, both weighted and with their drift taken out.
    let mut doubled = spec;
    doubled.params.a_nm_per_c *= 2.0;
    doubled.params.b_nm_per_c_s *= 2.0;
    let (mut num, mut den) = (0.0, 0.0);
    for &i in recordings {
        let (r1, r2) = (residuals_of(i, &spec)?, residuals_of(i, &doubled)?);
        for ((t, r1), r2) in targets.recordings[i].targets.iter().zip(r1).zip(r2) {
            if matches!(t.channel, Channel::Current(_)) {
                continue;
            }
            for (a, b) in r1.iter().zip(&r2) {
                let (model, data) = (b - a, b - 2.0 * a);
                num += model * data;
                den += model * model;
            }
        }
    }
    if num > 0.0 && den > 0.0 {
        spec.params.a_nm_per_c *= num / den;
        spec.params.b_nm_per_c_s *= num / den;
    }
    Ok(spec)
}

/// `(R1, R2, C)` from the first step of every recording that steps from
/// rest to a held voltage on some segment; medians over all such steps.
fn electrical(session: &Session, recordings: &[usize]) -> Option<(f64, f64, f64)> {
    let (mut r1s, mut r2s, mut cs) = (Vec::new(), Vec::new(), Vec::new());
    for &i in recordings {
        let r = &session.recordings[i];
        let start = r.rest_rows;
        let rows = r.rec.v_v.len();
        for (k, ch) in r.rec.channels.iter().enumerate() {
            let Channel::Current(seg) = ch.0 else {
                continue;
            };
            let values = &r.rec.channels[k].1;
            let v0 = r.rec.v_v.row(start)?[seg];
            if v0.abs() < 0.5 {
                continue;
            }
            // How long the voltage holds.
            let held = (start..rows)
                .take_while(|&row| r.reads_as(seg, row, v0))
                .count();
            if (held as f64) * r.dt_s < 0.5 {
                continue;
            }
            let i_at = |row: usize| values[row];
            let Some(jump) = i_at(start) else { continue };
            let tail = (start + held - held / 10..start + held).filter_map(i_at);
            let tail: Vec<f64> = tail.collect();
            if tail.is_empty() {
                continue;
            }
            let settled = tail.iter().sum::<f64>() / tail.len() as f64;
            let g2 = settled / v0;
            let g1 = jump / v0 - g2;
            if !(g1 > 0.0 && g2 > 0.0) {
                continue;
            }
            // τ1: first row where the decaying part falls below 1/e.
            let target = settled + (jump - settled) / std::f64::consts::E;
            let Some(n) = (start..start + held).position(|row| {
                i_at(row).is_some_and(|x| (x - target) * (jump - settled).signum() <= 0.0)
            }) else {
                continue;
            };
            let tau1 = (n.max(1)) as f64 * r.dt_s;
            r1s.push(1.0 / g1);
            r2s.push(1.0 / g2);
            cs.push(tau1 * g1);
        }
    }
    Some((median(r1s)?, median(r2s)?, median(cs)?))
}
