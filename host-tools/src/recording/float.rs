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

/// Writes finite numbers into one output buffer without allocating.
#[derive(Default)]
pub(crate) struct Formatter {
    ryu: ryu::Buffer,
    itoa: itoa::Buffer,
}

impl Formatter {
    /// Appends `x` exactly: the shortest decimal that reads back as `x`,
    /// without `ryu`'s trailing `.0`. `x` must be finite (checked by the
    /// caller, which refuses NaN and infinity by name).
    pub fn exact(&mut self, out: &mut Vec<u8>, x: f64) {
        debug_assert!(x.is_finite());
        // Fast path for what a DAQ writes (times to the ms, voltages to a
        // DAC step): if `x` is the nearest f64 to a decimal of at most
        // MEASURED_DECIMALS decimals, that decimal reads back as `x`. The
        // test is exact: `quanta / SCALE` is correctly rounded, as a reader
        // rounds, and below 1e5 distinct such decimals are distinct f64s,
        // so the decimal is also the shortest.
        if x.abs() < 1e5 {
            let quanta = (x * SCALE).round();
            if quanta / SCALE == x {
                return self.quanta(out, quanta as i64);
            }
        }
        let s = self.ryu.format_finite(x);
        let s = s.strip_suffix(".0").unwrap_or(s);
        out.extend_from_slice(s.as_bytes());
    }

    /// Appends a measured value rounded to [`MEASURED_DECIMALS`] decimals,
    /// trailing zeros dropped (`0.0125`, `-3`, `0`); `x` must be finite.
    pub fn measured(&mut self, out: &mut Vec<u8>, x: f64) {
        debug_assert!(x.is_finite());
        let quanta = (x * SCALE).round();
        if quanta.abs() >= MAX_QUANTA {
            return self.exact(out, x);
        }
        // Exact: |quanta| < 1e12 < 2^53.
        self.quanta(out, quanta as i64)
    }

    /// Appends `quanta * MEASURED_QUANTUM` as a decimal, trailing zeros
    /// dropped.
    fn quanta(&mut self, out: &mut Vec<u8>, quanta: i64) {
        if quanta < 0 {
            out.push(b'-');
        }
        let q = quanta.unsigned_abs();
        out.extend_from_slice(self.itoa.format(q / FRACTION).as_bytes());
        let mut frac = q % FRACTION;
        if frac == 0 {
            return;
        }
        let mut decimals = MEASURED_DECIMALS as usize;
        while frac % 10 == 0 {
            frac /= 10;
            decimals -= 1;
        }
        let digits = self.itoa.format(frac).as_bytes();
        out.push(b'.');
        out.extend(std::iter::repeat_n(b'0', decimals - digits.len()));
        out.extend_from_slice(digits);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exact(x: f64) -> String {
        let mut out = Vec::new();
        Formatter::default().exact(&mut out, x);
        String::from_utf8(out).unwrap()
    }

    fn measured(x: f64) -> String {
        let mut out = Vec::new();
        Formatter::default().measured(&mut out, x);
        String::from_utf8(out).unwrap()
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
