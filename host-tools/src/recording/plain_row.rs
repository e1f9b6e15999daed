//! The common data row, read eight bytes at a time: every field a plain
//! decimal of a few digits (`0.125`, `-2.4869`, `12`) or empty.
//!
//! A DAQ writes nothing else, and such a row is read here in one pass with
//! no error path: each run of digits is found and converted as one 64-bit
//! word (SWAR), not a byte at a time with a branch per byte (the 20 000
//! rows of `scripts/bench-simulate-job`: 1.10 ms against 1.55 ms). Anything else
//! (an exponent, eight digits in a run, a stray byte, a wrong field count)
//! is left to the reader's general path, which reads such fields with
//! `str::parse` and names whatever is wrong; so are rows this accepts but
//! whose numbers break a rule. Values are exactly those of the general
//! path (one correctly rounded division, Clinger's fast path).

/// Powers of ten exact in `f64`, for up to 14 decimals.
const POW10: [f64; 15] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14,
];

/// Integer powers of ten, for up to 7 decimals.
const POW10_INT: [u64; 8] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];

const ONES: u64 = 0x0101_0101_0101_0101;

/// Reads `row`'s fields into `values` (`values.len()` of them, an empty one
/// as NaN); `None` unless each is empty or a plain decimal of at most seven
/// digits before and seven after its point, and there are exactly that
/// many.
pub(super) fn plain_row(row: &[u8], values: &mut [f64]) -> Option<()> {
    let last = values.len().checked_sub(1)?;
    let mut at = 0;
    for (j, value) in values.iter_mut().enumerate() {
        let negative = row.get(at) == Some(&b'-');
        let start = at + usize::from(negative);
        let (whole, mut mantissa) = digits(word(row, start));
        let mut end = start + whole;
        let mut decimals = 0;
        if row.get(end) == Some(&b'.') {
            let (n, fraction) = digits(word(row, end + 1));
            if n == 0 || n == 8 {
                return None;
            }
            decimals = n;
            mantissa = mantissa * POW10_INT[n] + fraction;
            end += 1 + n;
        }
        *value = if whole == 0 && end == at {
            // Nothing here: an empty field (the caller decides if it may be).
            f64::NAN
        } else if whole == 0 || whole == 8 {
            return None;
        } else {
            // Below 10^14: as i64, one instruction to convert; the sign as
            // a bit, not a branch (signs alternate unpredictably).
            let x = mantissa as i64 as f64 / POW10[decimals];
            f64::from_bits(x.to_bits() | u64::from(negative) << 63)
        };
        let ends = if j == last {
            end == row.len()
        } else {
            row.get(end) == Some(&b',')
        };
        if !ends {
            return None;
        }
        at = end + 1;
    }
    Some(())
}

/// The eight bytes of `row` from `at` as a little-endian word (the first
/// byte lowest); bytes past the row's end read as 0, which is no digit.
#[inline]
fn word(row: &[u8], at: usize) -> u64 {
    if let Some(bytes) = row
        .get(at..at + 8)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
    {
        return u64::from_le_bytes(bytes);
    }
    // Near the row's end: its last eight bytes, shifted past those before
    // `at`, or a copy of a row shorter than a word.
    let len = row.len();
    if let Some(bytes) = len
        .checked_sub(8)
        .and_then(|from| <[u8; 8]>::try_from(&row[from..]).ok())
    {
        return u64::from_le_bytes(bytes)
            .checked_shr(8 * (at + 8).saturating_sub(len) as u32)
            .unwrap_or(0);
    }
    let mut bytes = [0u8; 8];
    let rest = row.get(at..).unwrap_or_default();
    bytes[..rest.len()].copy_from_slice(rest);
    u64::from_le_bytes(bytes)
}

