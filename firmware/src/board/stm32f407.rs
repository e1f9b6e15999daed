//! The real board: STM32F407VG at 168 MHz (8 MHz HSE, as on the
//! STM32F4-Discovery used for bring-up). `BOARD.md` describes the same
//! pin map in words; [`pins`] is the one place in code.
//!
//! - Segments: `N` of them (1..=8, `config::N`, set at build time by
//!   `FINRS_SEGMENTS`). Each is an H-bridge (slow decay: one input held
//!   high, the other PWM'd, [`PWM_HZ`]) from TIM1, TIM8, TIM2 or TIM4
//!   through `finrs_controller::HBridge`; the bridge driver (a DRV8833, an
//!   IN1/IN2 driver rated down to 2.7 V) inserts its own dead time, so
//!   plain PWM outputs with no complementary channels are enough. A channel
//!   is held high by a compare value of ARR + 1, the HAL's
//!   `max_duty_cycle` (RM0090, PWM mode 1: OCxREF stays high when CCRx
//!   exceeds ARR). Up to two segments
//!   (`config::DAC_SEGMENTS`, `FINRS_DAC_SEGMENTS`) use DAC1 (PA4) and DAC2
//!   (PA5) into a bipolar amplifier through `finrs_controller::DacOutput`
//!   instead; their bridge pins and timer channels stay unused. Only the
//!   timers and pins the configuration needs are set up.
//! - Sampling: TIM5's update event (TRGO) at the sample rate starts ADC1's
//!   injected group (load cell, then the shunts of segments 0..=2), ADC2's
//!   (shunts 3..=6) and ADC3's (shunt 7), each ADC only if used. ADC1 has
//!   the most conversions of the three, so its end of group (JEOC) comes
//!   last; it alone raises the ADC interrupt, which runs the sample task
//!   and reads all results. A group that ends again before the task has
//!   finished is a missed deadline.
//! - RTT: up channel 0 carries defmt, up channel 1 the binary frames
//!   ([`FRAME_RTT_BYTES`]), down channel 0 the commands; all never block.
//! - IWDG: [`WATCHDOG_MS`], fed by the sample task; frozen while a debugger
//!   halts the core.
//! - Calibration: records in flash sectors 10 and 11
//!   (`calibration_store::BOARD_REGION`), read at boot, appended by the
//!   sample task when the host sets one (the outputs are at 0 V then: the
//!   controller refuses a SetCalibration while driving). Through the HAL's
//!   flash driver (x8 parallelism, any supply voltage). A record programs
//!   32 bytes; while flash programs, reads of it stall the core (RM0090
//!   §3.5.4; DS8626 gives 16 µs typical a byte), so the tick overruns and
//!   its unseen periods go out as dropped samples. Only when a sector is
//!   full (every 4096 stores) is the other erased: DS8626 gives up to 4 s
//!   for a 128 KiB sector at x8, during which nothing runs. Each log's
//!   position is read at boot, before the watchdog starts, and kept in RAM:
//!   a store touches one record. Before each store touches the flash the
//!   watchdog is widened to cover the datasheet's longest program (and
//!   erase) on the fastest LSI (`flash_timing`: 25 ms for a calibration
//!   record, 58 ms for a model record, 5.9 s with an erase) and restored
//!   after.
//! - Panic, HardFault, NMI and any interrupt without a handler: every used
//!   timer's PWM outputs are forced low (the bridge open) and its compare
//!   registers zeroed, and every used DAC set to its 0 V code, by register
//!   writes (no driver can be trusted then) before anything else. A panic
//!   then logs its message and `udf` stops the core for probe-rs as
//!   panic-probe would (which we therefore do not link: its handler would
//!   log before it could zero anything); the others wait. The watchdog
//!   resets the core.
//! - Debug halt: the PWM timers run on (DBGMCU's DBG_TIMx_STOP bits are
//!   left clear). A stopped general-purpose timer would hold its pins at
//!   the level they had, in slow decay possibly one leg high and the other
//!   low, the full supply across the strip, above the limit; running, the
//!   bridge goes on at the last commanded average, within the limit. The
//!   watchdog is frozen, so that a breakpoint does not reset the board.

// The ADC and timer counts are constants that vary with the build's
// segment count: a comparison always true in one build is not in another.
#![allow(clippy::absurd_extreme_comparisons)]

use embedded_hal::pwm::{ErrorType, SetDutyCycle};
use finrs_controller::{DacOutput, DacWrite, FrameSink, HBridge, SegmentOutput, TickInput};
use rtt_target::{rtt_init, ChannelMode, DownChannel, UpChannel};
use stm32f4xx_hal::{
    dac::{DacOut, DacPin, C1, C2},
    gpio::{Output, Pin, PinState, PushPull},
    pac,
    prelude::*,
    rcc::{Config as RccConfig, Enable, Reset},
    timer::ErasedChannel,
    watchdog::IndependentWatchdog,
};

use super::Parts;
use crate::config::{
    BRIDGE_SUPPLY_V, DAC_GAIN, DAC_SEGMENTS, DAC_VREF_V, DAC_ZERO_CODE, N, PWM_HZ, SAMPLE_HZ,
};
use crate::{Mono, SYSCLK_HZ};
use finrs_firmware_support::calibration_store::{self, BOARD_REGION};
use finrs_firmware_support::flash_timing::store_watchdog_ms;
use finrs_firmware_support::keepalive::Keepalive;
use finrs_firmware_support::model_store;
use finrs_firmware_support::record_log::{Cursor, StoreError, Work};
use finrs_firmware_support::reset;
use finrs_firmware_support::supply::{self, Supplies, SupplyError, SupplyMonitor};
use finrs_firmware_support::sync::SyncMark;
use finrs_frames::Calibration;
use stm32f4xx_hal::flash::{FlashExt, LockedFlash, UnlockedFlash};

/// Watchdog period, ms: 20 sample periods, far beyond any normal jitter,
/// short enough that a hung firmware stops driving within a blink.
pub const WATCHDOG_MS: u32 = 20;

