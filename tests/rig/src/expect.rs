//! What a right diagnosis says for a rig session, written from the
//! contract (docs/FORMAT.md: the baseline, the catalogue and its notes)
//! before any tuning of the diagnosis, and how a verdict is scored
//! against it.
//!
//! | in the session | a right diagnosis |
//! |---|---|
//! | the baseline's own strip, a perfect bench | `none` |
//! | `z > p` (creep) | nothing for it: the baseline has it |
//! | any damping (every off-class strip) | names `damping` |
//! | `EI` off the laminate's by more than 20 % | names `beam-stiffness` where free runs show it; within 20 %, may |
//! | a catalogue effect hidden | names it, where the protocol can show it |
//! | `hydrodynamic-loading` | only in water: never named in air |
//! | `dehydration` | where the session's start times are known |
//! | `large-deflection` | where free runs track the tip along the strip |
//! | `segment-variation` | names it when a segment's `R1`, `C` or `K` is off segment 1's by more than 4 %; within that, may |
//! | hum, 1/f noise, mains pickup | no catalogue name; reported as the bench (`bench:mains-hum`, `bench:coloured-noise`): the opening rests show them; `unexplained` allowed |
//! | a compliant load cell, exposure | no catalogue name for them; `unexplained` allowed |
//! | crosstalk through a lag, quadratic drag, a `sinh` leak | the name, `unexplained` beside it allowed (forms the fit only approximates) |
//!
//! An effect the protocol cannot show may be named (it is there) but need
//! not be; a name for something the session does not have is wrong.
//!
//! On the lab-like bench ([`expected_lab`], [`crate::lab`]), written from
//! the contract's note on bench imperfections before any diagnosis ran:
//!
//! | on the lab bench | a right diagnosis |
//! |---|---|
//! | drift: the strip's curl, the sensors' wandering zeros | no catalogue name (not `beam-stiffness`, `dehydration`, `back-relaxation` or any other); a session whose only departure is drift is `none`; it may report the bench (`bench:drift`, or `bench:coloured-noise`: over a one-second rest a wander of minutes is the low end of 1/f noise) |
//! | dropouts and out-of-range stretches | nothing: empty fields are "not sampled" |
//! | quantised currents and load cell | nothing: the step is part of the channel's noise |
//! | the voltage read back (offset, noise, ADC step) | nothing: the drive as the DAQ measured it, millivolts off |
//! | a contact open after a step | no catalogue name; `unexplained` allowed (no candidate has a voltage without a current) |
//! | carry-over between recordings | no catalogue name (the relaxation carried is the baseline's own); it may report the bench (`bench:carry-over`); `unexplained` allowed (the opening second cannot show a 7–14 s relaxation's state) |
//! | the moment's ± asymmetry | no catalogue name; `unexplained` allowed. Not `electrochemical-nonlinearity`: current and charge stay linear in voltage (the catalogue's definition), only the moment per charge differs by sign; not `segment-variation`: every segment has the same asymmetry |
//! | a laser across at one point, 100 rows/s | `large-deflection` cannot be seen (nothing tracks along the strip); `damping` and `beam-stiffness` only where the free strip's first mode rings below a quarter of the row rate (free runs alone give `K/EI`; the ringing gives `EI`) |

use crate::bench::Bench;
use crate::lab::LabBench;
use crate::sample::{Hidden, Sample, SEGMENT_VARIATION};

/// What the protocol of a session lets a diagnosis see.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    /// Free runs with the camera.
    pub free: bool,
    /// Blocked runs with the load cell.
    pub blocked: bool,
    /// Each recording's start in the session is known.
    pub session_start: bool,
    /// Free runs track positions along the strip (the camera; a laser
    /// reads across only).
    pub along: bool,
    /// The strip's first mode rings where the sensors sample it (below a
    /// quarter of their rate): what shows its damping, and its stiffness
    /// without blocked runs.
    pub ringing: bool,
}

