//! The real board: STM32F407VG at 168 MHz (8 MHz HSE, as on the
//! STM32F4-Discovery used for bring-up). `BOARD.md` describes the same
//! pin map in words; [`pins`] is the one place in code.
//!
//! - Segments: H-bridges (sign-magnitude, one PWM input per bridge leg,
//!   [`PWM_HZ`]) from TIM1 and TIM8; the bridge driver (e.g. a DRV8871-class
//!   IN1/IN2 driver) inserts its own dead time, so plain PWM outputs with no
//!   complementary channels are enough. Each goes through
//!   `finrs_controller::HBridge`.
//! - Sampling: TIM5's update event (TRGO) at the sample rate starts ADC1's
//!   injected group: load cell, then the shunts of segments 0..=2, one
//!   conversion each, into JDR1..JDR4. The end of the group (JEOC) raises
//!   the ADC interrupt, which runs the sample task. A group that ends again
//!   before the task has finished is a missed deadline.
//! - RTT: up channel 0 carries defmt, up channel 1 the binary frames
//!   ([`FRAME_RTT_BYTES`]), down channel 0 the commands; all never block.
//! - IWDG: [`WATCHDOG_MS`], fed by the sample task; frozen while a debugger
//!   halts the core.
//! - Panic and HardFault: every PWM output is forced low and its compare
//!   register zeroed by register writes (no driver can be trusted then)
//!   before the message is logged; then `udf` stops the core for probe-rs
//!   as panic-probe would (which we therefore do not link: its handler
//!   would log before it could zero anything), and the watchdog resets it.

use embedded_hal::pwm::SetDutyCycle;
use finrs_controller::{FrameSink, HBridge, SegmentOutput, TickInput};
use rtt_target::{rtt_init, ChannelMode, DownChannel, UpChannel};
use stm32f4xx_hal::{
    pac,
    prelude::*,
    rcc::{Config as RccConfig, Enable, Reset},
    timer::ErasedChannel,
    watchdog::IndependentWatchdog,
};

use super::Parts;
use crate::config::{BRIDGE_SUPPLY_V, N, SAMPLE_HZ};
use crate::{Mono, SYSCLK_HZ};

/// H-bridge PWM frequency, Hz: above the audible range and the 20 kHz the
/// issue asks; TIM1/TIM8 at 168 MHz still give 6720 steps (12.7 bits).
pub const PWM_HZ: u32 = 25_000;

/// Watchdog period, ms: 20 sample periods, far beyond any normal jitter,
/// short enough that a hung firmware stops driving within a blink.
pub const WATCHDOG_MS: u32 = 20;

/// Frame up channel, bytes. A 3-segment Sample is 42 bytes, 42 kB/s at
/// 1 kHz. probe-rs polls RTT every few ms but a busy host or USB can stall
/// it for 100 ms: 4.2 kB; twice that for margin.
pub const FRAME_RTT_BYTES: usize = 8192;

/// Where every signal is: the one place in code (`BOARD.md` has the same
/// table, with segments 3..=7 and the DAC segments this build does not
/// wire).
pub mod pins {
    use stm32f4xx_hal::gpio::{gpioa, gpioc, gpioe, Analog, PA1, PA2, PA3, PC1};
    use stm32f4xx_hal::gpio::{PC6, PC7, PE11, PE13, PE14, PE9};

    /// ADC1 channel of the load cell (PA1).
    pub const LOAD_CELL_CHANNEL: u8 = 1;
    /// ADC1 channels of the shunts of segments 0..=2 (PA2, PA3, PC1).
    pub const SHUNT_CHANNELS: [u8; 3] = [2, 3, 11];

    /// The pins this build uses.
    pub struct Pins {
        /// Segment 0, bridge legs A/B: TIM1_CH1, TIM1_CH2.
        pub seg0: (PE9, PE11),
        /// Segment 1: TIM1_CH3, TIM1_CH4.
        pub seg1: (PE13, PE14),
        /// Segment 2: TIM8_CH1, TIM8_CH2.
        pub seg2: (PC6, PC7),
        /// Load cell, instrumentation amplifier output.
        pub load_cell: PA1<Analog>,
        /// Shunt amplifiers of segments 0..=2.
        pub shunts: (PA2<Analog>, PA3<Analog>, PC1<Analog>),
    }

    /// Takes the pins from the GPIO ports.
    pub fn take(a: gpioa::Parts, c: gpioc::Parts, e: gpioe::Parts) -> Pins {
        Pins {
            seg0: (e.pe9, e.pe11),
            seg1: (e.pe13, e.pe14),
            seg2: (c.pc6, c.pc7),
            load_cell: a.pa1.into_analog(),
            shunts: (
                a.pa2.into_analog(),
                a.pa3.into_analog(),
                c.pc1.into_analog(),
            ),
        }
    }
}

const _: () = assert!(
    N == 3,
    "the board module wires 3 segments (see BOARD.md for more)"
);