/// Frame up channel, bytes. A Sample is 19 + 8 N bytes: 43 at N = 3 (43
/// kB/s at 1 kHz), 83 at N = 8. probe-rs polls RTT every few ms but a busy
/// host or USB can stall it for 100 ms: 4.3 kB at N = 3, 8.3 kB at N = 8;
/// about twice that for margin.
pub const FRAME_RTT_BYTES: usize = if N <= 3 { 8192 } else { 16384 };

/// Polls of ADC2/ADC3's end-of-group flag after ADC1's before their results
/// count as late (they have no more conversions than ADC1 and the same
/// trigger, so they are normally done already).
const SECONDARY_ADC_POLLS: u32 = 200;

/// The ADC channels of the pin map, from `finrs_firmware_support::pins`
/// (checked there against the datasheet; `BOARD.md` has the whole table;
/// the bridge and DAC pins are taken in `init`, segment by segment). Which
/// of them a build uses follows `config::N` and `config::DAC_SEGMENTS`.
pub mod pins {
    use finrs_firmware_support::pins::{LOAD_CELL, SHUNTS};

    /// ADC channel of the load cell (PA1, ADC1).
    pub const LOAD_CELL_CHANNEL: u8 = LOAD_CELL.channel;
    /// ADC channels of the shunts of segments 0..=7: PA2, PA3, PC1 (ADC1),
    /// PB1, PC4, PC5, PB0 (ADC2), PC2 (ADC3).
    pub const SHUNT_CHANNELS: [u8; 8] = {
        let mut ch = [0; 8];
        let mut i = 0;
        while i < 8 {
            ch[i] = SHUNTS[i].channel;
            i += 1;
        }
        ch
    };
}

/// Whether segment `i` is wired in this build and driven by DAC1 (0) or
/// DAC2 (1).
const fn dac_of(i: usize) -> Option<usize> {
    match DAC_SEGMENTS {
        [Some(d), _] if d == i => Some(0),
        [_, Some(d)] if d == i => Some(1),
        _ => None,
    }
}

/// Whether segment `i` is wired in this build as an H-bridge.
const fn is_bridge(i: usize) -> bool {
    i < N && dac_of(i).is_none()
}

/// Which timers this build drives (two segments each).
const USES_TIM1: bool = is_bridge(0) || is_bridge(1);
const USES_TIM8: bool = is_bridge(2) || is_bridge(3);
const USES_TIM2: bool = is_bridge(4) || is_bridge(5);
const USES_TIM4: bool = is_bridge(6) || is_bridge(7);
/// Which DAC channels this build drives.
const USES_DAC1: bool = DAC_SEGMENTS[0].is_some();
const USES_DAC2: bool = DAC_SEGMENTS[1].is_some();

/// Shunts per ADC: ADC1 takes segments 0..=2, ADC2 3..=6, ADC3 7.
const ADC1_SHUNTS: usize = if N < 3 { N } else { 3 };
const ADC2_SHUNTS: usize = if N <= 3 {
    0
} else if N < 7 {
    N - 3
} else {
    4
};
const ADC3_SHUNTS: usize = N.saturating_sub(7);
/// The bridge supply's divider, read last in ADC3's group.
const SUPPLY_SENSE_CHANNEL: u8 = finrs_firmware_support::pins::BRIDGE_SUPPLY_SENSE.channel;

const _: () = {
    assert!(N >= 1 && N <= 8, "the board's pin map has 1..=8 segments");
    assert!(ADC1_SHUNTS + ADC2_SHUNTS + ADC3_SHUNTS == N);
    // ADC1's group (with the load cell) is never shorter than the others
    // (ADC3's with the supply's divider): its end is the end of all.
    assert!(ADC2_SHUNTS <= ADC1_SHUNTS + 1 && ADC3_SHUNTS <= ADC1_SHUNTS);
    assert!(finrs_firmware_support::pins::BRIDGE_SUPPLY_SENSE.adc == 3);
    assert!(USES_DAC1 || !USES_DAC2, "DAC2 is used only with DAC1");
    // The groups above are the ones the pin table wires the shunts to.
    use finrs_firmware_support::pins::adc_of_segment;
    assert!(adc_of_segment(0) == 1 && adc_of_segment(2) == 1);
    assert!(adc_of_segment(3) == 2 && adc_of_segment(6) == 2 && adc_of_segment(7) == 3);
};

/// One bridge leg: a PWM channel of one of the four timers.
pub enum Leg {
    /// TIM1 (segments 0, 1).
    T1(ErasedChannel<pac::TIM1>),
    /// TIM8 (segments 2, 3).
    T8(ErasedChannel<pac::TIM8>),
    /// TIM2 (segments 4, 5).
    T2(ErasedChannel<pac::TIM2>),
    /// TIM4 (segments 6, 7).
    T4(ErasedChannel<pac::TIM4>),
}

impl Leg {
    fn enable(&mut self) {
        match self {
            Leg::T1(c) => c.enable(),
            Leg::T8(c) => c.enable(),
            Leg::T2(c) => c.enable(),
            Leg::T4(c) => c.enable(),
        }
    }
}

impl ErrorType for Leg {
    type Error = core::convert::Infallible;
}

impl SetDutyCycle for Leg {
    fn max_duty_cycle(&self) -> u16 {
        match self {
            Leg::T1(c) => c.max_duty_cycle(),
            Leg::T8(c) => c.max_duty_cycle(),
            Leg::T2(c) => c.max_duty_cycle(),
            Leg::T4(c) => c.max_duty_cycle(),
        }
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        match self {
            Leg::T1(c) => c.set_duty_cycle(duty),
            Leg::T8(c) => c.set_duty_cycle(duty),
            Leg::T2(c) => c.set_duty_cycle(duty),
            Leg::T4(c) => c.set_duty_cycle(duty),
        }
    }
}

/// One DAC channel's 12-bit right-aligned data register.
pub enum DacChannel {
    /// DAC1, PA4.
    One(C1),
    /// DAC2, PA5.
    Two(C2),
}

