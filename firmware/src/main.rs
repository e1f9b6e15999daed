//! The fin driver firmware: RTIC 2 glue between the board and
//! `finrs_controller`, which holds all the logic (fault checks, waves through
//! the one limiter, tare and scale, frames, commands).
//!
//! One app, two boards, chosen by cargo feature (see `board`):
//! - `board` (default): the STM32F407 fin driver. ADC1 is triggered by a
//!   timer at the sample rate; its end-of-conversion interrupt runs
//!   [`app::sample`]. Frames leave on RTT up channel 1, defmt on channel 0,
//!   commands arrive on down channel 0. `cd firmware && cargo run --release`
//!   flashes it through probe-rs.
//! - `qemu` (`--no-default-features --features qemu`): QEMU's netduinoplus2
//!   with the model core as plant; SysTick paces the sample interrupt, frames
//!   go to a host file through semihosting, defmt to semihosting stdout.
//!   With `qemu-serial`, the virtual bench: frames and commands over USART1
//!   and the bench's world (fixture, camera) over USART2, for `finrs bench
//!   run --qemu`.
#![no_std]
#![no_main]
#![deny(unsafe_code, missing_docs)]

#[cfg(all(feature = "board", feature = "qemu"))]
compile_error!(
    "one board at a time: build the QEMU board with `--no-default-features --features qemu`"
);
#[cfg(not(any(feature = "board", feature = "qemu")))]
compile_error!("no board chosen: use the default feature `board` or `--features qemu`");

mod board;
use finrs_firmware_support::config;
use finrs_firmware_support::identity;
#[cfg(feature = "qemu")]
use finrs_firmware_support::sim;
mod stack;
use finrs_firmware_support::watermark;

use rtic_monotonics::systick::prelude::*;

// 1 kHz: the QEMU pacer's period is one tick; the board paces from its ADC
// trigger timer and uses the monotonic only for the command poll.
systick_monotonic!(Mono, 1_000);

// Log lines carry the monotonic's time, ms since start.
defmt::timestamp!("{=u64:ms}", u64::from(Mono::now().as_ticks()));

/// Core clock, Hz: the board's PLL setting, and the fixed rate at which
/// QEMU's SysTick counts whatever RCC says.
pub const SYSCLK_HZ: u32 = 168_000_000;

/// Interval between polls of the command channel, ms.
const COMMAND_POLL_MS: u32 = 10;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [EXTI1, EXTI2, EXTI3])]
mod app {
    use super::*;
    use crate::board::{self, CommandIn, FrameOut, Housekeeping, Io};
    use crate::config::{self, N};
    use finrs_controller::model_holder::{Fits, HoldsModel, Pick};
    use finrs_controller::shaper::{self, ELEMENTS, MAX_SHAPED_SEGMENTS};
    use finrs_controller::{Controller, FaultCode, Identity};
    use finrs_frames::{Command, CommandDecoder, CommandEvent};
    use model_core::state_len;

    /// The state length of the board's model strip.
    const S: usize = state_len(N, ELEMENTS);
    /// The sample time the model's strip is discretised at, s.
    const DT_S: f64 = 1.0 / config::SAMPLE_HZ as f64;
    /// What this build holds a model in: a shaper, or above
    /// `MAX_SHAPED_SEGMENTS` nothing that takes RAM for a strip.
    type Models = <Fits<{ N <= MAX_SHAPED_SEGMENTS }> as Pick<N, ELEMENTS, S>>::Holder;

    #[shared]
    struct Shared {
        controller: Controller<N>,
    }