/// Bench findings (`finrs diagnose`'s `rest.bench`) count as names with
/// this prefix, so that a bench imperfection reported where none is, or
/// not reported where the rests show it, scores like a catalogue name.
pub const BENCH: &str = "bench:";
/// Mains hum or pickup, as the diagnosis reports it.
pub const BENCH_HUM: &str = "bench:mains-hum";
/// 1/f sensor noise, as the diagnosis reports it.
pub const BENCH_COLOURED: &str = "bench:coloured-noise";
/// Drift, as a diagnosis may report it.
pub const BENCH_DRIFT: &str = "bench:drift";
/// The bench finding of recordings that open while the strip still moves
/// (`finrs diagnose`'s `carry-over`).
pub const BENCH_CARRY: &str = "bench:carry-over";

/// `EI` within this factor of the laminate's need not be named.
pub const STIFFNESS_TOLERANCE: f64 = 1.2;

/// Segment factors within this of one need not be named.
pub const VARIATION_TOLERANCE: f64 = 0.04;

/// What a right diagnosis of one session says.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Expected {
    /// Names it must give.
    pub required: Vec<&'static str>,
    /// Names it may give besides (present but not visible, or too weak).
    pub allowed: Vec<&'static str>,
    /// `unexplained` is a right verdict (beside the required names).
    pub unexplained_ok: bool,
}

/// How a verdict compares with what was expected.
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    /// Required names the verdict lacks.
    pub missed: Vec<String>,
    /// Names the verdict gives for something the session does not have.
    pub wrong: Vec<String>,
    /// The verdict word itself fits (`none` with nothing required and a
    /// perfect bench, `explained`, or an allowed `unexplained`).
    pub verdict_ok: bool,
}

impl Score {
    /// Every required name, no wrong one, a fitting verdict word.
    pub fn is_right(&self) -> bool {
        self.missed.is_empty() && self.wrong.is_empty() && self.verdict_ok
    }
}

/// What a right diagnosis says of a session of `hidden` on `bench`,
/// recorded with `protocol`.
pub fn expected(hidden: &Hidden, bench: &Bench, protocol: Protocol) -> Expected {
    let mut e = Expected::default();
    let mut name = |present: bool, visible: bool, name: &'static str| {
        if present && visible {
            e.required.push(name);
        } else if present {
            e.allowed.push(name);
        }
    };
    let moves = protocol.free || protocol.blocked;
    name(
        hidden.arcs,
        protocol.free && protocol.along,
        "large-deflection",
    );
    // Free and blocked runs both pin down EI; blocked runs alone show it
    // only through the held mode's ringing, free runs alone only through
    // the free mode's (else they give K/EI).
    if let Some(f) = hidden.ei_factor {
        let far = !(1.0 / STIFFNESS_TOLERANCE..=STIFFNESS_TOLERANCE).contains(&f);
        let pinned = protocol.free && (protocol.blocked || protocol.ringing);
        name(true, far && pinned, "beam-stiffness");
    }
    let damped = hidden.damping_ratio.is_some()
        || hidden
            .modal_damping
            .as_ref()
            .is_some_and(|z| z.iter().any(|&z| z > 0.0));
    name(damped, moves && protocol.ringing, "damping");
    name(hidden.water.is_some(), moves, "hydrodynamic-loading");
    name(
        hidden.electrochemistry.is_some(),
        true,
        "electrochemical-nonlinearity",
    );
    name(hidden.back_branch.is_some(), moves, "back-relaxation");
    name(
        hidden.drying_s.is_some(),
        protocol.session_start,
        "dehydration",
    );
    name(hidden.crosstalk.is_some(), moves, "segment-crosstalk");
    let varies = hidden.segment_factors.as_ref().is_some_and(|f| {
        f.iter().any(|s| {
            [s.r1, s.c, s.k]
                .iter()
                .any(|x| (x - 1.0).abs() > VARIATION_TOLERANCE)
        })
    });
    name(hidden.segment_factors.is_some(), varies, SEGMENT_VARIATION);
    // Hum and 1/f noise show in the opening rests (docs/FORMAT.md): a
    // diagnosis reports them as the bench.
    name(
        bench.hum.is_some() || hidden.mains_pickup.is_some(),
        true,
        BENCH_HUM,
    );
    name(bench.pink_fraction.is_some(), true, BENCH_COLOURED);
    e.unexplained_ok = !bench.is_perfect()
        || hidden.mains_pickup.is_some()
        || hidden.crosstalk_lag_s.is_some()
        || hidden.water.is_some()
        || hidden.electrochemistry.is_some();
    e
}