impl DacWrite for DacChannel {
    fn write_code(&mut self, code: u16) {
        match self {
            DacChannel::One(c) => c.set_value(code),
            DacChannel::Two(c) => c.set_value(code),
        }
    }
}

/// A segment's driver.
pub enum Segment {
    /// H-bridge from two PWM legs.
    Bridge(HBridge<Leg, Leg>),
    /// DAC into a bipolar amplifier.
    Dac(DacOutput<DacChannel>),
}

impl SegmentOutput for Segment {
    fn set_v(&mut self, v: f32) {
        match self {
            Segment::Bridge(b) => b.set_v(v),
            Segment::Dac(d) => d.set_v(v),
        }
    }

    fn off(&mut self) {
        match self {
            Segment::Bridge(b) => b.off(),
            Segment::Dac(d) => d.off(),
        }
    }
}

/// The ADCs and outputs as the sample task sees them.
pub struct Io {
    adc1: pac::ADC1,
    adc2: pac::ADC2,
    adc3: pac::ADC3,
    /// TIM3, the sample period counter.
    counter: pac::TIM3,
    periods: Periods,
    segments: [Segment; N],
    /// ADC2/ADC3's group was not done when ADC1's was.
    secondary_late: bool,
    /// The bridge supply, read every period by ADC3's group; `None` if the
    /// supplies were out of range at boot: nothing is ever driven then,
    /// nor while the last reading is out of the monitor's band, whatever
    /// the controller says.
    monitor: Option<SupplyMonitor>,
    /// This period's reading, if out of the band, for the sample task to
    /// latch as a `Supply` fault.
    supply_fault: Option<SupplyError>,
    watchdog: IndependentWatchdog,
    /// The calibration's records (flash sectors 10 and 11) and the
    /// model's (8 and 9).
    flash: LockedFlash,
    /// Each log's position, from the boot's scan; `None` if its region
    /// could not be read then (nothing is stored: a scan would outrun the
    /// watchdog).
    calibration_log: Option<Cursor>,
    model_log: Option<Cursor>,
    /// The camera's sync LED (`pins::SYNC_LED`) and when to light it.
    sync_led: Pin<'E', 7, Output<PushPull>>,
    /// The bridges' keep-alive into the nSLEEP monostable (BOARD.md).
    keepalive_pin: Pin<'E', 10, Output<PushPull>>,
    keepalive: Keepalive,
    sync: SyncMark,
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

/// Both legs of a bridge, off, then enabled.
fn legs(mut a: Leg, mut b: Leg) -> Option<(Leg, Leg)> {
    let _ = a.set_duty_cycle_fully_off();
    let _ = b.set_duty_cycle_fully_off();
    a.enable();
    b.enable();
    Some((a, b))
}

/// A DAC channel at its 0 V code, then enabled (in that order: enabled at
/// code 0 it would drive the amplifier to its negative rail).
fn dac_channel<D: DacPin + DacOut<u16>>(mut d: D) -> D {
    d.set_value(DAC_ZERO_CODE);
    d.enable();
    d
}

/// Clocks, RTT, outputs, ADC trigger, watchdog.
pub fn init(core: cortex_m::Peripherals, dp: pac::Peripherals) -> Parts {
    let (frames, commands) = init_rtt();
    // The reset flags, read and cleared before anything else touches RCC.
    let cause = reset::from_rcc_csr(dp.RCC.csr().read().bits());
    dp.RCC.csr().modify(|_, w| w.rmvf().set_bit());
    if cause.is_failure() {
        defmt::warn!(
            "reset cause: {} (the last run hung or failed)",
            cause.name()
        );
    } else {
        defmt::info!("reset cause: {}", cause.name());
    }
    let mut rcc = dp.RCC.freeze(
        RccConfig::hse(8.MHz())
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(42.MHz())
            .pclk2(84.MHz()),
    );
    Mono::start(core.SYST, SYSCLK_HZ);
    // RTT keeps working while idle sleeps (WFI). While a debugger halts
    // the core the watchdog stops (below) and the output timers run on
    // (module doc: a stopped timer can hold a bridge at the full supply);
    // their stop bits are cleared whatever a debugger set.
    dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
    dp.DBGMCU.apb1_fz().modify(|_, w| {
        w.dbg_tim2_stop().clear_bit();
        w.dbg_tim4_stop().clear_bit()
    });
    dp.DBGMCU
        .apb2_fz()
        .modify(|_, w| w.dbg_tim1_stop().clear_bit().dbg_tim8_stop().clear_bit());

    let a = dp.GPIOA.split(&mut rcc);
    let b = dp.GPIOB.split(&mut rcc);
    let c = dp.GPIOC.split(&mut rcc);
    let d = dp.GPIOD.split(&mut rcc);
    let e = dp.GPIOE.split(&mut rcc);

    // The supplies, before anything that drives is set up: the bridges'
    // duties are worked out from the supply measured here.
    const {
        assert!(finrs_firmware_support::pins::BRIDGE_SUPPLY_SENSE
            .pin
            .is(b'C', 3))
    };
    let _ = c.pc3.into_analog();
    let supply = measure_supplies(&dp.ADC1, &dp.ADC_COMMON, &mut rcc);
    let bridge_v = supply.map_or(BRIDGE_SUPPLY_V, |s| s.bridge_v);
    match &supply {
        Ok(s) => defmt::info!(
            "supplies: VDDA {=u32} mV, bridges {=u32} mV",
            (s.vdda_v * 1000.0) as u32,
            (s.bridge_v * 1000.0) as u32
        ),
        Err(e) => defmt::error!("{}", defmt::Display2Format(e)),
    }

    // H-bridges: only the timers and pins of bridge segments (the pins are
    // `pins::BRIDGE_LEGS`).
    let mut bridge_legs: [Option<(Leg, Leg)>; 8] = Default::default();
    if USES_TIM1 {
        let (_tim, (c1, c2, c3, c4)) = dp.TIM1.pwm_hz(PWM_HZ.Hz(), &mut rcc);
        if is_bridge(0) {
            let (la, lb) = (c1.with(e.pe9).erase(), c2.with(e.pe11).erase());
            bridge_legs[0] = legs(Leg::T1(la), Leg::T1(lb));
        }
        if is_bridge(1) {
            let (la, lb) = (c3.with(e.pe13).erase(), c4.with(e.pe14).erase());
            bridge_legs[1] = legs(Leg::T1(la), Leg::T1(lb));
        }
    }
    if USES_TIM8 {
        let (_tim, (c1, c2, c3, c4)) = dp.TIM8.pwm_hz(PWM_HZ.Hz(), &mut rcc);
        if is_bridge(2) {
            let (la, lb) = (c1.with(c.pc6).erase(), c2.with(c.pc7).erase());
            bridge_legs[2] = legs(Leg::T8(la), Leg::T8(lb));
        }
        if is_bridge(3) {
            let (la, lb) = (c3.with(c.pc8).erase(), c4.with(c.pc9).erase());
            bridge_legs[3] = legs(Leg::T8(la), Leg::T8(lb));
        }
    }
    if USES_TIM2 {
        let (_tim, (c1, c2, c3, c4)) = dp.TIM2.pwm_hz(PWM_HZ.Hz(), &mut rcc);
        if is_bridge(4) {
            let (la, lb) = (
                c1.with(a.pa15.into_floating_input()).erase(),
                c2.with(b.pb3.into_floating_input()).erase(),
            );
            bridge_legs[4] = legs(Leg::T2(la), Leg::T2(lb));
        }
        if is_bridge(5) {
            let (la, lb) = (c3.with(b.pb10).erase(), c4.with(b.pb11).erase());
            bridge_legs[5] = legs(Leg::T2(la), Leg::T2(lb));
        }
    }
    if USES_TIM4 {
        let (_tim, (c1, c2, c3, c4)) = dp.TIM4.pwm_hz(PWM_HZ.Hz(), &mut rcc);
        if is_bridge(6) {
            let (la, lb) = (c1.with(d.pd12).erase(), c2.with(d.pd13).erase());
            bridge_legs[6] = legs(Leg::T4(la), Leg::T4(lb));
        }
        if is_bridge(7) {
            let (la, lb) = (c3.with(d.pd14).erase(), c4.with(d.pd15).erase());
            bridge_legs[7] = legs(Leg::T4(la), Leg::T4(lb));
        }
    }

    // DACs: only the channels of DAC segments (PA4, PA5).
    let mut dacs: [Option<DacChannel>; 2] = [None, None];
    if USES_DAC2 {
        let (c1, c2) = dp
            .DAC
            .constrain((a.pa4.into_analog(), a.pa5.into_analog()), &mut rcc);
        dacs = [
            Some(DacChannel::One(dac_channel(c1))),
            Some(DacChannel::Two(dac_channel(c2))),
        ];
    } else if USES_DAC1 {
        let c1 = dp.DAC.constrain(a.pa4.into_analog(), &mut rcc);
        dacs[0] = Some(DacChannel::One(dac_channel(c1)));
    }

    let segments: [Result<Segment, &'static str>; N] = core::array::from_fn(|i| match dac_of(i) {
        Some(k) => match dacs[k].take() {
            Some(ch) => DacOutput::new(ch, DAC_GAIN, DAC_VREF_V, DAC_ZERO_CODE)
                .map(Segment::Dac)
                .map_err(|_| "DAC_GAIN, DAC_VREF_V or DAC_ZERO_CODE is invalid"),
            None => Err("a DAC segment's channel is not wired"),
        },
        None => match bridge_legs[i].take() {
            Some((la, lb)) => HBridge::new(la, lb, bridge_v)
                .map(Segment::Bridge)
                .map_err(|_| "the bridge supply is not a valid supply voltage"),
            None => Err("a bridge segment's legs are not wired"),
        },
    });
    let segments = segments.map(|s| match s {
        Ok(s) => s,
        // Compiled-in configuration: a build error only a run can show.
        Err(what) => defmt::panic!("segment outputs: {}", what),
    });

