//! The exact discretisation: against an independent matrix exponential
//! (nalgebra's Padé on the augmented matrix), and exactness in the step.

use model_core::zoh::discretise;
use model_core::{Extensions, Fixture, Params, Strip};
use nalgebra::DMatrix;

const S: usize = 18;
const M: usize = 3;

/// `[[A, B], [0, 0]] h`, exponentiated by nalgebra: Φ and Γ in its blocks.
fn reference(a: &[[f64; S]; S], b: &[[f64; M]; S], h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut aug = DMatrix::<f64>::zeros(S + M, S + M);
    for i in 0..S {
        for j in 0..S {
            aug[(i, j)] = a[i][j] * h;
        }
        for j in 0..M {
            aug[(i, S + j)] = b[i][j] * h;
        }
    }
    let e = aug.exp();
    (
        e.view((0, 0), (S, S)).into_owned(),
        e.view((0, S), (S, M)).into_owned(),
    )
}

/// Largest element-wise difference relative to the largest element.
fn rel_diff<const C: usize>(ours: &[[f64; C]; S], theirs: &DMatrix<f64>) -> f64 {
    let (mut diff, mut scale) = (0.0f64, 0.0f64);
    for i in 0..S {
        for j in 0..C {
            diff = diff.max((ours[i][j] - theirs[(i, j)]).abs());
            scale = scale.max(theirs[(i, j)].abs());
        }
    }
    diff / scale
}

/// A matrix with the strip's structure: undamped rotations up to 4 kHz
/// driven by a slow electrical block, plus a little damping to make it
/// less special than a pure rotation.
fn strip_like() -> ([[f64; S]; S], [[f64; M]; S]) {
    let mut a = [[0.0; S]; S];
    let mut b = [[0.0; M]; S];
    let omegas = [168.0, 1057.0, 2986.0, 6724.0, 12655.0, 25229.0];
    for (k, &w) in omegas.iter().enumerate() {
        a[k][6 + k] = w;
        a[6 + k][k] = -w;
        a[6 + k][6 + k] = -0.01 * w;
        for i in 0..M {
            a[6 + k][12 + 2 * i] = 3.0 / (k + 1) as f64 * (i as f64 - 1.0);
            a[6 + k][13 + 2 * i] = -0.07 * (k as f64 + 0.5);
        }
    }
    for i in 0..M {
        a[12 + 2 * i][12 + 2 * i] = -62.5;
        b[12 + 2 * i][i] = 62.5;
        a[13 + 2 * i][12 + 2 * i] = 1.0;
        a[13 + 2 * i][13 + 2 * i] = -0.1;
    }
    (a, b)
}

#[test]
fn zoh_matches_independent_expm() {
    let (a, b) = strip_like();
    for h in [1e-4, 1e-3, 1e-2] {
        let (phi_ref, gamma_ref) = reference(&a, &b, h);
        let mut work = a;
        let mut phi = [[0.0; S]; S];
        let mut gamma = [[0.0; M]; S];
        discretise(&mut work, &b, h, &mut phi, &mut gamma);
        let (dp, dg) = (rel_diff(&phi, &phi_ref), rel_diff(&gamma, &gamma_ref));
        // Measured: 6e-16, 3e-15, 3e-14 for h = 0.1, 1, 10 ms: rounding,
        // amplified by the squarings (‖A h‖ up to 250 here).
        assert!(dp < 1e-12, "h = {h}: Φ differs by {dp:e}");
        assert!(dg < 1e-12, "h = {h}: Γ differs by {dg:e}");
    }
}

#[test]
fn zoh_of_a_scalar_is_exact() {
    // ẋ = -a x + v: Φ = e^{-a h}, Γ = (1 - e^{-a h})/a.
    let a0 = 62.5;
    let h = 1e-3;
    let mut a = [[-a0]];
    let mut phi = [[0.0]];
    let mut gamma = [[0.0]];
    discretise(&mut a, &[[1.0]], h, &mut phi, &mut gamma);
    let e = (-a0 * h).exp();
    assert!((phi[0][0] - e).abs() < 1e-16);
    assert!((gamma[0][0] - (1.0 - e) / a0).abs() < 1e-18);
}

