//! The bridge's switching at 25 kHz into the strip's circuit, simulated
//! exactly between edges: the slow decay that [`HBridge`] drives keeps the
//! strip's average terminal voltage at duty × supply, within the limit;
//! the coast it replaced (one leg PWM'd, the other low) does not.
//!
//! The strip is the model's own circuit (`R1` in series with `C`, `R2`
//! across both, eq. 2.1–2.2). An IN1/IN2 driver of the DRV8833 class drives
//! its outputs from its inputs: 1/0 OUT1 at the supply and OUT2 low, 0/1 the
//! reverse, 1/1 both low (slow decay), 0/0 both open (coast). Driven, the
//! terminal voltage is what the outputs give; open, no current flows into
//! the strip, `C` discharges through `R1` and `R2` in series and the
//! terminals sit at `V_C R2 / (R1 + R2)` (below the supply: the outputs'
//! body diodes never conduct, which the simulation checks).
//!
//! The terminal current is then two-level, and the ADC converts once a
//! millisecond at a fixed phase of the PWM: the last test reads it there,
//! unfiltered as the board first did and through the shunt amplifier's
//! filter ([`SHUNT_FILTER`]), against the period's mean.

use std::cell::Cell;
use std::convert::Infallible;
use std::rc::Rc;

use embedded_hal::pwm::{ErrorType, SetDutyCycle};
use finrs_controller::{HBridge, SegmentOutput};
use finrs_firmware_support::config::{
    AMPS_PER_COUNT, BRIDGE_SUPPLY_V, MAX_ABS_V, PWM_HZ, SHUNT_FILTER,
};
use model_core::Params;

/// The board's bridge supply and limit, V.
const SUPPLY_V: f64 = BRIDGE_SUPPLY_V as f64;
const LIMIT_V: f64 = MAX_ABS_V as f64;
/// TIM1 at 168 MHz counting to 25 kHz: 6720 steps a period.
const PWM_STEPS: u16 = (168_000_000 / PWM_HZ) as u16;
const PERIOD_S: f64 = 1.0 / PWM_HZ as f64;

/// A timer channel whose duty the test reads back.
#[derive(Clone)]
struct Leg(Rc<Cell<u16>>);

impl ErrorType for Leg {
    type Error = Infallible;
}

impl SetDutyCycle for Leg {
    fn max_duty_cycle(&self) -> u16 {
        PWM_STEPS
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.0.set(duty);
        Ok(())
    }
}

/// The driver's inputs over one period: edge-aligned PWM (RM0090, PWM mode
/// 1 counting up: the output is high while the counter is below the
/// compare value, held high when the compare value is above the
/// auto-reload), both legs from one timer.
#[derive(Clone, Copy, Debug)]
struct Inputs {
    duty_a: u16,
    duty_b: u16,
}

/// What the driver on `supply_v` does to the terminals: a voltage, or open.
fn driver(in1: bool, in2: bool, supply_v: f64) -> Option<f64> {
    match (in1, in2) {
        (true, false) => Some(supply_v),
        (false, true) => Some(-supply_v),
        (true, true) => Some(0.0),
        (false, false) => None,
    }
}

/// The strip's circuit, the charge on `C` as its voltage, behind a
/// driver on `supply_v`.
struct Strip {
    r1_ohm: f64,
    r2_ohm: f64,
    c_f: f64,
    v_c: f64,
    supply_v: f64,
}

impl Strip {
    fn new(p: &Params, supply_v: f64) -> Self {
        Self {
            r1_ohm: p.r1_ohm,
            r2_ohm: p.r2_ohm,
            c_f: p.c_f,
            v_c: 0.0,
            supply_v,
        }
    }

