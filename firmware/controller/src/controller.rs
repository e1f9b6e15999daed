//! The [`Controller`]: one call per sample tick, plus host commands and
//! faults from outside. See the crate's docs for the order of a tick, the
//! drop accounting and the fault latch.

use core::fmt;

use finrs_drive::{Envelope, Generator, LimitError, Limiter, Limits, Program, WaveError};
use finrs_frames::{
    encode_dropped, encode_fault, encode_info, encode_sample, encode_tracking, Calibration,
    CalibrationOrigin, Command, Dropped, Fault, FaultCode, Info, ModelRecord, ResetCause, Sample,
    SampleFlags, DROPPED_FRAME_LEN, FAULT_FRAME_LEN, INFO_FRAME_LEN, MAX_FRAME_LEN,
};

use crate::config::{Config, ConfigError, ConfigRule};
use crate::tracker::{self, Target, Tracker};

/// The readings of one sample tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TickInput<const N: usize> {
    /// Sample periods since boot, one per `1/sample_hz`, counted in
    /// hardware: it rises by one each call, by more when the sample task
    /// ran too late to see a period (the periods it did not see are
    /// reported as dropped samples).
    pub tick: u64,
    /// Time since start, µs (carried into the frames as is).
    pub t_us: u32,
    /// Load-cell ADC reading, counts.
    pub load_cell_counts: u16,
    /// Each segment's current-sense ADC reading, counts.
    pub current_counts: [u16; N],
}

/// What to write to the segments' drivers now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickOutput<const N: usize> {
    /// The limited voltages, V: exactly 0 on every segment while a fault is
    /// latched. The same values go into the tick's Sample frame.
    pub voltages_v: [f32; N],
}

/// The up channel as the controller sees it.
pub trait FrameSink {
    /// Writes the whole frame and returns true, or writes nothing and
    /// returns false (channel full). Must never block.
    fn try_write(&mut self, frame: &[u8]) -> bool;
}

/// Why a command was refused. A refused command changes nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CommandRefused {
    /// SetWave: the program or envelope breaks a rule (field and rule).
    Wave(WaveError),
    /// SetLimit: the new limit breaks a rule (or would raise the limit).
    Limit(LimitError),
    /// SetWave: the program asks more than the voltage limit somewhere
    /// (its peak and the limit, V); the limiter would clip it.
    AboveLimit {
        /// The program's peak magnitude, V.
        peak_v: f32,
        /// The limit in force, V.
        limit_v: f32,
    },
    /// SetWave while a fault is latched: ClearFault first.
    Faulted,
    /// ClearFault while the fault's report has not been sent yet: a fault
    /// must be reported before it can be cleared.
    FaultNotReported,
    /// SetCalibration while a program drives the outputs (or they have not
    /// yet slewed to 0 V): Stop first, so that no recording mixes two
    /// scales and the flash write stalls no drive.
    CalibrationWhileDriving,
    /// SetCalibration: a value breaks a rule (field and rule).
    Calibration(ConfigError),
    /// SetModel while a program drives the outputs (or they have not yet
    /// slewed to 0 V): Stop first, so that no run changes model midway and
    /// the flash write stalls no drive.
    ModelWhileDriving,
    /// SetModel or SetMotion handed to the controller itself: these are
    /// shaped first, outside its lock (`shaper::command`).
    NotShaped,
}