/// ADC1 as the sample task sees it.
pub struct Io {
    adc: pac::ADC1,
    seg0: HBridge<ErasedChannel<pac::TIM1>, ErasedChannel<pac::TIM1>>,
    seg1: HBridge<ErasedChannel<pac::TIM1>, ErasedChannel<pac::TIM1>>,
    seg2: HBridge<ErasedChannel<pac::TIM8>, ErasedChannel<pac::TIM8>>,
    watchdog: IndependentWatchdog,
}

/// RTT up channel 1, in NoBlockSkip mode: a frame goes whole or not at all.
pub struct FrameOut {
    channel: UpChannel,
}

impl FrameSink for FrameOut {
    fn try_write(&mut self, frame: &[u8]) -> bool {
        self.channel.write(frame) == frame.len()
    }
}

/// RTT down channel 0.
pub struct CommandIn {
    channel: DownChannel,
}

impl CommandIn {
    /// Reads what the host has written (never blocks).
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        self.channel.read(buf)
    }
}

/// Nothing to do at low priority on the board.
pub struct Housekeeping;

/// Clocks, RTT, outputs, ADC trigger, watchdog.
pub fn init(core: cortex_m::Peripherals, dp: pac::Peripherals) -> Parts {
    let (frames, commands) = init_rtt();
    let mut rcc = dp.RCC.freeze(
        RccConfig::hse(8.MHz())
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(42.MHz())
            .pclk2(84.MHz()),
    );
    Mono::start(core.SYST, SYSCLK_HZ);
    // RTT keeps working while idle sleeps (WFI); the watchdog and the
    // output timers stop while a debugger halts the core.
    dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());

    let pins = pins::take(
        dp.GPIOA.split(&mut rcc),
        dp.GPIOC.split(&mut rcc),
        dp.GPIOE.split(&mut rcc),
    );

    // H-bridges.
    let (_tim1, (c1, c2, c3, c4)) = dp.TIM1.pwm_hz(PWM_HZ.Hz(), &mut rcc);
    let (_tim8, (c81, c82, ..)) = dp.TIM8.pwm_hz(PWM_HZ.Hz(), &mut rcc);
    let mut legs1 = [
        c1.with(pins.seg0.0).erase(),
        c2.with(pins.seg0.1).erase(),
        c3.with(pins.seg1.0).erase(),
        c4.with(pins.seg1.1).erase(),
    ];
    let mut legs8 = [c81.with(pins.seg2.0).erase(), c82.with(pins.seg2.1).erase()];
    for leg in legs1.iter_mut() {
        let _ = leg.set_duty_cycle_fully_off();
        leg.enable();
    }
    for leg in legs8.iter_mut() {
        let _ = leg.set_duty_cycle_fully_off();
        leg.enable();
    }
    let [l0, l1, l2, l3] = legs1;
    let [l4, l5] = legs8;
    let bridges = (
        HBridge::new(l0, l1, BRIDGE_SUPPLY_V),
        HBridge::new(l2, l3, BRIDGE_SUPPLY_V),
        HBridge::new(l4, l5, BRIDGE_SUPPLY_V),
    );
    let (Ok(seg0), Ok(seg1), Ok(seg2)) = bridges else {
        defmt::panic!("BRIDGE_SUPPLY_V is not a valid supply voltage");
    };

    // The ADC pins stay in analog mode for good.
    let _analog = (pins.load_cell, pins.shunts);
    let adc = init_adc(dp.ADC1, &dp.ADC_COMMON, &mut rcc);
    init_trigger(dp.TIM5, &mut rcc);

    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.stop_on_debug(&dp.DBGMCU, true);
    watchdog.start(WATCHDOG_MS.millis());

    Parts {
        io: Io {
            adc,
            seg0,
            seg1,
            seg2,
            watchdog,
        },
        frames,
        commands,
        housekeeping: Housekeeping,
    }
}

#[allow(unsafe_code)] // rtt_init! writes the control block (a static) once
fn init_rtt() -> (FrameOut, CommandIn) {
    let channels = rtt_init! {
        up: {
            0: { size: 1024, mode: ChannelMode::NoBlockSkip, name: "defmt" }
            1: { size: FRAME_RTT_BYTES, mode: ChannelMode::NoBlockSkip, name: "frames" }
        }
        down: {
            0: { size: 64, name: "commands" }
        }
    };
    rtt_target::set_defmt_channel(channels.up.0);
    (
        FrameOut {
            channel: channels.up.1,
        },
        CommandIn {
            channel: channels.down.0,
        },
    )
}