    /// Holds the terminals at `u` (or open) for `dt_s`; returns the
    /// integrals of the terminal voltage and of `C`'s over it, exactly.
    fn hold(&mut self, u: Option<f64>, dt_s: f64) -> (f64, f64) {
        let start = self.v_c;
        match u {
            Some(u) => {
                let tau_s = self.r1_ohm * self.c_f;
                let decay = (-dt_s / tau_s).exp();
                self.v_c = u + (start - u) * decay;
                (u * dt_s, u * dt_s + (start - u) * tau_s * (1.0 - decay))
            }
            None => {
                let tau_s = (self.r1_ohm + self.r2_ohm) * self.c_f;
                let share = self.r2_ohm / (self.r1_ohm + self.r2_ohm);
                assert!(
                    (start * share).abs() <= self.supply_v,
                    "an open terminal at {} V would turn a body diode on",
                    start * share
                );
                let decay = (-dt_s / tau_s).exp();
                self.v_c = start * decay;
                let c_integral = start * tau_s * (1.0 - decay);
                (share * c_integral, c_integral)
            }
        }
    }

    /// One PWM period; returns the mean terminal voltage, the mean and the
    /// largest magnitude of `C`'s voltage over it (monotonic within a span,
    /// so largest at a span's end).
    fn period(&mut self, inputs: Inputs) -> (f64, f64, f64) {
        let step_s = PERIOD_S / f64::from(PWM_STEPS);
        let (a, b) = (inputs.duty_a, inputs.duty_b);
        // The edges split the period into at most three spans.
        let (first, second) = (a.min(b), a.max(b));
        let (mut terminal, mut c, mut c_peak) = (0.0, 0.0, self.v_c.abs());
        for (from, to) in [(0, first), (first, second), (second, PWM_STEPS)] {
            if to > from {
                let u = driver(from < a, from < b, self.supply_v);
                let (t, v) = self.hold(u, f64::from(to - from) * step_s);
                terminal += t;
                c += v;
                c_peak = c_peak.max(self.v_c.abs());
            }
        }
        (terminal / PERIOD_S, c / PERIOD_S, c_peak)
    }
}

/// What the strip settles to under fixed inputs.
#[derive(Debug)]
struct Settled {
    /// Terminal voltage, mean over the last periods, V.
    terminal_v: f64,
    /// `C`'s voltage, its mean and largest magnitude over them, V.
    c_mean_v: f64,
    c_peak_v: f64,
}

/// Runs the strip from rest for ten of its slowest time constants, then
/// measures a thousand periods, on the board's supply.
fn settle(p: &Params, inputs: Inputs) -> Settled {
    settle_on(p, inputs, SUPPLY_V)
}

/// The strip behind a driver on `supply_v`, run from rest under `inputs`
/// for ten of its slowest time constants.
fn settled_strip(p: &Params, inputs: Inputs, supply_v: f64) -> Strip {
    let mut strip = Strip::new(p, supply_v);
    let slowest_s = (p.r1_ohm + p.r2_ohm) * p.c_f;
    let periods = (10.0 * slowest_s / PERIOD_S).ceil() as usize;
    for _ in 0..periods {
        strip.period(inputs);
    }
    strip
}

/// [`settle`] behind a driver on `supply_v`.
fn settle_on(p: &Params, inputs: Inputs, supply_v: f64) -> Settled {
    let mut strip = settled_strip(p, inputs, supply_v);
    let (mut terminal, mut c_sum, mut c_peak) = (0.0, 0.0, 0.0f64);
    let n = 1000;
    for _ in 0..n {
        let (t, c, peak) = strip.period(inputs);
        terminal += t;
        c_sum += c;
        c_peak = c_peak.max(peak);
    }
    Settled {
        terminal_v: terminal / n as f64,
        c_mean_v: c_sum / n as f64,
        c_peak_v: c_peak,
    }
}

/// The inputs [`HBridge`] sets for `v`.
fn slow_decay(v: f32) -> Inputs {
    slow_decay_told(v, SUPPLY_V as f32, None)
}

/// The inputs an [`HBridge`] made on `boot_v` sets for `v`, told the supply
/// `measured_v` (if any) before.
fn slow_decay_told(v: f32, boot_v: f32, measured_v: Option<f32>) -> Inputs {
    let (a, b) = (Leg(Rc::default()), Leg(Rc::default()));
    let mut bridge = HBridge::new(a.clone(), b.clone(), boot_v).unwrap();
    if let Some(measured_v) = measured_v {
        bridge.set_supply_v(measured_v).unwrap();
    }
    bridge.set_v(v);
    Inputs {
        duty_a: a.0.get(),
        duty_b: b.0.get(),
    }
}

