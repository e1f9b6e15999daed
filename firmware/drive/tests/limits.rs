//! Limits' validation and the limiter's clamp, slew, NaN handling and stop.

use finrs_drive::{LimitError, Limiter, Limits, HARD_LIMIT_V};

#[test]
fn limits_are_refused_by_field_and_rule() {
    use LimitError::*;
    for (max, slew, want) in [
        (4.0001, 10.0, MaxAbsAboveHardLimit),
        (100.0, 10.0, MaxAbsAboveHardLimit),
        (0.0, 10.0, MaxAbsNotPositive),
        (-1.0, 10.0, MaxAbsNotPositive),
        (f32::NAN, 10.0, MaxAbsNotFinite),
        (f32::INFINITY, 10.0, MaxAbsNotFinite),
        (2.0, 0.0, SlewNotPositive),
        (2.0, -5.0, SlewNotPositive),
        (2.0, f32::NAN, SlewNotFinite),
        (2.0, f32::INFINITY, SlewNotFinite),
    ] {
        assert_eq!(Limits::new(max, slew), Err(want), "{max}, {slew}");
    }
    let l = Limits::new(HARD_LIMIT_V, 10.0).unwrap();
    assert_eq!((l.max_abs_v(), l.slew_v_per_s()), (4.0, 10.0));
    assert_eq!(
        MaxAbsAboveHardLimit.to_string(),
        "max_abs_v must not exceed HARD_LIMIT_V (4 V)"
    );
}

#[test]
fn the_voltage_limit_can_only_be_lowered() {
    let mut l = Limits::new(3.0, 10.0).unwrap();
    assert_eq!(l.set_max_abs_v_lower(2.0), Ok(()));
    assert_eq!(l.set_max_abs_v_lower(2.0), Ok(()));
    for (v, want) in [
        (2.5, LimitError::MaxAbsRaised),
        (4.0, LimitError::MaxAbsRaised),
        (5.0, LimitError::MaxAbsAboveHardLimit),
        (f32::NAN, LimitError::MaxAbsNotFinite),
        (f32::NEG_INFINITY, LimitError::MaxAbsNotFinite),
        (0.0, LimitError::MaxAbsNotPositive),
        (-1.0, LimitError::MaxAbsNotPositive),
    ] {
        assert_eq!(l.set_max_abs_v_lower(v), Err(want), "{v}");
        assert_eq!(l.max_abs_v(), 2.0, "unchanged after {v}");
    }
}

#[test]
fn outputs_are_clamped_and_slew_limited() {
    let mut lim = Limiter::<2>::new(Limits::new(3.0, 100.0).unwrap());
    // 0.1 V per 1 ms step toward +3 (clamped from 10) and −3 (from −1e9).
    for i in 1..=30 {
        let out = lim.apply([10.0, -1e9], 1e-3);
        let want = (0.1 * i as f32).min(3.0);
        assert!((out[0] - want).abs() < 1e-5 && (out[1] + want).abs() < 1e-5);
    }
    for _ in 0..10 {
        assert_eq!(lim.apply([10.0, -1e9], 1e-3), [3.0, -3.0]);
    }
    // A lowered limit applies at once, ahead of the slew limit.
    lim.limits_mut().set_max_abs_v_lower(1.0).unwrap();
    assert_eq!(lim.apply([10.0, -1e9], 1e-3), [1.0, -1.0]);
    // A long step allows a large move.
    assert_eq!(lim.apply([-1.0, 0.5], 1.0), [-1.0, 0.5]);
}

#[test]
fn a_broken_request_moves_toward_zero_and_a_broken_step_holds() {
    let mut lim = Limiter::<4>::new(Limits::new(4.0, 100.0).unwrap());
    for _ in 0..20 {
        lim.apply([2.0; 4], 1e-3);
    }
    assert_eq!(lim.last_v(), [2.0; 4]);
    let out = lim.apply([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 2.0], 1e-3);
    for v in &out[..3] {
        assert!((v - 1.9).abs() < 1e-5, "{out:?}");
    }
    assert_eq!(out[3], 2.0);
    // A step that is not a finite positive time: no time is known to have
    // passed, so nothing moves (not even toward the 0 V it now asks).
    for dt in [0.0, -0.0, -1e-3, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(lim.apply([3.0; 4], dt), out, "dt = {dt}");
    }
    // Then, asking 0 V: down to zero at the slew rate.
    for i in 1..=30 {
        let v = lim.apply([0.0; 4], 1e-3)[3];
        assert!((v - (2.0 - 0.1 * i as f32).max(0.0)).abs() < 1e-5);
    }
}

#[test]
fn stop_drops_every_output_to_zero_at_once() {
    let mut lim = Limiter::<8>::new(Limits::new(4.0, 1.0).unwrap());
    lim.apply([3.0; 8], 10.0);
    assert_eq!(lim.last_v(), [3.0; 8]);
    assert_eq!(lim.stop(), [0.0; 8]);
    assert_eq!(lim.last_v(), [0.0; 8]);
    // And restarts from zero, slew-limited.
    assert_eq!(lim.apply([3.0; 8], 0.5), [0.5; 8]);
}

#[test]
fn apply_reporting_says_what_the_limits_did() {
    use finrs_drive::Applied;
    let mut l = Limiter::<2>::new(Limits::new(1.0, 100.0).unwrap());
    // 0.1 V a step at 1 ms: a step to 0.05 V is reached, to 0.5 V slewed.
    let none = Applied::default();
    assert_eq!(l.apply_reporting([0.05, 0.0], 1e-3).1, none);
    let (out, a) = l.apply_reporting([0.5, 0.0], 1e-3);
    assert_eq!(
        (out[0], a),
        (
            0.15,
            Applied {
                clamped: false,
                slewed: true
            }
        )
    );
    // Beyond the limit: clamped, and slewed on the way.
    let (_, a) = l.apply_reporting([0.0, -3.0], 1e-3);
    assert_eq!(
        a,
        Applied {
            clamped: true,
            slewed: true
        }
    );
    for _ in 0..20 {
        l.apply_reporting([0.0, -3.0], 1e-3);
    }
    assert_eq!(
        l.apply_reporting([0.0, -3.0], 1e-3),
        (
            [0.0, -1.0],
            Applied {
                clamped: true,
                slewed: false
            }
        )
    );
    // A non-finite request is a request for 0 V, not a clamp.
    let (_, a) = l.apply_reporting([0.0, f32::NAN], 1e-3);
    assert!(!a.clamped && a.slewed);
    // apply is the same step without the report.
    let mut m = l.clone();
    assert_eq!(
        l.apply([0.3, 0.3], 1e-3),
        m.apply_reporting([0.3, 0.3], 1e-3).0
    );
}
