//! The simulated board: QEMU's netduinoplus2 (STM32F405, the same Cortex-M4F
//! and memory map as the STM32F407) with the model core as plant.
//!
//! - The segment outputs feed `model_core::Strip` (the example session's parameters,
//!   blocked fixture, stepped once per sample with the voltages the
//!   controller commanded; with `plant-damping`, a damped strip; with
//!   `plant-drying`, one that dries from boot); the load-cell ADC reads the plant's blocking
//!   force in counts ([`NEWTONS_PER_COUNT`], zero at
//!   [`sim::LOAD_CELL_ZERO_COUNTS`]) with deterministic xorshift noise of at
//!   most [`sim::LOAD_CELL_NOISE_COUNTS`] before the rounding; the shunts
//!   read the plant's segment currents, with at most
//!   [`sim::SHUNT_NOISE_COUNTS`].
//! - QEMU emulates neither the clock tree nor reliable TIM timing, but its
//!   SysTick counts at 168 MHz: [`pace`] pends the ADC interrupt (the sample
//!   task) every millisecond from the SysTick monotonic.
//! - There is no RTT: frames go to the host file [`FRAMES_FILE`] (in QEMU's
//!   working directory) through semihosting, defmt to semihosting stdout,
//!   so the two streams never mix. Frames are queued by the sample task and
//!   written in batches every [`FLUSH_MS`] ms by the low-priority
//!   housekeeping task, so a semihosting call never sits in the 1 ms path.
//! - Commands, if the host file [`COMMANDS_FILE`] exists, are read from it
//!   as from the board's RTT down channel.
//! - After [`sim::RUN_S`] simulated seconds the run flushes and exits
//!   through semihosting; a panic or HardFault exits with a failure code
//!   (the board's `udf`, which stops the core for probe-rs, would hang QEMU).
//! - With `qemu-serial` (the virtual bench, see [`serial`]) frames and
//!   commands go over USART1 to a host that sends them as it goes, instead
//!   of the two files, and the run goes on until QEMU is stopped. The files
//!   stay for the SIL tests: a script of commands read at boot makes their
//!   runs repeat exactly.

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m::peripheral::NVIC;
use cortex_m_semihosting::debug;
#[cfg(not(feature = "qemu-serial"))]
use cortex_m_semihosting::{nr, syscall};
use defmt_semihosting as _;
use finrs_controller::{FrameSink, SegmentOutput, TickInput};
use heapless::spsc::{Consumer, Producer, Queue};
use model_core::{state_len, Extensions, Fixture, Params, Strip};
use rtic_monotonics::systick::prelude::*;
use stm32f4xx_hal::pac::{self, Interrupt};

use super::Parts;
use crate::config::{
    AMPS_PER_COUNT, CURRENT_ZERO_COUNTS, N, NEWTONS_PER_COUNT, OVERCURRENT_A, SAMPLE_HZ,
};
use crate::{sim, Mono, SYSCLK_HZ};

#[cfg(feature = "qemu-serial")]
mod serial;
#[cfg(feature = "qemu-serial")]
mod world;

/// The host file the frames go to, relative to QEMU's working directory.
#[cfg(not(feature = "qemu-serial"))]
pub const FRAMES_FILE: &str = "finrs-frames.bin\0";

/// The host file commands are read from, if it exists.
#[cfg(not(feature = "qemu-serial"))]
pub const COMMANDS_FILE: &str = "finrs-commands.bin\0";

/// Interval between flushes of the frame queue, ms.
pub const FLUSH_MS: u32 = 20;

/// Frame queue, bytes: 43-byte frames (N = 3) at 1 kHz fill 860 bytes per
/// flush interval; 4096 leaves a margin of almost five intervals (of about
/// two and a half with N = 8's 83-byte frames, which the SIL test also runs).
const QUEUE_LEN: usize = 4096;

const S: usize = state_len(N, 1);
/// The run's length in ticks; none for the virtual bench, whose run goes
/// on until QEMU is stopped.
const RUN_TICKS: Option<u64> = if cfg!(feature = "qemu-serial") {
    None
} else {
    Some(sim::RUN_S as u64 * SAMPLE_HZ as u64)
};

/// Set when the run's time is up; the housekeeping task then exits.
static DONE: AtomicBool = AtomicBool::new(false);