    #[local]
    struct Local {
        io: Io,
        frames: FrameOut,
        commands: CommandIn,
        housekeeping: Housekeeping,
        shaper: Models,
        stored_model: Option<finrs_frames::ModelRecord>,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        // First thing: the stack's guard, then init's stack use is
        // measured from here.
        stack::guard();
        stack::paint_init();
        let mut parts = board::init(cx.core, cx.device);
        let mut controller = match config::controller_config()
            .map_err(|_| "limits")
            .and_then(|c| Controller::<N>::new(c).map_err(|_| "controller"))
        {
            Ok(c) => c,
            // The configuration is compiled in: this is a build error that
            // only a run can show. The panic handler zeroes the outputs.
            Err(what) => defmt::panic!("invalid compiled-in configuration: {}", what),
        };
        // The Info frame goes before the first Sample.
        controller.set_identity(Identity {
            version: identity::version(env!("CARGO_PKG_VERSION")),
            git_hash: identity::git_hash(option_env!("FINRS_GIT_HASH")),
            dac_segments: config::DAC_SEGMENT_IDS,
            bridge_supply_v: parts.supply.map_or(config::BRIDGE_SUPPLY_V, |s| s.bridge_v),
            reset_cause: parts.reset_cause,
        });
        if let Some(stored) = parts.stored_calibration {
            if controller.use_stored_calibration(stored).is_err() {
                defmt::warn!("calibration: the stored record breaks a rule; build defaults");
            }
        }
        if parts.supply.is_err() {
            // Reported, and latched; the board also never drives (its
            // `write_v` holds every output off), whatever ClearFault does.
            controller.fault(FaultCode::Supply, None, &mut parts.frames);
        }
        defmt::info!(
            "fin driver up: {} segments at {} Hz, limit {} V",
            N,
            config::SAMPLE_HZ,
            config::POWER_UP_LIMIT_V
        );
        if commands::spawn().is_err() || pace::spawn().is_err() || housekeeping::spawn().is_err() {
            defmt::panic!("a task was spawned twice");
        }
        stack::record_init();
        (
            Shared { controller },
            Local {
                io: parts.io,
                frames: parts.frames,
                commands: parts.commands,
                housekeeping: parts.housekeeping,
                shaper: Models::empty(),
                stored_model: parts.stored_model,
            },
        )
    }

    /// One sample period: read the load cell and shunts, run the
    /// controller's tick, write the outputs, feed the watchdog. Bound to the
    /// ADC interrupt on both boards (QEMU's pacer pends it).
    #[task(binds = ADC, priority = 3, shared = [controller], local = [io, frames, latched: bool = false])]
    fn sample(mut cx: sample::Context) {
        let io = cx.local.io;
        let frames = cx.local.frames;
        // Numbered by the board's period count, not by this task's runs.
        let Some(input) = io.read() else {
            return;
        };
        // The bridge supply drifted (read this period): latched before the
        // tick, whose voltages are then 0 (`write_v` holds the outputs off
        // on its own while a reading is out of band).
        if let Some(e) = io.take_supply_fault() {
            cx.shared.controller.lock(|c| {
                // Once: a supply that stays out raises it every period.
                if c.fault_state().is_none() {
                    defmt::error!("{}", defmt::Display2Format(&e));
                    c.fault(FaultCode::Supply, None, frames);
                }
            });
        }
        let (out, faulted, to_store, model_to_store) = cx.shared.controller.lock(|c| {
            let out = c.tick(&input, frames);
            (
                out,
                c.fault_state().is_some(),
                c.take_calibration_to_store(),
                c.take_model_to_store(),
            )
        });
        // A latched fault keeps the outputs off: the controller's 0 V would
        // hold a bridge braked, not open.
        io.write_v((!faulted).then_some(&out.voltages_v));
        io.feed_watchdog();
        // Only this task moves it: a core that stops lets the bridges sleep.
        io.keep_alive(!faulted);
        // Here, where the watchdog is, with the outputs at 0 V (the
        // controller takes a calibration only then): the write overruns
        // this tick on purpose, and the periods it hides go out as dropped
        // samples, not as a missed deadline.
        let stored = to_store.is_some() || model_to_store.is_some();
        if let Some(calibration) = to_store {
            let ok = io.store_calibration(&calibration);
            cx.shared.controller.lock(|c| c.calibration_stored(ok));
        }
        // Likewise a model (its write's outcome is in the log only).
        if let Some(record) = model_to_store {
            io.store_model(&record);
        }
        // The next period's conversion already finished: this one overran.
        if io.deadline_missed() && !stored {
            cx.shared
                .controller
                .lock(|c| c.fault(FaultCode::MissedDeadline, None, frames));
        }
        let fault = cx.shared.controller.lock(|c| c.fault_state());
        if let Some((code, segment)) = fault {
            // A fault raised after this tick's write: off at once (while one
            // is latched, `write_v` already keeps the outputs off).
            if !faulted {
                io.off();
            }
            if !*cx.local.latched {
                *cx.local.latched = true;
                defmt::error!(
                    "fault latched at tick {}: {} (segment {})",
                    input.tick,
                    fault_name(code),
                    segment
                );
            }
        } else {
            *cx.local.latched = false;
        }
    }

