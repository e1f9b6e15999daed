//! The shunt amplifier's output filter, and what it makes of the
//! bridge's two-level current.
//!
//! In slow decay ([`finrs_controller::HBridge`]) a segment's terminals sit
//! at the supply for the duty `d` of each PWM period and at 0 V for the
//! rest, so its terminal current is two-level: on the seed's strip
//! (`R1` 160 Ω, `R2` 700 Ω) at 2 V, +25.9 mA while driving and −12.5 mA
//! while braking, 2.86 mA on average. The strip's capacitor holds its
//! voltage over a 40 µs period (its ripple is under 2 mV), so within each
//! span the current is flat, and its jump is `V_s (1/R1 + 1/R2)` whatever
//! the duty. An ADC that converts once a millisecond lands at the same
//! phase of every period (1 ms is 25 periods of the same clock), and read
//! unfiltered it returns one of the two levels, not the mean.
//!
//! So the amplifier's output reaches the ADC through two first-order
//! low-pass sections of one corner `f_c`, buffered from each other
//! (`H(s) = 1/(1 + sτ)²`, `τ = 1/(2π f_c)`). Their settled output over a
//! period is the mean plus a ripple that the two poles shrink by about
//! `(f_c / f_PWM)²`; [`ShuntFilter::settled_a`] gives it exactly, at any
//! phase, for the QEMU board's plant and the host's tests.
//!
//! ```
//! use finrs_firmware_support::shunt_filter::ShuntFilter;
//!
//! let filter = ShuntFilter { corner_hz: 1_000.0, pwm_hz: 25_000.0 };
//! // The seed's strip at 2 V: braking −12.5 mA, driving +25.9 mA, d = 0.4.
//! let (brake_a, drive_a, duty) = (-12.5e-3, 25.9e-3, 0.4);
//! let mean_a = brake_a + duty * (drive_a - brake_a);
//! for k in 0..16 {
//!     let read_a = filter.settled_a(brake_a, drive_a, duty, k as f32 / 16.0);
//!     assert!((read_a - mean_a).abs() < 0.05e-3, "{read_a} A against {mean_a} A");
//! }
//! ```

/// Two equal first-order low-pass sections between the shunt amplifier
/// and the ADC, behind a bridge switching at `pwm_hz`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShuntFilter {
    /// Each section's corner `f_c`, Hz.
    pub corner_hz: f32,
    /// The bridge's PWM frequency `f_PWM`, Hz.
    pub pwm_hz: f32,
}

impl ShuntFilter {
    /// Each section's time constant `τ = 1/(2π f_c)`, s.
    pub fn tau_s(&self) -> f32 {
        1.0 / (2.0 * core::f32::consts::PI * self.corner_hz)
    }

    /// The filter's settled output, A, at `phase` (0..1, a fraction of the
    /// PWM period after the timer's update event) when the bridge brakes
    /// (`brake_a`) for the first `1 − duty` of every period and drives
    /// (`drive_a`) for the last `duty`, as edge-aligned PWM mode 1 lays out
    /// slow decay (RM0090, TIMx_CCMRx OCxM = 110: the output high while the
    /// counter is below the compare value). Settled means the levels have
    /// held for many `τ`; their mean is `brake_a + duty (drive_a −
    /// brake_a)`. `duty` and `phase` outside 0..1 are clamped and wrapped.
    pub fn settled_a(&self, brake_a: f32, drive_a: f32, duty: f32, phase: f32) -> f32 {
        let duty = duty.clamp(0.0, 1.0);
        // Time since the driving span began, in units of τ.
        let period = 1.0 / (self.pwm_hz * self.tau_s());
        let since = phase - (1.0 - duty);
        let since = (since - libm::floorf(since)) * period;
        let width = duty * period;
        brake_a + (drive_a - brake_a) * self.settled_fraction(since, width, period)
    }