/// A segment output that holds the voltage the plant sees.
#[derive(Clone, Copy, Default)]
struct PlantSegment {
    v: f32,
}

impl SegmentOutput for PlantSegment {
    fn set_v(&mut self, v: f32) {
        self.v = v;
    }
    fn off(&mut self) {
        self.v = 0.0;
    }
}

/// The simulated ADC inputs and segment outputs.
pub struct Io {
    /// In a static: the model (9 KiB for N = 8) then never passes through
    /// `Parts` and RTIC's resource hand-over, which would copy it on the
    /// stack several times.
    plant: &'static Strip<f32, N, 1, S>,
    x: [f32; S],
    segments: [PlantSegment; N],
    currents_a: [f32; N],
    noise: u32,
    /// Sample periods so far: the pacer pends one sample task per period,
    /// so here the count is the tasks'.
    tick: u64,
    /// The bridge supply read every period, as on the board (QEMU's holds
    /// at its boot value); `None` if the supplies were out of range at
    /// boot: nothing is ever driven then, nor while the last reading is
    /// out of the monitor's band (as on the board).
    monitor: Option<finrs_firmware_support::supply::SupplyMonitor>,
    /// This period's reading, if out of the band.
    supply_fault: Option<finrs_firmware_support::supply::SupplyError>,
    /// The virtual bench's clamp and camera: the plant above is then the
    /// blocked strip, used while the world says blocked.
    #[cfg(feature = "qemu-serial")]
    world: world::World,
}

/// Frames into the queue that housekeeping flushes.
pub struct FrameOut {
    queue: Producer<'static, u8>,
}

impl FrameSink for FrameOut {
    fn try_write(&mut self, frame: &[u8]) -> bool {
        // All or nothing: only start if the whole frame fits.
        if self.queue.capacity() - self.queue.len() < frame.len() {
            return false;
        }
        frame.iter().all(|&b| self.queue.enqueue(b).is_ok())
    }
}

/// The down channel's stand-in: the host file `COMMANDS_FILE` in QEMU's
/// working directory, read through semihosting as it goes (no file, no
/// commands); with `qemu-serial`, USART1's received bytes.
pub struct CommandIn {
    #[cfg(not(feature = "qemu-serial"))]
    fd: Option<usize>,
}

impl CommandIn {
    /// Reads the bytes USART1 received into `buf` (0 when none came).
    #[cfg(feature = "qemu-serial")]
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        serial::LINK_RX.read(buf)
    }

    /// Reads the next command bytes into `buf` (0 at the end of the file).
    #[cfg(not(feature = "qemu-serial"))]
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        let Some(fd) = self.fd else {
            return 0;
        };
        // SAFETY: READ writes at most `buf.len()` bytes into the slice we
        // borrow mutably.
        #[allow(unsafe_code)]
        let not_read = unsafe { syscall!(READ, fd, buf.as_mut_ptr(), buf.len()) };
        match buf.len().checked_sub(not_read) {
            Some(n) => n,
            None => {
                defmt::error!("reading the commands file failed; no more commands");
                self.fd = None;
                0
            }
        }
    }
}

/// The flushing side of the frame queue and the semihosting file (or,
/// with `qemu-serial`, USART1's transmitter).
pub struct Housekeeping {
    queue: Consumer<'static, u8>,
    #[cfg(not(feature = "qemu-serial"))]
    fd: usize,
    #[cfg(feature = "qemu-serial")]
    tx: serial::Tx<pac::USART1>,
    /// The world's messages (camera frames), flushed to USART2.
    #[cfg(feature = "qemu-serial")]
    world_queue: Consumer<'static, u8>,
    #[cfg(feature = "qemu-serial")]
    world_tx: serial::Tx<pac::USART2>,
    batch: [u8; 1024],
}