/// ADC1: 12-bit, 21 MHz (PCLK2 / 4), injected group of 4 started by
/// TIM5_TRGO on its rising edge, JEOC interrupt at the group's end. 84
/// cycles of sampling (4 µs) per channel suit the amplifiers' outputs; the
/// group takes 4 × (84 + 12) / 21 MHz ≈ 18 µs of the 1 ms period.
fn init_adc(adc: pac::ADC1, common: &pac::ADC_COMMON, rcc: &mut pac::RCC) -> pac::ADC1 {
    pac::ADC1::enable(rcc);
    pac::ADC1::reset(rcc);
    common.ccr().modify(|_, w| w.adcpre().div4());
    adc.cr1().write(|w| w.scan().set_bit().jeocie().set_bit());
    // 84 cycles (0b100) on every channel we use.
    adc.smpr2().write(|w| {
        w.smp1().cycles84();
        w.smp2().cycles84();
        w.smp3().cycles84()
    });
    adc.smpr1().write(|w| w.smp11().cycles84());
    // JL = 3: four conversions, JSQ1..4 in order.
    #[allow(unsafe_code)]
    // SAFETY: channel numbers are the pin map's, all below 19.
    adc.jsqr().write(|w| unsafe {
        w.jl().set(3);
        w.jsq1().bits(pins::LOAD_CELL_CHANNEL);
        w.jsq2().bits(pins::SHUNT_CHANNELS[0]);
        w.jsq3().bits(pins::SHUNT_CHANNELS[1]);
        w.jsq4().bits(pins::SHUNT_CHANNELS[2])
    });
    adc.cr2().write(|w| {
        w.jexten().rising_edge();
        w.jextsel().tim5trgo();
        w.adon().set_bit()
    });
    adc
}

/// TIM5 counts at 1 MHz (84 MHz / 84) and updates at the sample rate; its
/// update event is TRGO.
fn init_trigger(tim: pac::TIM5, rcc: &mut pac::RCC) {
    pac::TIM5::enable(rcc);
    pac::TIM5::reset(rcc);
    tim.psc().write(|w| w.psc().set(84 - 1));
    tim.arr().write(|w| w.arr().set(1_000_000 / SAMPLE_HZ - 1));
    tim.egr().write(|w| w.ug().set_bit());
    tim.cr2().write(|w| w.mms().update());
    tim.cr1().write(|w| w.cen().set_bit());
}

impl Io {
    /// The group that just ended, as sample `tick`; `None` if no group
    /// ended (a spurious interrupt).
    pub fn read(&mut self, tick: u64) -> Option<TickInput<N>> {
        let sr = self.adc.sr().read();
        if sr.jeoc().bit_is_clear() {
            return None;
        }
        self.adc
            .sr()
            .modify(|_, w| w.jeoc().clear_bit().jstrt().clear_bit());
        let counts = |i: usize| self.adc.jdr(i).read().jdata().bits();
        Some(TickInput {
            tick,
            t_us: (tick * 1_000_000 / u64::from(SAMPLE_HZ)) as u32,
            load_cell_counts: counts(0),
            current_counts: [counts(1), counts(2), counts(3)],
        })
    }

    /// Writes the controller's voltages to the bridges.
    pub fn write_v(&mut self, v: &[f32; N]) {
        self.seg0.set_v(v[0]);
        self.seg1.set_v(v[1]);
        self.seg2.set_v(v[2]);
    }

    /// Every bridge off.
    pub fn off(&mut self) {
        self.seg0.off();
        self.seg1.off();
        self.seg2.off();
    }

    /// Feeds the IWDG.
    pub fn feed_watchdog(&mut self) {
        self.watchdog.feed();
    }

    /// Whether the next group already ended: this period overran.
    pub fn deadline_missed(&mut self) -> bool {
        self.adc.sr().read().jeoc().bit_is_set()
    }
}

/// The ADC trigger timer paces the sample task: nothing to do.
pub async fn pace() -> ! {
    loop {
        core::future::pending::<()>().await;
    }
}

/// Nothing to do at low priority on the board.
pub async fn housekeeping(_: &mut Housekeeping) -> ! {
    loop {
        core::future::pending::<()>().await;
    }
}

/// Forces every bridge input low by register writes, whatever state the
/// drivers are in: compare registers to 0 and each channel's output mode to
/// "force inactive" (the pin then stays low even if the counter runs on).
fn zero_outputs_now() {
    // SAFETY: called only on the way to a halt (panic, HardFault), when no
    // other code will touch these timers again; each write is to a timer's
    // own compare and mode registers.
    #[allow(unsafe_code)]
    let dp = unsafe { pac::Peripherals::steal() };
    for ccr in dp.TIM1.ccr_iter() {
        ccr.write(|w| w.ccr().set(0));
    }
    dp.TIM1
        .ccmr1_output()
        .modify(|_, w| w.oc1m().force_inactive().oc2m().force_inactive());
    dp.TIM1
        .ccmr2_output()
        .modify(|_, w| w.oc3m().force_inactive().oc4m().force_inactive());
    for ccr in dp.TIM8.ccr_iter() {
        ccr.write(|w| w.ccr().set(0));
    }
    dp.TIM8
        .ccmr1_output()
        .modify(|_, w| w.oc1m().force_inactive().oc2m().force_inactive());
    dp.TIM8
        .ccmr2_output()
        .modify(|_, w| w.oc3m().force_inactive().oc4m().force_inactive());
}

/// Outputs to zero first, then the message, then stop for the debugger
/// (the watchdog resets the board if none is attached).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    zero_outputs_now();
    defmt::error!("panic: {}", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

/// A fault other than a panic: outputs to zero, then wait for the watchdog.
#[cortex_m_rt::exception]
#[allow(unsafe_code)] // cortex-m-rt requires the HardFault handler to be `unsafe fn`
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    zero_outputs_now();
    loop {
        cortex_m::asm::nop();
    }
}
