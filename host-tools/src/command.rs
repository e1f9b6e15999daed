//! Commands for the firmware's RTT down channel: `finrs wave`, `tare`,
//! `stop`, `limit` and `clear-fault` build a [`Command`], check it on the
//! host with the firmware's own rules, and encode it with
//! [`encode_command`].
//!
//! A wave is the `--wave` syntax of `finrs simulate` (`step:V[,V..]`,
//! `sine:AMP,HZ,LAG_DEG`, `chirp:AMP,HZ0,HZ1`, `pulses:AMP,ON_S,OFF_S`) or
//! `standing:AMP,HZ`, mapped onto a [`Program`] and an [`Envelope`] and
//! refused unless [`Generator::new`] accepts it for the fin's segment
//! count and its peak stays within [`HARD_LIMIT_V`].
//!
//! ```
//! use finrs::command::{wave_command, WaveRequest};
//! use finrs_frames::Command;
//!
//! let mut req = WaveRequest::new("sine:2,1,120", 4);
//! req.ramp_in_s = 2.0;
//! let Command::SetWave { program, envelope } = wave_command(&req).unwrap() else {
//!     unreachable!()
//! };
//! assert_eq!(envelope.ramp_in_s, 2.0);
//! assert!(matches!(program, finrs_drive::Program::Travelling { .. }));
//!
//! let e = wave_command(&WaveRequest::new("sine:2,300,0", 4)).unwrap_err();
//! assert_eq!(e, "wave `sine:2,300,0`: Travelling.frequency_hz must be within 0.001..=100 Hz");
//! ```

use finrs_drive::{Envelope, Generator, Limits, Program, HARD_LIMIT_V, MAX_SEGMENTS};
use finrs_frames::{encode_command, Command, MAX_COMMAND_LEN};

use crate::wave::Wave;

/// A wave for the firmware, as the command line gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveRequest {
    /// The wave, e.g. `sine:2,1,120`.
    pub spec: String,
    /// Segments of the fin, 1..=8 (the generator's N).
    pub segments: usize,
    /// Constant added to a `sine:` or `standing:` wave, V.
    pub offset_v: f64,
    /// Time to full amplitude, s.
    pub ramp_in_s: f64,
    /// Time at full amplitude, s (infinite: for ever).
    pub hold_s: f64,
    /// Time from full amplitude to zero, s.
    pub ramp_out_s: f64,
    /// Length of one `chirp:` sweep, s.
    pub sweep_s: f64,
}

impl WaveRequest {
    /// A request with the defaults of `finrs wave`: no offset, 1 s ramp in,
    /// held for ever, 10 s sweeps.
    pub fn new(spec: &str, segments: usize) -> Self {
        WaveRequest {
            spec: spec.to_string(),
            segments,
            offset_v: 0.0,
            ramp_in_s: 1.0,
            hold_s: f64::INFINITY,
            ramp_out_s: 0.0,
            sweep_s: 10.0,
        }
    }
}