    // The ADC pins go to analog mode for good (a pin's mode outlives its
    // handle). The typed pins below are the support crate's table's.
    const _: () = {
        use finrs_firmware_support::pins::{LOAD_CELL, SHUNTS};
        assert!(LOAD_CELL.pin.is(b'A', 1));
        assert!(SHUNTS[0].pin.is(b'A', 2) && SHUNTS[1].pin.is(b'A', 3));
        assert!(SHUNTS[2].pin.is(b'C', 1) && SHUNTS[3].pin.is(b'B', 1));
        assert!(SHUNTS[4].pin.is(b'C', 4) && SHUNTS[5].pin.is(b'C', 5));
        assert!(SHUNTS[6].pin.is(b'B', 0) && SHUNTS[7].pin.is(b'C', 2));
    };
    let _ = a.pa1.into_analog();
    let _ = a.pa2.into_analog();
    if N > 1 {
        let _ = a.pa3.into_analog();
    }
    if N > 2 {
        let _ = c.pc1.into_analog();
    }
    if N > 3 {
        let _ = b.pb1.into_analog();
    }
    if N > 4 {
        let _ = c.pc4.into_analog();
    }
    if N > 5 {
        let _ = c.pc5.into_analog();
    }
    if N > 6 {
        let _ = b.pb0.into_analog();
    }
    if N > 7 {
        let _ = c.pc2.into_analog();
    }
    init_adcs(&dp.ADC1, &dp.ADC2, &dp.ADC3, &dp.ADC_COMMON, &mut rcc);
    init_trigger(dp.TIM5, &dp.TIM3, &mut rcc);

    let mut flash = LockedFlash::new(dp.FLASH);
    // The only reads of the whole logs (tens of ms for a full sector),
    // before the watchdog starts; each store after touches one record.
    let (stored_calibration, calibration_log) =
        match calibration_store::load(&mut flash, BOARD_REGION) {
            Ok((found, cursor)) => (found, Some(cursor)),
            Err(_) => {
                defmt::warn!("calibration: flash unreadable, build defaults, no store");
                (None, None)
            }
        };
    if let Some(s) = stored_calibration {
        defmt::info!("calibration: record {} from flash", s.seq);
    }
    let (stored_model, model_log) = match model_store::load(&mut flash, model_store::BOARD_REGION) {
        Ok((found, cursor)) => (found, Some(cursor)),
        Err(_) => {
            defmt::warn!("model: flash unreadable, none held, no store");
            (None, None)
        }
    };

