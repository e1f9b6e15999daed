//! Helpers shared by the tests: a configurable sink that keeps what it
//! accepts, decoding it with the frames crate, and a typical config.
#![allow(dead_code)] // each test binary uses a different subset

use finrs_controller::shaper::{command, Shaped, Shaper, ELEMENTS};
use finrs_controller::{Config, Controller, FrameSink, Identity};
use finrs_drive::Limits;
use finrs_frames::{Command, ModelRecord, Motion, StripModel};
use finrs_frames::{Decoder, Event, ResetCause, Stats};
use model_core::{state_len, Phasor};
use rtic_core::Exclusive;

/// A sink that accepts or refuses each frame as told, and keeps the bytes
/// of those it accepts.
#[derive(Default)]
pub struct Channel {
    pub bytes: Vec<u8>,
    /// Refuse every frame while set.
    pub full: bool,
    /// Frames offered so far (accepted or not).
    pub offered: usize,
    /// Accept only the frames whose length is at most this, if set.
    pub max_len: Option<usize>,
    /// Refuse this many frames before accepting again.
    pub refuse_next: usize,
}

impl FrameSink for Channel {
    fn try_write(&mut self, frame: &[u8]) -> bool {
        self.offered += 1;
        if self.refuse_next > 0 {
            self.refuse_next -= 1;
            return false;
        }
        if self.full || self.max_len.is_some_and(|m| frame.len() > m) {
            return false;
        }
        self.bytes.extend_from_slice(frame);
        true
    }
}

impl Channel {
    /// Decodes everything accepted so far.
    pub fn events(&self) -> (Vec<Event>, Stats) {
        let mut d = Decoder::new();
        let mut events = Vec::new();
        d.push(&self.bytes, &mut |e| events.push(e));
        d.finish(&mut |e| events.push(e));
        (events, d.stats())
    }

    /// Takes the accepted bytes' events and clears the buffer.
    pub fn take_events(&mut self) -> Vec<Event> {
        let (e, _) = self.events();
        self.bytes.clear();
        e
    }
}

pub fn config() -> Config {
    Config {
        sample_hz: 1000,
        limits: Limits::new(2.0, 100.0).unwrap(),
        calibration: finrs_frames::Calibration {
            newtons_per_count: 1e-3,
            current_zero_counts: [2048; 8],
        },
        adc_full_scale: 4095,
        saturation_margin_counts: 2,
        amps_per_count: 1e-3,
        overcurrent_a: 0.5,
        tare_samples: 10,
    }
}

/// The readings of tick `tick` (1 kHz: `t_us` = 1000 · `tick`).
pub fn input<const N: usize>(
    tick: u64,
    load_cell_counts: u16,
    current_counts: [u16; N],
) -> finrs_controller::TickInput<N> {
    finrs_controller::TickInput {
        tick,
        t_us: (tick * 1000) as u32,
        load_cell_counts,
        current_counts,
    }
}

/// Three segments past the power-up tare at 1000 counts (shunts at 2048),
/// with an identity (its first Info taken), the channel emptied; and the
/// next tick's number.
pub fn tared() -> (Controller<3>, Channel, u64) {
    let mut c = Controller::<3>::new(config()).unwrap();
    c.set_identity(Identity {
        version: [0, 1, 0],
        git_hash: 0,
        dac_segments: [None, None],
        bridge_supply_v: 5.0,
        reset_cause: ResetCause::PowerOn,
    });
    let mut ch = Channel::default();
    for tick in 0..10 {
        c.tick(&input(tick, 1000, [2048; 3]), &mut ch);
    }
    assert!(!c.taring());
    ch.bytes.clear();
    (c, ch, 10)
}

/// A SetMotion of `motion` rising over `ramp_in_s`, held for ever, from
/// `t_session_s`, tracked or not.
pub fn set_motion(motion: Motion, ramp_in_s: f32, t_session_s: f32, tracked: bool) -> Command {
    Command::SetMotion {
        motion,
        envelope: finrs_drive::Envelope {
            ramp_in_s,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
        t_session_s,
        tracked,
    }
}

/// The phasor `Y` of an output `Re(Y e^{jθk})` of a 1 Hz motion sampled
/// at 1 kHz, by lock-in over the last 10 s of a run of `steps` ticks.
pub struct LastTenSeconds {
    steps: u64,
    y: Phasor,
}

impl LastTenSeconds {
    /// For a run of `steps` ticks.
    pub fn new(steps: u64) -> Self {
        Self {
            steps,
            y: Phasor::ZERO,
        }
    }

    /// `value`, the output at sample `k` (the state after tick `k − 1`).
    pub fn add(&mut self, k: u64, value: f64) {
        if k + 10_000 >= self.steps {
            let theta = 2.0 * core::f64::consts::PI / 1000.0;
            self.y += Phasor::unit(-theta * k as f64).scale(2.0 * value / 10_000.0);
        }
    }

    /// `Y`.
    pub fn phasor(&self) -> Phasor {
        self.y
    }
}

/// The amplitude error of `y` against `amplitude` (a fraction) and its
/// phase, degrees.
pub fn error_against(y: Phasor, amplitude: f64) -> (f64, f64) {
    (
        y.amplitude() / amplitude - 1.0,
        y.sine_phase_rad().to_degrees(),
    )
}

/// The state length of the board's model strip for 3 segments.
pub const S3: usize = state_len(3, ELEMENTS);

/// A 3-segment controller on `config` past its tare, its channel and next
/// tick, and a shaper holding `m` (the SetModel taken).
pub fn tared_with_model(
    config: Config,
    m: &StripModel,
) -> (Controller<3>, Channel, u64, Shaper<3, ELEMENTS, S3>) {
    let mut c = Controller::<3>::new(config).unwrap();
    let mut ch = Channel::default();
    let mut tick = 0;
    while c.taring() {
        c.tick(&input(tick, 1000, [2048; 3]), &mut ch);
        tick += 1;
    }
    let mut shaper = Shaper::new();
    let set = Command::SetModel(ModelRecord::encode(m));
    assert_eq!(
        command(set, &mut shaper, 1e-3, &mut Exclusive(&mut c)),
        Ok(Shaped::ModelSet)
    );
    (c, ch, tick, shaper)
}
