//! Numbers as a recording writes them: fast, and no more digits than a
//! reader can use.
//!
//! Time and voltages are the inputs of every model run: they are written
//! exactly (the shortest text that reads back as the same `f64`, by `ryu`),
//! so a recording written and read again drives a model identically.
//!
//! Measured channels (currents, positions, force) are written to
//! [`MEASURED_DECIMALS`] decimals of their SI unit: 0.1 nA, 0.1 nm, 0.1 nN.
//! That is 10⁵ to 10⁶ times finer than the sensors' resolution and noise on
//! the bench (0.1 mA for currents, 0.05 mm camera pixels, 0.02 mN on the
//! load cell; see `docs/speed-simulate-job.md`), so rounding to it loses
//! nothing a measurement could carry, where `f64`'s 17 digits would mostly
//! be simulation round-off. A value read back is within
//! [`max_written_error`] of the one written.

/// Decimals written for measured channels, in their SI unit.
pub const MEASURED_DECIMALS: u32 = 10;

/// The step of measured channels as written: `10^-MEASURED_DECIMALS` of the
/// SI unit (A, m, N).
pub const MEASURED_QUANTUM: f64 = 1e-10;

const SCALE: f64 = 1e10;
const FRACTION: u64 = 10_000_000_000;
/// Beyond this many quanta (100 A, m or N) a value is written exactly
/// instead: far outside any bench, and where `x * SCALE` stays far below
/// 2⁵³ the product's own rounding is negligible.
const MAX_QUANTA: f64 = 1e12;

/// How far a measured value `x` read back may lie from `x`: half a quantum,
/// the product's rounding (below 10⁻⁴ quantum, see `MAX_QUANTA`) and the
/// reader's rounding to the nearest `f64` (half an ulp of `x`, doubled
/// here for the ulp of a neighbour).
pub fn max_written_error(x: f64) -> f64 {
    0.5001 * MEASURED_QUANTUM + 2.0 * f64::EPSILON * x.abs()
}

/// The most bytes a number takes as written: sign, whole part, point and
/// decimals (`ryu` writes at most 24; `-inf` and `NaN` fewer).
pub(crate) const WIDEST: usize = 32;

/// Writes numbers into a window of an output buffer without allocating:
/// each call fills the start of `dst` and says how many bytes it wrote.
#[derive(Default)]
pub(crate) struct Formatter {
    ryu: ryu::Buffer,
    itoa: itoa::Buffer,
}

impl Formatter {
    /// Writes `x` exactly: the shortest decimal that reads back as `x`,
    /// without `ryu`'s trailing `.0`. NaN and infinity are written as
    /// `NaN`, `inf`, `-inf` (which the reader refuses: only unchecked text
    /// can hold them).
    #[inline]
    pub fn exact(&mut self, dst: &mut [u8; WIDEST], x: f64) -> usize {
        // Fast path for what a DAQ writes (times to the ms, voltages to a
        // DAC step): if `x` is the nearest f64 to a decimal of at most
        // MEASURED_DECIMALS decimals, that decimal reads back as `x`. The
        // test is exact: `quanta / SCALE` is correctly rounded, as a reader
        // rounds, and below 1e5 distinct such decimals are distinct f64s,
        // so the decimal is also the shortest.
        if x.abs() < 1e5 {
            let quanta = round(x * SCALE);
            if quanta as f64 / SCALE == x {
                return quanta_text(dst, quanta, &mut self.itoa);
            }
        }
        self.shortest(dst, x)
    }

    /// [`Formatter::exact`] past its fast path: `ryu`, or the name of a
    /// value that is not finite.
    #[inline(never)]
    fn shortest(&mut self, dst: &mut [u8; WIDEST], x: f64) -> usize {
        let text = if x.is_finite() {
            let s = self.ryu.format_finite(x);
            s.strip_suffix(".0").unwrap_or(s)
        } else if x.is_nan() {
            "NaN"
        } else if x > 0.0 {
            "inf"
        } else {
            "-inf"
        };
        dst[..text.len()].copy_from_slice(text.as_bytes());
        text.len()
    }

    /// Writes a measured value rounded to [`MEASURED_DECIMALS`] decimals,
    /// trailing zeros dropped (`0.0125`, `-3`, `0`); not finite, as
    /// [`Formatter::exact`].
    #[inline]
    pub fn measured(&mut self, dst: &mut [u8; WIDEST], x: f64) -> usize {
        let scaled = x * SCALE;
        // Also false for NaN.
        if scaled.abs() < MAX_QUANTA {
            return quanta_text(dst, round(scaled), &mut self.itoa);
        }
        self.exact(dst, x)
    }
}

