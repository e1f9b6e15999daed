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

use finrs_drive::Limits;
use finrs_frames::{encode_command, Command, MAX_COMMAND_LEN};

use crate::wave::{Wave, WaveOptions};

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

    /// The request's shaping options.
    pub fn options(&self) -> WaveOptions {
        WaveOptions {
            offset_v: self.offset_v,
            ramp_in_s: self.ramp_in_s,
            hold_s: self.hold_s,
            ramp_out_s: self.ramp_out_s,
            sweep_s: self.sweep_s,
        }
    }
}

/// The `SetWave` command for a request, or the field and rule it breaks.
pub fn wave_command(req: &WaveRequest) -> Result<Command, String> {
    let generator = Wave::parse(&req.spec)?.generator(req.segments, &req.options())?;
    Ok(Command::SetWave {
        program: generator.program(),
        envelope: generator.envelope(),
    })
}

/// The `SetLimit` command, refused unless the limit is one the firmware
/// accepts (finite, above 0, at most
/// [`HARD_LIMIT_V`](finrs_drive::HARD_LIMIT_V)).
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
    use finrs_drive::Program;
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
        assert_eq!(
            refuse(WaveRequest::new("step:5", 3)),
            "wave `step:5`: peak 5 V (largest level) exceeds the hard limit of ±4 V"
        );
        assert_eq!(
            refuse(WaveRequest::new("step:1,2", 3)),
            "wave `step:1,2`: step has 2 levels for 3 segments"
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
            "--segments must be 1..=8, got 9"
        );
        let mut r = WaveRequest::new("pulses:1,1,1", 3);
        r.offset_v = 0.5;
        assert_eq!(
            refuse(r),
            "--offset-v applies to sine: and standing: waves only, not `pulses:1,1,1`"
        );
        let mut r = WaveRequest::new("standing:1,1", 3);
        r.offset_v = 3.5;
        assert_eq!(
            refuse(r),
            "wave `standing:1,1`: peak 4.5 V (amplitude plus offset) exceeds the hard limit of ±4 V"
        );
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
