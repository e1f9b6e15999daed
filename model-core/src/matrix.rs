//! Fixed-size dense matrices as nested arrays, `[[f64; C]; R]`.
//!
//! Only the handful of operations the discretisation needs. Matrices live on
//! the stack; callers pass output buffers so that nothing large is copied.

/// A row-major `R × C` matrix.
pub type Mat<const R: usize, const C: usize> = [[f64; C]; R];

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
