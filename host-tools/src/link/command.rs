//! Commands for the firmware's RTT down channel: `finrs wave`, `tare`,
//! `stop`, `limit` and `clear-fault` build a [`Command`], check it on the
//! host with the firmware's own rules, and encode it with
//! [`encode_command`].
//!
//! A wave is the `--wave` syntax of `finrs simulate`, parsed and mapped
//! onto the firmware's [`Program`](finrs_drive::Program) and
//! [`Envelope`](finrs_drive::Envelope) by the one parser,
//! [`crate::wave`]: refused unless
//! [`Generator::new`](finrs_drive::Generator::new) accepts it for the
//! fin's segment count and its peak stays within
//! [`HARD_LIMIT_V`](finrs_drive::HARD_LIMIT_V), so `finrs simulate` and
//! `finrs wave` accept the same texts and drive the same voltages.
//!
//! ```
//! use finrs::link::command::wave_command;
//! use finrs::wave::WaveOptions;
//! use finrs_frames::Command;
//!
//! let options = WaveOptions { ramp_in_s: 2.0, ..WaveOptions::steady(10.0) };
//! let Command::SetWave { program, envelope } = wave_command("sine:2,1,120", 4, &options).unwrap() else {
//!     unreachable!()
//! };
//! assert_eq!(envelope.ramp_in_s, 2.0);
//! assert!(matches!(program, finrs_drive::Program::Travelling { .. }));
//!
//! let e = wave_command("sine:2,300,0", 4, &options).unwrap_err();
//! assert_eq!(e.to_string(), "wave `sine:2,300,0`: Travelling.frequency_hz must be within 0.001..=100 Hz");
//! ```

use finrs_drive::Limits;
use finrs_frames::{encode_command, Command, Motion, MAX_COMMAND_LEN};

use crate::wave::{MotionWave, Wave, WaveError, WaveOptions};

/// The `SetWave` command for the wave `spec` on `segments` segments shaped
/// by `options`, or the field and rule it breaks; for a motion, the
/// `SetMotion` that the board shapes with the model it holds (`finrs
/// tune`), its frequency and envelope checked here by the generator's
/// rules.
pub fn wave_command(
    spec: &str,
    segments: usize,
    options: &WaveOptions,
) -> Result<Command, WaveError> {
    let wave = Wave::parse(spec)?;
    let Some(MotionWave {
        motion, tracked, ..
    }) = wave.motion()
    else {
        let generator = wave.generator(segments, options)?;
        return Ok(Command::SetWave {
            program: generator.program(),
            envelope: generator.envelope(),
        });
    };
    let silent = match motion {
        Motion::Travelling { frequency_hz, .. } | Motion::Force { frequency_hz, .. } => {
            format!("harmonic:{frequency_hz},0,0")
        }
        Motion::Step { .. } => "step:0".to_string(),
    };
    // The voltages are the board's to find; the envelope (and a sine's
    // frequency) follow the rules of a silent wave of the same kind.
    let generator = Wave::parse(&silent)?
        .generator(segments, options)
        .map_err(|e| match e {
            WaveError::Firmware { rule, .. } => WaveError::Firmware {
                wave: spec.to_string(),
                rule,
            },
            other => other,
        })?;
    Ok(Command::SetMotion {
        motion,
        envelope: generator.envelope(),
        // Unknown here: see `at_session_time`.
        t_session_s: f32::NAN,
        tracked,
    })
}

/// `command` with its motion's start set to `t_session_s` on the clock of
/// the model's drying law (the session's, from its first recording): the
/// board needs it for a model that dries. Any other command as it is.
pub fn at_session_time(command: Command, t_session_s: f64) -> Command {
    match command {
        Command::SetMotion {
            motion,
            envelope,
            tracked,
            ..
        } => Command::SetMotion {
            motion,
            envelope,
            t_session_s: t_session_s as f32,
            tracked,
        },
        other => other,
    }
}

/// A voltage limit the firmware would refuse.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("limit {max_abs_v} V: {rule}")]
pub struct LimitCommandError {
    /// The limit asked for, V.
    pub max_abs_v: f64,
    /// The firmware's rule it breaks.
    pub rule: finrs_drive::LimitError,
}