/// The `SetWave` command for a request, or the field and rule it breaks.
pub fn wave_command(req: &WaveRequest) -> Result<Command, String> {
    let spec = &req.spec;
    if !(1..=MAX_SEGMENTS).contains(&req.segments) {
        return Err(format!(
            "--segments must be 1..={MAX_SEGMENTS}, got {}",
            req.segments
        ));
    }
    let f = |x: f64| x as f32;
    let (program, peak_v) = if let Some(args) = spec.strip_prefix("standing:") {
        let values: Vec<f64> = args
            .split(',')
            .map(|a| {
                a.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("wave `{spec}`: `{a}` is not a number"))
            })
            .collect::<Result<_, _>>()?;
        let [amplitude_v, frequency_hz] = values[..] else {
            return Err(format!(
                "wave `{spec}`: standing takes AMPLITUDE_V,FREQUENCY_HZ"
            ));
        };
        (
            Program::Standing {
                amplitude_v: f(amplitude_v),
                frequency_hz: f(frequency_hz),
                offset_v: f(req.offset_v),
            },
            amplitude_v.abs() + req.offset_v.abs(),
        )
    } else {
        let wave = Wave::parse(spec)?;
        wave.check_segments(req.segments)
            .map_err(|e| format!("wave `{spec}`: {e}"))?;
        if req.offset_v != 0.0 && !matches!(wave, Wave::Sine { .. }) {
            return Err(format!(
                "--offset-v applies to sine: and standing: waves only, not `{spec}`"
            ));
        }
        match wave {
            Wave::Step { levels_v } => {
                let mut levels = [0.0f32; MAX_SEGMENTS];
                for (k, level) in levels.iter_mut().take(req.segments).enumerate() {
                    *level = f(levels_v[if levels_v.len() == 1 { 0 } else { k }]);
                }
                let peak = levels_v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                (Program::Steps { levels_v: levels }, peak)
            }
            Wave::Sine {
                amplitude_v,
                frequency_hz,
                lag_deg,
            } => (
                Program::Travelling {
                    amplitude_v: f(amplitude_v),
                    frequency_hz: f(frequency_hz),
                    lag_deg_per_segment: f(lag_deg),
                    offset_v: f(req.offset_v),
                },
                amplitude_v.abs() + req.offset_v.abs(),
            ),
            Wave::Chirp {
                amplitude_v,
                start_hz,
                end_hz,
            } => (
                Program::Chirp {
                    amplitude_v: f(amplitude_v),
                    start_hz: f(start_hz),
                    end_hz: f(end_hz),
                    duration_s: f(req.sweep_s),
                },
                amplitude_v.abs(),
            ),
            Wave::Pulses {
                amplitude_v,
                on_s,
                off_s,
            } => (
                Program::Pulses {
                    amplitude_v: f(amplitude_v),
                    on_s: f(on_s),
                    off_s: f(off_s),
                },
                amplitude_v.abs(),
            ),
        }
    };
    let envelope = Envelope {
        ramp_in_s: f(req.ramp_in_s),
        hold_s: f(req.hold_s),
        ramp_out_s: f(req.ramp_out_s),
    };
    validate(req.segments, program, envelope).map_err(|e| format!("wave `{spec}`: {e}"))?;
    // The firmware's limiter would clip a larger wave out of shape.
    if peak_v.is_nan() || peak_v > f64::from(HARD_LIMIT_V) {
        return Err(format!(
            "wave `{spec}`: peak {peak_v} V (amplitude plus offset) exceeds the hard limit of ±{HARD_LIMIT_V} V"
        ));
    }
    Ok(Command::SetWave { program, envelope })
}

/// Checks the program and envelope as the firmware's `Generator<N>` will.
fn validate(segments: usize, program: Program, envelope: Envelope) -> Result<(), String> {
    let checked = match segments {
        1 => Generator::<1>::new(program, envelope).map(drop),
        2 => Generator::<2>::new(program, envelope).map(drop),
        3 => Generator::<3>::new(program, envelope).map(drop),
        4 => Generator::<4>::new(program, envelope).map(drop),
        5 => Generator::<5>::new(program, envelope).map(drop),
        6 => Generator::<6>::new(program, envelope).map(drop),
        7 => Generator::<7>::new(program, envelope).map(drop),
        8 => Generator::<8>::new(program, envelope).map(drop),
        n => return Err(format!("--segments must be 1..={MAX_SEGMENTS}, got {n}")),
    };
    checked.map_err(|e| e.to_string())
}

/// The `SetLimit` command, refused unless the limit is one the firmware
/// accepts (finite, above 0, at most [`HARD_LIMIT_V`]).
pub fn limit_command(max_abs_v: f64) -> Result<Command, String> {
    let v = max_abs_v as f32;
    // Any valid slew will do: only the voltage is being checked.
    Limits::new(v, 1.0).map_err(|e| format!("limit {max_abs_v} V: {e}"))?;
    Ok(Command::SetLimit { max_abs_v: v })
}

