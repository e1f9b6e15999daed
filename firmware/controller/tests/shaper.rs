//! The shaper: a SetModel checked and held (and named in Info), a
//! SetMotion turned into voltages that move the model's own tip as asked,
//! refusals with their reasons, and nothing changed by a refused command.

mod common;

use common::{input, tared, Channel};
use finrs_controller::shaper::{command, ShapeRefused, Shaped, Shaper, ELEMENTS};
use finrs_controller::CommandRefused;
use finrs_drive::{Envelope, Generator, Program};
use finrs_frames::{Command, Decoder, Event, ModelFormatError, ModelRecord, Motion, StripModel};
use model_core::{state_len, Extensions, Fixture, HarmonicError, Params, Phasor, Strip};
use rtic_core::Exclusive;

const N: usize = 3;
const S: usize = state_len(N, ELEMENTS);
const DT_S: f64 = 1e-3;

/// The seed's `main.m` strip, damped (an undamped mode rings for ever).
fn model() -> StripModel {
    StripModel {
        params: Params::main_m_2006(),
        extensions: Extensions {
            damping_ratio: 0.05,
            crosstalk: 0.1,
            ..Extensions::NONE
        },
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    }
}

fn motion(tip_amp_m: f32, frequency_hz: f32, lag_deg_per_segment: f32) -> Command {
    Command::SetMotion {
        motion: Motion::Travelling {
            tip_amp_m,
            frequency_hz,
            lag_deg_per_segment,
        },
        envelope: Envelope {
            ramp_in_s: 0.0,
            hold_s: f32::INFINITY,
            ramp_out_s: 0.0,
        },
        t_session_s: f32::NAN,
        tracked: false,
    }
}

fn infos(ch: &Channel) -> Vec<finrs_frames::Info> {
    let mut d = Decoder::new();
    let mut out = Vec::new();
    d.push(&ch.bytes, &mut |e| {
        if let Event::Info(i) = e {
            out.push(i)
        }
    });
    out
}

/// The shaped program's voltages, as the generator writes them, drive the
/// same model's free strip; read by lock-in over the last ten periods, the
/// tip moves as asked within 0.5 % and 0.5°.
#[test]
fn the_shaped_voltages_move_the_models_tip_as_asked() {
    let record = ModelRecord::encode(&model());
    let mut shaper = Shaper::<N, ELEMENTS, S>::new();
    shaper.install(Shaper::check(&record, DT_S).unwrap());
    let asked = Motion::Travelling {
        tip_amp_m: 2e-4,
        frequency_hz: 1.0,
        lag_deg_per_segment: 60.0,
    };
    let steady = Envelope::STEADY;
    let program = shaper
        .program(&asked, steady, 4.0, f32::NAN)
        .unwrap()
        .program;
    assert!(matches!(program, Program::Harmonic { .. }));
    let generator = Generator::<N>::new(program, steady).unwrap();
    // The plant: the model decoded from the record, in f64.
    let m = record.decode().unwrap();
    let plant = Strip::<f64, N, 4, { state_len(N, 4) }>::with_extensions(
        &m.params,
        &m.extensions,
        Fixture::Free,
        DT_S,
    )
    .unwrap();
    let mut x = plant.rest();
    // 60 s: the relaxation (τ = 10 s) settles; the last 10 s are read.
    let steps = 60_000u64;
    let theta = 2.0 * core::f64::consts::PI * DT_S;
    let mut y = Phasor::ZERO;
    for k in 0..steps {
        let v = generator.voltages_at_tick_v(k, 1000).map(f64::from);
        plant.step(&mut x, &v);
        // The tip after step k holds the sample at k + 1.
        if k + 1 >= steps - 10_000 {
            let tip = plant.tip_deflection_m(&x);
            y += Phasor::unit(-theta * (k + 1) as f64).scale(2.0 * tip / 10_000.0);
        }
    }
    // `y` is the tip's phasor, Re(y e^{jθk}): the asked sine has phase 0.
    assert!(
        (y.amplitude() / 2e-4 - 1.0).abs() < 5e-3,
        "tip amplitude {} m",
        y.amplitude()
    );
    assert!(
        y.sine_phase_rad().to_degrees().abs() < 0.5,
        "tip phase {}°",
        y.sine_phase_rad().to_degrees()
    );
}

#[test]
fn a_motion_beyond_the_limit_is_refused_with_what_is_reachable() {
    let (mut c, _, _) = tared();
    let limit = c.limits().max_abs_v();
    let mut shaper = Shaper::<N, ELEMENTS, S>::new();
    let mut lock = Exclusive(&mut c);
    let set = Command::SetModel(ModelRecord::encode(&model()));
    assert_eq!(
        command(set, &mut shaper, DT_S, &mut lock),
        Ok(Shaped::ModelSet)
    );
    let e = command(motion(5e-3, 1.0, 60.0), &mut shaper, DT_S, &mut lock).unwrap_err();
    let ShapeRefused::Unreachable {
        needs_v,
        segment,
        limit_v,
        reachable_m,
    } = e
    else {
        panic!("{e}")
    };
    assert_eq!(limit_v, limit);
    assert!(needs_v > limit && (1..=3).contains(&segment), "{e}");
    assert!(e.to_string().contains("within it the model reaches"), "{e}");
    // Nothing runs; what is reachable is accepted, and drives up to the
    // limit.
    assert!(!c.running());
    let mut lock = Exclusive(&mut c);
    let reachable = motion(0.999 * reachable_m, 1.0, 60.0);
    assert_eq!(
        command(reachable, &mut shaper, DT_S, &mut lock),
        Ok(Shaped::WaveSet)
    );
    assert!(c.running());
    let Program::Harmonic { amplitudes_v, .. } = c.generator().program() else {
        panic!("a harmonic program")
    };
    let peak = amplitudes_v.iter().fold(0.0f32, |m, &a| m.max(a));
    assert!(peak <= limit && peak > 0.998 * limit, "peak {peak} V");
}

