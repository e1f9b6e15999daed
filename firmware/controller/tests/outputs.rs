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

#[test]
fn h_bridge_sign_and_rounding() {
    assert_eq!(after(1000, 8.0, 2.0), (250, 0));
    assert_eq!(after(1000, 8.0, -2.0), (0, 250));
    assert_eq!(after(1000, 8.0, 0.0), (0, 0));
    assert_eq!(after(1000, 8.0, -0.0), (0, 0));
    // 2.5 rounds up, 2.25 down.
    assert_eq!(after(10, 4.0, 1.0), (3, 0));
    assert_eq!(after(10, 4.0, 0.9), (2, 0));
    assert_eq!(after(10, 4.0, -0.9), (0, 2));
    // Full scale of a 16-bit timer.
    assert_eq!(after(u16::MAX, 5.0, 5.0), (u16::MAX, 0));
}

#[test]
fn h_bridge_clamps_to_its_supply_and_turns_off_on_nan() {
    assert_eq!(after(1000, 3.0, 4.0), (1000, 0));
    assert_eq!(after(1000, 3.0, -400.0), (0, 1000));
    assert_eq!(after(1000, 3.0, f32::INFINITY), (1000, 0));
    assert_eq!(after(1000, 3.0, f32::NEG_INFINITY), (0, 1000));
    assert_eq!(after(1000, 3.0, f32::NAN), (0, 0));
}

#[test]
fn h_bridge_starts_off_and_turns_the_idle_side_off_first() {
    let (mut b, log) = bridge(100, 4.0);
    assert_eq!(*log.borrow(), [('A', 0), ('B', 0)], "new() turns off");
    log.borrow_mut().clear();
    b.set_v(2.0);
    b.set_v(-1.0);
    b.off();
    assert_eq!(
        *log.borrow(),
        [('B', 0), ('A', 50), ('A', 0), ('B', 25), ('A', 0), ('B', 0)]
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
    }
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
    let mut b = HBridge::new(pwm('A', true), pwm('B', false), 4.0).unwrap();
    b.set_v(-2.0);
    assert_eq!(b.errors(), 0, "side A is not driven for negative volts");
    b.set_v(2.0);
    assert_eq!(b.errors(), 1);
    assert_eq!(duties(b), (0, 0));
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
fn dac_codes_round_and_clamp() {
    // Gain 2 on a 3.3 V reference: 6.6 V / 4095 codes.
    assert_eq!(dac_after(2.0, 3.3, 2048, 0.0), 2048);
    assert_eq!(dac_after(2.0, 3.3, 2048, 1.0), 2048 + 620); // 620.45
    assert_eq!(dac_after(2.0, 3.3, 2048, -1.0), 2048 - 620);
    assert_eq!(dac_after(2.0, 3.3, 2048, 6.6 / 4095.0 * 0.6), 2049);
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
        prop_assert!(a == 0 || b == 0, "one side at a time");
        if v.is_finite() {
            let want = (v.abs() / supply_v).min(1.0) * f32::from(max);
            prop_assert!((f32::from(a.max(b)) - want).abs() <= 0.5 + want * 1e-6);
        }
        let code = dac_after(gain, 3.3, zero, v);
        prop_assert!(code <= 4095);
    }
}