/// What a right diagnosis says of a literature strip's session
/// ([`crate::literature`]): as [`expected`], with the spectrum's damping,
/// the reaction and the drying in place of the rig's own forms; each
/// departure required only at or above the diagnosis's plausible strength
/// ([`crate::literature::plausible`]) and allowed below it; `damping`
/// wherever a run rings, whatever its strength (the spectrum's first-mode
/// ratio is reported beside the others for the power curves, and never
/// excuses a miss);
/// `beam-stiffness` judged on the stiffness the metadata's geometry
/// predicts against the relaxed and the instantaneous true ones (both
/// beyond the tolerance: required). `unexplained` is right beside the
/// required names: the electrode line and the spectrum are in no
/// catalogue form.
pub fn expected_literature(
    sample: &Sample,
    hidden: &Hidden,
    bench: &Bench,
    protocol: Protocol,
) -> Expected {
    use crate::literature::{plausible, strengths};
    let Some(lit) = &hidden.literature else {
        return expected(hidden, bench, protocol);
    };
    let mut e = expected(hidden, bench, protocol);
    let moves = protocol.free || protocol.blocked;
    let mut name = |present: bool, visible: bool, name: &'static str| {
        e.required.retain(|n| *n != name);
        e.allowed.retain(|n| *n != name);
        if present && visible {
            e.required.push(name);
        } else if present {
            e.allowed.push(name);
        }
    };
    name(lit.relaxing() > 0.0, moves && protocol.ringing, "damping");
    // Their strengths are weighed with the others' below.
    name(lit.reaction.is_some(), true, "electrochemical-nonlinearity");
    name(lit.drying.is_some(), protocol.session_start, "dehydration");
    // The fit's laminate stiffness from the metadata over the true
    // laminate's: EI goes as the width and the cube of the thickness.
    let [_, width, thickness] = lit.measured;
    let f = hidden.ei_factor.unwrap_or(1.0) / (width * thickness.powi(3));
    let far = |x: f64| !(1.0 / STIFFNESS_TOLERANCE..=STIFFNESS_TOLERANCE).contains(&x);
    let pinned = protocol.free && (protocol.blocked || protocol.ringing);
    name(
        true,
        pinned && far(f) && far(f * (1.0 - lit.relaxing())),
        "beam-stiffness",
    );
    // Below its plausible strength a departure may be named, need not be;
    // the damping is every literature strip's, and stays required.
    for (n, x) in strengths(sample, hidden) {
        if n != "damping" && x < plausible(n) && e.required.contains(&n) {
            e.required.retain(|r| *r != n);
            e.allowed.push(n);
        }
    }
    e.unexplained_ok = true;
    e
}

