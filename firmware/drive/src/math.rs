//! Small f32 helpers that `core` lacks and that must be exact or accurate
//! where micromath's approximations are not (its `ln` is off by up to 0.1,
//! its `exp` by 8e-4 relative: too coarse for a chirp's phase).

use core::f32::consts::LN_2;

/// 2²³: every f32 at least this large is an integer.
const INTEGER_F32: f32 = 8_388_608.0;

/// `x − ⌊x⌋` in [0, 1); exact. NaN and infinities give 0.
pub(crate) fn frac(x: f32) -> f32 {
    if x.is_nan() || abs(x) >= INTEGER_F32 {
        return 0.0;
    }
    let f = x - (x as i32) as f32; // exact: both have x's exponent or less
    if f < 0.0 {
        // f + 1 rounds to 1 for f above −2⁻²⁵; the wrap of 1 is 0.
        let g = f + 1.0;
        if g < 1.0 {
            g
        } else {
            0.0
        }
    } else {
        f
    }
}

/// The fractional part of `a · b`, in [0, 1), with an error of about
/// 1e-7 however large the product: `a · b` is split into its rounded value
/// and the exact rounding error (Dekker's two-product, needing no FMA), and
/// each part is reduced exactly before they are added.
pub(crate) fn frac_of_product(a: f32, b: f32) -> f32 {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    frac(frac(p) + frac(err))
}

/// Splits `a` into a high part of 12 significant bits and the rest, so that
/// products of the parts are exact.
fn split(a: f32) -> (f32, f32) {
    let c = 4097.0 * a; // 2¹² + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// |x|, bitwise (`f32::abs` came to `core` only recently).
pub(crate) fn abs(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
}

/// Natural logarithm of a finite `x` ≥ 2⁻¹²⁶ (normal), to a few ulps.
pub(crate) fn ln(x: f32) -> f32 {
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127;
    // Mantissa m in [1, 2), then moved to [√½, √2) so that s is small.
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    // ln m = 2 atanh s = 2 (s + s³/3 + s⁵/5 + …), |s| ≤ 0.172.
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = 1.0 + s2 * (1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0))));
    e as f32 * LN_2 + 2.0 * s * series
}

/// `(eᵘ − 1)/u` for 0 ≤ u ≤ 80, to a few ulps; 1 at u = 0. Written this
/// way so that a chirp's phase needs no cancelling subtraction.
pub(crate) fn expm1_over(u: f32) -> f32 {
    if u < 0.5 {
        // Σ uⁿ/(n+1)!, n = 0..=9: the first term left out is below 3e-11.
        let mut sum = 1.0 / 3_628_800.0; // 1/10!
        let mut factorial = 3_628_800.0f32;
        for n in (1..10).rev() {
            factorial /= (n + 1) as f32;
            sum = 1.0 / factorial + u * sum;
        }
        sum
    } else {
        (exp(u) - 1.0) / u
    }
}

/// `e^{−x}` for `x ≥ 0` (+∞ too), to a few ulps; 0 above 80, where it is
/// below 2e-35.
pub(crate) fn exp_neg(x: f32) -> f32 {
    if x > 80.0 {
        0.0
    } else {
        1.0 / exp(x)
    }
}

/// eᵘ for 0 ≤ u ≤ 80: u = k ln 2 + y with |y| ≤ ln2/2, eʸ by its Taylor
/// series to y⁸ (the rest is below 2e-10), then scaled by 2ᵏ exactly.
fn exp(u: f32) -> f32 {
    // ln 2 in two parts (as in musl's expf): k·LN_2_HI is exact for the
    // k used here, so y keeps its precision.
    const LN_2_HI: f32 = f32::from_bits(0x3f31_7180); // 0.693138…
    const LN_2_LO: f32 = f32::from_bits(0x3717_f7d1); // 9.058e-6
    let k = (u / LN_2 + 0.5) as i32;
    let y = (u - k as f32 * LN_2_HI) - k as f32 * LN_2_LO;
    let mut sum = 1.0f32;
    for n in (1..=8).rev() {
        sum = 1.0 + y * sum / n as f32;
    }
    sum * f32::from_bits(((k + 127) as u32) << 23)
}
