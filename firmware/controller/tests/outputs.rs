//! Segment outputs with mock PWM and DAC: duty rounding, sign, clamping,
//! off, refused configurations and PWM errors.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::pwm::{ErrorKind, ErrorType, SetDutyCycle};
use finrs_controller::{DacOutput, DacWrite, HBridge, OutputError, SegmentOutput};
use proptest::prelude::*;

#[derive(Debug)]
struct PwmError;

impl embedded_hal::pwm::Error for PwmError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// A PWM channel that logs each duty written to a log shared by both sides.
struct Pwm {
    name: char,
    max: u16,
    duty: u16,
    fail: bool,
    log: Rc<RefCell<Vec<(char, u16)>>>,
}

impl ErrorType for Pwm {
    type Error = PwmError;
}

impl SetDutyCycle for Pwm {
    fn max_duty_cycle(&self) -> u16 {
        self.max
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), PwmError> {
        assert!(duty <= self.max, "duty {duty} above max {}", self.max);
        if self.fail && duty != 0 {
            return Err(PwmError);
        }
        self.duty = duty;
        self.log.borrow_mut().push((self.name, duty));
        Ok(())
    }
}

type Log = Rc<RefCell<Vec<(char, u16)>>>;

fn bridge(max: u16, supply_v: f32) -> (HBridge<Pwm, Pwm>, Log) {
    let log = Rc::new(RefCell::new(Vec::new()));
    let pwm = |name| Pwm {
        name,
        max,
        duty: 0xBEEF,
        fail: false,
        log: log.clone(),
    };
    (HBridge::new(pwm('A'), pwm('B'), supply_v).unwrap(), log)
}

fn duties(b: HBridge<Pwm, Pwm>) -> (u16, u16) {
    let (a, b) = b.release();
    (a.duty, b.duty)
}

fn after(max: u16, supply_v: f32, v: f32) -> (u16, u16) {
    let (mut b, _) = bridge(max, supply_v);
    b.set_v(v);
    duties(b)
}

/// (leg A, leg B) duties after `v`. Slow decay: one leg held fully on, the
/// other high (braking) for all but the forward steps.
#[test]
fn h_bridge_sign_and_rounding() {
    assert_eq!(after(1000, 8.0, 2.0), (1000, 750));
    assert_eq!(after(1000, 8.0, -2.0), (750, 1000));
    // 0 V is held: both legs on, both outputs low.
    assert_eq!(after(1000, 8.0, 0.0), (1000, 1000));
    assert_eq!(after(1000, 8.0, -0.0), (1000, 1000));
    // The forward steps are rounded down: 2.5 and 2.25 steps drive 2.
    assert_eq!(after(10, 4.0, 1.0), (10, 8));
    assert_eq!(after(10, 4.0, 0.9), (10, 8));
    assert_eq!(after(10, 4.0, -0.9), (8, 10));
    assert_eq!(after(10, 4.0, 0.39), (10, 10), "under one step drives none");
    // Full scale of a 16-bit timer.
    assert_eq!(after(u16::MAX, 5.0, 5.0), (u16::MAX, 0));
}

#[test]
fn h_bridge_clamps_to_its_supply_and_opens_on_nan() {
    assert_eq!(after(1000, 3.0, 4.0), (1000, 0));
    assert_eq!(after(1000, 3.0, -400.0), (0, 1000));
    assert_eq!(after(1000, 3.0, f32::INFINITY), (1000, 0));
    assert_eq!(after(1000, 3.0, f32::NEG_INFINITY), (0, 1000));
    assert_eq!(after(1000, 3.0, f32::NAN), (0, 0));
}

#[test]
fn h_bridge_starts_open_and_sets_the_held_leg_first() {
    let (mut b, log) = bridge(100, 4.0);
    assert_eq!(*log.borrow(), [('A', 0), ('B', 0)], "new() opens both");
    log.borrow_mut().clear();
    b.set_v(2.0);
    b.set_v(-1.0);
    b.off();
    assert_eq!(
        *log.borrow(),
        [
            ('A', 100),
            ('B', 50),
            ('B', 100),
            ('A', 75),
            ('A', 0),
            ('B', 0)
        ]
    );
    assert_eq!(b.errors(), 0);
    assert_eq!(duties(b), (0, 0));
}

#[test]
fn h_bridge_refuses_a_bad_supply() {
    for supply_v in [0.0, -5.0, f32::NAN, f32::INFINITY] {
        let log = Rc::new(RefCell::new(Vec::new()));
        let pwm = |name| Pwm {
            name,
            max: 100,
            duty: 0,
            fail: false,
            log: log.clone(),
        };
        let e = HBridge::new(pwm('A'), pwm('B'), supply_v).err().unwrap();
        assert_eq!(e.field, "supply_v", "{supply_v}");
        // A measured supply that breaks the rule is refused, the old kept.
        let mut good = HBridge::new(pwm('A'), pwm('B'), 5.0).unwrap();
        assert_eq!(good.set_supply_v(supply_v).unwrap_err().field, "supply_v");
        assert_eq!(good.supply_v(), 5.0);
    }
}