/// What a right diagnosis says of a session of `hidden` on `bench` and the
/// lab bench `lab`, recorded with `protocol` (the table at the top): as
/// [`expected`], with drift reported as the bench if at all, and
/// `unexplained` allowed beside an open contact, a carried-over state or
/// an asymmetric moment; never for drift, dropouts, steps or the voltage
/// as read back.
pub fn expected_lab(
    hidden: &Hidden,
    bench: &Bench,
    lab: &LabBench,
    protocol: Protocol,
) -> Expected {
    let mut e = expected(hidden, bench, protocol);
    if lab.drifts() {
        for n in [BENCH_DRIFT, BENCH_COLOURED] {
            if !e.required.contains(&n) && !e.allowed.contains(&n) {
                e.allowed.push(n);
            }
        }
    }
    if lab.carry_over && !e.allowed.contains(&BENCH_CARRY) {
        e.allowed.push(BENCH_CARRY);
    }
    e.unexplained_ok |=
        lab.contact.is_some() || lab.carry_over || lab.asymmetry.is_some_and(|a| a != 0.0);
    e
}

/// The names a verdict gives, as scored: its catalogue `causes`, then its
/// bench findings (`bench` holds what each found, one per channel) as
/// `bench:` names, each once.
pub fn names_given<S: AsRef<str>>(
    causes: &[String],
    bench: impl IntoIterator<Item = S>,
) -> Vec<String> {
    let mut names = causes.to_vec();
    for what in bench {
        let name = format!("{BENCH}{}", what.as_ref());
        if !names.contains(&name) {
            names.push(name);
        }
    }
    names
}