/// Writes `quanta * MEASURED_QUANTUM` as a decimal, trailing zeros dropped;
/// returns its length.
#[inline]
fn quanta_text(dst: &mut [u8; WIDEST], quanta: i64, itoa: &mut itoa::Buffer) -> usize {
    // The sign always written, then kept or overwritten: no branch on a
    // sign that alternates unpredictably.
    dst[0] = b'-';
    let mut n = usize::from(quanta < 0);
    let q = quanta.unsigned_abs();
    // Measured values mostly lie below one unit: no division then.
    let (whole, frac) = if q < FRACTION {
        (0, q)
    } else {
        (q / FRACTION, q % FRACTION)
    };
    if whole < 10 {
        dst[n] = b'0' + whole as u8;
        n += 1;
    } else {
        let text = itoa.format(whole).as_bytes();
        // |quanta| < 2^63: at most nine digits before the point.
        dst[n..n + text.len()].copy_from_slice(text);
        n += text.len();
    }
    // The point, the first two decimals from a table and the last eight
    // as one word (SWAR), then the trailing zeros cut, counted from the
    // word: no loop over digits.
    let (high, low) = ((frac / 100_000_000) as usize, frac % 100_000_000);
    let digits = eight_digit_values(low);
    let text = &mut dst[n..n + 11];
    text[0] = b'.';
    text[1..3].copy_from_slice(&DIGIT_PAIRS[2 * high..2 * high + 2]);
    text[3..].copy_from_slice(&(digits | 0x3030_3030_3030_3030).to_le_bytes());
    // The last digit lies in the word's top byte; frac > 0, so if all
    // eight are zero the pair's second digit is not, unless it is 0 too
    // and the first one ends the text.
    let zeros = if digits != 0 {
        (digits.leading_zeros() / 8) as usize
    } else if high % 10 != 0 {
        8
    } else {
        9
    };
    if frac == 0 {
        n
    } else {
        n + 11 - zeros
    }
}

/// The eight decimal digits of `n < 10^8` as byte values 0 to 9, the most
/// significant in the lowest byte (the order they are written in): split
/// into halves, quarters and digits in parallel lanes of one word, each
/// division by 10⁴, 10², 10 a multiplication and a shift.
fn eight_digit_values(n: u64) -> u64 {
    debug_assert!(n < 100_000_000);
    // Lanes of 32 bits: the first four digits low, the last four high.
    let fours = (n / 10_000) | ((n % 10_000) << 32);
    // ⌊x / 100⌋ = (x · 10486) >> 20 for x < 10⁴ (lanes stay below 2³²).
    let hundreds = ((fours * 10_486) >> 20) & 0x0000_007F_0000_007F;
    let pairs = hundreds | ((fours - hundreds * 100) << 16);
    // ⌊x / 10⌋ = (x · 103) >> 10 for x < 100 (lanes stay below 2¹⁶).
    let tens = ((pairs * 103) >> 10) & 0x000F_000F_000F_000F;
    tens | ((pairs - tens * 10) << 8)
}

/// `00`, `01`, … `99` back to back.
const DIGIT_PAIRS: [u8; 200] = {
    let mut pairs = [0u8; 200];
    let mut i = 0;
    while i < 100 {
        pairs[2 * i] = b'0' + (i / 10) as u8;
        pairs[2 * i + 1] = b'0' + (i % 10) as u8;
        i += 1;
    }
    pairs
};