/// Sets up the simulated board.
///
/// Not inlined: the plant's set-up (`Strip::new`) needs tens of KiB of
/// stack for a moment; inlined into RTIC's `main`, whose frame lives as long
/// as the program, it would stay reserved below every task.
#[inline(never)]
// Without `qemu-serial` the link is two host files: USART1 and the NVIC
// stay unused.
#[cfg_attr(not(feature = "qemu-serial"), allow(unused_mut, unused_variables))]
pub fn init(mut core: cortex_m::Peripherals, device: pac::Peripherals) -> Parts {
    // No clock setup: QEMU does not emulate RCC (waiting for the PLL would
    // hang); SysTick runs at 168 MHz regardless.
    Mono::start(core.SYST, SYSCLK_HZ);
    let built = Strip::with_extensions(
        &plant_params(),
        &plant_extensions(),
        Fixture::Blocked,
        1.0 / f64::from(SAMPLE_HZ),
    );
    let supply = supplies();
    if let Err(e) = &supply {
        defmt::error!("{}", defmt::Display2Format(e));
    }
    let plant = match built {
        Ok(p) => cortex_m::singleton!(: Strip<f32, N, 1, S> = p),
        Err(_) => defmt::panic!("the example session's parameters do not make a plant"),
    };
    let Some(plant) = plant else {
        defmt::panic!("board init ran twice");
    };
    let plant: &'static Strip<f32, N, 1, S> = plant;
    let Some(queue) = cortex_m::singleton!(: Queue<u8, QUEUE_LEN> = Queue::new()) else {
        defmt::panic!("board init ran twice");
    };
    let (producer, consumer) = queue.split();
    #[cfg(not(feature = "qemu-serial"))]
    let fd = match open_host_file(FRAMES_FILE, nr::open::W_TRUNC_BINARY) {
        Some(fd) => fd,
        None => defmt::panic!("cannot open the frames file through semihosting"),
    };
    let x = plant.rest();
    #[cfg(feature = "qemu-serial")]
    let (world, world_queue) = world_parts();
    Parts {
        io: Io {
            plant,
            x,
            segments: [PlantSegment::default(); N],
            currents_a: [0.0; N],
            noise: sim::NOISE_SEED,
            tick: 0,
            monitor: supply
                .ok()
                .map(finrs_firmware_support::supply::SupplyMonitor::new),
            supply_fault: None,
            #[cfg(feature = "qemu-serial")]
            world,
        },
        frames: FrameOut { queue: producer },
        commands: CommandIn {
            #[cfg(not(feature = "qemu-serial"))]
            fd: open_host_file(COMMANDS_FILE, nr::open::R_BINARY),
        },
        housekeeping: Housekeeping {
            queue: consumer,
            #[cfg(not(feature = "qemu-serial"))]
            fd,
            #[cfg(feature = "qemu-serial")]
            tx: serial::enable(device.USART1, Interrupt::USART1, &mut core.NVIC),
            #[cfg(feature = "qemu-serial")]
            world_queue,
            #[cfg(feature = "qemu-serial")]
            world_tx: serial::enable(device.USART2, Interrupt::USART2, &mut core.NVIC),
            batch: [0; 1024],
        },
        // QEMU's netduinoplus2 has no reset flags to read, and no supplies.
        reset_cause: finrs_frames::ResetCause::Unknown,
        supply,
        // No flash to keep one across runs.
        stored_calibration: None,
        stored_model: None,
    }
}

/// The plant's parameters: the example session's; with `plant-variant`
/// another strip of the same kind ([`sim::PLANT_VARIANT`]); or with
/// `plant-creep` the same strip creeping (`z = 0.24/s > p = 0.1/s`, Table 4-2's
/// network) with the same DC moment per volt.
fn plant_params() -> Params {
    let example = Params::baseline_air_example();
    if cfg!(feature = "plant-variant") {
        let (r1, c, k) = sim::PLANT_VARIANT;
        return Params {
            r1_ohm: example.r1_ohm * r1,
            c_f: example.c_f * c,
            a_nm_per_c: example.a_nm_per_c * k,
            b_nm_per_c_s: example.b_nm_per_c_s * k,
            ..example
        };
    }
    if !cfg!(feature = "plant-creep") {
        return example;
    }
    let (z_per_s, p_per_s) = (0.24, 0.1);
    let dc_nm_per_v = example.b_nm_per_c_s / example.p_per_s * example.c_f;
    let k_nm_per_c = dc_nm_per_v / example.c_f * p_per_s / z_per_s;
    Params {
        a_nm_per_c: k_nm_per_c,
        b_nm_per_c_s: k_nm_per_c * z_per_s,
        p_per_s,
        ..example
    }
}