/// Scores a verdict (`none`, `explained` or `unexplained`) naming `causes`
/// against what was expected.
pub fn score(expected: &Expected, verdict: &str, causes: &[String]) -> Score {
    let missed = expected
        .required
        .iter()
        .filter(|r| !causes.iter().any(|c| c == *r))
        .map(|r| r.to_string())
        .collect();
    let wrong = causes
        .iter()
        .filter(|c| {
            !expected.required.contains(&c.as_str()) && !expected.allowed.contains(&c.as_str())
        })
        .cloned()
        .collect();
    let verdict_ok = match verdict {
        // Bench findings come beside any verdict word.
        "none" => expected.required.iter().all(|r| r.starts_with(BENCH)),
        "explained" => {
            expected.required.iter().any(|r| !r.starts_with(BENCH))
                || causes.iter().any(|c| !c.starts_with(BENCH))
        }
        "unexplained" => expected.unexplained_ok,
        _ => false,
    };
    Score {
        missed,
        wrong,
        verdict_ok,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::SegmentFactors;
    use rand::SeedableRng;

    const FULL: Protocol = Protocol {
        free: true,
        blocked: true,
        session_start: true,
        along: true,
        ringing: true,
    };
    const BOARD: Protocol = Protocol {
        free: false,
        blocked: true,
        session_start: true,
        along: false,
        ringing: true,
    };
    /// The lab protocol's: free runs, a laser across, the first mode
    /// above a quarter of 100 rows/s.
    const LASER: Protocol = Protocol {
        free: true,
        blocked: false,
        session_start: true,
        along: false,
        ringing: false,
    };

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn the_baselines_own_strip_on_a_perfect_bench_is_none() {
        let e = expected(&Hidden::default(), &Bench::default(), FULL);
        assert_eq!(e, Expected::default());
        assert!(score(&e, "none", &[]).is_right());
        assert!(!score(&e, "unexplained", &[]).is_right());
        let s = score(&e, "explained", &names(&["damping"]));
        assert_eq!(s.wrong, ["damping"]);
    }

    #[test]
    fn a_literature_strips_departures_are_required_from_their_plausible_strength() {
        use crate::literature::Literature;
        let mut rng = rand::rngs::StdRng::seed_from_u64(4);
        let sample = crate::sample::Sample::draw_off_class(&mut rng);
        let mut h = Literature::draw(
            &["electrochemical-nonlinearity", "segment-crosstalk"],
            &sample,
            150.0,
            &mut rng,
        )
        .unwrap();
        h.crosstalk = Some(0.2);
        // A spectrum that damps the free first mode by about 12 %: one
        // term of 0.4 whose time is the mode's.
        let omega = crate::literature::first_modes_rad_s(&sample, &h)[0];
        let lit = h.literature.as_mut().unwrap();
        lit.spectrum = vec![(0.4, 1.0 / omega)];
        lit.reaction = Some(Literature::reaction_for(&sample, 0.5, 1.23, 0.06));
        let lit = h.literature.as_ref().unwrap();
        let zeta = lit.first_mode_damping(&sample, &h);
        assert!(zeta > 0.1, "{zeta}");
        let e = expected_literature(&sample, &h, &Bench::default(), FULL);
        for n in [
            "damping",
            "electrochemical-nonlinearity",
            "segment-crosstalk",
        ] {
            assert!(e.required.contains(&n), "{n} in {e:?}");
        }
        // The electrode line and the spectrum are in no catalogue form.
        assert!(e.unexplained_ok);
        // Below the plausible strengths: allowed, not required.
        h.crosstalk = Some(0.02);
        let lit = h.literature.as_mut().unwrap();
        lit.spectrum = vec![(0.02, 1.0 / omega)];
        lit.reaction = Some(Literature::reaction_for(&sample, 0.05, 1.23, 0.06));
        let e = expected_literature(&sample, &h, &Bench::default(), FULL);
        // A spectrum that barely damps still has to be found.
        let lit = h.literature.as_ref().unwrap();
        assert!(lit.first_mode_damping(&sample, &h) < 0.05);
        assert!(e.required.contains(&"damping"), "{e:?}");
        for n in ["electrochemical-nonlinearity", "segment-crosstalk"] {
            assert!(
                !e.required.contains(&n) && e.allowed.contains(&n),
                "{n} in {e:?}"
            );
        }
        // Nothing but the base: dehydration is a false name.
        let s = score(&e, "unexplained", &names(&["damping", "dehydration"]));
        assert_eq!(s.wrong, ["dehydration"]);
    }

    #[test]
    fn an_off_class_strip_must_be_called_damped_and_soft_where_free_runs_show_it() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let mut h = Hidden::draw_off_class(&[], &mut rng).unwrap();
        h.ei_factor = Some(0.3);
        let e = expected(&h, &Bench::default(), FULL);
        assert_eq!(e.required, ["beam-stiffness", "damping"]);
        assert!(!e.unexplained_ok);
        let s = score(&e, "explained", &names(&["damping"]));
        assert_eq!(s.missed, ["beam-stiffness"]);
        // The board alone cannot pin EI down: naming it is allowed.
        let e = expected(&h, &Bench::default(), BOARD);
        assert_eq!(e.required, ["damping"]);
        assert_eq!(e.allowed, ["beam-stiffness"]);
        // A strip within 20 % of the laminate need not be called soft.
        h.ei_factor = Some(0.9);
        let e = expected(&h, &Bench::default(), FULL);
        assert_eq!(e.allowed, ["beam-stiffness"]);
    }

    #[test]
    fn bench_imperfections_allow_unexplained_but_no_name() {
        let bench = Bench {
            hum: Some(2.0),
            ..Bench::default()
        };
        let e = expected(&Hidden::default(), &bench, FULL);
        assert!(e.required == [BENCH_HUM] && e.allowed.is_empty() && e.unexplained_ok);
        assert!(score(&e, "unexplained", &names(&[BENCH_HUM])).is_right());
        assert!(score(&e, "none", &names(&[BENCH_HUM])).is_right());
        // The rests show hum: not reporting it misses it.
        assert_eq!(score(&e, "none", &[]).missed, [BENCH_HUM]);
        let s = score(&e, "explained", &names(&[BENCH_HUM, "segment-crosstalk"]));
        assert!(!s.is_right() && s.wrong == ["segment-crosstalk"]);
        // A load cell that gives shows in no rest: nothing to report.
        let bench = Bench {
            load_cell_mode_ratio: Some(0.6),
            ..Bench::default()
        };
        let e = expected(&Hidden::default(), &bench, FULL);
        assert!(e.required.is_empty() && e.unexplained_ok);
        let s = score(&e, "none", &names(&[BENCH_COLOURED]));
        assert_eq!(s.wrong, [BENCH_COLOURED]);
    }

    #[test]
    fn what_the_protocol_cannot_show_need_not_be_named() {
        let h = Hidden {
            arcs: true,
            drying_s: Some(200.0),
            ..Hidden::default()
        };
        let e = expected(
            &h,
            &Bench::default(),
            Protocol {
                session_start: false,
                ..BOARD
            },
        );
        assert!(e.required.is_empty());
        assert_eq!(e.allowed, ["large-deflection", "dehydration"]);
        assert!(score(&e, "none", &[]).is_right());
        assert!(score(&e, "explained", &names(&["dehydration"])).is_right());
    }

    #[test]
    fn segment_variation_is_required_when_a_factor_is_off_by_more_than_the_tolerance() {
        let mut h = Hidden {
            segment_factors: Some(vec![
                SegmentFactors::ONE,
                SegmentFactors {
                    r1: 1.1,
                    ..SegmentFactors::ONE
                },
            ]),
            ..Hidden::default()
        };
        let e = expected(&h, &Bench::default(), FULL);
        assert_eq!(e.required, [SEGMENT_VARIATION]);
        h.segment_factors = Some(vec![SegmentFactors::ONE; 3]);
        let e = expected(&h, &Bench::default(), FULL);
        assert_eq!(e.allowed, [SEGMENT_VARIATION]);
    }

    #[test]
    fn drift_alone_is_none_and_never_a_catalogue_name() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(2);
        let lab = LabBench::draw(&crate::lab::DRIFT, &mut rng).unwrap();
        let e = expected_lab(&Hidden::default(), &Bench::default(), &lab, FULL);
        assert!(e.required.is_empty() && !e.unexplained_ok, "{e:?}");
        assert!(score(&e, "none", &[]).is_right());
        assert!(score(&e, "none", &names(&[BENCH_DRIFT])).is_right());
        assert!(!score(&e, "unexplained", &[]).is_right());
        for wrong in [
            "beam-stiffness",
            "dehydration",
            "back-relaxation",
            "damping",
        ] {
            let s = score(&e, "explained", &names(&[wrong]));
            assert_eq!(s.wrong, [wrong]);
        }
    }

    #[test]
    fn the_lab_benchs_faults_allow_unexplained_but_no_name() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let lab = LabBench::draw(&crate::lab::LAB_ARTEFACTS, &mut rng).unwrap();
        let e = expected_lab(&Hidden::default(), &Bench::default(), &lab, FULL);
        assert!(e.required.is_empty() && e.unexplained_ok);
        assert!(score(&e, "unexplained", &[]).is_right());
        let s = score(&e, "explained", &names(&["electrochemical-nonlinearity"]));
        assert_eq!(s.wrong, ["electrochemical-nonlinearity"]);
        // Dropouts, steps and the voltage as read back alone: nothing to
        // leave unexplained.
        let lab = LabBench::draw(&["dropouts", "quantisation", "readback"], &mut rng).unwrap();
        let e = expected_lab(&Hidden::default(), &Bench::default(), &lab, FULL);
        assert_eq!(e, Expected::default());
    }

    #[test]
    fn a_laser_across_shows_neither_the_arc_nor_a_fast_modes_damping() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(4);
        let mut h = Hidden::draw_off_class(&["large-deflection"], &mut rng).unwrap();
        h.ei_factor = Some(0.3);
        let e = expected(&h, &Bench::default(), LASER);
        assert!(e.required.is_empty(), "{e:?}");
        assert_eq!(e.allowed, ["large-deflection", "beam-stiffness", "damping"]);
        let e = expected(
            &h,
            &Bench::default(),
            Protocol {
                ringing: true,
                ..LASER
            },
        );
        assert_eq!(e.required, ["beam-stiffness", "damping"]);
    }
}
