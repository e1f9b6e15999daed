//! Drive waves described on the command line, for simulating without a
//! recording: `step:2.5`, `step:2,1,-2`, `sine:2.5,1,120`, `chirp:2,0.1,20`,
//! `pulses:2.5,20,20`.

use std::f64::consts::PI;

/// The safe range of the seed's Nafion samples, V (as in `FORMAT.md`).
pub const SAFE_VOLTAGE_V: f64 = 4.0;

/// A wave on every segment.
#[derive(Clone, Debug, PartialEq)]
pub enum Wave {
    /// Constant voltages; one value means every segment.
    Step {
        /// Voltage per segment, V.
        levels_v: Vec<f64>,
    },
    /// Travelling sine: segment `k` (0-based) lags by `k` times the lag.
    Sine {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Phase lag per segment, degrees.
        lag_deg: f64,
    },
    /// Logarithmic chirp, all segments in phase.
    Chirp {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
    },
    /// Pulse train: `on` seconds at the amplitude, `off` at zero (the seed's
    /// 20 s pulses).
    Pulses {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Time on, s.
        on_s: f64,
        /// Time off, s.
        off_s: f64,
    },
}

impl Wave {
    /// Parses `kind:a,b,c`; the message names the rule broken.
    pub fn parse(spec: &str) -> Result<Wave, String> {
        let (kind, args) = spec
            .split_once(':')
            .ok_or_else(|| format!("wave `{spec}`: expected KIND:VALUES, e.g. step:2.5"))?;
        let values = args
            .split(',')
            .map(|a| {
                a.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("wave `{spec}`: `{a}` is not a finite number"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        let need = |n: usize, usage: &str| {
            if values.len() == n {
                Ok(())
            } else {
                Err(format!("wave `{spec}`: {kind} takes {usage}"))
            }
        };
        let wave = match kind {
            "step" => Wave::Step {
                levels_v: values.clone(),
            },
            "sine" => {
                need(3, "AMPLITUDE_V,FREQUENCY_HZ,LAG_DEG")?;
                Wave::Sine {
                    amplitude_v: values[0],
                    frequency_hz: values[1],
                    lag_deg: values[2],
                }
            }
            "chirp" => {
                need(3, "AMPLITUDE_V,START_HZ,END_HZ")?;
                Wave::Chirp {
                    amplitude_v: values[0],
                    start_hz: values[1],
                    end_hz: values[2],
                }
            }
            "pulses" => {
                need(3, "AMPLITUDE_V,ON_S,OFF_S")?;
                Wave::Pulses {
                    amplitude_v: values[0],
                    on_s: values[1],
                    off_s: values[2],
                }
            }
            other => {
                return Err(format!(
                    "wave `{spec}`: unknown kind `{other}` (step, sine, chirp, pulses)"
                ))
            }
        };
        wave.check(spec)?;
        Ok(wave)
    }

    fn check(&self, spec: &str) -> Result<(), String> {
        let peak = match self {
            Wave::Step { levels_v } => levels_v.iter().fold(0.0f64, |m, v| m.max(v.abs())),
            Wave::Sine { amplitude_v, .. }
            | Wave::Chirp { amplitude_v, .. }
            | Wave::Pulses { amplitude_v, .. } => amplitude_v.abs(),
        };
        if peak > SAFE_VOLTAGE_V {
            return Err(format!(
                "wave `{spec}`: {peak} V exceeds the safe range of ±{SAFE_VOLTAGE_V} V"
            ));
        }
        let positive = |name: &str, v: f64| {
            if v > 0.0 {
                Ok(())
            } else {
                Err(format!("wave `{spec}`: {name} must be positive"))
            }
        };
        match *self {
            Wave::Sine { frequency_hz, .. } => positive("frequency", frequency_hz),
            Wave::Chirp {
                start_hz, end_hz, ..
            } => {
                positive("start frequency", start_hz)?;
                positive("end frequency", end_hz)
            }
            Wave::Pulses { on_s, off_s, .. } => {
                positive("on time", on_s)?;
                positive("off time", off_s)
            }
            Wave::Step { .. } => Ok(()),
        }
    }

    /// Checks that a step names one level or one per segment.
    pub fn check_segments(&self, segments: usize) -> Result<(), String> {
        match self {
            Wave::Step { levels_v } if levels_v.len() != 1 && levels_v.len() != segments => Err(
                format!("step has {} levels for {segments} segments", levels_v.len()),
            ),
            _ => Ok(()),
        }
    }

    /// Voltage on `segment` (0-based) at `t_s` after the drive starts, over
    /// a drive of `duration_s`.
    pub fn voltage_v(&self, segment: usize, t_s: f64, duration_s: f64) -> f64 {
        match self {
            Wave::Step { levels_v } => levels_v[if levels_v.len() == 1 { 0 } else { segment }],
            Wave::Sine {
                amplitude_v,
                frequency_hz,
                lag_deg,
            } => {
                amplitude_v
                    * (2.0 * PI * frequency_hz * t_s - segment as f64 * lag_deg.to_radians()).sin()
            }
            Wave::Chirp {
                amplitude_v,
                start_hz,
                end_hz,
            } => {
                // Phase of f(t) = f0 (f1/f0)^(t/T): 2π f0 T (r^(t/T) − 1)/ln r.
                let ratio = end_hz / start_hz;
                let phase = if (ratio - 1.0).abs() < 1e-12 {
                    2.0 * PI * start_hz * t_s
                } else {
                    2.0 * PI * start_hz * duration_s * (ratio.powf(t_s / duration_s) - 1.0)
                        / ratio.ln()
                };
                amplitude_v * phase.sin()
            }
            Wave::Pulses {
                amplitude_v,
                on_s,
                off_s,
            } => {
                if t_s % (on_s + off_s) < *on_s {
                    *amplitude_v
                } else {
                    0.0
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_kind() {
        assert_eq!(
            Wave::parse("step:2,1,-2").unwrap(),
            Wave::Step {
                levels_v: vec![2.0, 1.0, -2.0]
            }
        );
        let sine = Wave::parse("sine:2.5,1,120").unwrap();
        assert!((sine.voltage_v(1, 0.0, 1.0) - 2.5 * (-120f64.to_radians()).sin()).abs() < 1e-12);
        let chirp = Wave::parse("chirp:2,0.1,20").unwrap();
        assert!(chirp.voltage_v(0, 3.0, 12.0).abs() <= 2.0);
        let pulses = Wave::parse("pulses:2.5,20,20").unwrap();
        assert_eq!(pulses.voltage_v(0, 19.9, 100.0), 2.5);
        assert_eq!(pulses.voltage_v(0, 20.1, 100.0), 0.0);
    }

    #[test]
    fn refuses_with_reasons() {
        for (spec, needle) in [
            ("step", "KIND:VALUES"),
            ("step:5", "safe range"),
            ("sine:2,1", "takes AMPLITUDE_V"),
            ("sine:2,0,1", "frequency must be positive"),
            ("wobble:1", "unknown kind"),
            ("step:x", "not a finite number"),
            ("step:nan", "not a finite number"),
        ] {
            let err = Wave::parse(spec).unwrap_err();
            assert!(err.contains(needle), "{spec}: {err}");
        }
        assert!(Wave::parse("step:1,2").unwrap().check_segments(3).is_err());
    }
}
