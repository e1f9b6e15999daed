//! The seed's three-segment simulation (section 4.2: steps of 2, 1 and −2 V,
//! n = 3) against the output kept in `tests/scenarios/expected/seed_4_2.txt`, as the
//! rtic examples compare QEMU runs with expected files. The seed's own
//! figure is not in its text, so the run is also checked against the
//! analytic facts it must obey. `FINRS_BLESS=1` rewrites the file.

use std::path::Path;

use finrs_tests::{run_scenario, SCENARIOS};
use model_core::Params;

fn numbers(line: &str) -> (usize, Vec<f64>) {
    let mut it = line.split(' ').skip(1);
    let k = it.next().unwrap().parse().unwrap();
    (k, it.map(|s| s.parse().unwrap()).collect())
}

#[test]
fn seed_4_2_matches_expected_file() {
    let sc = &SCENARIOS[0];
    assert_eq!(sc.name, "seed_4_2");
    let mut now = String::new();
    run_scenario::<f64, _>(sc, &mut now).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("expected/seed_4_2.txt");
    if std::env::var_os("FINRS_BLESS").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    let kept = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (FINRS_BLESS=1 writes it)", path.display()));
    let (kept, now): (Vec<&str>, Vec<&str>) = (kept.lines().collect(), now.lines().collect());
    assert_eq!(kept.len(), now.len());
    for (a, b) in kept.iter().zip(&now) {
        let ((ka, va), (kb, vb)) = (numbers(a), numbers(b));
        assert_eq!(ka, kb);
        for (x, y) in va.iter().zip(&vb) {
            // Relative 1e-9 with an absolute floor far below any signal.
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1e-9),
                "sample {ka}: kept {x:e}, now {y:e}"
            );
        }
    }
}

#[test]
fn seed_4_2_obeys_the_analytic_facts() {
    let p = Params::main_m_2006();
    let mut out = String::new();
    run_scenario::<f64, _>(&SCENARIOS[0], &mut out).unwrap();
    let levels = [2.0, 1.0, -2.0];
    for line in out.lines() {
        let (k, v) = numbers(line);
        let (moments, currents) = (&v[2..5], &v[5..8]);
        // Identical segments: moments in proportion to the voltages.
        assert!((moments[1] * 2.0 - moments[0]).abs() <= 1e-12 * moments[0].abs().max(1e-12));
        assert!((moments[2] + moments[0]).abs() <= 1e-12 * moments[0].abs().max(1e-12));
        if k == 0 {
            for (i, lv) in currents.iter().zip(levels) {
                assert!((i - (lv / p.r1_ohm + lv / p.r2_ohm)).abs() < 1e-15);
            }
        }
        if k >= 1000 {
            // After 1 s (60 τ1) the current is V/R2.
            for (i, lv) in currents.iter().zip(levels) {
                assert!((i - lv / p.r2_ohm).abs() < 1e-12, "sample {k}: {i}");
            }
        }
    }
    // Moment of segment 1 after 10 s: u = C (a v_C + (b − a p) r), with
    // v_C = V (1 − e^{−λt}), λ = 1/τ1, and the network's state
    // r = V ((1 − e^{−pt})/p − (e^{−λt} − e^{−pt})/(p − λ)).
    let (_, last) = numbers(out.lines().last().unwrap());
    let (v, t, l, pp) = (2.0, 10.0, 1.0 / p.tau1_s(), p.p_per_s);
    let v_c = v * (1.0 - (-l * t).exp());
    let r = v * ((1.0 - (-pp * t).exp()) / pp - ((-l * t).exp() - (-pp * t).exp()) / (pp - l));
    let expected = p.c_f * (p.a_nm_per_c * v_c + (p.b_nm_per_c_s - p.a_nm_per_c * pp) * r);
    assert!(
        (last[2] / expected - 1.0).abs() < 2e-3,
        "{} vs {expected}",
        last[2]
    );
}
