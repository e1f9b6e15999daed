//! Recordings made from a wave: the drive only, ready to simulate.

use crate::recording::{Fixture, Medium, Metadata, Recording};
use crate::wave::Wave;

/// When and how a wave is applied.
#[derive(Clone, Copy, Debug)]
pub struct Drive {
    /// Segments driven.
    pub segments: usize,
    /// How the tip is held.
    pub fixture: Fixture,
    /// Rest at 0 V before the wave, s.
    pub rest_s: f64,
    /// Duration of the wave, s.
    pub duration_s: f64,
    /// Rest at 0 V after the wave, s.
    pub off_s: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
}

/// A voltage-only recording of the seed's strip driven by `wave`.
pub fn drive_recording(wave: &Wave, d: &Drive) -> anyhow::Result<Recording> {
    if !(1..=8).contains(&d.segments) {
        anyhow::bail!("--segments must be 1..=8, got {}", d.segments);
    }
    wave.check_segments(d.segments)
        .map_err(anyhow::Error::msg)?;
    for (name, v) in [("--rest-s", d.rest_s), ("--off-s", d.off_s)] {
        if !(v.is_finite() && v >= 0.0) {
            anyhow::bail!("{name} must be zero or positive, got {v}");
        }
    }
    for (name, v) in [("--duration-s", d.duration_s), ("--rate-hz", d.rate_hz)] {
        if !(v.is_finite() && v > 0.0) {
            anyhow::bail!("{name} must be positive, got {v}");
        }
    }
    let total_s = d.rest_s + d.duration_s + d.off_s;
    let rows = (total_s * d.rate_hz).round() as usize + 1;
    if rows > 50_000_000 {
        anyhow::bail!("{rows} rows is more than this tool writes (50 million)");
    }
    let mut t_s = Vec::with_capacity(rows);
    let mut v_v = Vec::with_capacity(rows);
    for k in 0..rows {
        let t = k as f64 / d.rate_hz;
        let local = t - d.rest_s;
        let on = local >= 0.0 && local < d.duration_s;
        v_v.push(
            (0..d.segments)
                .map(|s| {
                    if on {
                        wave.voltage_v(s, local, d.duration_s)
                    } else {
                        0.0
                    }
                })
                .collect(),
        );
        t_s.push(t);
    }
    let g = crate::params::Geometry::THESIS_2006;
    Ok(Recording {
        meta: Metadata {
            segments: d.segments,
            length_m: g.length_m,
            width_m: g.width_m,
            thickness_m: g.thickness_m,
            fixture: d.fixture,
            medium: Medium::Air,
            sample: Some("thesis_2006".to_string()),
            cation: None,
            dots_s_m: None,
            notes: None,
        },
        t_s,
        v_v,
        channels: Vec::new(),
    })
}