/// `y` rounded to the nearest integer, halves to even, as
/// `f64::round_ties_even` does, for `|y| < 2^51`. That is a library call
/// on x86-64 without SSE4.1; here the addition rounds: `y + 1.5·2^52`
/// lies where `f64`s are one apart. No branch on which way (a branch
/// there is mispredicted half the time).
fn round(y: f64) -> i64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    debug_assert!(y.abs() < 2_251_799_813_685_248.0);
    ((y + MAGIC) - MAGIC) as i64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(x: f64) -> String {
        let mut dst = [0; WIDEST];
        let n = Formatter::default().exact(&mut dst, x);
        String::from_utf8(dst[..n].to_vec()).unwrap()
    }

    fn measured(x: f64) -> String {
        let mut dst = [0; WIDEST];
        let n = Formatter::default().measured(&mut dst, x);
        String::from_utf8(dst[..n].to_vec()).unwrap()
    }

    #[test]
    fn exact_is_shortest_and_reads_back() {
        assert_eq!(exact(0.0), "0");
        assert_eq!(exact(2.5), "2.5");
        assert_eq!(exact(-4.0), "-4");
        assert_eq!(exact(0.001), "0.001");
        assert_eq!(exact(0.1 + 0.2), "0.30000000000000004");
        assert_eq!(exact(1.0 / 3.0), "0.3333333333333333");
        assert_eq!(exact(12.345), "12.345");
        assert_eq!(exact(-2.4869), "-2.4869");
        for x in [
            1e-300,
            5e-324,
            123456.789,
            -1e21,
            f64::MAX,
            99999.99999,
            1e-10,
        ] {
            assert_eq!(exact(x).parse::<f64>().unwrap(), x, "{x}");
        }
        // The fast path and ryu agree wherever both apply.
        let mut ryu = ryu::Buffer::new();
        for k in 0..20_000 {
            for x in [
                k as f64 * 1e-3,
                2.5 * (k as f64 * 0.01).sin(),
                k as f64 * 0.1,
            ] {
                let x: f64 = format!("{x:.4}").parse().unwrap();
                let r = ryu.format_finite(x);
                assert_eq!(exact(x), r.strip_suffix(".0").unwrap_or(r), "{x}");
            }
        }
    }

    #[test]
    fn round_is_f64_round_ties_even() {
        // Up to the exact path's 1e5 in quanta.
        let mut y = 1e-3f64;
        while y < 1e15 {
            for v in [
                y,
                -y,
                y.floor() + 0.5,
                -(y.floor() + 0.5),
                0.5 - f64::EPSILON / 4.0,
            ] {
                assert_eq!(round(v), v.round_ties_even() as i64, "{v}");
            }
            y *= 1.011;
        }
        assert_eq!(
            (round(0.0), round(-0.0), round(2.5), round(-2.5)),
            (0, 0, 2, -2)
        );
    }

    proptest::proptest! {
        /// Any number of quanta is written as its plain decimal: the
        /// whole part, the ten decimals, trailing zeros and a bare point cut.
        #[test]
        fn quanta_are_written_as_their_decimal(
            q in -1_000_000_000_000i64..1_000_000_000_000,
            zeros in 0u32..11,
        ) {
            for q in [q, q / 10i64.pow(zeros) * 10i64.pow(zeros)] {
                let mut dst = [0; WIDEST];
                let n = quanta_text(&mut dst, q, &mut itoa::Buffer::new());
                let out = dst[..n].to_vec();
                let (sign, q_abs) = (if q < 0 { "-" } else { "" }, q.unsigned_abs());
                let text = format!("{sign}{}.{:010}", q_abs / FRACTION, q_abs % FRACTION);
                let want = text.trim_end_matches('0').trim_end_matches('.');
                proptest::prop_assert_eq!(String::from_utf8(out).unwrap(), want);
            }
        }
    }

    #[test]
    fn measured_is_rounded_to_the_quantum() {
        assert_eq!(measured(0.0), "0");
        assert_eq!(measured(-0.0), "0");
        assert_eq!(measured(3.0), "3");
        assert_eq!(measured(0.0125), "0.0125");
        assert_eq!(measured(-0.000_014_999_999_999_999_999), "-0.000015");
        assert_eq!(measured(0.012_345_678_912_345), "0.0123456789");
        assert_eq!(measured(0.012_345_678_96), "0.012345679");
        assert_eq!(measured(4e-11), "0");
        assert_eq!(measured(-6e-11), "-0.0000000001");
        assert_eq!(measured(-12.5), "-12.5");
        // Out of any bench's range: exact rather than rounded.
        assert_eq!(measured(1e3), "1000");
        assert_eq!(measured(123.456_789_012_345_67), "123.45678901234567");
    }

    #[test]
    fn measured_reads_back_within_the_stated_error() {
        let mut x = 1.234_567_890_123_456_7e-14;
        while x < 200.0 {
            for v in [x, -x, x * 1.000_000_3, x * 7.77] {
                let back: f64 = measured(v).parse().unwrap();
                assert!(
                    (back - v).abs() <= max_written_error(v),
                    "{v} written as {} reads back as {back}",
                    measured(v)
                );
            }
            x *= 1.37;
        }
    }
}
