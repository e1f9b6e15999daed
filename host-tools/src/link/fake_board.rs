//! A board for the host's tests: the firmware's own controller on
//! simulated sensors with known true zeros and scale, a load set by the
//! test, and a strip whose blocking force follows the mean drive voltage
//! through a first-order lag; 50 ticks (50 ms) per read. Its frames go
//! through a channel of the board's size that refuses a frame that does
//! not fit, as RTT does, so that a pause of the host (an operator's
//! prompt, [`FakeBoard::pause`]) leaves the oldest frames buffered and
//! the rest dropped, as on the board.

use std::cell::Cell;
use std::rc::Rc;

use finrs_controller::shaper::{self, Exclusive, Shaper, ELEMENTS};
use finrs_controller::{Config, Controller, FrameSink, Identity, TickInput};
use finrs_drive::Limits;
use finrs_frames::{Calibration, Command, CommandDecoder, CommandEvent, ResetCause};

use crate::link::board::Board;
use crate::link::capture::Link;
use crate::link::probe::ProbeError;

pub const N: usize = 3;
pub const NOMINAL_SCALE: f32 = 2.5e-5;
pub const TRUE_SCALE: f64 = 3.1e-5;
pub const TRUE_ZEROS: [u16; N] = [2056, 2041, 2048];
pub const AMPS_PER_COUNT: f32 = 2.5e-4;
/// The board's sample rate, Hz (its model's strip is discretised at it).
const SAMPLE_HZ: u32 = 1000;

/// The board's RTT up channel for frames at N = 3, bytes.
const CHANNEL_BYTES: usize = 8192;

/// Frames waiting for the host; a frame that does not fit is refused.
struct Channel(Vec<u8>);

impl FrameSink for Channel {
    fn try_write(&mut self, frame: &[u8]) -> bool {
        if self.0.len() + frame.len() > CHANNEL_BYTES {
            return false;
        }
        self.0.extend_from_slice(frame);
        true
    }
}

/// The firmware's controller on simulated sensors: a load (N, set by the
/// test), the shunts at their true zeros plus a decaying discharge, and
/// ±`noise` counts of noise; 50 ticks per read.
pub struct FakeBoard {
    pub c: Controller<N>,
    tick: u64,
    decoder: CommandDecoder,
    shaper: Shaper<N, ELEMENTS, { model_core::state_len(N, ELEMENTS) }>,
    load_n: Rc<Cell<f64>>,
    noise: u32,
    rng: u32,
    /// Counts added to every shunt at tick 0, decaying with `tau_ticks`.
    pub discharge_counts: f64,
    pub tau_ticks: f64,
    pub stores: usize,
    /// The last model handed over to store.
    pub stored_model: Option<finrs_frames::ModelRecord>,
    /// The strip's blocking force, N, lagging the mean voltage.
    pub strip_force_n: f64,
    /// Blocking force per volt of mean drive at steady state, N/V.
    pub newtons_per_volt: f64,
    last_v: [f32; N],
    /// Ticks to run before the next read with nobody reading (set by a
    /// test's prompt), then the load to put on.
    pub pause: Rc<Cell<(u64, Option<f64>)>>,
    channel: Channel,
}

impl FakeBoard {
    pub fn new(load_n: Rc<Cell<f64>>) -> Self {
        let config = Config {
            sample_hz: SAMPLE_HZ,
            limits: Limits::new(3.64, 200.0).unwrap(),
            calibration: Calibration {
                newtons_per_count: NOMINAL_SCALE,
                current_zero_counts: [2048; 8],
            },
            adc_full_scale: 4095,
            saturation_margin_counts: 8,
            amps_per_count: AMPS_PER_COUNT,
            overcurrent_a: 0.4,
            tare_samples: 200,
        };
        let mut c = Controller::new(config).unwrap();
        c.set_identity(Identity {
            version: [0, 1, 0],
            git_hash: 0,
            dac_segments: [None, None],
            bridge_supply_v: 5.0,
            reset_cause: ResetCause::PowerOn,
        });
        Self {
            c,
            tick: 0,
            decoder: CommandDecoder::new(),
            shaper: Shaper::new(),
            load_n,
            noise: 3,
            rng: 0x1234_5678,
            discharge_counts: 0.0,
            tau_ticks: 1.0,
            stores: 0,
            stored_model: None,
            strip_force_n: 0.0,
            newtons_per_volt: 1e-3,
            last_v: [0.0; N],
            pause: Rc::new(Cell::new((0, None))),
            channel: Channel(Vec::new()),
        }
    }

    fn noise(&mut self) -> f64 {
        let x = finrs_firmware_support::sim::xorshift32(&mut self.rng);
        f64::from(x % (2 * self.noise + 1)) - f64::from(self.noise)
    }
}

impl FakeBoard {
    /// Runs a pause the test asked for (it is over before the host does
    /// anything else), then puts on its load.
    fn catch_up(&mut self) {
        let (ticks, load) = self.pause.replace((0, None));
        self.run(ticks);
        if let Some(l) = load {
            self.load_n.set(l);
        }
    }

    /// `ticks` sample periods, their frames into the channel.
    fn run(&mut self, ticks: u64) {
        for _ in 0..ticks {
            // The strip's force lags the mean voltage by 50 ms.
            let mean_v = self.last_v.iter().map(|&v| f64::from(v)).sum::<f64>() / N as f64;
            self.strip_force_n += (self.newtons_per_volt * mean_v - self.strip_force_n) / 50.0;
            let load_counts =
                2000.0 + (self.load_n.get() + self.strip_force_n) / TRUE_SCALE + self.noise();
            let discharge = self.discharge_counts * (-(self.tick as f64) / self.tau_ticks).exp();
            let current_counts = std::array::from_fn(|k| {
                (f64::from(TRUE_ZEROS[k]) + discharge + self.noise()) as u16
            });
            let applied = self.c.tick(
                &TickInput {
                    tick: self.tick,
                    t_us: (self.tick * 1000) as u32,
                    load_cell_counts: load_counts.round() as u16,
                    current_counts,
                },
                &mut self.channel,
            );
            self.last_v = applied.voltages_v;
            // Stored at once, as the board stores them at 0 V.
            if let Some(model) = self.c.take_model_to_store() {
                self.stored_model = Some(model);
            }
            if self.c.take_calibration_to_store().is_some() {
                self.stores += 1;
                self.c.calibration_stored(true);
            }
            self.tick += 1;
        }
    }
}

impl Link for FakeBoard {
    fn read_force(&mut self, buf: &mut [u8]) -> Result<usize, ProbeError> {
        self.catch_up();
        self.run(50);
        let n = self.channel.0.len().min(buf.len());
        buf[..n].copy_from_slice(&self.channel.0[..n]);
        self.channel.0.drain(..n);
        Ok(n)
    }

    fn read_log(&mut self, _: &mut [u8]) -> Result<usize, ProbeError> {
        Ok(0)
    }
}

impl Board for FakeBoard {
    fn send(&mut self, command: &Command) -> Result<(), ProbeError> {
        self.catch_up();
        let bytes = crate::link::command::encode(command);
        let mut c = Exclusive(&mut self.c);
        let shaper = &mut self.shaper;
        self.decoder.push(&bytes, &mut |e| {
            if let CommandEvent::Command(cmd) = e {
                // A refusal changes nothing, as on the board.
                let _ = shaper::command(cmd, shaper, 1.0 / f64::from(SAMPLE_HZ), &mut c);
            }
        });
        Ok(())
    }
}
