//! The small float trait that makes the core generic over `f32` and `f64`.
//!
//! Only what the stepper and the outputs need: the discretisation itself
//! always runs in `f64` (see [`crate::discrete`]), so `T` matters only for
//! the per-sample update, which is what runs on the board.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real scalar: `f32` on the board, `f64` on the host.
pub trait Real:
    Copy
    + Default
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// Additive identity.
    const ZERO: Self;
    /// Converts from `f64`, rounding to nearest.
    fn from_f64(x: f64) -> Self;
    /// Converts to `f64` exactly.
    fn to_f64(self) -> f64;
    /// Unit roundoff, `2⁻²⁴` or `2⁻⁵³`.
    const UNIT_ROUNDOFF: f64;
    /// The float `n` units in the last place above (below, for `n < 0`)
    /// this finite one.
    fn ulps(self, n: i32) -> Self;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    const UNIT_ROUNDOFF: f64 = 5.960_464_477_539_063e-8;
    fn ulps(self, n: i32) -> Self {
        // Sign and magnitude bits as one ordered integer (±0 both 0).
        let bits = self.to_bits();
        let mag = i64::from(bits & 0x7fff_ffff);
        let key = if bits >> 31 == 1 { -mag } else { mag } + i64::from(n);
        let mag = key.unsigned_abs() as u32;
        f32::from_bits(if key < 0 { mag | 0x8000_0000 } else { mag })
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    const UNIT_ROUNDOFF: f64 = 1.110_223_024_625_156_5e-16;
    fn ulps(self, n: i32) -> Self {
        let bits = self.to_bits();
        let mag = (bits & 0x7fff_ffff_ffff_ffff) as i64;
        let key = if bits >> 63 == 1 { -mag } else { mag } + i64::from(n);
        let mag = key.unsigned_abs();
        f64::from_bits(if key < 0 {
            mag | 0x8000_0000_0000_0000
        } else {
            mag
        })
    }
}

#[cfg(test)]
mod tests {
    use super::Real;

    #[test]
    fn ulps_step_through_zero_and_the_sign() {
        assert_eq!(1.0f32.ulps(1), 1.0 + f32::EPSILON);
        assert_eq!(1.0f32.ulps(-1), 1.0 - f32::EPSILON / 2.0);
        assert_eq!((-1.0f32).ulps(1), -1.0 + f32::EPSILON / 2.0);
        assert_eq!(0.0f32.ulps(-1), -f32::from_bits(1));
        assert_eq!((-f32::from_bits(1)).ulps(2), f32::from_bits(1));
        assert_eq!(2.0f64.ulps(-1), 2.0 - f64::EPSILON);
        assert_eq!((-0.5f64).ulps(-1), -0.5 - f64::EPSILON / 2.0);
    }
}