    // The camera's sync LED, dark until a drive starts.
    const { assert!(finrs_firmware_support::pins::SYNC_LED.is(b'E', 7)) };
    let sync_led = e.pe7.into_push_pull_output();
    // The bridges' keep-alive, low (asleep) until the first sample period.
    const { assert!(finrs_firmware_support::pins::KEEPALIVE.is(b'E', 10)) };
    let keepalive_pin = e.pe10.into_push_pull_output();

    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.stop_on_debug(&dp.DBGMCU, true);
    watchdog.start(WATCHDOG_MS.millis());

    Parts {
        io: Io {
            adc1: dp.ADC1,
            adc2: dp.ADC2,
            adc3: dp.ADC3,
            counter: dp.TIM3,
            periods: Periods {
                last_count: 0,
                total: 0,
            },
            segments,
            secondary_late: false,
            monitor: supply.ok().map(SupplyMonitor::new),
            supply_fault: None,
            watchdog,
            flash,
            calibration_log,
            model_log,
            sync_led,
            sync: SyncMark::new(),
            keepalive_pin,
            keepalive: Keepalive::new(),
        },
        frames,
        commands,
        housekeeping: Housekeeping,
        reset_cause: cause,
        supply,
        stored_calibration: stored_calibration.map(|s| s.calibration),
        stored_model,
    }
}