/// The bytes of a command on the down channel.
pub fn encode(c: &Command) -> Vec<u8> {
    let mut buf = [0u8; MAX_COMMAND_LEN];
    // MAX_COMMAND_LEN holds the longest command, so this cannot fail.
    let n = encode_command(c, &mut buf).unwrap_or(0);
    buf[..n].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use finrs_frames::{CommandDecoder, CommandEvent};

    fn program(spec: &str, segments: usize) -> Program {
        match wave_command(&WaveRequest::new(spec, segments)).unwrap() {
            Command::SetWave { program, .. } => program,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn every_simulate_wave_kind_maps_onto_a_program() {
        assert_eq!(
            program("sine:2.5,1,120", 3),
            Program::Travelling {
                amplitude_v: 2.5,
                frequency_hz: 1.0,
                lag_deg_per_segment: 120.0,
                offset_v: 0.0
            }
        );
        assert_eq!(
            program("step:2,1,-2", 3),
            Program::Steps {
                levels_v: [2.0, 1.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
        assert_eq!(
            program("step:1.5", 2),
            Program::Steps {
                levels_v: [1.5, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
        assert_eq!(
            program("chirp:2,0.1,20", 3),
            Program::Chirp {
                amplitude_v: 2.0,
                start_hz: 0.1,
                end_hz: 20.0,
                duration_s: 10.0
            }
        );
        assert_eq!(
            program("pulses:2.5,20,20", 1),
            Program::Pulses {
                amplitude_v: 2.5,
                on_s: 20.0,
                off_s: 20.0
            }
        );
        assert_eq!(
            program("standing:1,0.5", 4),
            Program::Standing {
                amplitude_v: 1.0,
                frequency_hz: 0.5,
                offset_v: 0.0
            }
        );
    }

    #[test]
    fn invalid_waves_are_refused_with_field_and_rule() {
        let refuse = |req: WaveRequest| wave_command(&req).unwrap_err();
        assert_eq!(
            refuse(WaveRequest::new("sine:2,300,0", 3)),
            "wave `sine:2,300,0`: Travelling.frequency_hz must be within 0.001..=100 Hz"
        );
        let mut r = WaveRequest::new("chirp:2,5,1", 3);
        assert_eq!(
            refuse(r.clone()),
            "wave `chirp:2,5,1`: Chirp.end_hz must be above start_hz"
        );
        r.spec = "chirp:2,1,5".into();
        r.sweep_s = 0.0;
        assert_eq!(
            refuse(r),
            "wave `chirp:2,1,5`: Chirp.duration_s must be above 0"
        );
        let mut r = WaveRequest::new("sine:2,1,0", 3);
        r.ramp_in_s = f64::NAN;
        assert!(refuse(r).contains("ramp_in_s must be finite"));
        let mut r = WaveRequest::new("sine:3,1,0", 3);
        r.offset_v = 1.5;
        assert!(
            refuse(r).contains("peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V")
        );
        assert!(refuse(WaveRequest::new("step:5", 3)).contains("exceeds the safe range"));
        assert!(
            refuse(WaveRequest::new("step:1,2", 3)).contains("step has 2 levels for 3 segments")
        );
        assert!(refuse(WaveRequest::new("standing:1", 3))
            .contains("standing takes AMPLITUDE_V,FREQUENCY_HZ"));
        assert!(refuse(WaveRequest::new("sine:1,1,0", 9)).contains("--segments must be 1..=8"));
        let mut r = WaveRequest::new("pulses:1,1,1", 3);
        r.offset_v = 0.5;
        assert!(refuse(r).contains("--offset-v applies to sine: and standing:"));
    }

    #[test]
    fn limits_follow_the_firmware_rules() {
        assert_eq!(limit_command(1.5), Ok(Command::SetLimit { max_abs_v: 1.5 }));
        assert_eq!(
            limit_command(4.5).unwrap_err(),
            "limit 4.5 V: max_abs_v must not exceed HARD_LIMIT_V (4 V)"
        );
        assert!(limit_command(0.0).unwrap_err().contains("must be above 0"));
        assert!(limit_command(f64::NAN)
            .unwrap_err()
            .contains("must be finite"));
    }

    #[test]
    fn encoded_commands_decode_to_themselves() {
        let commands = [
            wave_command(&WaveRequest::new("sine:2,1,120", 3)).unwrap(),
            Command::Tare,
            Command::Stop,
            limit_command(2.0).unwrap(),
            Command::ClearFault,
        ];
        let bytes: Vec<u8> = commands.iter().flat_map(encode).collect();
        let mut got = Vec::new();
        let mut d = CommandDecoder::new();
        d.push(&bytes, &mut |e| match e {
            CommandEvent::Command(c) => got.push(c),
            CommandEvent::Refused(e) => panic!("{e:?}"),
        });
        assert_eq!(got, commands);
    }
}