#[test]
fn a_model_is_named_in_info_and_refused_while_driving() {
    let (mut c, mut ch, _) = tared();
    let mut shaper = Shaper::<N, ELEMENTS, S>::new();
    let record = ModelRecord::encode(&model());
    {
        let mut lock = Exclusive(&mut c);
        command(Command::SetModel(record), &mut shaper, DT_S, &mut lock).unwrap();
    }
    assert_eq!(c.take_model_to_store(), Some(record));
    assert_eq!(c.take_model_to_store(), None, "handed over once");
    c.tick(&input(10, 1000, [2048; N]), &mut ch);
    assert_eq!(
        infos(&ch).last().map(|i| i.model_crc),
        Some(Some(record.crc()))
    );
    // Driving: another model is refused, the one held stays.
    let mut lock = Exclusive(&mut c);
    command(motion(1e-4, 1.0, 60.0), &mut shaper, DT_S, &mut lock).unwrap();
    let mut other = model();
    other.params.r1_ohm = 200.0;
    let other = ModelRecord::encode(&other);
    assert_eq!(
        command(Command::SetModel(other), &mut shaper, DT_S, &mut lock),
        Err(ShapeRefused::Controller(CommandRefused::ModelWhileDriving))
    );
    assert_eq!(shaper.record(), Some(&record));
    // Handed to the controller itself, neither command is taken.
    assert_eq!(
        c.command(Command::SetModel(other)),
        Err(CommandRefused::NotShaped)
    );
    assert_eq!(
        c.command(motion(1e-4, 1.0, 60.0)),
        Err(CommandRefused::NotShaped)
    );
}

#[test]
fn bad_models_and_motions_are_refused_with_their_reason() {
    let (mut c, _, _) = tared();
    let mut shaper = Shaper::<N, ELEMENTS, S>::new();
    let mut lock = Exclusive(&mut c);
    assert_eq!(
        command(motion(1e-4, 1.0, 60.0), &mut shaper, DT_S, &mut lock),
        Err(ShapeRefused::NoModel)
    );
    let mut record = ModelRecord::encode(&model());
    record.0[0] = 7;
    assert_eq!(
        command(Command::SetModel(record), &mut shaper, DT_S, &mut lock),
        Err(ShapeRefused::Format(ModelFormatError::Version(7)))
    );
    let mut bad = model();
    bad.params.r1_ohm = -1.0;
    let e = command(
        Command::SetModel(ModelRecord::encode(&bad)),
        &mut shaper,
        DT_S,
        &mut lock,
    )
    .unwrap_err();
    assert!(
        matches!(e, ShapeRefused::Model(_)) && e.to_string().contains("r1_ohm"),
        "{e}"
    );
    // A nonlinear model has no single-sine inverse: refused when sent.
    let mut cubic = model();
    cubic.extensions.charge_cubic_per_v2 = 0.01;
    assert!(matches!(
        command(
            Command::SetModel(ModelRecord::encode(&cubic)),
            &mut shaper,
            DT_S,
            &mut lock
        ),
        Err(ShapeRefused::NotInvertible(HarmonicError::Nonlinear { .. }))
    ));
    assert_eq!(shaper.record(), None, "nothing refused is held");
    // So has one whose water drags as the speed squared, by its field.
    let mut dragged = model();
    dragged.extensions.drag_quadratic_n_s2_per_m3 = 10.0;
    assert_eq!(
        command(
            Command::SetModel(ModelRecord::encode(&dragged)),
            &mut shaper,
            DT_S,
            &mut lock
        )
        .map(|_| ()),
        Err(ShapeRefused::NotInvertible(HarmonicError::Nonlinear {
            field: "drag_quadratic_n_s2_per_m3"
        }))
    );
    assert_eq!(shaper.record(), None, "nothing refused is held");
    command(
        Command::SetModel(ModelRecord::encode(&model())),
        &mut shaper,
        DT_S,
        &mut lock,
    )
    .unwrap();
    // At or past Nyquist's frequency, and beyond the generator's range.
    assert!(matches!(
        command(motion(1e-4, 600.0, 60.0), &mut shaper, DT_S, &mut lock),
        Err(ShapeRefused::Harmonic(HarmonicError::Frequency { .. }))
    ));
    assert!(matches!(
        command(motion(1e-4, 0.0, 60.0), &mut shaper, DT_S, &mut lock),
        Err(ShapeRefused::Harmonic(HarmonicError::Frequency { .. }))
    ));
    assert!(!c.running());
}

#[test]
fn above_the_bound_a_model_is_refused_for_its_size_and_a_motion_has_none() {
    // The build whose stack cannot hold a model's check (`MAX_SHAPED_SEGMENTS`):
    // the refusals come before any strip is built, so that the build leaves
    // those frames out (scripts/check-stack).
    const N8: usize = 8;
    const S8: usize = state_len(N8, ELEMENTS);
    const { assert!(N8 > finrs_controller::shaper::MAX_SHAPED_SEGMENTS) };
    let record = ModelRecord::encode(&model());
    assert!(matches!(
        Shaper::<N8, ELEMENTS, S8>::check(&record, DT_S),
        Err(ShapeRefused::TooManySegments(8))
    ));
    let shaper = Shaper::<N8, ELEMENTS, S8>::new();
    let Command::SetMotion { motion: m, .. } = motion(1e-4, 1.0, 60.0) else {
        unreachable!()
    };
    assert!(matches!(
        shaper.program(&m, Envelope::STEADY, 4.0, 0.0),
        Err(ShapeRefused::NoModel)
    ));
}