/// The plant's optional terms: none, or with `plant-damping` a modal
/// damping ratio of [`sim::PLANT_DAMPING_RATIO`].
fn plant_extensions() -> Extensions {
    Extensions {
        damping_ratio: if cfg!(feature = "plant-damping") {
            sim::PLANT_DAMPING_RATIO
        } else {
            0.0
        },
        ..Extensions::NONE
    }
}

/// The supplies QEMU "measures": nominal, or with `inject-supply-fault` a
/// bridge supply of 4.3 V, below its range.
fn supplies(
) -> Result<finrs_firmware_support::supply::Supplies, finrs_firmware_support::supply::SupplyError> {
    let bridge_v = if cfg!(feature = "inject-supply-fault") {
        4.3
    } else {
        finrs_firmware_support::config::BRIDGE_SUPPLY_V
    };
    finrs_firmware_support::supply::check(finrs_firmware_support::config::DAC_VREF_V, bridge_v)
}

impl Io {
    /// The ADC counts of the next sample period, `None` once the run is
    /// over.
    pub fn read(&mut self) -> Option<TickInput<N>> {
        let tick = self.tick;
        if RUN_TICKS.is_some_and(|end| tick >= end) {
            DONE.store(true, Ordering::Release);
            return None;
        }
        self.tick += 1;
        let noise = self.next_noise_counts(sim::LOAD_CELL_NOISE_COUNTS);
        let force_counts = self.force_n() / NEWTONS_PER_COUNT;
        let load_cell_counts =
            to_counts(f32::from(sim::LOAD_CELL_ZERO_COUNTS) + force_counts + noise);
        let mut current_counts = [0u16; N];
        for (c, i) in current_counts.iter_mut().zip(self.currents_a) {
            let noise = self.next_noise_counts(sim::SHUNT_NOISE_COUNTS);
            *c = to_counts(f32::from(CURRENT_ZERO_COUNTS) + i / AMPS_PER_COUNT + noise);
        }
        if cfg!(feature = "inject-overcurrent") && tick >= sim::INJECT_TICK {
            // 1.1 × the threshold: an overcurrent, below ADC saturation.
            current_counts[sim::INJECT_SEGMENT] =
                to_counts(f32::from(CURRENT_ZERO_COUNTS) + 1.1 * OVERCURRENT_A / AMPS_PER_COUNT);
        }
        self.follow_supply();
        Some(TickInput {
            tick,
            t_us: (tick * 1_000_000 / u64::from(SAMPLE_HZ)) as u32,
            load_cell_counts,
            current_counts,
        })
    }

    /// The period's reading of the bridge supply, as the board's: the
    /// divider's counts of the supply QEMU booted with (its segments are
    /// the plant's, with no duty to work out).
    fn follow_supply(&mut self) {
        use finrs_firmware_support::supply::bridge_sense_counts;
        let Some(monitor) = self.monitor.as_mut() else {
            return;
        };
        let vdda_v = finrs_firmware_support::config::DAC_VREF_V;
        let counts = bridge_sense_counts(monitor.boot_v(), vdda_v) + 0.5;
        if let Err(e) = monitor.update(counts as u16) {
            self.supply_fault = Some(e);
        }
    }

    /// This period's supply reading if it was out of the monitor's band:
    /// the sample task latches it as a `Supply` fault.
    pub fn take_supply_fault(&mut self) -> Option<finrs_firmware_support::supply::SupplyError> {
        self.supply_fault.take()
    }

    /// Applies the commanded voltages (`None`: every output off) and steps
    /// the plant one sample.
    pub fn write_v(&mut self, v: Option<&[f32; N]>) {
        let in_band = self
            .monitor
            .as_ref()
            .is_some_and(finrs_firmware_support::supply::SupplyMonitor::in_band);
        match v.filter(|_| in_band) {
            Some(v) => {
                for (s, &v) in self.segments.iter_mut().zip(v) {
                    s.set_v(v);
                }
            }
            None => self.off(),
        }
        let dry = drying(self.tick);
        let applied = self.segments.map(|s| dry * s.v);
        #[cfg(feature = "qemu-serial")]
        {
            // `read` counted this period already.
            let tick = self.tick.saturating_sub(1);
            if self.world.poll(tick) {
                self.x = self.plant.rest();
            }
            if let Some(currents) = self.world.step(&applied, tick) {
                self.currents_a = currents;
                return;
            }
        }
        self.plant.step(&mut self.x, &applied);
        self.currents_a = self.shunt_readings(dry);
    }