/// The `SetLimit` command, refused unless the limit is one the firmware
/// accepts (finite, above 0, at most
/// [`HARD_LIMIT_V`](finrs_drive::HARD_LIMIT_V)).
pub fn limit_command(max_abs_v: f64) -> Result<Command, LimitCommandError> {
    let v = max_abs_v as f32;
    // Any valid slew will do: only the voltage is being checked.
    Limits::new(v, 1.0).map_err(|rule| LimitCommandError { max_abs_v, rule })?;
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
    use finrs_drive::Program;
    use finrs_frames::{CommandDecoder, CommandEvent};

    /// A request as `finrs wave` makes it by default: no offset, 1 s ramp
    /// in, held for ever, 10 s sweeps.
    #[derive(Clone)]
    struct WaveRequest {
        spec: String,
        segments: usize,
        options: WaveOptions,
    }

    impl WaveRequest {
        fn new(spec: &str, segments: usize) -> Self {
            WaveRequest {
                spec: spec.to_string(),
                segments,
                options: WaveOptions {
                    ramp_in_s: 1.0,
                    ..WaveOptions::steady(10.0)
                },
            }
        }
    }

    fn request(req: &WaveRequest) -> Result<Command, WaveError> {
        wave_command(&req.spec, req.segments, &req.options)
    }

    fn program(spec: &str, segments: usize) -> Program {
        match request(&WaveRequest::new(spec, segments)).unwrap() {
            Command::SetWave { program, .. } => program,
            other => panic!("{other:?}"),
        }
    }

    /// A motion goes to the board as itself, with the envelope asked; a
    /// frequency the generator refuses is refused here, naming the motion.
    #[test]
    fn a_motion_is_sent_for_the_board_to_shape() {
        let req = WaveRequest::new("motion:0.0002,1.5,60", 3);
        let Command::SetMotion {
            motion,
            envelope,
            t_session_s,
            tracked,
        } = request(&req).unwrap()
        else {
            panic!("a SetMotion")
        };
        assert!(tracked, "motion: is tracked");
        assert!(t_session_s.is_nan(), "no session time yet");
        let at = super::at_session_time(request(&req).unwrap(), 42.5);
        assert!(
            matches!(at, Command::SetMotion { t_session_s, .. } if t_session_s == 42.5),
            "{at:?}"
        );
        assert_eq!(
            motion,
            Motion::Travelling {
                tip_amp_m: 2e-4,
                frequency_hz: 1.5,
                lag_deg_per_segment: 60.0
            }
        );
        assert_eq!((envelope.ramp_in_s, envelope.hold_s), (1.0, f32::INFINITY));
        let ff = request(&WaveRequest::new("motion-ff:0.0002,1.5,60", 3)).unwrap();
        assert!(
            matches!(ff, Command::SetMotion { tracked: false, .. }),
            "motion-ff: is not tracked: {ff:?}"
        );
        let force = request(&WaveRequest::new("force:0.001,1,60", 3)).unwrap();
        assert!(
            matches!(
                force,
                Command::SetMotion {
                    motion: Motion::Force { force_amp_n, .. },
                    tracked: true,
                    ..
                } if force_amp_n == 1e-3
            ),
            "{force:?}"
        );
        let ff = request(&WaveRequest::new("force-ff:0.001,1,60", 3)).unwrap();
        assert!(
            matches!(ff, Command::SetMotion { tracked: false, .. }),
            "{ff:?}"
        );
        let e = request(&WaveRequest::new("motion:0.0002,300,60", 3)).unwrap_err();
        assert!(
            e.to_string().starts_with("wave `motion:0.0002,300,60`: ")
                && e.to_string().contains("frequency_hz"),
            "{e}"
        );
        // A step goes as itself, untracked, its rise the ramp-in asked; a
        // bad envelope is refused here, naming the step.
        let step = request(&WaveRequest::new("motion-step:0.001", 3)).unwrap();
        let Command::SetMotion {
            motion,
            envelope,
            tracked,
            ..
        } = step
        else {
            panic!("a SetMotion: {step:?}")
        };
        assert_eq!(motion, Motion::Step { tip_m: 1e-3 });
        assert!(!tracked && envelope.ramp_in_s == 1.0, "{step:?}");
        let mut bad = WaveRequest::new("motion-step:0.001", 3);
        bad.options.ramp_in_s = -1.0;
        let e = request(&bad).unwrap_err();
        assert!(
            e.to_string().starts_with("wave `motion-step:0.001`: ")
                && e.to_string().contains("ramp_in_s"),
            "{e}"
        );
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
        assert_eq!(
            program("harmonic:1,2,0,1.5,-60,0.5,-120", 3),
            Program::Harmonic {
                frequency_hz: 1.0,
                offset_v: 0.0,
                amplitudes_v: [2.0, 1.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
                phases_deg: [0.0, -60.0, -120.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
        // One pair for every segment.
        assert_eq!(
            program("harmonic:2,1,90", 2),
            Program::Harmonic {
                frequency_hz: 2.0,
                offset_v: 0.0,
                amplitudes_v: [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                phases_deg: [90.0, 90.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
    }

    #[test]
    fn invalid_waves_are_refused_with_field_and_rule() {
        let refuse = |req: WaveRequest| request(&req).unwrap_err().to_string();
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
        r.options.sweep_s = 0.0;
        assert_eq!(
            refuse(r),
            "wave `chirp:2,1,5`: Chirp.duration_s must be above 0"
        );
        let mut r = WaveRequest::new("sine:2,1,0", 3);
        r.options.ramp_in_s = f64::NAN;
        assert!(refuse(r).contains("ramp_in_s must be finite"));
        let mut r = WaveRequest::new("sine:3,1,0", 3);
        r.options.offset_v = 1.5;
        assert!(
            refuse(r).contains("peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V")
        );
        assert_eq!(
            refuse(WaveRequest::new("step:5", 3)),
            "wave `step:5`: peak 5 V (largest level) exceeds the hard limit of ±4 V"
        );
        assert_eq!(
            refuse(WaveRequest::new("step:1,2", 3)),
            "wave `step:1,2`: 2 levels for 3 segments"
        );
        assert_eq!(
            refuse(WaveRequest::new("standing:1", 3)),
            "wave `standing:1`: standing takes AMPLITUDE_V,FREQUENCY_HZ, got 1 value(s)"
        );
        assert_eq!(
            refuse(WaveRequest::new("standing:1,x", 3)),
            "wave `standing:1,x`: `x` is not a finite number"
        );
        assert_eq!(
            refuse(WaveRequest::new("sine:1,1,0", 9)),
            "segments must be 1..=8, got 9"
        );
        let mut r = WaveRequest::new("pulses:1,1,1", 3);
        r.options.offset_v = 0.5;
        assert_eq!(
            refuse(r),
            "offset_v applies to sine:, standing: and harmonic: waves only, not `pulses:1,1,1`"
        );
        assert_eq!(
            refuse(WaveRequest::new("harmonic:1,2,0,1", 3)),
            "wave `harmonic:1,2,0,1`: harmonic takes FREQUENCY_HZ then AMPLITUDE_V,PHASE_DEG \
             per segment (or one pair for all), got 4 value(s)"
        );
        assert_eq!(
            refuse(WaveRequest::new("harmonic:1,2,0,1,0", 3)),
            "wave `harmonic:1,2,0,1,0`: harmonic has 2 amplitude-phase pairs for 3 segments"
        );
        assert_eq!(
            refuse(WaveRequest::new("harmonic:1,2,0,4.5,0,1,0", 3)),
            "wave `harmonic:1,2,0,4.5,0,1,0`: peak 4.5 V (largest amplitude plus offset) \
             exceeds the hard limit of ±4 V"
        );
        assert_eq!(
            refuse(WaveRequest::new("harmonic:1,2,0,-1,0,1,0", 3)),
            "wave `harmonic:1,2,0,-1,0,1,0`: Harmonic.amplitudes_v must be at least 0"
        );
        let mut r = WaveRequest::new("standing:1,1", 3);
        r.options.offset_v = 3.5;
        assert_eq!(
            refuse(r),
            "wave `standing:1,1`: peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V"
        );
    }

    #[test]
    fn limits_follow_the_firmware_rules() {
        assert_eq!(limit_command(1.5), Ok(Command::SetLimit { max_abs_v: 1.5 }));
        assert_eq!(
            limit_command(4.5).unwrap_err().to_string(),
            "limit 4.5 V: max_abs_v must not exceed HARD_LIMIT_V (4 V)"
        );
        assert!(limit_command(0.0)
            .unwrap_err()
            .to_string()
            .contains("must be above 0"));
        assert!(limit_command(f64::NAN)
            .unwrap_err()
            .to_string()
            .contains("must be finite"));
    }

    #[test]
    fn encoded_commands_decode_to_themselves() {
        let commands = [
            request(&WaveRequest::new("sine:2,1,120", 3)).unwrap(),
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
