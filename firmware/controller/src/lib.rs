//! `finrs-controller`: the fin driver firmware's hardware-independent
//! logic. `no_std`, allocation-free, f32; the RTIC app calls it once per
//! sample tick with the ADC readings, writes the voltages it returns to the
//! segments' drivers ([`HBridge`] or [`DacOutput`]), hands it the host's
//! commands ([`finrs_frames::Command`]) and faults found outside (missed
//! deadline, watchdog), and gives it a [`FrameSink`] for the up channel.
//! A SetModel or a SetMotion goes through the [`shaper`] first, which
//! holds the fitted model and turns a motion into each segment's sine
//! outside the controller's lock. Everything here runs in the host's
//! tests.
//!
//! # A tick
//!
//! [`Controller::tick`], in this order:
//!
//! 1. Converts the readings: currents i = (counts − zero) · A/count.
//! 2. Tare: an unsaturated load-cell reading joins the tare in progress.
//! 3. Checks the readings: |i| above `overcurrent_a` on any segment, a
//!    current channel or the load cell saturated (within
//!    `saturation_margin_counts` of either end). A fault found when none is
//!    latched latches (below), and the tick ends there with zeros and a
//!    Fault frame instead of a Sample.
//! 4. Voltages: zeros at once while a fault is latched
//!    ([`Limiter::stop`](finrs_drive::Limiter::stop)); otherwise the
//!    program's voltages at its own tick count
//!    ([`Generator::voltages_at_tick_v`](finrs_drive::Generator::voltages_at_tick_v))
//!    or 0 V when stopped, through the one
//!    [`Limiter`](finrs_drive::Limiter) with dt = 1/`sample_hz`. These are
//!    both the [`TickOutput`] and the voltages in the Sample frame.
//! 5. Frames: a pending Fault frame, then a pending Dropped frame, then the
//!    Sample {seq, t_us, force = (counts − tare) · N/count, voltages,
//!    currents}. Each goes only if everything before it went.
//!
//! # Drop accounting
//!
//! The sink never blocks: it takes a whole frame or refuses it. As the
//! frames crate's docs require, every Sample takes the next sequence
//! number whether it is sent or not. A Sample not sent (refused, or held
//! back because a Fault or Dropped frame before it was refused) starts or
//! extends one pending report {first_seq, count}; the samples it covers are
//! always consecutive, because none was sent since it started. The report
//! goes out as one Dropped frame right before the next Sample that is sent,
//! and no Sample is sent until it has: so every hole in the numbers is
//! covered by a Dropped frame, and the host's decoder sees no
//! [`Gap`](finrs_frames::Event::Gap). (The count saturates at 2³² − 1, 49
//! days of a sink refusing everything at 1 kHz.)
//!
//! # Fault latch
//!
//! A fault (overcurrent, ADC saturation, or one from outside through
//! [`Controller::fault`]) zeroes every output at once, bypassing the slew
//! limit (a fault means the hardware may be in danger), and latches: while
//! latched every output is exactly 0 V, SetWave is refused, and later
//! faults do not replace the first. Its Fault frame carries the sequence
//! number of the Sample being produced (it consumes none); if the sink
//! refuses it, it waits and goes before anything else, and ClearFault is
//! refused until it has gone: a fault is never lost nor cleared unseen.
//! ClearFault leaves the outputs at 0 V until a new SetWave: restarting a
//! wave is the host's explicit decision. Samples keep flowing while
//! latched (zero voltages, live force and currents), so the host sees what
//! the strip does.
//!
//! # Tare
//!
//! A tare averages the next `tare_samples` unsaturated load-cell readings;
//! meanwhile frames keep flowing with the previous offset, and a Tare
//! command during a tare restarts it. At power-up there is no previous
//! offset: force is relative to the first unsaturated reading until the
//! first tare is done (honest readings rather than invented zeros).
//!
//! # Power-up
//!
//! The controller starts stopped: outputs at 0 V while the first tare
//! measures the zero with the strip unpowered, and still at 0 V after it,
//! until the host sends a SetWave. Nothing drives the strip by itself after
//! a reset, a watchdog's in a crash loop included. A SetWave sent during
//! that first tare waits for it and starts at its time 0 on the tick that
//! completes it (a Stop during the tare cancels it). A Tare command while
//! a wave runs measures the loaded strip: Stop first for a true zero.
//!
//! # Commands
//!
//! See [`Controller::command`]. SetWave is validated by
//! [`Generator::new`](finrs_drive::Generator::new) (refused with its field
//! and rule) and starts at the next tick with its own time 0; the slew
//! limit keeps the outputs continuous. SetLimit may only lower the voltage
//! limit, which takes effect at once (the limiter clamps at the next tick,
//! stepping down faster than the slew limit if need be). Stop slews the
//! outputs to 0 V and keeps them there until a SetWave. A refused command
//! changes nothing.
//!
//! # Safety invariant
//!
//! Whatever the ticks, readings and commands: every output satisfies |v| ≤
//! the `max_abs_v` in force (≤ [`HARD_LIMIT_V`](finrs_drive::HARD_LIMIT_V)),
//! each step from the previous output (clamped to the limit in force) is at
//! most `slew_v_per_s` · dt, and while a fault is latched every output is
//! exactly 0. `tests/safety.rs` checks this over random sequences.
//!
//! # Example
//!
//! ```
//! use finrs_controller::{Calibration, Config, Controller, FrameSink, TickInput};
//! use finrs_drive::Limits;
//!
//! struct Channel(Vec<u8>);
//! impl FrameSink for Channel {
//!     fn try_write(&mut self, frame: &[u8]) -> bool {
//!         self.0.extend_from_slice(frame);
//!         true
//!     }
//! }
//!
//! let config = Config {
//!     sample_hz: 1000,
//!     limits: Limits::new(2.0, 100.0).unwrap(),
//!     calibration: Calibration {
//!         newtons_per_count: 1e-4,
//!         current_zero_counts: [2048; 8],
//!     },
//!     adc_full_scale: 4095,
//!     saturation_margin_counts: 2,
//!     amps_per_count: 1e-3,
//!     overcurrent_a: 0.5,
//!     tare_samples: 100,
//! };
//! let mut controller = Controller::<3>::new(config).unwrap();
//! let mut up = Channel(Vec::new());
//! // Stopped until asked: the host's wave, which waits for the first tare.
//! let (program, envelope) = finrs_drive::default_program();
//! controller
//!     .command(finrs_frames::Command::SetWave { program, envelope })
//!     .unwrap();
//! for tick in 0..2000u64 {
//!     let input = TickInput {
//!         tick,
//!         t_us: (tick * 1000) as u32,
//!         load_cell_counts: 2100,
//!         current_counts: [2048; 3],
//!     };
//!     let out = controller.tick(&input, &mut up);
//!     assert!(out.voltages_v.iter().all(|v| v.abs() <= 2.0));
//! }
//! assert_eq!(controller.tare_offset_counts(), 2100.0);
//! assert_eq!(controller.next_seq(), 2000);
//! assert!(controller.running());
//! ```

#![no_std]
#![deny(missing_docs, unsafe_code)]

mod config;
mod controller;
pub mod model_holder;
mod output;
pub mod shaper;
pub mod tracker;

pub use config::{Config, ConfigError, ConfigRule};
pub use controller::{CommandRefused, Controller, FrameSink, Identity, TickInput, TickOutput};
pub use finrs_frames::{Calibration, CalibrationOrigin, FaultCode};
pub use output::{DacOutput, DacWrite, HBridge, OutputError, SegmentOutput, DAC_MAX_CODE};