    /// What the shunts read at the next sample: the new state under the
    /// voltage still applied. A bridge applies it as the supply for the
    /// duty `|v| / V_s` of each period and 0 V for the rest, so its shunt
    /// reads the two currents through the shunt's filter at the segment's
    /// phase ([`sim::SHUNT_SAMPLE_PHASE`]); their mean is the current
    /// under `v` (the plant's circuit is linear in it). A DAC segment's
    /// voltage is held, and so is its current.
    fn shunt_readings(&self, dry: f32) -> [f32; N] {
        use finrs_firmware_support::config::{BRIDGE_SUPPLY_V, DAC_SEGMENTS, SHUNT_FILTER};
        let phase = core::array::from_fn(|i| sim::SHUNT_SAMPLE_PHASE[i]);
        // The plant's currents under `u`, dried as its voltages.
        let currents_a = |u: &[f32; N]| self.plant.currents_a(&self.x, &u.map(|u| dry * u));
        let v = self.segments.map(|s| s.v);
        let mut read = SHUNT_FILTER.bridge_readings_a(&v, BRIDGE_SUPPLY_V, &phase, currents_a);
        if DAC_SEGMENTS.iter().any(Option::is_some) {
            let held = currents_a(&v);
            for i in DAC_SEGMENTS.into_iter().flatten() {
                read[i] = held[i];
            }
        }
        read
    }

    /// The force on the load cell: the blocked strip's, none when the
    /// virtual bench's strip is free.
    fn force_n(&self) -> f32 {
        #[cfg(feature = "qemu-serial")]
        if self.world.is_free() {
            return 0.0;
        }
        self.plant.blocking_force_n(&self.x)
    }

    /// Every output to zero (the plant sees 0 V from its next step).
    pub fn off(&mut self) {
        for s in &mut self.segments {
            s.off();
        }
    }

    /// QEMU does not emulate the IWDG: nothing to feed.
    pub fn feed_watchdog(&mut self) {}

    /// QEMU's board has no bridges to keep awake
    /// (`finrs_firmware_support::keepalive`, the real board's).
    pub fn keep_alive(&mut self, _healthy: bool) {}

    /// QEMU's netduinoplus2 models no flash programming: a calibration the
    /// host sets is used but not stored (the Info frame says "unsaved").
    pub fn store_calibration(&mut self, _: &finrs_frames::Calibration) -> bool {
        false
    }

    /// Likewise a model: used, not stored.
    pub fn store_model(&mut self, _: &finrs_frames::ModelRecord) -> bool {
        false
    }

    /// Whether the pacer pended the next sample before this one finished.
    pub fn deadline_missed(&mut self) -> bool {
        NVIC::is_pending(Interrupt::ADC)
    }

    /// Uniform noise in ±`amplitude` counts (xorshift32).
    fn next_noise_counts(&mut self, amplitude: f32) -> f32 {
        let x = sim::xorshift32(&mut self.noise);
        (x as f32 / u32::MAX as f32 * 2.0 - 1.0) * amplitude
    }
}

/// The `plant-drying` strip's admittance factor at sample `tick` (1
/// without the feature): `e^{−t/τ}`, t from boot. Scaling the voltage the
/// strip sees scales its currents and its moments alike, which is what
/// scaling every `1/R1`, `1/R2` and `C` does.
fn drying(tick: u64) -> f32 {
    if !cfg!(feature = "plant-drying") {
        return 1.0;
    }
    let t_s = tick as f32 / SAMPLE_HZ as f32;
    libm::expf(-t_s / sim::PLANT_DRYING_TIME_S)
}

/// Rounds to the 12-bit ADC's range.
fn to_counts(c: f32) -> u16 {
    let r = c + 0.5;
    if r <= 0.0 {
        0
    } else if r >= 4095.0 {
        4095
    } else {
        r as u16
    }
}

