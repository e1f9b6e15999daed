//! Complex amplitudes of sinusoids: `y_k = Re(Y e^{jθk})`.
//!
//! The few operations the steady-state response needs, in `f64`, so the
//! core stays free of a complex-number dependency.
//!
//! ```
//! use model_core::Phasor;
//! // 2 V sine with no phase: v_k = 2 sin(θk) = Re(−2j e^{jθk}).
//! let v = Phasor::from_sine(2.0, 0.0);
//! assert!((v.amplitude() - 2.0).abs() < 1e-15);
//! assert!((v.sine_phase_rad()).abs() < 1e-15);
//! ```

use core::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// A complex amplitude `re + j im`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phasor {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Phasor {
    /// `0`.
    pub const ZERO: Phasor = Phasor { re: 0.0, im: 0.0 };

    /// `re + j im`.
    pub const fn new(re: f64, im: f64) -> Phasor {
        Phasor { re, im }
    }

    /// The real number `x`.
    pub const fn real(x: f64) -> Phasor {
        Phasor { re: x, im: 0.0 }
    }

    /// `e^{jθ}`.
    pub fn unit(theta_rad: f64) -> Phasor {
        let (s, c) = libm::sincos(theta_rad);
        Phasor { re: c, im: s }
    }

    /// The phasor of `amplitude · sin(θk + phase_rad)`:
    /// `amplitude · e^{j(phase − π/2)}`.
    pub fn from_sine(amplitude: f64, phase_rad: f64) -> Phasor {
        Phasor::unit(phase_rad - core::f64::consts::FRAC_PI_2).scale(amplitude)
    }

    /// `|Y|`: the sinusoid's amplitude.
    pub fn amplitude(self) -> f64 {
        libm::hypot(self.re, self.im)
    }

    /// The phase `φ` of `|Y| sin(θk + φ)`, rad, in `(−π, π]`.
    pub fn sine_phase_rad(self) -> f64 {
        // arg(Y) + π/2, kept in (−π, π].
        libm::atan2(self.re, -self.im)
    }

    /// `x · Y`.
    pub fn scale(self, x: f64) -> Phasor {
        Phasor::new(self.re * x, self.im * x)
    }

    /// `|Y|²`.
    pub fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    /// The sample this phasor gives at step `k` of angle `theta_rad` per
    /// step: `Re(Y e^{jθk})`.
    pub fn at(self, theta_rad: f64, k: u64) -> f64 {
        let u = Phasor::unit(theta_rad * k as f64);
        self.re * u.re - self.im * u.im
    }
}

impl Add for Phasor {
    type Output = Phasor;
    fn add(self, o: Phasor) -> Phasor {
        Phasor::new(self.re + o.re, self.im + o.im)
    }
}

impl AddAssign for Phasor {
    fn add_assign(&mut self, o: Phasor) {
        *self = *self + o;
    }
}

impl Sub for Phasor {
    type Output = Phasor;
    fn sub(self, o: Phasor) -> Phasor {
        Phasor::new(self.re - o.re, self.im - o.im)
    }
}

impl Neg for Phasor {
    type Output = Phasor;
    fn neg(self) -> Phasor {
        Phasor::new(-self.re, -self.im)
    }
}

impl Mul for Phasor {
    type Output = Phasor;
    fn mul(self, o: Phasor) -> Phasor {
        Phasor::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

impl Div for Phasor {
    type Output = Phasor;
    /// Smith's division: no overflow from squaring the divisor's parts.
    fn div(self, o: Phasor) -> Phasor {
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            Phasor::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            Phasor::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Phasor;

    #[test]
    fn the_arithmetic_is_the_complex_numbers() {
        let (a, b) = (Phasor::new(1.5, -2.0), Phasor::new(-0.25, 3.0));
        let p = a * b;
        assert_eq!(
            (p.re, p.im),
            (1.5 * -0.25 + 2.0 * 3.0, 1.5 * 3.0 + 2.0 * 0.25)
        );
        for d in [b, Phasor::new(3.0, -0.25), Phasor::new(1e-300, 2e-300)] {
            let back = (a / d) * d;
            assert!((back - a).amplitude() < 1e-14 * a.amplitude(), "{d:?}");
        }
        assert_eq!(-a + a, Phasor::ZERO);
    }

    #[test]
    fn a_sine_s_phasor_gives_its_samples() {
        let (amp, phase, theta) = (0.7, 1.1, 0.013);
        let y = Phasor::from_sine(amp, phase);
        for k in [0_u64, 1, 17, 4000] {
            let want = amp * libm::sin(theta * k as f64 + phase);
            assert!((y.at(theta, k) - want).abs() < 1e-12);
        }
        assert!((y.sine_phase_rad() - phase).abs() < 1e-14);
        assert!(
            (Phasor::from_sine(1.0, core::f64::consts::PI)
                .sine_phase_rad()
                .abs()
                - core::f64::consts::PI)
                .abs()
                < 1e-14
        );
    }
}