    /// What each bridge segment's shunt reads when slow decay applies `v`
    /// from `supply_v`, segment `i` at `phase[i]`:
    /// [`settled_a`](Self::settled_a) with the currents `currents_a(u)`
    /// gives at the terminal voltages `u` = 0 (braking) and `±supply_v`
    /// (driving, the sign of `v`) for the duty `|v| / supply_v`.
    pub fn bridge_readings_a<const N: usize>(
        &self,
        v: &[f32; N],
        supply_v: f32,
        phase: &[f32; N],
        currents_a: impl Fn(&[f32; N]) -> [f32; N],
    ) -> [f32; N] {
        let brake_a = currents_a(&[0.0; N]);
        let drive_a = currents_a(&v.map(|v| if v < 0.0 { -supply_v } else { supply_v }));
        core::array::from_fn(|i| {
            self.settled_a(brake_a[i], drive_a[i], v[i].abs() / supply_v, phase[i])
        })
    }

    /// The settled response to a unit pulse of `width` every `period`,
    /// `since` after a pulse began (all in τ): the sum over every earlier
    /// pulse of the step response `1 − e^{−t}(1 + t)` begun at its start
    /// less the one begun at its end, summed as geometric series by
    /// [`Tails`].
    fn settled_fraction(&self, since: f32, width: f32, period: f32) -> f32 {
        let tails = Tails::new(period);
        if since < width {
            1.0 - tails.at(since) + tails.at(since - width + period)
        } else {
            tails.at(since - width) - tails.at(since)
        }
    }
}

/// `Σ_{k≥0} e^{−(t + kT)} (1 + t + kT)` for `t ≥ 0`, with `T` in τ: what
/// the step responses begun `t`, `t + T`, … ago still lack of 1.
struct Tails {
    /// `1/(1 − q)` and `T q/(1 − q)²`, with `q = e^{−T}`.
    geometric: f32,
    ramp: f32,
}

impl Tails {
    fn new(period: f32) -> Self {
        let q = libm::expf(-period);
        let geometric = 1.0 / (1.0 - q);
        Self {
            geometric,
            ramp: period * q * geometric * geometric,
        }
    }

    fn at(&self, t: f32) -> f32 {
        libm::expf(-t) * ((1.0 + t) * self.geometric + self.ramp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILTER: ShuntFilter = ShuntFilter {
        corner_hz: 1_000.0,
        pwm_hz: 25_000.0,
    };

    /// The settled output averages to the input's mean over a period
    /// (the filter's DC gain is 1), for every duty.
    #[test]
    fn the_settled_output_averages_to_the_mean() {
        for duty in [0.0, 0.05, 0.4, 0.8, 1.0] {
            let n = 4000;
            let mean: f32 = (0..n)
                .map(|k| FILTER.settled_a(0.0, 1.0, duty, (k as f32 + 0.5) / n as f32))
                .sum::<f32>()
                / n as f32;
            assert!((mean - duty).abs() < 1e-4, "duty {duty}: mean {mean}");
        }
    }

    /// The output is continuous across the period's wrap and the drive
    /// span's edges, as a filtered signal must be.
    #[test]
    fn the_settled_output_is_continuous() {
        let duty = 0.3;
        let eps = 1e-6;
        for edge in [0.0f32, 1.0 - duty] {
            let before = FILTER.settled_a(0.0, 1.0, duty, edge - eps);
            let after = FILTER.settled_a(0.0, 1.0, duty, edge + eps);
            assert!(
                (before - after).abs() < 1e-4,
                "at {edge}: {before} / {after}"
            );
        }
    }

    /// Held levels read as themselves.
    #[test]
    fn a_constant_current_reads_as_itself() {
        for phase in [0.0, 0.3, 0.99] {
            assert!((FILTER.settled_a(2e-3, 2e-3, 0.4, phase) - 2e-3).abs() < 1e-9);
            assert!((FILTER.settled_a(-1e-3, 5e-3, 0.0, phase) + 1e-3).abs() < 1e-9);
            assert!((FILTER.settled_a(-1e-3, 5e-3, 1.0, phase) - 5e-3).abs() < 1e-8);
        }
    }
}