/// Zero-order hold is exact for a held input: ten steps of h/10 and one of
/// h land on the same state. This bounds the discretisation error of the
/// whole model, not just of the exponential.
#[test]
fn held_input_is_exact_across_step_sizes() {
    let p = Params::main_m_2006();
    for fixture in [Fixture::Free, Fixture::Blocked] {
        let coarse = Strip::<f64, 3, 1, 18>::new(&p, fixture, 1e-3).unwrap();
        let fine = Strip::<f64, 3, 1, 18>::new(&p, fixture, 1e-4).unwrap();
        let (mut xc, mut xf) = (coarse.rest(), fine.rest());
        let v = [2.0, 1.0, -2.0];
        let mut worst = 0.0f64;
        for _ in 0..2000 {
            coarse.step(&mut xc, &v);
            for _ in 0..10 {
                fine.step(&mut xf, &v);
            }
            let (a, b) = match fixture {
                Fixture::Free => (coarse.tip_deflection_m(&xc), fine.tip_deflection_m(&xf)),
                Fixture::Blocked => (coarse.blocking_force_n(&xc), fine.blocking_force_n(&xf)),
            };
            worst = worst.max((a - b).abs());
        }
        // Tip ≈ 1e-2 m, force ≈ 3e-2 N; measured 3e-14 (free), 5e-14 (blocked).
        assert!(
            worst < 1e-12,
            "{fixture:?}: coarse and fine differ by {worst:e}"
        );
    }
}

/// A naive integrator would need a step far below the 4 kHz mode; the exact
/// discretisation is stable at any step, even 0.1 s.
#[test]
fn long_steps_stay_bounded() {
    let p = Params::main_m_2006();
    let s = Strip::<f64, 3, 1, 18>::new(&p, Fixture::Free, 0.1).unwrap();
    let mut x = s.rest();
    for _ in 0..10_000 {
        s.step(&mut x, &[2.5; 3]);
        assert!(s.tip_deflection_m(&x).abs() < 0.05);
    }
}

/// `Strip::new` exponentiates block by block (one 4-state system per mode);
/// that must equal the exponential of the whole continuous system, and the
/// step must apply exactly that `Φ` and `Γ`.
#[test]
fn block_discretisation_equals_the_dense_one() {
    fn check<const N: usize, const E: usize, const S: usize>(fixture: Fixture, h: f64) {
        let p = Params::main_m_2006();
        // Every linear term on, so the blocks carry damping, added mass
        // and crosstalk too.
        let ext = Extensions {
            damping_mass_per_s: 3.0,
            damping_stiffness_s: 2e-5,
            added_mass_kg_per_m: 0.02,
            drag_n_s_per_m2: 0.01,
            crosstalk: 0.2,
            ..Extensions::NONE
        };
        let s = Strip::<f64, N, E, S>::with_extensions(&p, &ext, fixture, h).unwrap();
        let (mut a, b) = Strip::<f64, N, E, S>::continuous(&p, &ext, fixture).unwrap();
        let (mut phi, mut gamma) = ([[0.0; S]; S], [[0.0; N]; S]);
        discretise(&mut a, &b, h, &mut phi, &mut gamma);
        let (ours_phi, ours_gamma) = (s.phi(), s.gamma());
        let scale_g = gamma.iter().flatten().fold(0.0f64, |m, g| m.max(g.abs()));
        for i in 0..S {
            for j in 0..S {
                let d = (ours_phi[i][j] - phi[i][j]).abs();
                // Φ is O(1); the dense run squares a larger norm, so allow its rounding.
                assert!(
                    d < 1e-11,
                    "{fixture:?} N={N} E={E} h={h}: Φ[{i}][{j}] off by {d:e}"
                );
            }
            for j in 0..N {
                let d = (ours_gamma[i][j] - gamma[i][j]).abs() / scale_g;
                assert!(
                    d < 1e-11,
                    "{fixture:?} N={N} E={E} h={h}: Γ[{i}][{j}] off by {d:e}"
                );
            }
        }
        // The step applies Φ x + Γ v, for a state with every entry set.
        let mut x: [f64; S] = core::array::from_fn(|j| ((j * 7 % 11) as f64 - 5.0) * 1e-3);
        let v: [f64; N] = core::array::from_fn(|i| 1.0 - i as f64);
        let want: [f64; S] = core::array::from_fn(|i| {
            (0..S).map(|j| ours_phi[i][j] * x[j]).sum::<f64>()
                + (0..N).map(|j| ours_gamma[i][j] * v[j]).sum::<f64>()
        });
        s.step(&mut x, &v);
        for i in 0..S {
            assert!(
                (x[i] - want[i]).abs() < 1e-15,
                "{fixture:?} N={N} E={E}: x[{i}]"
            );
        }
    }
    for fixture in [Fixture::Free, Fixture::Blocked] {
        for h in [1e-4, 1e-3, 1e-2] {
            check::<1, 1, 6>(fixture, h);
            check::<3, 1, 18>(fixture, h);
            check::<3, 2, { model_core::state_len(3, 2) }>(fixture, h);
            check::<8, 1, { model_core::state_len(8, 1) }>(fixture, h);
        }
    }
}