/// The inputs of the drive this replaced: the duty on one leg, the other
/// low, open for the rest of the period.
fn coast(v: f32) -> Inputs {
    let duty = (f64::from(v.abs()) / SUPPLY_V * f64::from(PWM_STEPS)).round() as u16;
    if v >= 0.0 {
        Inputs {
            duty_a: duty,
            duty_b: 0,
        }
    } else {
        Inputs {
            duty_a: 0,
            duty_b: duty,
        }
    }
}

/// The seed's two circuits: `main.m`'s (`τ1` 16 ms) and Table 4-2's
/// (1.6 s), both with `R1 / (R1 + R2)` near 0.19.
fn strips() -> [(&'static str, Params); 2] {
    [
        ("main.m", Params::main_m_2006()),
        ("Table 4-2", Params::table_4_2_2006()),
    ]
}

#[test]
fn slow_decay_holds_the_strip_at_the_commanded_voltage_within_the_limit() {
    for (name, p) in strips() {
        for v in [0.5f32, 2.0, -2.0, 4.0, -4.0] {
            let s = settle(&p, slow_decay(v));
            let v = f64::from(v);
            // One PWM step is 0.74 mV; the forward steps are rounded down.
            let step_v = SUPPLY_V / f64::from(PWM_STEPS);
            assert!(
                s.terminal_v.abs() <= v.abs() + 1e-9 && s.terminal_v.abs() > v.abs() - step_v,
                "{name}, {v} V: terminal {s:?}"
            );
            assert!(s.terminal_v.signum() == v.signum(), "{name}, {v} V: {s:?}");
            // No mean current through R1 once settled: C sits at the mean.
            assert!(
                (s.c_mean_v - s.terminal_v).abs() < 1e-6,
                "{name}, {v} V: {s:?}"
            );
            assert!(s.terminal_v.abs() <= LIMIT_V, "{name}, {v} V: {s:?}");
            // The 25 kHz ripple on C: under 2 mV at 4 V on main.m's 16 ms.
            assert!(s.c_peak_v <= LIMIT_V + 2e-3, "{name}, {v} V: {s:?}");
        }
    }
}

#[test]
fn coast_leaves_the_strip_charged_above_the_command_and_the_limit() {
    for (name, p) in strips() {
        // Steady state by hand: charging for the duty d, discharging
        // through R1 + R2 for the rest: V_C = d Vs / (d + (1 − d) R1 / (R1 + R2)),
        // and the terminals' mean comes out equal to it.
        let r = p.r1_ohm / (p.r1_ohm + p.r2_ohm);
        for v in [2.0f32, 4.0, -4.0] {
            let s = settle(&p, coast(v));
            let d = f64::from(v.abs()) / SUPPLY_V;
            let want = d * SUPPLY_V / (d + (1.0 - d) * r);
            assert!(
                (s.terminal_v.abs() - want).abs() < 2e-3 * want,
                "{name}, {v} V: {s:?}, expected {want:.3} V"
            );
            assert!(
                s.terminal_v.abs() > 1.15 * f64::from(v.abs()),
                "{name}, {v} V: {s:?}"
            );
        }
        let at_limit = settle(&p, coast(4.0));
        assert!(at_limit.terminal_v > LIMIT_V + 0.5, "{name}: {at_limit:?}");
        assert!(at_limit.c_mean_v > LIMIT_V + 0.5, "{name}: {at_limit:?}");
    }
}

#[test]
fn a_bridge_told_the_measured_supply_holds_the_limit_when_the_supply_rises() {
    // The supply at boot was 5.0 V; it is now 5.5 V (a bench supply
    // turned up). One PWM step at 5.5 V is 0.82 mV.
    let (boot_v, now_v) = (5.0f32, 5.5f64);
    let step_v = now_v / f64::from(PWM_STEPS);
    for (name, p) in strips() {
        for v in [4.0f32, -4.0, 2.0] {
            let want = f64::from(v);
            // Working the duties out from the boot's supply: 10 % more on
            // the strip, past the limit at 4 V.
            let stale = settle_on(&p, slow_decay_told(v, boot_v, None), now_v);
            assert!(
                (stale.terminal_v - 1.1 * want).abs() < 2.0 * step_v,
                "{name}, {v} V: {stale:?}"
            );
            // Told the supply as read (`SupplyMonitor` on the board, every
            // tick): the command, within a step below it.
            let told = settle_on(&p, slow_decay_told(v, boot_v, Some(now_v as f32)), now_v);
            assert!(
                told.terminal_v.abs() <= want.abs() + 1e-9
                    && told.terminal_v.abs() > want.abs() - 1.01 * step_v,
                "{name}, {v} V: {told:?}"
            );
            assert!(told.terminal_v.abs() <= LIMIT_V, "{name}, {v} V: {told:?}");
        }
        let stale = settle_on(&p, slow_decay_told(4.0, boot_v, None), now_v);
        assert!(stale.terminal_v > LIMIT_V + 0.35, "{name}: {stale:?}");
    }
}

/// The shunt's two sections (`H(s) = 1/(1 + sτ)²`), stepped exactly over a
/// span of held input.
struct Sections {
    tau_s: f64,
    x: [f64; 2],
}

impl Sections {
    /// Holds the input at `i` for `dt_s`: the first section relaxes to it,
    /// the second to the first (`x2(t) = i + (x2 − i) e^{−t/τ} + (x1 − i)
    /// (t/τ) e^{−t/τ}`).
    fn hold(&mut self, i: f64, dt_s: f64) {
        let decay = (-dt_s / self.tau_s).exp();
        let [x1, x2] = self.x;
        self.x = [
            i + (x1 - i) * decay,
            i + (x2 - i) * decay + (x1 - i) * dt_s / self.tau_s * decay,
        ];
    }
}

/// One settled period of the terminal current, step by step of the PWM
/// counter: what an ADC converting at counter value `k` reads, raw and
/// through the shunt's filter.
struct Readings {
    raw_a: Vec<f64>,
    filtered_a: Vec<f64>,
    /// The current's mean over the period, A.
    mean_a: f64,
    /// The current's mean over the braking and the driving span, A.
    brake_a: f64,
    drive_a: f64,
    /// The driving span's share of the period.
    duty: f64,
}

impl Strip {
    /// The terminal current over one step of `dt_s` at terminal voltage
    /// `u` (driven): `(u − v_C)/R1 + u/R2` averaged over the step.
    fn driven_current(&mut self, u: f64, dt_s: f64) -> f64 {
        let (u_integral, c_integral) = self.hold(Some(u), dt_s);
        (u_integral - c_integral) / (self.r1_ohm * dt_s) + u / self.r2_ohm
    }

    /// Runs `periods` more periods at the counter's resolution with the
    /// shunt's filter after the current (started at the first period's
    /// mean, so that it settles in a few τ), and returns the last one's
    /// readings.
    fn readings(&mut self, inputs: Inputs, periods: usize) -> Readings {
        let step_s = PERIOD_S / f64::from(PWM_STEPS);
        let mut filter = Sections {
            tau_s: f64::from(SHUNT_FILTER.tau_s()),
            x: [0.0; 2],
        };
        let mut raw = vec![0.0; usize::from(PWM_STEPS)];
        let mut filtered = raw.clone();
        for p in 0..periods {
            for k in 0..PWM_STEPS {
                let u = driver(k < inputs.duty_a, k < inputs.duty_b, self.supply_v)
                    .expect("slow decay never leaves the terminals open");
                filtered[usize::from(k)] = filter.x[1];
                raw[usize::from(k)] = self.driven_current(u, step_s);
                filter.hold(raw[usize::from(k)], step_s);
            }
            if p == 0 {
                let mean = raw.iter().sum::<f64>() / raw.len() as f64;
                filter.x = [mean; 2];
            }
        }
        // The spans: both legs high (or low) brake, one high drives.
        let driving: Vec<bool> = (0..PWM_STEPS)
            .map(|k| (k < inputs.duty_a) != (k < inputs.duty_b))
            .collect();
        let span_mean = |drive: bool| {
            let (sum, n) = raw
                .iter()
                .zip(&driving)
                .filter(|(_, &d)| d == drive)
                .fold((0.0, 0usize), |(s, n), (&i, _)| (s + i, n + 1));
            if n == 0 {
                0.0
            } else {
                sum / n as f64
            }
        };
        Readings {
            mean_a: raw.iter().sum::<f64>() / raw.len() as f64,
            brake_a: span_mean(false),
            drive_a: span_mean(true),
            duty: driving.iter().filter(|&&d| d).count() as f64 / driving.len() as f64,
            raw_a: raw,
            filtered_a: filtered,
        }
    }
}

#[test]
fn the_shunts_read_the_period_mean_through_the_filter_and_not_without_it() {
    let count_a = f64::from(AMPS_PER_COUNT);
    // The ADC converts once a millisecond, 25 periods of the same clock:
    // at one counter value, which depends on when the timers started. So
    // every value is tried (one in 105, 64 phases).
    let phases = (0..PWM_STEPS).step_by(105);
    let mut worst_filtered_counts = 0.0f64;
    let mut worst_closed_counts = 0.0f64;
    let mut worst_share = 0.0f64;
    for (name, p) in strips() {
        for v in [0.1f32, 0.5, 1.0, 2.0, -2.0, 3.0, 4.0, -4.0] {
            let inputs = slow_decay(v);
            let mut strip = settled_strip(&p, inputs, SUPPLY_V);
            // 25 periods: 1 ms, 6 τ of the filter.
            let r = strip.readings(inputs, 25);
            let mut worst_raw_counts = 0.0f64;
            for k in phases.clone() {
                let k = usize::from(k);
                let raw_counts = (r.raw_a[k] - r.mean_a).abs() / count_a;
                let filtered_counts = (r.filtered_a[k] - r.mean_a).abs() / count_a;
                worst_raw_counts = worst_raw_counts.max(raw_counts);
                worst_filtered_counts = worst_filtered_counts.max(filtered_counts);
                // Through the filter: the mean, within a quarter of a count
                // (62.5 µA) and 0.16 % of the levels' jump (as
                // `SHUNT_FILTER` says), at every phase.
                let jump_a = (r.drive_a - r.brake_a).abs();
                worst_share = worst_share.max((r.filtered_a[k] - r.mean_a).abs() / jump_a);
                assert!(
                    filtered_counts < 0.25 && (r.filtered_a[k] - r.mean_a).abs() < 0.0016 * jump_a,
                    "{name}, {v} V, counter {k}: filtered {} A, mean {} A, jump {jump_a} A",
                    r.filtered_a[k],
                    r.mean_a
                );
                // The closed form the QEMU board's plant uses agrees with
                // the step-by-step filter within a tenth of a count: it
                // takes each span's current as flat, where the capacitor's
                // ripple slopes it (by 0.08 count at 2 V on main.m's
                // 100 µF).
                let phase = k as f32 / f32::from(PWM_STEPS);
                let closed_a = SHUNT_FILTER.settled_a(
                    r.brake_a as f32,
                    r.drive_a as f32,
                    r.duty as f32,
                    phase,
                );
                worst_closed_counts = worst_closed_counts
                    .max((f64::from(closed_a) - r.filtered_a[k]).abs() / count_a);
                assert!(
                    (f64::from(closed_a) - r.filtered_a[k]).abs() < 0.1 * count_a,
                    "{name}, {v} V, counter {k}: closed form {closed_a} A, stepped {} A",
                    r.filtered_a[k]
                );
            }
            // Unfiltered, as the board first read them: one of the two
            // levels, the larger share of their jump off the mean at some
            // phase (at 2 V on the seed's strip, +25.9 or −12.5 mA against
            // 2.86 mA).
            let jump_counts = (r.drive_a - r.brake_a).abs() / count_a;
            assert!(
                worst_raw_counts > 0.49 * jump_counts && worst_raw_counts > 10.0,
                "{name}, {v} V: raw reads at most {worst_raw_counts} counts off (jump {jump_counts})"
            );
        }
    }
    eprintln!(
        "through the filter: worst {worst_filtered_counts:.3} counts, {:.3} % of the jump; closed form off by {worst_closed_counts:.3} counts",
        100.0 * worst_share
    );
    assert!(worst_filtered_counts > 0.01, "the ripple is resolved");
}
