//! Fixed-size dense matrices as nested arrays, `[[f64; C]; R]`.
//!
//! Only the handful of operations the discretisation needs. Matrices live on
//! the stack; callers pass output buffers so that nothing large is copied.

/// A row-major `R × C` matrix.
pub type Mat<const R: usize, const C: usize> = [[f64; C]; R];

/// A matrix with one row per beam freedom (`2NE` rows, `S` columns of
/// which the beam uses the first `2NE`): the beam's square matrices in
/// `2NE/S` (a third for `E = 1`) of an `S × S` array's stack. The nesting
/// spells `2NE` rows without arithmetic on const generics; [`rows`] and
/// [`rows_mut`] see it as `2NE` rows.
pub type DofMat<T, const N: usize, const E: usize, const S: usize> = [[[[T; S]; E]; 2]; N];

/// A zero [`DofMat`].
pub const fn dof_zeros<T: Copy, const N: usize, const E: usize, const S: usize>(
    zero: T,
) -> DofMat<T, N, E, S> {
    [[[[zero; S]; E]; 2]; N]
}

/// The `2NE` rows of a [`DofMat`].
pub fn rows<T, const N: usize, const E: usize, const S: usize>(
    m: &DofMat<T, N, E, S>,
) -> &[[T; S]] {
    m.as_flattened().as_flattened()
}

/// The `2NE` rows of a [`DofMat`], mutable.
pub fn rows_mut<T, const N: usize, const E: usize, const S: usize>(
    m: &mut DofMat<T, N, E, S>,
) -> &mut [[T; S]] {
    m.as_flattened_mut().as_flattened_mut()
}

/// A `2NE × 2NE` matrix over the beam's freedoms, row-major, exactly that
/// size (a ninth of an `S × S` array for `E = 1`): the nesting spells
/// `2NE` without arithmetic on const generics. Indexed `m[(row, col)]`.
#[derive(Clone)]
pub struct Square<const N: usize, const E: usize>([[[DofRow<N, E>; E]; 2]; N]);

/// One row of a [`Square`]: `2NE` entries.
type DofRow<const N: usize, const E: usize> = [[[f64; E]; 2]; N];

impl<const N: usize, const E: usize> Square<N, E> {
    /// Rows and columns: `2NE`.
    pub const DIM: usize = 2 * N * E;

    /// The zero matrix.
    pub const fn zeros() -> Self {
        Square([[[[[[0.0; E]; 2]; N]; E]; 2]; N])
    }

    /// Row `i`, `2NE` entries.
    pub fn row(&self, i: usize) -> &[f64] {
        self.0.as_flattened().as_flattened()[i]
            .as_flattened()
            .as_flattened()
    }

    /// Every entry to zero.
    pub fn clear(&mut self) {
        *self = Self::zeros();
    }
}

impl<const N: usize, const E: usize> core::ops::Index<(usize, usize)> for Square<N, E> {
    type Output = f64;
    #[inline]
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        // A column past the last would alias the next row.
        debug_assert!(j < Self::DIM, "column {j} of a {0}×{0} matrix", Self::DIM);
        &self.0.as_flattened().as_flattened()[i]
            .as_flattened()
            .as_flattened()[j]
    }
}

impl<const N: usize, const E: usize> core::ops::IndexMut<(usize, usize)> for Square<N, E> {
    #[inline]
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        debug_assert!(j < Self::DIM, "column {j} of a {0}×{0} matrix", Self::DIM);
        &mut self.0.as_flattened_mut().as_flattened_mut()[i]
            .as_flattened_mut()
            .as_flattened_mut()[j]
    }
}

/// The `S × S` identity.
pub fn identity<const S: usize>() -> Mat<S, S> {
    let mut m = [[0.0; S]; S];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

/// `out = a · b`.
pub fn mul<const R: usize, const K: usize, const C: usize>(
    a: &Mat<R, K>,
    b: &Mat<K, C>,
    out: &mut Mat<R, C>,
) {
    for (out_row, a_row) in out.iter_mut().zip(a.iter()) {
        *out_row = [0.0; C];
        // i-k-j order: the inner loop runs along contiguous rows of `b`.
        for (&a_ik, b_row) in a_row.iter().zip(b.iter()) {
            if a_ik != 0.0 {
                for (o, &b_kj) in out_row.iter_mut().zip(b_row.iter()) {
                    *o += a_ik * b_kj;
                }
            }
        }
    }
}

/// The induced 1-norm: the largest absolute column sum.
pub fn norm1<const R: usize, const C: usize>(a: &Mat<R, C>) -> f64 {
    let mut best = 0.0_f64;
    for j in 0..C {
        let mut sum = 0.0;
        for row in a.iter() {
            sum += libm::fabs(row[j]);
        }
        if sum > best {
            best = sum;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every `(i, j)` of a `Square` is its own entry, in row-major order,
    /// and `row(i)` sees exactly row `i`: the nesting neither aliases nor
    /// reorders entries.
    #[test]
    fn square_entries_are_distinct_and_row_major() {
        let mut m = Square::<3, 2>::zeros();
        let dim = Square::<3, 2>::DIM;
        assert_eq!(dim, 12);
        assert_eq!(core::mem::size_of::<Square<3, 2>>(), 12 * 12 * 8);
        for i in 0..dim {
            for j in 0..dim {
                m[(i, j)] = (100 * i + j) as f64;
            }
        }
        for i in 0..dim {
            let row = m.row(i);
            assert_eq!(row.len(), dim);
            for (j, &x) in row.iter().enumerate() {
                assert_eq!(x, (100 * i + j) as f64, "entry ({i}, {j})");
                assert_eq!(m[(i, j)], x);
            }
        }
        m.clear();
        assert!((0..dim).all(|i| m.row(i).iter().all(|&x| x == 0.0)));
    }

    /// A `DofMat` has `2NE` rows of `S` entries, each its own.
    #[test]
    fn dof_mat_has_2ne_rows() {
        let mut m = dof_zeros::<f64, 2, 3, 28>(0.0);
        assert_eq!(rows(&m).len(), 12);
        for (i, row) in rows_mut(&mut m).iter_mut().enumerate() {
            row[i] = i as f64 + 1.0;
        }
        for (i, row) in rows(&m).iter().enumerate() {
            assert_eq!(row.iter().sum::<f64>(), i as f64 + 1.0);
            assert_eq!(row[i], i as f64 + 1.0);
        }
    }
}