/// VDDA against the internal reference and the bridge supply through its
/// divider, by ADC1's regular group, once (`init_adcs` then resets the
/// ADCs and sets up the injected groups).
fn measure_supplies(
    adc: &pac::ADC1,
    common: &pac::ADC_COMMON,
    rcc: &mut pac::RCC,
) -> Result<Supplies, SupplyError> {
    pac::ADC1::enable(rcc);
    pac::ADC1::reset(rcc);
    common
        .ccr()
        .modify(|_, w| w.adcpre().div4().tsvrefe().set_bit());
    adc.cr2().write(|w| w.adon().set_bit());
    // The ADC's stabilisation (3 µs) and VREFINT's start-up (10 µs, the
    // datasheet's maxima), with margin: 20 µs at 168 MHz.
    cortex_m::asm::delay(SYSCLK_HZ / 50_000);
    let sense = finrs_firmware_support::pins::BRIDGE_SUPPLY_SENSE.channel;
    #[allow(unsafe_code)]
    // SAFETY: SMPR1 takes any bit pattern: 480 cycles (0b111, 23 µs at
    // 21 MHz; VREFINT needs 10 µs) on channel 17 and the sense channel, both
    // in 10..=18.
    unsafe {
        adc.smpr1()
            .write(|w| w.bits(0b111 << (3 * (17 - 10)) | 0b111 << (3 * u32::from(sense - 10))));
    }
    let convert = |channel: u8| -> u16 {
        #[allow(unsafe_code)]
        // SAFETY: one conversion (L = 0) of a channel below 19.
        unsafe {
            adc.sqr1().write(|w| w.bits(0));
            adc.sqr3().write(|w| w.bits(u32::from(channel)));
        }
        adc.sr().modify(|_, w| w.eoc().clear_bit());
        adc.cr2().modify(|_, w| w.swstart().set_bit());
        // About 25 µs; a conversion that never ends reads as 0, which
        // fails the check below.
        for _ in 0..100_000 {
            if adc.sr().read().eoc().bit_is_set() {
                return adc.dr().read().data().bits();
            }
        }
        0
    };
    let vrefint = convert(17);
    let sense_counts = convert(sense);
    common.ccr().modify(|_, w| w.tsvrefe().clear_bit());
    #[allow(unsafe_code)]
    // SAFETY: VREFINT_CAL, the factory's reading of VREFINT at 3.3 V, a
    // u16 in system memory at 0x1FFF_7A2A (STM32F405/407 datasheet,
    // "Internal reference voltage calibration values").
    let cal = unsafe { core::ptr::read_volatile(0x1FFF_7A2A as *const u16) };
    let vdda_v = supply::vdda_v(cal, vrefint).unwrap_or(0.0);
    supply::check(vdda_v, supply::bridge_supply_v(sense_counts, vdda_v))
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

/// ADC1 (load cell, shunts 0..=2), ADC2 (shunts 3..=6) and ADC3 (shunt
/// 7, then the bridge supply's divider on PC3, IN13), those in use:
/// 12-bit, 21 MHz (PCLK2 / 4), an injected group each started by
/// TIM5_TRGO on its rising edge; only ADC1 raises the interrupt (JEOC).
/// 84 cycles of sampling (4 µs) per channel suit the amplifiers' outputs
/// and the divider's 3.2 kΩ; ADC1's group of at most 4 takes 4 × (84 +
/// 12) / 21 MHz ≈ 18 µs of the 1 ms period, the others (ADC3's 2 at most)
/// run beside it.
fn init_adcs(
    adc1: &pac::ADC1,
    adc2: &pac::ADC2,
    adc3: &pac::ADC3,
    common: &pac::ADC_COMMON,
    rcc: &mut pac::RCC,
) {
    // One reset for all three, before any is set up: RCC_APB2RSTR has one
    // ADC reset bit, ADCRST (bit 8, RM0090: "ADC interface reset (common to
    // all ADCs)"), and the HAL
    // resets ADC2 and ADC3 through that same bit (stm32f4xx-hal 0.23,
    // rcc/f4/enable.rs: `bus_reset!(ADC2 => 8)`, `bus_reset!(ADC3 => 8)`).
    // A reset after ADC1's set-up wiped it (no JEOC, so no sample task, no
    // watchdog feed: a reset every 20 ms) and put the common prescaler back
    // to /2, 42 MHz against the 36 MHz maximum.
    pac::ADC1::enable(rcc);
    if ADC2_SHUNTS > 0 {
        pac::ADC2::enable(rcc);
    }
    pac::ADC3::enable(rcc);
    pac::ADC1::reset(rcc);
    common.ccr().modify(|_, w| w.adcpre().div4());
    let mut group1 = [pins::LOAD_CELL_CHANNEL; 4];
    group1[1..=ADC1_SHUNTS].copy_from_slice(&pins::SHUNT_CHANNELS[..ADC1_SHUNTS]);
    init_group(adc1, &group1[..=ADC1_SHUNTS], true);
    if ADC2_SHUNTS > 0 {
        init_group(adc2, &pins::SHUNT_CHANNELS[3..3 + ADC2_SHUNTS], false);
    }
    // PC3 is ADC123_IN13 (`pins::DATASHEET_LQFP100`): ADC3 reads it after
    // shunt 7, if any, so the supply is read every period with the rest.
    let mut group3 = [SUPPLY_SENSE_CHANNEL; 2];
    group3[..ADC3_SHUNTS].copy_from_slice(&pins::SHUNT_CHANNELS[7..7 + ADC3_SHUNTS]);
    init_group(adc3, &group3[..=ADC3_SHUNTS], false);
}

/// One ADC's injected group: `channels` (1..=4, each below 19) in order,
/// 84-cycle sampling, TIM5_TRGO rising edge, JEOC interrupt if `interrupt`.
fn init_group(adc: &pac::adc1::RegisterBlock, channels: &[u8], interrupt: bool) {
    adc.cr1()
        .write(|w| w.scan().set_bit().jeocie().bit(interrupt));
    // 84 cycles (0b100) on the channels used: SMPR2 holds channels 0..=9,
    // SMPR1 10..=18, three bits each.
    let (mut smpr1, mut smpr2) = (0u32, 0u32);
    for &ch in channels {
        if ch < 10 {
            smpr2 |= 0b100 << (3 * u32::from(ch));
        } else {
            smpr1 |= 0b100 << (3 * u32::from(ch - 10));
        }
    }
    // A group of JL + 1 conversions runs JSQ(4 - JL)..JSQ4 (RM0090 13.13.12)
    // and leaves its results in JDR1.. in order: channels go right-aligned.
    let len = channels.len().clamp(1, 4);
    let mut jsqr = ((len - 1) as u32) << 20;
    for (k, &ch) in channels.iter().take(len).enumerate() {
        let slot = 4 - len + k;
        jsqr |= u32::from(ch & 0x1f) << (5 * slot);
    }
    #[allow(unsafe_code)]
    // SAFETY: SMPRx and JSQR take any bit pattern; the fields written are
    // the pin map's channels (below 19) and a length of 1..=4.
    unsafe {
        adc.smpr1().write(|w| w.bits(smpr1));
        adc.smpr2().write(|w| w.bits(smpr2));
        adc.jsqr().write(|w| w.bits(jsqr));
    }
    adc.cr2().write(|w| {
        w.jexten().rising_edge();
        w.jextsel().tim5trgo();
        w.adon().set_bit()
    });
}

/// TIM5 counts at 1 MHz (84 MHz / 84) and updates at the sample rate; its
/// update event is TRGO, which starts the ADCs' groups and clocks TIM3, the
/// sample period counter ([`Periods`]). TIM3 is set up before TIM5 runs so
/// that it sees every update from the first.
fn init_trigger(tim: pac::TIM5, counter: &pac::TIM3, rcc: &mut pac::RCC) {
    pac::TIM5::enable(rcc);
    pac::TIM5::reset(rcc);
    tim.psc().write(|w| w.psc().set(84 - 1));
    tim.arr().write(|w| w.arr().set(1_000_000 / SAMPLE_HZ - 1));
    tim.egr().write(|w| w.ug().set_bit());
    tim.cr2().write(|w| w.mms().update());
    // TIM3 in external clock mode 1 on its internal trigger ITR2, which is
    // TIM5's TRGO (RM0090, TIM2 to TIM5, "TIMx internal trigger
    // connection": TIM3's ITR0..3 are TIM1, TIM2, TIM5, TIM4): each TIM5
    // update counts one, up to 0xFFFF and round.
    pac::TIM3::enable(rcc);
    pac::TIM3::reset(rcc);
    counter.arr().write(|w| w.arr().set(0xFFFF));
    counter
        .smcr()
        .write(|w| w.ts().itr2().sms().ext_clock_mode());
    counter.cr1().write(|w| w.cen().set_bit());
    tim.cr1().write(|w| w.cen().set_bit());
}

/// Sample periods since boot, counted in hardware: TIM3's 16-bit count of
/// TIM5's updates, widened to 64 bits at each reading. A sample task that
/// starts more than a period late reads a count that has moved by more
/// than one (the ADCs' results are the last period's), so no period goes
/// unnumbered and time does not drift. The widening needs a reading at
/// least every 65 535 periods (65 s), which the watchdog guarantees.
struct Periods {
    last_count: u16,
    total: u64,
}

impl Periods {
    /// The periods counted so far.
    fn read(&mut self, counter: &pac::TIM3) -> u64 {
        let count = counter.cnt().read().cnt().bits();
        self.total += u64::from(count.wrapping_sub(self.last_count));
        self.last_count = count;
        self.total
    }
}

impl Io {
    /// The groups that just ended, numbered by the hardware's period count;
    /// `None` if ADC1's group did not end (a spurious interrupt).
    pub fn read(&mut self) -> Option<TickInput<N>> {
        if self.adc1.sr().read().jeoc().bit_is_clear() {
            return None;
        }
        let tick = self.periods.read(&self.counter);
        self.adc1
            .sr()
            .modify(|_, w| w.jeoc().clear_bit().jstrt().clear_bit());
        if ADC2_SHUNTS > 0 && !secondary_done(&self.adc2) {
            self.secondary_late = true;
        }
        if !secondary_done(&self.adc3) {
            self.secondary_late = true;
        }
        let counts = |adc: &pac::adc1::RegisterBlock, i: usize| adc.jdr(i).read().jdata().bits();
        let mut current_counts = [0u16; N];
        for (i, c) in current_counts.iter_mut().enumerate() {
            *c = match i {
                0..=2 => counts(&self.adc1, i + 1),
                3..=6 => counts(&self.adc2, i - 3),
                _ => counts(&self.adc3, 0),
            };
        }
        self.follow_supply(counts(&self.adc3, ADC3_SHUNTS));
        Some(TickInput {
            tick,
            t_us: (tick * 1_000_000 / u64::from(SAMPLE_HZ)) as u32,
            load_cell_counts: counts(&self.adc1, 0),
            current_counts,
        })
    }

    /// The period's reading of the bridge supply: the bridges work their
    /// next duties out from it, or, out of the monitor's band, nothing is
    /// driven and the fault waits for [`take_supply_fault`](Self::take_supply_fault).
    fn follow_supply(&mut self, sense_counts: u16) {
        let Some(monitor) = self.monitor.as_mut() else {
            return;
        };
        match monitor.update(sense_counts) {
            Ok(duty_supply_v) => {
                for segment in self.segments.iter_mut() {
                    if let Segment::Bridge(b) = segment {
                        // Finite and above 0 by the monitor's band.
                        let _ = b.set_supply_v(duty_supply_v);
                    }
                }
            }
            Err(e) => self.supply_fault = Some(e),
        }
    }

    /// This period's supply reading if it was out of the monitor's band
    /// (every period while it stays out): the sample task latches it as a
    /// `Supply` fault.
    pub fn take_supply_fault(&mut self) -> Option<SupplyError> {
        self.supply_fault.take()
    }

    /// Writes the controller's voltages to the segments, or turns them off
    /// (`None`: a bridge opened, where 0 V would brake it).
    /// The sync LED follows what is applied: lit for a moment when a drive
    /// starts after a rest (`finrs_firmware_support::sync`).
    pub fn write_v(&mut self, v: Option<&[f32; N]>) {
        let in_band = self.monitor.as_ref().is_some_and(SupplyMonitor::in_band);
        let applied = match v.filter(|_| in_band) {
            Some(v) => {
                for (segment, &v) in self.segments.iter_mut().zip(v) {
                    segment.set_v(v);
                }
                *v
            }
            None => {
                self.off();
                [0.0; N]
            }
        };
        let lit = self.sync.update(&applied).lit;
        self.sync_led.set_state(PinState::from(lit));
    }

    /// Every segment off.
    pub fn off(&mut self) {
        for segment in self.segments.iter_mut() {
            segment.off();
        }
    }

    /// Feeds the IWDG.
    pub fn feed_watchdog(&mut self) {
        self.watchdog.feed();
    }

    /// Moves the bridges' keep-alive (`finrs_firmware_support::keepalive`):
    /// flipped each period while `healthy`, low while a fault is latched.
    pub fn keep_alive(&mut self, healthy: bool) {
        let high = self.keepalive.level(healthy);
        self.keepalive_pin.set_state(PinState::from(high));
    }

    /// Appends `calibration` to the flash records; true once it reads back.
    /// Call with the outputs at 0 V: it stalls the core (module doc).
    pub fn store_calibration(&mut self, calibration: &Calibration) -> bool {
        let Self {
            flash,
            watchdog,
            calibration_log,
            ..
        } = self;
        store(
            flash,
            watchdog,
            calibration_log,
            "calibration",
            |f, at, before| calibration_store::save(f, BOARD_REGION, at, calibration, before),
        )
    }

    /// Appends `record` to the model's log in flash (sectors 8 and 9), as
    /// [`store_calibration`](Self::store_calibration) does the
    /// calibration's: 256 bytes programmed, a sector erased only when the
    /// other is full.
    pub fn store_model(&mut self, record: &finrs_frames::ModelRecord) -> bool {
        let Self {
            flash,
            watchdog,
            model_log,
            ..
        } = self;
        store(flash, watchdog, model_log, "model", |f, at, before| {
            model_store::save(f, model_store::BOARD_REGION, at, record, before)
        })
    }

    /// Whether the next group already ended (this period overran), or
    /// ADC2/ADC3's group was late (their results are then a period old).
    pub fn deadline_missed(&mut self) -> bool {
        core::mem::take(&mut self.secondary_late) || self.adc1.sr().read().jeoc().bit_is_set()
    }
}

/// Runs one store's `save` at the log's position `log` on the unlocked
/// flash, the watchdog widened first to cover the datasheet's longest time
/// for what the store says it will do (`flash_timing`) and set back after;
/// logs the outcome under `what`.
fn store<E>(
    flash: &mut LockedFlash,
    watchdog: &mut IndependentWatchdog,
    log: &mut Option<Cursor>,
    what: &str,
    save: impl FnOnce(
        &mut UnlockedFlash<'_>,
        &mut Cursor,
        &mut dyn FnMut(Work),
    ) -> Result<u32, StoreError<E>>,
) -> bool {
    let Some(at) = log else {
        defmt::error!("{=str}: its flash was unreadable at boot; not stored", what);
        return false;
    };
    let mut widened = false;
    let result = {
        let mut unlocked = flash.unlocked();
        save(&mut unlocked, at, &mut |work| {
            widened = true;
            set_watchdog(watchdog, store_watchdog_ms(work, WATCHDOG_MS));
        })
    };
    if widened {
        set_watchdog(watchdog, WATCHDOG_MS);
    }
    match result {
        Ok(seq) => {
            defmt::info!("{=str}: stored as record {}", what, seq);
            true
        }
        Err(_) => {
            defmt::error!("{=str}: the flash write failed; not stored", what);
            false
        }
    }
}

/// A new watchdog period, in force before this returns: the IWDG takes a
/// new prescaler and reload value up to 5 LSI periods after they are
/// written (RM0090 §21.3.2, PVU/RVU), and a reload before that would load
/// the old one; 1 ms covers 5 periods of the slowest LSI (17 kHz).
fn set_watchdog(watchdog: &mut IndependentWatchdog, period_ms: u32) {
    watchdog.start(period_ms.millis());
    cortex_m::asm::delay(SYSCLK_HZ / 1_000);
    watchdog.feed();
}

/// Waits (bounded) for a secondary ADC's group to end and clears its flag;
/// false if it did not end in [`SECONDARY_ADC_POLLS`] polls.
fn secondary_done(adc: &pac::adc1::RegisterBlock) -> bool {
    for _ in 0..SECONDARY_ADC_POLLS {
        if adc.sr().read().jeoc().bit_is_set() {
            adc.sr()
                .modify(|_, w| w.jeoc().clear_bit().jstrt().clear_bit());
            return true;
        }
    }
    false
}

/// The ADC trigger timer paces the sample task: nothing to do.
pub async fn pace() -> ! {
    loop {
        core::future::pending::<()>().await;
    }
}

/// Interval between reports of the stack's use, s.
const STACK_REPORT_S: u32 = 10;

/// Reports the stack's use every [`STACK_REPORT_S`] (a scan of the painted
/// words, well under a millisecond at this priority).
pub async fn housekeeping(_: &mut Housekeeping) -> ! {
    loop {
        // Qualified: the HAL's prelude has its own `delay` and `secs`.
        let period = rtic_monotonics::fugit::ExtU32::secs(STACK_REPORT_S);
        <Mono as rtic_monotonics::Timebase>::delay(period).await;
        crate::stack::report();
    }
}

/// Forces every bridge input low and every DAC segment to 0 V by register
/// writes, whatever state the drivers are in: compare registers to 0 and
/// each channel's output mode to "force inactive" (the pin then stays low
/// even if the counter runs on), DAC data to the 0 V code. Only the
/// peripherals this build clocks are touched.
fn zero_outputs_now() {
    // SAFETY: called only on the way to a halt (panic, HardFault, NMI, an
    // unexpected interrupt), when no
    // other code will touch these peripherals again; each write is to a
    // timer's own compare and mode registers or the DAC's data registers.
    #[allow(unsafe_code)]
    let dp = unsafe { pac::Peripherals::steal() };
    macro_rules! zero_timer {
        ($tim:expr) => {
            for ccr in $tim.ccr_iter() {
                ccr.write(|w| w.ccr().set(0));
            }
            $tim.ccmr1_output()
                .modify(|_, w| w.oc1m().force_inactive().oc2m().force_inactive());
            $tim.ccmr2_output()
                .modify(|_, w| w.oc3m().force_inactive().oc4m().force_inactive());
        };
    }
    if USES_TIM1 {
        zero_timer!(dp.TIM1);
    }
    if USES_TIM8 {
        zero_timer!(dp.TIM8);
    }
    if USES_TIM2 {
        zero_timer!(dp.TIM2);
    }
    if USES_TIM4 {
        zero_timer!(dp.TIM4);
    }
    if USES_DAC1 {
        dp.DAC.dhr12r1().write(|w| w.daccdhr().set(DAC_ZERO_CODE));
    }
    if USES_DAC2 {
        dp.DAC.dhr12r2().write(|w| w.daccdhr().set(DAC_ZERO_CODE));
    }
}

/// Outputs to zero first, then the message, then stop for the debugger
/// (the watchdog resets the board if none is attached). The message only
/// on the first entry: rtt-target's logger panics when it is already
/// taken, so a panic while a log line is written (or in this message)
/// would enter here again and log again, each entry a frame deeper, until
/// the stack ran off the RAM (scripts/check-stack bounds one entry).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    zero_outputs_now();
    if !PANICKED.swap(true, core::sync::atomic::Ordering::Relaxed) {
        defmt::error!("panic: {}", defmt::Display2Format(info));
    }
    cortex_m::asm::udf()
}