#[test]
fn h_bridge_works_its_duty_out_from_the_supply_it_was_last_told() {
    let (mut b, _) = bridge(1000, 5.0);
    b.set_v(2.0);
    b.set_supply_v(5.5).unwrap();
    b.set_v(2.0);
    let (a, legb) = b.release();
    // 2 V of 5.5: 363.6 forward steps, rounded down, 636 braking.
    assert_eq!((a.duty, legb.duty), (1000, 1000 - 363));
}

#[test]
fn a_pwm_error_turns_both_sides_off_and_counts() {
    let log = Rc::new(RefCell::new(Vec::new()));
    let pwm = |name, fail| Pwm {
        name,
        max: 100,
        duty: 0,
        fail,
        log: log.clone(),
    };
    // Side A fails on any duty but 0, and every set_v writes one to it
    // (its braking duty or fully on).
    for v in [2.0, -2.0] {
        let mut b = HBridge::new(pwm('A', true), pwm('B', false), 4.0).unwrap();
        b.off();
        assert_eq!(b.errors(), 0, "opening writes 0 to both legs");
        b.set_v(v);
        assert_eq!(b.errors(), 1, "{v} V");
        assert_eq!(duties(b), (0, 0), "opened after the error at {v} V");
    }
}

#[derive(Default)]
struct Dac {
    codes: Vec<u16>,
}

impl DacWrite for Dac {
    fn write_code(&mut self, code: u16) {
        self.codes.push(code);
    }
}

fn dac_after(gain: f32, vref_v: f32, zero_code: u16, v: f32) -> u16 {
    let mut d = DacOutput::new(Dac::default(), gain, vref_v, zero_code).unwrap();
    d.set_v(v);
    let dac = d.release();
    assert_eq!(dac.codes[0], zero_code, "new() writes 0 V");
    *dac.codes.last().unwrap()
}

#[test]
fn dac_codes_round_toward_zero_volts_and_clamp() {
    // Gain 2 on a 3.3 V reference: 6.6 V / 4095 codes.
    assert_eq!(dac_after(2.0, 3.3, 2048, 0.0), 2048);
    assert_eq!(dac_after(2.0, 3.3, 2048, 1.0), 2048 + 620); // 620.45
    assert_eq!(dac_after(2.0, 3.3, 2048, -1.0), 2048 - 620);
    // Never more than asked: 0.6 of a code is none, 1.9 codes one.
    assert_eq!(dac_after(2.0, 3.3, 2048, 6.6 / 4095.0 * 0.6), 2048);
    assert_eq!(dac_after(2.0, 3.3, 2048, 6.6 / 4095.0 * 1.9), 2049);
    assert_eq!(dac_after(2.0, 3.3, 2048, -6.6 / 4095.0 * 1.9), 2047);
    assert_eq!(dac_after(2.0, 3.3, 2048, 10.0), 4095);
    assert_eq!(dac_after(2.0, 3.3, 2048, -10.0), 0);
    assert_eq!(dac_after(2.0, 3.3, 2048, f32::INFINITY), 4095);
    assert_eq!(dac_after(2.0, 3.3, 2048, f32::NEG_INFINITY), 0);
    assert_eq!(dac_after(2.0, 3.3, 2048, f32::NAN), 2048);
    // An inverting amplifier.
    assert_eq!(dac_after(-2.0, 3.3, 2048, 1.0), 2048 - 620);
    let mut d = DacOutput::new(Dac::default(), 2.0, 3.3, 100).unwrap();
    d.set_v(3.0);
    d.off();
    assert_eq!(d.release().codes, [100, 100 + 1861, 100]);
}

#[test]
fn dac_refuses_bad_configuration() {
    let e = |gain, vref_v, zero| {
        DacOutput::new(Dac::default(), gain, vref_v, zero)
            .err()
            .map(|e: OutputError| e.field)
    };
    assert_eq!(e(0.0, 3.3, 2048), Some("gain"));
    assert_eq!(e(f32::NAN, 3.3, 2048), Some("gain"));
    assert_eq!(e(2.0, 0.0, 2048), Some("vref_v"));
    assert_eq!(e(2.0, f32::INFINITY, 2048), Some("vref_v"));
    assert_eq!(e(2.0, 3.3, 4096), Some("zero_code"));
    assert_eq!(e(2.0, 3.3, 4095), None);
}

proptest! {
    #[test]
    fn outputs_never_panic_and_stay_in_range(
        v in any::<u32>().prop_map(f32::from_bits),
        max in 1u16..,
        supply_v in 0.1f32..100.0,
        gain in prop_oneof![-50.0f32..-0.1, 0.1f32..50.0],
        zero in 0u16..=4095,
    ) {
        let (a, b) = after(max, supply_v, v);
        prop_assert!(a <= max && b <= max);
        if v.is_nan() {
            prop_assert_eq!((a, b), (0, 0), "NaN opens the bridge");
        } else {
            prop_assert!(a == max || b == max, "one leg held on");
            // Forward steps: never above |v| / supply, at most one below.
            let forward = f32::from(max - a.min(b));
            let want = (v.abs() / supply_v).min(1.0) * f32::from(max);
            prop_assert!(forward <= want * (1.0 + 1e-6), "{forward} > {want}");
            prop_assert!(forward > want - 1.0 - want * 1e-6, "{forward} << {want}");
            if v > 0.0 {
                prop_assert!(a == max, "positive volts hold leg A");
            }
        }
        let code = dac_after(gain, 3.3, zero, v);
        prop_assert!(code <= 4095);
    }
}