/// The run of ASCII digits at the start of `w`: its length (8 when all
/// eight bytes are digits: the run may go on) and its value.
#[inline]
fn digits(w: u64) -> (usize, u64) {
    // A byte's top bit is set here if it is below `0` or above `9`. Carries
    // and borrows only run towards later bytes, past the first non-digit,
    // so they never hide it.
    let below = w.wrapping_sub(0x30 * ONES);
    let above = w.wrapping_add(0x46 * ONES);
    let not_digit = (below | above) & (0x80 * ONES);
    let n = (not_digit.trailing_zeros() / 8) as usize;
    // The n digits moved to the top bytes (zeros below read as leading
    // zeros), then pairs, fours and eights joined by a multiplication each.
    let d = (w & (0x0F * ONES))
        .checked_shl(64 - 8 * n as u32)
        .unwrap_or(0);
    let d = d.wrapping_mul(10 * (1 << 8) + 1) >> 8;
    let d = (d & 0x00FF_00FF_00FF_00FF).wrapping_mul(100 * (1 << 16) + 1) >> 16;
    let d = (d & 0x0000_FFFF_0000_FFFF).wrapping_mul(10_000 * (1 << 32) + 1) >> 32;
    (n, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The general path's reading of one field: empty is NaN.
    fn general(field: &str) -> Option<f64> {
        if field.is_empty() {
            return Some(f64::NAN);
        }
        field.parse().ok().filter(|x: &f64| x.is_finite())
    }

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn plain_rows_read_as_str_parse_reads_them() {
        let mut v = [0.0; 4];
        for row in [
            "0.000,0.0000,-2.4869,0.000143",
            "19.999,-0,3,",
            ",1,2,3",
            "1234567.1234567,9999999,-0.0000001,12",
        ] {
            assert!(plain_row(row.as_bytes(), &mut v).is_some(), "{row}");
            for (x, field) in v.iter().zip(row.split(',')) {
                assert!(same(*x, general(field).unwrap()), "{row}: {field}");
            }
        }
        for row in [
            "0,1,2",
            "0,1,2,3,4",
            "0,1,2,3,",
            "1e3,1,2,3",
            "12345678,1,2,3",
            "0.12345678,1,2,3",
            "1.,1,2,3",
            ".5,1,2,3",
            "-,1,2,3",
            "+1,1,2,3",
            "1 ,1,2,3",
            "nan,1,2,3",
            "1,2,3,4\r",
            "0,1,2,3é",
            "",
        ] {
            assert!(plain_row(row.as_bytes(), &mut v).is_none(), "{row}");
        }
    }

    proptest::proptest! {
        /// Whatever row this reads, it reads as `str::parse` reads each
        /// field; rows of plain decimals it always reads.
        #[test]
        fn rows_read_as_str_parse_reads_them(
            fields in proptest::collection::vec("-?[0-9]{0,9}(\\.[0-9]{0,9})?|[0-9.eE+-]{0,4}", 1..6),
            plain in proptest::collection::vec((proptest::bool::ANY, 1u64..10_000_000, 0usize..8), 1..6),
        ) {
            let row = fields.join(",");
            let mut v = vec![0.0; fields.len()];
            if plain_row(row.as_bytes(), &mut v).is_some() {
                for (x, field) in v.iter().zip(&fields) {
                    let want = general(field);
                    proptest::prop_assert!(want.is_some_and(|w| same(*x, w)), "{}: {}", row, field);
                }
            }
            let fields: Vec<String> = plain
                .iter()
                .map(|&(negative, m, d)| {
                    let s = format!("{m:0width$}", width = d + 1);
                    let (whole, fraction) = s.split_at(s.len() - d);
                    let sign = if negative { "-" } else { "" };
                    if d == 0 { format!("{sign}{whole}") } else { format!("{sign}{whole}.{fraction}") }
                })
                .collect();
            let row = fields.join(",");
            let mut v = vec![0.0; fields.len()];
            proptest::prop_assert!(plain_row(row.as_bytes(), &mut v).is_some(), "{}", row);
            for (x, field) in v.iter().zip(&fields) {
                proptest::prop_assert!(same(*x, general(field).unwrap()), "{}: {}", row, field);
            }
        }
    }
}
