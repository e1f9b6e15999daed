//! `finrs seed-check`: the seed's facts against the baseline and the
//! extended model, and the reasons, as numbers that could come out wrong.

use finrs::analysis::seed_check::seed_check;

#[test]
fn the_seed_check_explains_each_fact() {
    let c = seed_check().unwrap();
    let row = |q: &str| c.rows.iter().find(|r| r.quantity.starts_with(q)).unwrap();
    // 13 mm across is the baseline's calibration; nothing along without arcs.
    let across = row("tip across");
    assert!((across.baseline - 0.013).abs() < 1e-4, "{across:?}");
    let along = row("tip along");
    assert_eq!(along.baseline, 0.0);
    assert!((-2.6e-3..-1.9e-3).contains(&along.extended), "{along:?}");
    // The baseline's forces are two orders of magnitude above Table 4-1's;
    // the freed EI brings them within a factor of two.
    for r in c
        .rows
        .iter()
        .filter(|r| r.quantity.starts_with("peak blocking force"))
    {
        assert!(r.baseline / r.measured > 100.0, "{r:?}");
        let ratio = r.extended / r.measured;
        assert!((0.5..2.1).contains(&ratio), "{r:?}");
    }
    assert!(c.implied_ei_nm2 < 1e-2 * c.laminate_ei_nm2);
    // Current: far from linear, and the cubic leak does better than R2 alone.
    assert!(c.current_exponent > 2.0);
    let currents: Vec<_> = c
        .rows
        .iter()
        .filter(|r| r.quantity.starts_with("current"))
        .collect();
    let err = |f: &dyn Fn(&finrs::analysis::seed_check::Row) -> f64| {
        currents
            .iter()
            .map(|r| (f(r) - r.measured).powi(2))
            .sum::<f64>()
    };
    assert!(err(&|r| r.extended) < 0.1 * err(&|r| r.baseline));
    assert_eq!(c.explanations.len(), 3);
}