impl fmt::Display for CommandRefused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Wave(e) => write!(f, "SetWave refused: {e}"),
            Self::Limit(e) => write!(f, "SetLimit refused: {e}"),
            Self::AboveLimit { peak_v, limit_v } => {
                f.write_str("SetWave refused: the program peaks at ")?;
                write_volts(f, *peak_v)?;
                f.write_str(", above the ")?;
                write_volts(f, *limit_v)?;
                f.write_str(" limit")
            }
            Self::Faulted => f.write_str("SetWave refused: a fault is latched (ClearFault first)"),
            Self::FaultNotReported => {
                f.write_str("ClearFault refused: the fault has not been reported yet")
            }
            Self::CalibrationWhileDriving => f.write_str(
                "SetCalibration refused: the outputs are driven (Stop, and wait for 0 V, first)",
            ),
            Self::Calibration(e) => write!(f, "SetCalibration refused: {e}"),
            Self::ModelWhileDriving => f.write_str(
                "SetModel refused: the outputs are driven (Stop, and wait for 0 V, first)",
            ),
            Self::NotShaped => f.write_str(
                "SetModel and SetMotion go through the shaper (shaper::command), not to the controller",
            ),
        }
    }
}

impl core::error::Error for CommandRefused {}

/// `v` (finite, at least 0) as volts to the hundredth, e.g. `2.50 V`, in
/// integer arithmetic: an f32 `Display` would link core's float formatting
/// into the firmware (about 14 KB of flash, measured), for one message.
fn write_volts(f: &mut fmt::Formatter<'_>, v: f32) -> fmt::Result {
    // Below 2³² hundredths; the cast saturates beyond (a program's peak is
    // at most 1000 V, its limit 4 V).
    let hundredths = (v * 100.0 + 0.5) as u32;
    write!(f, "{}.{:02} V", hundredths / 100, hundredths % 100)
}

/// The program a controller holds before any SetWave: 0 V on every
/// segment (it never runs: the controller starts stopped).
const IDLE_PROGRAM: Program = Program::Steps { levels_v: [0.0; 8] };
const IDLE_ENVELOPE: Envelope = Envelope {
    ramp_in_s: 0.0,
    hold_s: f32::INFINITY,
    ramp_out_s: 0.0,
};

/// What drives the outputs when no fault is latched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Power-up: outputs held at 0 V until the first tare is done; then
    /// the program a SetWave gave meanwhile starts (`then_run`), or the
    /// outputs stay at 0 V. Nothing drives the strip until the host asks:
    /// after any reset (a watchdog's in a crash loop among them) the
    /// firmware waits, stopped.
    PowerUpTare { then_run: bool },
    /// The program drives the outputs; it started at `start_tick` (set by
    /// the first tick after a SetWave, so that it starts at its time 0).
    Running { start_tick: Option<u64> },
    /// Outputs slew to 0 V and stay there until a SetWave.
    Stopped,
}

/// A tare in progress.
#[derive(Clone, Copy, Debug)]
struct Tare {
    sum_counts: u32,
    taken: u16,
}

/// The firmware's hardware-independent logic for `N` segments (1..=8).
#[derive(Clone, Debug)]
pub struct Controller<const N: usize> {
    config: Config,
    dt_s: f32,
    generator: Generator<N>,
    limiter: Limiter<N>,
    mode: Mode,
    fault: Option<(FaultCode, Option<u8>)>,
    /// The latched fault's report, until the sink takes it.
    pending_fault: Option<Fault>,
    faults_while_latched: u32,
    tare_offset_counts: f32,
    /// Whether any unsaturated load-cell reading has been seen yet.
    offset_known: bool,
    tare: Option<Tare>,
    next_seq: u32,
    /// Samples dropped and not yet reported.
    dropped: Option<Dropped>,
    last_t_us: u32,
    /// The previous tick's count, to find periods no tick saw.
    last_tick: Option<u64>,
    unseen_periods: u64,
    /// What the board said of itself, for the Info frame.
    identity: Option<Identity>,
    /// An Info frame is due (after [`Controller::set_identity`] and on
    /// RequestInfo), until the sink takes one.
    info_pending: bool,
    /// Where `config.calibration` came from.
    calibration_origin: CalibrationOrigin,
    /// A calibration the host set, for the board to store in flash.
    calibration_to_store: Option<Calibration>,
    /// The CRC of the model record the shaper holds, for the Info frame.
    model_crc: Option<u16>,
    /// A model the host set, for the board to store in flash.
    model_to_store: Option<ModelRecord>,
    /// The tracker holding the running motion, if it is held (tracked, or
    /// its model dries).
    tracker: Option<Tracker<N>>,
}

