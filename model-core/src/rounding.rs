//! A mode's step rounded to the board's float without letting it grow.
//!
//! An undamped mode turns by `[[c, s], [−s, c]]` each step. Rounded to
//! `f32` entry by entry, `c² + s²` is off one by up to an ulp, and the
//! ringing grows or shrinks by half that every step: on the seed's strip,
//! −2.7 % to +2.4 % over 10⁶ steps (17 minutes at 1 kHz). A 2×2 block
//! with complex eigenvalues scales its ringing by `√det` each step, so of
//! the roundings within [`REACH`] ulps of each entry the one is taken
//! whose determinant is nearest the exact one without exceeding it: the
//! mode cannot grow. It can still decay by up to an ulp of the determinant
//! a step (for a small turn, `c ≈ 1` sits on a grid of 6·10⁻⁸ and no
//! rounding of `s` within a few ulps makes up the rest), a damping ratio
//! below 10⁻⁶, four orders under any real strip's (`tests/long_run.rs`).

use crate::real::Real;

/// Units in the last place each entry may move from its nearest rounding.
const REACH: i32 = 2;

/// The 2×2 block `m` rounded to `T`: each entry within [`REACH`] ulps of
/// its nearest, the determinant at most `det m` and as near it as they
/// allow, then the entries as near their nearest as they allow.
pub(crate) fn round_block<T: Real>(m: [[f64; 2]; 2]) -> [[T; 2]; 2] {
    let nearest = m.map(|row| row.map(T::from_f64));
    // In f64 the determinant's own rounding is as large as a nudge: the
    // nearest entries are as good as any.
    if T::UNIT_ROUNDOFF < 1e-12 {
        return nearest;
    }
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    // Products of two f32 are exact in f64.
    let det_of =
        |b: &[[T; 2]; 2]| b[0][0].to_f64() * b[1][1].to_f64() - b[0][1].to_f64() * b[1][0].to_f64();
    let width = 2 * REACH + 1;
    let mut best = nearest;
    let mut best_key = (f64::INFINITY, i32::MAX);
    for code in 0..width.pow(4) {
        let offset = |i: u32| (code / width.pow(i)) % width - REACH;
        let mut b = nearest;
        for (i, e) in b.iter_mut().flatten().enumerate() {
            *e = e.ulps(offset(i as u32));
        }
        let d = det_of(&b);
        if d > det {
            continue;
        }
        let key = (det - d, (0..4).map(|i| offset(i).abs()).sum::<i32>());
        if key < best_key {
            best = b;
            best_key = key;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::round_block;
    use crate::real::Real;

    #[test]
    fn a_rounded_rotation_keeps_its_determinant_from_above() {
        let mut worst_gap = 0.0f64;
        // Entry by entry, the determinant lands above one for some turns.
        let mut above = 0;
        for i in 1..200 {
            let angle = 0.0137 * i as f64;
            let (s, c) = libm::sincos(angle);
            let m = [[c, s], [-s, c]];
            let r: [[f32; 2]; 2] = round_block(m);
            let (c32, s32) = (c as f32 as f64, s as f32 as f64);
            above += usize::from(c32 * c32 + s32 * s32 > 1.0);
            let det = r[0][0].to_f64() * r[1][1].to_f64() - r[0][1].to_f64() * r[1][0].to_f64();
            assert!(det <= 1.0, "angle {angle}: det {det}");
            worst_gap = worst_gap.max(1.0 - det);
            for (row, exact) in r.iter().zip(m) {
                for (e, x) in row.iter().zip(exact) {
                    // Within the reach: a few ulps.
                    assert!((e.to_f64() - x).abs() <= 3.0 * f32::EPSILON as f64);
                }
            }
        }
        assert!(above > 10, "{above}");
        // Below, by less than an ulp of the determinant.
        assert!(
            worst_gap < f32::EPSILON as f64,
            "worst 1 - det {worst_gap:e}"
        );
        // f64 is left as rounded.
        let m = [[0.6, 0.8], [-0.8, 0.6]];
        assert_eq!(round_block::<f64>(m), m);
    }
}
