//! Column letters and the limits of a spreadsheet: how a place in an
//! export is named in the mapping and in a refusal.

/// Columns a spreadsheet has (Excel's `A` to `XFD`): a column beyond it
/// is refused, so that a damaged file cannot make the reader allocate
/// billions of cells.
pub const MAX_COLUMNS: usize = 16_384;

/// Rows a spreadsheet has (Excel's 1 048 576), for the same reason.
pub const MAX_ROWS: usize = 1_048_576;

/// The letters of the 0-based column `col`: 0 is `A`, 25 `Z`, 26 `AA`.
pub fn column_letters(col: usize) -> String {
    let mut out = Vec::new();
    let mut n = col + 1;
    while n > 0 {
        let rem = (n - 1) % 26;
        out.push(b'A' + rem as u8);
        n = (n - 1) / 26;
    }
    out.reverse();
    String::from_utf8(out).expect("ASCII letters")
}

/// The 0-based column that `letters` name (`A` is 0; lower case is
/// accepted), if they name one within [`MAX_COLUMNS`].
pub fn parse_column_letters(letters: &str) -> Option<usize> {
    if letters.is_empty() || letters.len() > 3 {
        return None;
    }
    let mut n = 0usize;
    for b in letters.bytes() {
        if !b.is_ascii_alphabetic() {
            return None;
        }
        n = n * 26 + usize::from(b.to_ascii_uppercase() - b'A') + 1;
    }
    (n <= MAX_COLUMNS).then(|| n - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn letters_round_trip_over_every_column() {
        assert_eq!(column_letters(0), "A");
        assert_eq!(column_letters(25), "Z");
        assert_eq!(column_letters(26), "AA");
        assert_eq!(column_letters(MAX_COLUMNS - 1), "XFD");
        for col in 0..MAX_COLUMNS {
            assert_eq!(parse_column_letters(&column_letters(col)), Some(col));
        }
        assert_eq!(parse_column_letters("c"), Some(2));
        for bad in ["", "XFE", "ZZZZ", "A1", "1", "Ä", "-"] {
            assert_eq!(parse_column_letters(bad), None, "{bad}");
        }
    }
}