/// Pends the sample interrupt every millisecond of SysTick time.
pub async fn pace() -> ! {
    let mut next = Mono::now();
    loop {
        next += 1.millis();
        Mono::delay_until(next).await;
        NVIC::pend(Interrupt::ADC);
    }
}

/// Flushes the frame queue to the host file in batches; at the end of the
/// run, flushes the rest and exits QEMU with success.
pub async fn housekeeping(h: &mut Housekeeping) -> ! {
    loop {
        Mono::delay(FLUSH_MS.millis()).await;
        let done = DONE.load(Ordering::Acquire);
        let ok = h.flush();
        if !ok {
            defmt::error!("writing frames to the host failed");
            exit(false);
        }
        if done {
            crate::stack::report();
            defmt::info!("run over after {} s", sim::RUN_S);
            exit(true);
        }
    }
}

impl Housekeeping {
    fn flush(&mut self) -> bool {
        #[cfg(feature = "qemu-serial")]
        while let Some(b) = self.world_queue.dequeue() {
            self.world_tx.write(&[b]);
        }
        loop {
            let mut n = 0;
            while n < self.batch.len() {
                match self.queue.dequeue() {
                    Some(b) => {
                        self.batch[n] = b;
                        n += 1;
                    }
                    None => break,
                }
            }
            if n == 0 {
                return true;
            }
            #[cfg(feature = "qemu-serial")]
            self.tx.write(&self.batch[..n]);
            #[cfg(not(feature = "qemu-serial"))]
            if !write_host(self.fd, &self.batch[..n]) {
                return false;
            }
        }
    }
}

/// Opens a host file in semihosting `mode` (`nr::open::*`).
#[cfg(not(feature = "qemu-serial"))]
fn open_host_file(name_nul: &str, mode: usize) -> Option<usize> {
    let name = name_nul.as_bytes();
    // SAFETY: the semihosting OPEN call reads `name.len() - 1` bytes of a
    // NUL-terminated name we own; no Rust API opens a host file.
    #[allow(unsafe_code)]
    let fd = unsafe { syscall!(OPEN, name.as_ptr(), mode, name.len() - 1) };
    (fd as isize >= 0).then_some(fd)
}

/// Writes all of `bytes` to a host file.
#[cfg(not(feature = "qemu-serial"))]
fn write_host(fd: usize, mut bytes: &[u8]) -> bool {
    while !bytes.is_empty() {
        // SAFETY: WRITE reads `bytes.len()` bytes from a slice we borrow.
        #[allow(unsafe_code)]
        let left = unsafe { syscall!(WRITE, fd, bytes.as_ptr(), bytes.len()) };
        // It returns the count not written: no progress is an error.
        if left >= bytes.len() {
            return false;
        }
        bytes = &bytes[bytes.len() - left..];
    }
    true
}

/// What the stack guard's MemManage handler calls
/// (`finrs_firmware_support::stack_guard`): the run ends with a failure
/// code, as a HardFault's does.
pub extern "C" fn stack_overflow_stop() -> ! {
    exit(false)
}

fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

/// A fault ends QEMU with a failure code instead of hanging it.
#[cortex_m_rt::exception]
#[allow(unsafe_code)] // cortex-m-rt requires the HardFault handler to be `unsafe fn`
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    exit(false)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    exit(false)
}

/// The virtual bench's world, with the free strip's model, and its
/// message queue's reading end.
#[cfg(feature = "qemu-serial")]
fn world_parts() -> (world::World, Consumer<'static, u8>) {
    let built = Strip::with_extensions(
        &plant_params(),
        &plant_extensions(),
        Fixture::Free,
        1.0 / f64::from(SAMPLE_HZ),
    );
    let free = match built {
        Ok(p) => cortex_m::singleton!(: Strip<f32, N, 1, S> = p),
        Err(_) => defmt::panic!("the example session's parameters do not make a free strip"),
    };
    let Some(free) = free else {
        defmt::panic!("board init ran twice");
    };
    // A camera frame is at most 42 bytes, one per 33 ms: a flush every
    // 20 ms finds at most one.
    let Some(queue) = cortex_m::singleton!(: Queue<u8, 512> = Queue::new()) else {
        defmt::panic!("board init ran twice");
    };
    let (producer, consumer) = queue.split();
    (world::World::new(free, producer), consumer)
}
