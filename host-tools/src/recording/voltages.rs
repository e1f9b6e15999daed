//! A recording's drive: every row's segment voltages in one flat array.
//!
//! One allocation for the whole drive instead of one per row: a 20 000-row
//! recording used to cost 20 000 allocations to read and as many frees,
//! and the model reads the rows in order, as they lie in memory.

use std::ops::{Index, IndexMut};
use std::slice::ChunksExact;

/// Voltages, V, row-major: row `r` holds segments `0..segments()`
/// (`v_v[r][k]` is segment `k + 1`'s voltage on row `r`).
#[derive(Clone, Debug, PartialEq)]
pub struct Voltages {
    segments: usize,
    v_v: Vec<f64>,
}

impl Voltages {
    /// No rows yet, room for `rows` of `segments` voltages.
    ///
    /// # Panics
    /// If `segments` is 0: a row needs at least one segment.
    pub fn with_capacity(segments: usize, rows: usize) -> Voltages {
        assert!(segments > 0, "a drive has at least one segment");
        Voltages {
            segments,
            v_v: Vec::with_capacity(segments * rows),
        }
    }

    /// `rows` rows at 0 V.
    ///
    /// # Panics
    /// If `segments` is 0.
    pub fn zeros(segments: usize, rows: usize) -> Voltages {
        let mut v = Voltages::with_capacity(segments, rows);
        v.v_v.resize(segments * rows, 0.0);
        v
    }

    /// The rows given, each of `segments` voltages.
    ///
    /// # Panics
    /// If `segments` is 0 or a row has another length.
    pub fn from_rows<R: AsRef<[f64]>>(
        segments: usize,
        rows: impl IntoIterator<Item = R>,
    ) -> Voltages {
        let mut v = Voltages::with_capacity(segments, 0);
        for row in rows {
            v.push(row.as_ref());
        }
        v
    }

    /// Appends one row.
    ///
    /// # Panics
    /// If `row` does not hold one voltage per segment.
    pub fn push(&mut self, row: &[f64]) {
        assert_eq!(row.len(), self.segments, "one voltage per segment");
        // One at a time: a row is a few values, too few for the call to
        // `memcpy` a copy of a slice of unknown length becomes.
        self.v_v.reserve(row.len());
        for &v in row {
            self.v_v.push(v);
        }
    }

    /// Voltages per row.
    pub fn segments(&self) -> usize {
        self.segments
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.v_v.len() / self.segments
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.v_v.is_empty()
    }

    /// The rows in order, each a slice of `segments()` voltages.
    pub fn rows(&self) -> ChunksExact<'_, f64> {
        self.v_v.chunks_exact(self.segments)
    }

    /// Row `row`, if there is one.
    pub fn row(&self, row: usize) -> Option<&[f64]> {
        let start = row.checked_mul(self.segments)?;
        self.v_v.get(start..start + self.segments)
    }

    /// Every voltage, row after row.
    pub fn as_flat(&self) -> &[f64] {
        &self.v_v
    }

    /// Every voltage, row after row, to change in place.
    pub fn as_flat_mut(&mut self) -> &mut [f64] {
        &mut self.v_v
    }
}

impl Index<usize> for Voltages {
    type Output = [f64];

    /// Row `row`; panics past the last row, as a slice does.
    fn index(&self, row: usize) -> &[f64] {
        &self.v_v[row * self.segments..(row + 1) * self.segments]
    }
}

impl IndexMut<usize> for Voltages {
    fn index_mut(&mut self, row: usize) -> &mut [f64] {
        &mut self.v_v[row * self.segments..(row + 1) * self.segments]
    }
}

impl<'a> IntoIterator for &'a Voltages {
    type Item = &'a [f64];
    type IntoIter = ChunksExact<'a, f64>;

    fn into_iter(self) -> ChunksExact<'a, f64> {
        self.rows()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_lie_in_order() {
        let mut v = Voltages::with_capacity(2, 3);
        assert!(v.is_empty());
        v.push(&[1.0, 2.0]);
        v.push(&[3.0, 4.0]);
        assert_eq!((v.len(), v.segments()), (2, 2));
        assert_eq!(&v[1], &[3.0, 4.0]);
        assert_eq!(v.row(0), Some(&[1.0, 2.0][..]));
        assert_eq!(v.row(2), None);
        assert_eq!(v.row(usize::MAX), None);
        assert_eq!(v.as_flat(), &[1.0, 2.0, 3.0, 4.0]);
        v[0][1] = -2.0;
        let rows: Vec<&[f64]> = v.rows().collect();
        assert_eq!(rows, vec![&[1.0, -2.0][..], &[3.0, 4.0][..]]);
        assert_eq!(v, Voltages::from_rows(2, [[1.0, -2.0], [3.0, 4.0]]));
        assert_eq!(Voltages::zeros(3, 2).as_flat(), &[0.0; 6]);
    }

    #[test]
    #[should_panic(expected = "one voltage per segment")]
    fn a_short_row_is_refused() {
        Voltages::with_capacity(3, 1).push(&[1.0]);
    }
}