/// Set by the panic handler's first entry.
static PANICKED: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// A fault other than a panic: outputs to zero, then wait for the watchdog.
/// Nothing is logged: a HardFault can preempt a critical section, the
/// logger's among them. `cargo run` passes `--no-catch-hardfault` to
/// probe-rs (`.cargo/config.toml`), whose `run` otherwise halts the core at
/// this vector, before this body can zero anything, with the watchdog
/// frozen by the halt.
#[cortex_m_rt::exception]
#[allow(unsafe_code)] // cortex-m-rt requires the HardFault handler to be `unsafe fn`
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    zero_outputs_now();
    loop {
        cortex_m::asm::nop();
    }
}

/// What the stack guard's MemManage handler calls, on the stack's top
/// again (`finrs_firmware_support::stack_guard`): an overflow, so outputs
/// to zero, then wait for the watchdog; nothing is logged, for the
/// HardFault's reason.
pub extern "C" fn stack_overflow_stop() -> ! {
    zero_outputs_now();
    loop {
        cortex_m::asm::nop();
    }
}

/// The non-maskable interrupt (on this part the clock security system, if
/// enabled, or a debugger's request): nothing here expects one, so it is a
/// fault. Outputs to zero, then wait for the watchdog; nothing is logged,
/// for the HardFault's reason.
#[cortex_m_rt::exception]
#[allow(unsafe_code)] // an NMI handler must be `unsafe fn`: it preempts critical sections
unsafe fn NonMaskableInt() {
    zero_outputs_now();
    loop {
        cortex_m::asm::nop();
    }
}

/// Any exception or interrupt that has no handler of its own: outputs to
/// zero, the IRQ number logged (every one of these is masked by a critical
/// section, so the logger's is not broken into), then interrupts off, so
/// no task drives again, and wait for the watchdog.
#[cortex_m_rt::exception]
#[allow(unsafe_code)] // cortex-m-rt requires the default handler to be `unsafe fn`
unsafe fn DefaultHandler(irqn: i16) {
    zero_outputs_now();
    defmt::error!("unexpected interrupt {}: outputs off", irqn);
    cortex_m::interrupt::disable();
    loop {
        cortex_m::asm::nop();
    }
}