/// What only the board knows of itself, for the Info frame (the rest comes
/// from the controller's configuration).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Identity {
    /// Firmware version: major, minor, patch.
    pub version: [u8; 3],
    /// The first 32 bits of the git commit, 0 if unknown.
    pub git_hash: u32,
    /// The segments driven by DAC1 and DAC2, if any.
    pub dac_segments: [Option<u8>; 2],
    /// The H-bridges' supply, V.
    pub bridge_supply_v: f32,
    /// Why the core last reset.
    pub reset_cause: ResetCause,
}

impl<const N: usize> Controller<N> {
    /// Checks `config` and starts stopped: outputs at 0 V, a first tare of
    /// `tare_samples` readings under way, and no program until a SetWave
    /// (one given during the tare starts when it is done).
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        const { assert!(N >= 1 && N <= finrs_frames::MAX_SEGMENTS, "1..=8 segments") };
        config.validate()?;
        // Valid for every N (the tests build it for N = 1..=8); refusing
        // it here beats a panic should finrs-drive ever change its rules.
        let generator = Generator::new(IDLE_PROGRAM, IDLE_ENVELOPE).map_err(|_| ConfigError {
            field: "idle_program",
            rule: ConfigRule::RefusedByGenerator,
        })?;
        Ok(Self {
            config,
            dt_s: config.dt_s(),
            generator,
            limiter: Limiter::new(config.limits),
            mode: Mode::PowerUpTare { then_run: false },
            fault: None,
            pending_fault: None,
            faults_while_latched: 0,
            tare_offset_counts: 0.0,
            offset_known: false,
            tare: Some(Tare {
                sum_counts: 0,
                taken: 0,
            }),
            next_seq: 0,
            dropped: None,
            last_t_us: 0,
            last_tick: None,
            unseen_periods: 0,
            identity: None,
            info_pending: false,
            calibration_origin: CalibrationOrigin::Defaults,
            calibration_to_store: None,
            model_crc: None,
            model_to_store: None,
            tracker: None,
        })
    }

    /// Uses `calibration`, read from the board's flash at boot, in place of
    /// the configuration's; refused (the defaults kept) if a value breaks a
    /// rule, as a damaged or foreign record might.
    pub fn use_stored_calibration(&mut self, calibration: Calibration) -> Result<(), ConfigError> {
        let config = Config {
            calibration,
            ..self.config
        };
        config.validate()?;
        self.config = config;
        self.calibration_origin = CalibrationOrigin::Stored;
        Ok(())
    }

    /// The calibration a SetCalibration asked to store, if any, and only
    /// while nothing drives (a SetWave that followed it at once defers the
    /// store to the next stop: a flash write stalls the core). Taken: the
    /// board stores it once, then reports with
    /// [`calibration_stored`](Self::calibration_stored).
    pub fn take_calibration_to_store(&mut self) -> Option<Calibration> {
        if self.driving() {
            return None;
        }
        self.calibration_to_store.take()
    }

    /// Whether a program drives the outputs, is about to (a wave waiting
    /// for the power-up tare), or they have not yet slewed to 0 V.
    fn driving(&self) -> bool {
        let wants = self.fault.is_none()
            && matches!(
                self.mode,
                Mode::Running { .. } | Mode::PowerUpTare { then_run: true }
            );
        wants || self.limiter.last_v().iter().any(|&v| v != 0.0)
    }

    /// A model checked by the shaper (`shaper::command` calls this under
    /// the lock): refused while the outputs are driven; else the Info frame
    /// names it from now on (and goes out again), and the board is handed
    /// it to store ([`take_model_to_store`](Self::take_model_to_store)).
    pub fn model_set(&mut self, record: &ModelRecord) -> Result<(), CommandRefused> {
        if self.driving() {
            return Err(CommandRefused::ModelWhileDriving);
        }
        self.model_crc = Some(record.crc());
        self.model_to_store = Some(*record);
        self.info_pending = self.identity.is_some();
        Ok(())
    }

    /// A shaped motion (`shaper::command` calls this under the lock): its
    /// `program` as a SetWave with `envelope` (refused as one), then held
    /// by a tracker if `target` is given (the currents' admittance, the
    /// model's drying law, as the target says).
    pub fn motion(
        &mut self,
        program: Program,
        envelope: Envelope,
        target: Option<Target<N>>,
    ) -> Result<(), CommandRefused> {
        self.command(Command::SetWave { program, envelope })?;
        self.tracker = target.map(|t| Tracker::new(t, self.config.sample_hz));
        Ok(())
    }

    /// Whether a tracker holds the running motion.
    pub fn tracking(&self) -> bool {
        self.tracker.is_some()
    }

    /// A model read from the board's flash at boot and checked by the
    /// shaper: the Info frame names it (and goes out again); nothing to
    /// store.
    pub fn use_stored_model(&mut self, record: &ModelRecord) {
        self.model_crc = Some(record.crc());
        // The first Info may have gone out before the model was checked.
        self.info_pending = self.identity.is_some();
    }

    /// The model a SetModel asked to store, if any, and only while nothing
    /// drives (as [`take_calibration_to_store`](Self::take_calibration_to_store)).
    pub fn take_model_to_store(&mut self) -> Option<ModelRecord> {
        if self.driving() {
            return None;
        }
        self.model_to_store.take()
    }

    /// The board's report of a store: the origin becomes `Stored` or
    /// `Unsaved`, and an Info frame tells the host.
    pub fn calibration_stored(&mut self, stored: bool) {
        self.calibration_origin = if stored {
            CalibrationOrigin::Stored
        } else {
            CalibrationOrigin::Unsaved
        };
        self.info_pending = self.identity.is_some();
    }

    /// The calibration in force and where it came from.
    pub fn calibration(&self) -> (Calibration, CalibrationOrigin) {
        (self.config.calibration, self.calibration_origin)
    }

    /// One sample tick: checks the readings, updates the tare, computes the
    /// limited voltages and sends the frames (see the crate's docs).
    /// Returns the voltages to write now.
    pub fn tick(&mut self, input: &TickInput<N>, sink: &mut impl FrameSink) -> TickOutput<N> {
        self.last_t_us = input.t_us;
        self.send_pending_info(sink);
        // Periods between the last tick and this one were never sampled:
        // their numbers are taken and reported as dropped, so the host sees
        // the hole and the clock stays the hardware's.
        if let Some(last) = self.last_tick {
            let unseen = input.tick.saturating_sub(last).saturating_sub(1);
            self.skip(unseen);
        }
        self.last_tick = Some(input.tick);
        let currents_a: [f32; N] =
            core::array::from_fn(|k| self.config.current_a(k, input.current_counts[k]));
        let counts = input.load_cell_counts;
        let saturated = self.config.load_cell_saturated(counts);
        if !saturated {
            if !self.offset_known {
                // Until the first tare is done, force is relative to the
                // first good reading.
                self.tare_offset_counts = f32::from(counts);
                self.offset_known = true;
            }
            self.feed_tare(counts);
        }
        if let Some((code, segment)) = self.check(input, &currents_a, saturated) {
            if self.fault.is_none() {
                self.latch(code, segment, input.t_us);
                self.send_pending_fault(sink);
                // No Sample on the faulting tick: the Fault frame stands in
                // for it (it carries the sequence number, consuming none).
                return TickOutput {
                    voltages_v: self.limiter.stop(),
                };
            }
        }
        let force_n = (f32::from(counts) - self.tare_offset_counts)
            * self.config.calibration.newtons_per_count;
        self.track(&currents_a, force_n, input.t_us, sink);
        let (voltages_v, limiter_flags) = self.next_voltages(input.tick);
        self.send_sample(
            &Sample {
                seq: self.next_seq,
                t_us: input.t_us,
                force_n,
                flags: SampleFlags(limiter_flags | self.state_flags()),
                voltages_v,
                currents_a,
            },
            sink,
        );
        TickOutput { voltages_v }
    }

    /// Applies a host command; a refused command changes nothing.
    ///
    /// - SetWave: refused while a fault is latched, with the field and
    ///   rule [`Generator::new`] names, or if the program's peak
    ///   ([`Generator::peak_abs_v`]) is above the voltage limit; else the
    ///   program starts at its time 0 on the next tick, the slew limit
    ///   carrying the outputs over.
    /// - Tare: (re)starts a tare of `tare_samples` readings.
    /// - Stop: outputs slew to 0 V and stay there until a SetWave.
    /// - SetLimit: lowers the voltage limit (a raise or an invalid value is
    ///   refused with the [`LimitError`]). Lowering is never refused for
    ///   the running program's sake: a program above the new limit is
    ///   clipped by the limiter.
    /// - ClearFault: clears the latch once its Fault frame has been sent
    ///   (refused before); outputs stay at 0 V until a SetWave. Without a
    ///   latched fault it does nothing.
    /// - RequestInfo: an Info frame goes out at the next tick (once the
    ///   board has given its [`Identity`]).
    /// - SetCalibration: refused while the outputs are driven or not yet
    ///   at 0 V, or with the field and rule a value breaks; else used from
    ///   the next tick and handed to the board to store
    ///   ([`take_calibration_to_store`](Self::take_calibration_to_store)).
    ///   The tare (in counts) is kept.
    pub fn command(&mut self, command: Command) -> Result<(), CommandRefused> {
        match command {
            Command::SetWave { program, envelope } => {
                if self.fault.is_some() {
                    return Err(CommandRefused::Faulted);
                }
                let generator = Generator::new(program, envelope).map_err(CommandRefused::Wave)?;
                let (peak_v, limit_v) = (generator.peak_abs_v(), self.limiter.limits().max_abs_v());
                if peak_v > limit_v {
                    return Err(CommandRefused::AboveLimit { peak_v, limit_v });
                }
                self.generator = generator;
                self.tracker = None;
                self.mode = match self.mode {
                    Mode::PowerUpTare { .. } => Mode::PowerUpTare { then_run: true },
                    _ => Mode::Running { start_tick: None },
                };
            }
            Command::Tare => {
                self.tare = Some(Tare {
                    sum_counts: 0,
                    taken: 0,
                })
            }
            Command::Stop => {
                self.tracker = None;
                self.mode = match self.mode {
                    Mode::PowerUpTare { .. } => Mode::PowerUpTare { then_run: false },
                    _ => Mode::Stopped,
                }
            }
            Command::SetLimit { max_abs_v } => self
                .limiter
                .limits_mut()
                .set_max_abs_v_lower(max_abs_v)
                .map_err(CommandRefused::Limit)?,
            Command::ClearFault => {
                if self.pending_fault.is_some() {
                    return Err(CommandRefused::FaultNotReported);
                }
                self.fault = None;
            }
            Command::RequestInfo => self.info_pending = self.identity.is_some(),
            Command::SetModel(_) | Command::SetMotion { .. } => {
                return Err(CommandRefused::NotShaped)
            }
            Command::SetCalibration(calibration) => {
                if self.driving() {
                    return Err(CommandRefused::CalibrationWhileDriving);
                }
                let config = Config {
                    calibration,
                    ..self.config
                };
                config.validate().map_err(CommandRefused::Calibration)?;
                self.config = config;
                self.calibration_origin = CalibrationOrigin::Unsaved;
                self.calibration_to_store = Some(calibration);
            }
        }
        Ok(())
    }

    /// A fault detected outside (missed deadline, watchdog): latches it,
    /// zeroes the limiter's outputs and sends (or queues) its Fault frame.
    /// The caller must write zeros to the drivers at once ([`outputs_v`]
    /// returns them). A `segment` not below N is reported as no segment.
    /// While a fault is latched a new one only counts
    /// ([`faults_while_latched`]): the first fault stays latched.
    ///
    /// [`outputs_v`]: Self::outputs_v
    /// [`faults_while_latched`]: Self::faults_while_latched
    pub fn fault(&mut self, code: FaultCode, segment: Option<u8>, sink: &mut impl FrameSink) {
        if self.fault.is_some() {
            self.faults_while_latched = self.faults_while_latched.saturating_add(1);
            return;
        }
        let segment = segment.filter(|&s| usize::from(s) < N);
        self.latch(code, segment, self.last_t_us);
        self.send_pending_fault(sink);
    }

    /// The latched fault and its segment, if any.
    pub fn fault_state(&self) -> Option<(FaultCode, Option<u8>)> {
        self.fault
    }

    /// The load cell's zero, counts: the average of the last tare, or the
    /// first good reading until the first tare is done.
    pub fn tare_offset_counts(&self) -> f32 {
        self.tare_offset_counts
    }

    /// The generator of the current (or last) program.
    pub fn generator(&self) -> &Generator<N> {
        &self.generator
    }

    /// The limits in force.
    pub fn limits(&self) -> Limits {
        self.limiter.limits()
    }

    /// The last voltages returned, V (zeros once a fault is latched).
    pub fn outputs_v(&self) -> [f32; N] {
        self.limiter.last_v()
    }

    /// The sequence number the next Sample will take.
    pub fn next_seq(&self) -> u32 {
        self.next_seq
    }

    /// Samples dropped and not yet reported by a Dropped frame.
    pub fn pending_dropped(&self) -> Option<Dropped> {
        self.dropped
    }

    /// Whether the latched fault's Fault frame still waits for the sink.
    pub fn fault_report_pending(&self) -> bool {
        self.pending_fault.is_some()
    }

    /// Faults raised through [`fault`](Self::fault) while another was
    /// latched (not reported in-band: the first fault stays latched).
    pub fn faults_while_latched(&self) -> u32 {
        self.faults_while_latched
    }

    /// Whether a tare is in progress.
    pub fn taring(&self) -> bool {
        self.tare.is_some()
    }

    /// Whether a program drives the outputs (no fault, not stopped, not
    /// holding for the power-up tare).
    pub fn running(&self) -> bool {
        self.fault.is_none() && matches!(self.mode, Mode::Running { .. })
    }

    fn feed_tare(&mut self, counts: u16) {
        let Some(t) = &mut self.tare else { return };
        // At most 65535 readings of at most 65535 counts: no overflow.
        t.sum_counts += u32::from(counts);
        t.taken += 1;
        if t.taken >= self.config.tare_samples {
            let n = u32::from(t.taken);
            // Quotient and remainder apart: exact where a sum in f32 is not.
            self.tare_offset_counts =
                (t.sum_counts / n) as f32 + (t.sum_counts % n) as f32 / n as f32;
            self.tare = None;
            if let Mode::PowerUpTare { then_run } = self.mode {
                self.mode = if then_run {
                    Mode::Running { start_tick: None }
                } else {
                    Mode::Stopped
                };
            }
        }
    }

    /// The first fault the readings show: overcurrent (lowest segment
    /// first), then a saturated current channel, then a saturated load cell.
    fn check(
        &self,
        input: &TickInput<N>,
        currents_a: &[f32; N],
        load_cell_saturated: bool,
    ) -> Option<(FaultCode, Option<u8>)> {
        let limit = self.config.overcurrent_a;
        if let Some(k) = currents_a.iter().position(|&i| i > limit || i < -limit) {
            return Some((FaultCode::Overcurrent, Some(k as u8)));
        }
        if let Some(k) = input
            .current_counts
            .iter()
            .enumerate()
            .position(|(k, &c)| self.config.current_saturated(k, c))
        {
            return Some((FaultCode::AdcSaturation, Some(k as u8)));
        }
        load_cell_saturated.then_some((FaultCode::AdcSaturation, None))
    }

    fn latch(&mut self, code: FaultCode, segment: Option<u8>, t_us: u32) {
        self.fault = Some((code, segment));
        self.tracker = None;
        self.limiter.stop();
        // After ClearFault the outputs stay at 0 until a SetWave.
        self.mode = Mode::Stopped;
        self.pending_fault = Some(Fault {
            seq: self.next_seq,
            t_us,
            code,
            segment,
        });
    }

    /// Feeds the running motion's tracker the voltages of the period that
    /// just ended and the currents read at its end; at the end of each
    /// period of the wave, drives its corrected program (within the limit
    /// in force) and sends its Tracking frame (none if the channel is full:
    /// the next period's is newer).
    fn track(&mut self, currents_a: &[f32; N], force_n: f32, t_us: u32, sink: &mut impl FrameSink) {
        if !self.running() {
            return;
        }
        let applied_v = self.limiter.last_v();
        let Some(t) = &mut self.tracker else { return };
        let Some(c) = t.feed(&applied_v, currents_a, force_n) else {
            return;
        };
        let (program, flags) = t.program(&c, self.limiter.limits().max_abs_v());
        match Generator::new(program, self.generator.envelope()) {
            Ok(g) => self.generator = g,
            // Not reached (amplitudes within the limit, the motion's
            // frequency already checked); if it were, the model's program
            // runs on untracked.
            Err(_) => {
                self.tracker = None;
                return;
            }
        }
        let mut buf = [0u8; MAX_FRAME_LEN];
        if let Ok(n) = encode_tracking(&tracker::frame(&c, flags, t_us), &mut buf) {
            let _ = sink.try_write(&buf[..n]);
        }
    }

    /// The tick's voltages, and the limiter's part in them
    /// ([`SampleFlags::LIMITED`], [`SampleFlags::SLEWED`]).
    fn next_voltages(&mut self, tick: u64) -> ([f32; N], u8) {
        if self.fault.is_some() {
            return (self.limiter.stop(), 0);
        }
        let wanted = match &mut self.mode {
            Mode::PowerUpTare { .. } | Mode::Stopped => [0.0; N],
            Mode::Running { start_tick } => {
                let start = *start_tick.get_or_insert(tick);
                // A tick behind the start (a caller's bug) asks for time 0.
                self.generator
                    .voltages_at_tick_v(tick.saturating_sub(start), self.config.sample_hz)
            }
        };
        let (out, applied) = self.limiter.apply_reporting(wanted, self.dt_s);
        let flag = |set: bool, bit: u8| if set { bit } else { 0 };
        let flags =
            flag(applied.clamped, SampleFlags::LIMITED) | flag(applied.slewed, SampleFlags::SLEWED);
        (out, flags)
    }

    /// The state bits of a Sample frame, beside the limiter's.
    fn state_flags(&self) -> u8 {
        let mut flags = 0;
        if self.tare.is_some() {
            flags |= SampleFlags::TARING;
        }
        if self.fault.is_some() {
            flags |= SampleFlags::FAULT;
        }
        if self.running() {
            flags |= SampleFlags::RUNNING;
        }
        flags
    }

    /// Sends the pending Fault frame; true if none is pending afterwards.
    fn send_pending_fault(&mut self, sink: &mut impl FrameSink) -> bool {
        if let Some(f) = self.pending_fault {
            let mut buf = [0u8; FAULT_FRAME_LEN];
            // Cannot fail: the buffer fits and segments are below N ≤ 8.
            if let Ok(n) = encode_fault(&f, &mut buf) {
                if sink.try_write(&buf[..n]) {
                    self.pending_fault = None;
                }
            }
        }
        self.pending_fault.is_none()
    }

    /// Sends the pending Dropped frame; true if none is pending afterwards.
    fn send_pending_dropped(&mut self, sink: &mut impl FrameSink) -> bool {
        if let Some(d) = self.dropped {
            let mut buf = [0u8; DROPPED_FRAME_LEN];
            if let Ok(n) = encode_dropped(&d, &mut buf) {
                if sink.try_write(&buf[..n]) {
                    self.dropped = None;
                }
            }
        }
        self.dropped.is_none()
    }

    /// The board's [`Identity`]: an Info frame goes out at the next tick,
    /// before its Sample, and again on each RequestInfo.
    pub fn set_identity(&mut self, identity: Identity) {
        self.identity = Some(identity);
        self.info_pending = true;
    }

    /// What the Info frame says now, once the board has given its
    /// [`Identity`].
    pub fn info(&self) -> Option<Info> {
        let id = self.identity?;
        let c = &self.config;
        Some(Info {
            version: id.version,
            git_hash: id.git_hash,
            segments: N as u8,
            dac_segments: id.dac_segments,
            sample_hz: c.sample_hz,
            calibration: c.calibration,
            amps_per_count: c.amps_per_count,
            max_abs_v: self.limiter.limits().max_abs_v(),
            slew_v_per_s: self.limiter.limits().slew_v_per_s(),
            bridge_supply_v: id.bridge_supply_v,
            overcurrent_a: c.overcurrent_a,
            calibration_origin: self.calibration_origin,
            reset_cause: id.reset_cause,
            model_crc: self.model_crc,
        })
    }

    /// Sends the Info frame if one is due; if the sink refuses it, it stays
    /// due (it holds back nothing: it carries no sequence number).
    fn send_pending_info(&mut self, sink: &mut impl FrameSink) {
        if !self.info_pending {
            return;
        }
        let Some(info) = self.info() else { return };
        let mut buf = [0u8; INFO_FRAME_LEN];
        // The identity's DAC segments are the board's own: an encoding
        // error is a bug there, and the frame is dropped, not retried.
        let sent = match encode_info(&info, &mut buf) {
            Ok(n) => sink.try_write(&buf[..n]),
            Err(_) => true,
        };
        self.info_pending = !sent;
    }

    /// Takes `count` sequence numbers for samples never taken and adds them
    /// to the pending Dropped report.
    fn skip(&mut self, count: u64) {
        if count == 0 {
            return;
        }
        // A Dropped frame's count is a u32; numbers wrap at 2³² anyway.
        let count = u32::try_from(count).unwrap_or(u32::MAX);
        match &mut self.dropped {
            // Consecutive: the pending report ends at the sample before.
            Some(d) => d.count = d.count.saturating_add(count),
            None => {
                self.dropped = Some(Dropped {
                    first_seq: self.next_seq,
                    count,
                })
            }
        }
        self.next_seq = self.next_seq.wrapping_add(count);
        self.unseen_periods = self.unseen_periods.saturating_add(u64::from(count));
    }

    /// Sample periods no tick saw so far (the sample task ran more than a
    /// period late), each reported as a dropped sample.
    pub fn unseen_periods(&self) -> u64 {
        self.unseen_periods
    }

    /// Sends `s` after any pending Fault and Dropped frames, or counts it
    /// dropped; either way it consumes its sequence number.
    fn send_sample(&mut self, s: &Sample<N>, sink: &mut impl FrameSink) {
        self.next_seq = self.next_seq.wrapping_add(1);
        let mut buf = [0u8; MAX_FRAME_LEN];
        let sent = self.send_pending_fault(sink)
            && self.send_pending_dropped(sink)
            && match encode_sample(s, &mut buf) {
                Ok(n) => sink.try_write(&buf[..n]),
                Err(_) => false,
            };
        if !sent {
            match &mut self.dropped {
                // Consecutive: a pending report always ends at the sample
                // before this one, since nothing was sent in between.
                Some(d) => d.count = d.count.saturating_add(1),
                None => {
                    self.dropped = Some(Dropped {
                        first_seq: s.seq,
                        count: 1,
                    })
                }
            }
        }
    }
}