    /// Reads the command channel, decodes, and hands commands to the
    /// controller, a model or a motion through the shaper first (outside
    /// the controller's lock: building the model's strip takes
    /// milliseconds); refusals (framing or value) are logged and change
    /// nothing.
    #[task(priority = 1, shared = [controller], local = [commands, shaper, stored_model, decoder: CommandDecoder = CommandDecoder::new()])]
    async fn commands(mut cx: commands::Context) {
        // The model stored last, checked as a SetModel's is: here, at the
        // lowest priority, not in `init`, where building its strip would
        // hold the first samples back.
        if let Some(record) = cx.local.stored_model.take() {
            match Models::check(&record, DT_S) {
                Ok(model) => {
                    cx.shared.controller.lock(|c| c.use_stored_model(&record));
                    cx.local.shaper.install(model);
                    defmt::info!("model: {=u16:04x} from flash", record.crc());
                }
                Err(e) => defmt::warn!(
                    "model: the stored record is refused: {}",
                    defmt::Display2Format(&e.brief())
                ),
            }
        }
        let mut buf = [0u8; 64];
        loop {
            let n = cx.local.commands.read(&mut buf);
            let controller = &mut cx.shared.controller;
            let shaper = &mut *cx.local.shaper;
            cx.local.decoder.push(&buf[..n], &mut |event| match event {
                CommandEvent::Command(command) => {
                    let name = command_name(&command);
                    match shaper::command(command, shaper, DT_S, controller) {
                        Ok(_) => defmt::info!("command accepted: {}", name),
                        // The message names the command, the field and the rule.
                        Err(e) => defmt::error!("{}", defmt::Display2Format(&e.brief())),
                    }
                }
                CommandEvent::Refused(e) => {
                    defmt::error!("command refused: {}", defmt::Display2Format(&e))
                }
            });
            Mono::delay(COMMAND_POLL_MS.millis()).await;
        }
    }

    /// Paces the sample task where no hardware does (QEMU).
    #[task(priority = 4)]
    async fn pace(_: pace::Context) {
        board::pace().await
    }

    /// Board chores at low priority (QEMU: flush frames, end the run;
    /// both: report the stack's use). Above the command task: a model's
    /// check there takes tens of milliseconds, which would hold QEMU's
    /// frame flush back until its queue overflowed.
    #[task(priority = 2, local = [housekeeping])]
    async fn housekeeping(cx: housekeeping::Context) {
        // The tasks' stack use is measured from here on (init's is kept).
        stack::repaint_for_tasks();
        board::housekeeping(cx.local.housekeeping).await
    }

    /// The command's name for the log (its values would pull in core's
    /// float formatting, several KiB of flash).
    fn command_name(command: &Command) -> &'static str {
        match command {
            Command::SetWave { .. } => "SetWave",
            Command::Tare => "Tare",
            Command::Stop => "Stop",
            Command::SetLimit { .. } => "SetLimit",
            Command::ClearFault => "ClearFault",
            Command::RequestInfo => "RequestInfo",
            Command::SetCalibration(_) => "SetCalibration",
            Command::SetModel(_) => "SetModel",
            Command::SetMotion { .. } => "SetMotion",
        }
    }

    fn fault_name(code: FaultCode) -> &'static str {
        match code {
            FaultCode::Overcurrent => "overcurrent",
            FaultCode::AdcSaturation => "ADC saturation",
            FaultCode::MissedDeadline => "missed deadline",
            FaultCode::Other => "other",
            FaultCode::Supply => "supply out of range",
        }
    }
}
