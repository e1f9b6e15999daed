//! `finrs seed-check`: the seed's facts against the baseline and the
//! extended model, read as the seed reports them, and the reasons, as
//! numbers that could come out wrong.

use finrs::analysis::seed_check::{
    seed_check, CHAPTER_1_MODULUS_PA, CHAPTER_2_MODULUS_PA, TABLE_4_1,
};

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

    // Section 4.1.4's 1 V force with the 13 mm: EI several times below the
    // laminate's, a modulus between chapter 1's and chapter 2's.
    let one_volt = row("peak blocking force at 1 V");
    assert!(one_volt.baseline / one_volt.measured > 3.0, "{one_volt:?}");
    assert!((one_volt.extended / one_volt.measured - 1.0).abs() < 1e-9);
    let times_below = c.laminate_ei_nm2 / c.implied_ei_nm2;
    assert!((3.0..10.0).contains(&times_below), "{times_below}");
    assert!(
        (CHAPTER_1_MODULUS_PA.0..1.5 * CHAPTER_2_MODULUS_PA).contains(&c.implied_modulus_pa),
        "{}",
        c.implied_modulus_pa
    );
    // Table 4-1's forces on the same strip are far below that reading,
    // and grow much faster than the voltage: a contradiction, said so.
    for r in c
        .rows
        .iter()
        .filter(|r| r.quantity.starts_with("peak blocking force") && r.quantity.contains("Table"))
    {
        assert!(r.extended / r.measured > 10.0, "{r:?}");
    }
    assert!(c.table_over_reading < 0.1, "{}", c.table_over_reading);
    assert!(c.force_exponent > 3.0 && c.current_exponent > 2.0);
    assert!(c.contradictions[0].contains("4.1.4"));

    // The table's currents are peak currents of the 25 mm strip's circuit,
    // whose resistances are twice the 50 mm strip's.
    let file = finrs::model::params::ModelFile::main_m_2006();
    assert_eq!(
        c.scaled_r1_r2_ohm,
        (2.0 * file.electrical.r1_ohm, 2.0 * file.electrical.r2_ohm)
    );
    let (v, i, _) = TABLE_4_1[0];
    let four = row("peak current at 4 V");
    assert_eq!(four.measured, i);
    let (r1, r2) = c.scaled_r1_r2_ohm;
    assert!(
        (four.baseline - (v / r1 + v / r2)).abs() < 1e-12,
        "{four:?}"
    );
    // One R1 fits the four better than the area's.
    let currents: Vec<_> = c
        .rows
        .iter()
        .filter(|r| r.quantity.starts_with("peak current"))
        .collect();
    let err = |f: &dyn Fn(&finrs::analysis::seed_check::Row) -> f64| {
        currents
            .iter()
            .map(|r| (f(r) - r.measured).powi(2))
            .sum::<f64>()
    };
    assert!(err(&|r| r.extended) < err(&|r| r.baseline));
    assert!(c.table_r1_ohm < r1, "{}", c.table_r1_ohm);
    assert_eq!(c.explanations.len(), 4);
}
