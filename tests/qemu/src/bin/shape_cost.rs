//! The board's shaper and gain tracker for N = 3, kept out of line so that
//! their machine code can be counted (`scripts/count-step-cycles`):
//! checking a SetModel (the model's strip built in `f32`, and its answer to
//! a 1 Hz sine), then the program of a SetMotion, each run ten times in
//! QEMU; then the tracker's share of a sample tick, 2500 ordinary ticks of
//! a 1 Hz motion, and 100 ticks that each end a period of the wave (the
//! worst tick: the fit's update, the corrected program, its generator and
//! its Tracking frame); then a step's program (`motion-step:`, on a
//! creeping strip) ten times, a force wave's (the held strip built)
//! three times, and the generator's voltages of a held step
//! in its rise (its worst: a sine, a cosine and an exponential) for 1000
//! ticks.
#![no_std]
#![no_main]
#![deny(missing_docs)]

use cortex_m_rt::entry;
use finrs_controller::shaper::{CheckedModel, ShapeRefused, ShapedMotion, Shaper, ELEMENTS};
use finrs_controller::tracker::{self, Correction, Shape, Sine, Target, Tracker};
use finrs_drive::{Envelope, Generator, Program};
use finrs_frames::{encode_tracking, ModelRecord, Motion, StripModel, MAX_FRAME_LEN};
use finrs_qemu_tests::exit;
use model_core::{state_len, Extensions, Params};

const N: usize = 3;
const S: usize = state_len(N, ELEMENTS);

/// A SetModel's check, whose instructions are counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_shape_check_n3(
    record: &ModelRecord,
) -> Result<CheckedModel<N, ELEMENTS, S>, ShapeRefused> {
    Shaper::check(record, 1e-3)
}

/// A SetMotion's program, whose instructions are counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_shape_program_n3(
    shaper: &Shaper<N, ELEMENTS, S>,
    motion: &Motion,
) -> Result<ShapedMotion<N>, ShapeRefused> {
    shaper.program(motion, Envelope::STEADY, 4.0, f32::NAN)
}

/// A SetMotion's force wave (the model's held strip built for it),
/// whose instructions are counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_shape_force_n3(
    shaper: &Shaper<N, ELEMENTS, S>,
    motion: &Motion,
) -> Result<ShapedMotion<N>, ShapeRefused> {
    // A limit of its own: a body identical to `finrs_shape_program_n3`'s
    // would be folded into it by the linker, and not found in the trace.
    shaper.program(motion, Envelope::STEADY, 3.5, f32::NAN)
}

/// A SetMotion's held step (rising over 1 s), whose instructions are
/// counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_shape_step_n3(
    shaper: &Shaper<N, ELEMENTS, S>,
    motion: &Motion,
) -> Result<ShapedMotion<N>, ShapeRefused> {
    let rising = Envelope {
        ramp_in_s: 1.0,
        ..Envelope::STEADY
    };
    shaper.program(motion, rising, 4.0, f32::NAN)
}

/// The generator's voltages at a tick, counted (a held step's rise).
#[no_mangle]
#[inline(never)]
pub fn finrs_held_step_tick_n3(g: &Generator<N>, tick: u64) -> [f32; N] {
    g.voltages_at_tick_v(tick, 1000)
}

/// The tracker's share of an ordinary tick, counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_track_tick_n3(
    t: &mut Tracker<N>,
    v: &[f32; N],
    i: &[f32; N],
) -> Option<Correction<N>> {
    t.feed(v, i, 0.0)
}

/// The tracker's share of a tick that ends a period, counted: the
/// controller's work then (`Controller::track`).
#[no_mangle]
#[inline(never)]
pub fn finrs_track_period_end_n3(t: &mut Tracker<N>, v: &[f32; N], i: &[f32; N]) -> usize {
    let Some(c) = t.feed(v, i, 0.0) else { return 0 };
    let (program, flags) = t.program(&c, 4.0);
    let made = Generator::<N>::new(program, Envelope::STEADY).is_ok();
    let mut buf = [0u8; MAX_FRAME_LEN];
    let sent = encode_tracking(&tracker::frame(&c, flags, 0), &mut buf).unwrap_or(0);
    usize::from(made) + sent
}

#[entry]
fn main() -> ! {
    let record = ModelRecord::encode(&StripModel {
        params: Params::main_m_2006(),
        extensions: Extensions {
            damping_ratio: 0.05,
            ..Extensions::NONE
        },
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    });
    let mut shaper = Shaper::new();
    let mut ok = true;
    for _ in 0..10 {
        match finrs_shape_check_n3(&record) {
            Ok(m) => shaper.install(m),
            Err(_) => ok = false,
        }
    }
    let motion = Motion::Travelling {
        tip_amp_m: 2e-4,
        frequency_hz: 1.0,
        lag_deg_per_segment: 60.0,
    };
    for _ in 0..10 {
        // The seed's strip needs about 3.1 V on a segment for 0.2 mm at 1 Hz.
        ok &= matches!(
            finrs_shape_program_n3(&shaper, &motion),
            Ok(ShapedMotion { program: Program::Harmonic { amplitudes_v, .. }, .. })
                if amplitudes_v[0] > 1.0 && amplitudes_v[0] < 4.0
        );
    }
    let sine = Sine {
        frequency_hz: 1.0,
        amplitudes_v: [1.0, 0.8, 0.6],
        phases_deg: [0.0, -60.0, -120.0],
        admittance_a_per_v: [[2e-3, 1e-4]; N],
        force_n_per_v: None,
    };
    let target = Target {
        shape: Shape::Sine(sine),
        tracked: true,
        // The drying law's once a period too: the worst tick.
        drying: Some(tracker::Drying {
            rate_per_s: 1e-3,
            curvature: 0.5,
            t_start_s: 120.0,
        }),
    };
    let (v, i) = ([0.5, -0.3, 0.2], [1e-3, -6e-4, 4e-4]);
    let mut ordinary = Tracker::new(target, 1000);
    let mut ends = 0;
    for _ in 0..2500 {
        ends += usize::from(finrs_track_tick_n3(&mut ordinary, &v, &i).is_some());
    }
    // 2500 ticks hold two periods' ends: the drying law corrects at both
    // (the first is the currents' settling one).
    ok &= ends == 2;
    // A 1.37 kHz "wave" at 1 kHz: every tick ends a period, with the
    // reference's phase set afresh at an angle that is not 0 (libm's fast
    // path).
    let mut every = Tracker::new(
        Target {
            shape: Shape::Sine(Sine {
                frequency_hz: 1370.0,
                ..sine
            }),
            ..target
        },
        1000,
    );
    let mut done = 0;
    for _ in 0..100 {
        done += usize::from(finrs_track_period_end_n3(&mut every, &v, &i) > 0);
    }
    ok &= done == 100;
    // Table 4-2's creeping strip: 1 mm held, its start z/p = 2.4 times its
    // level.
    let record = ModelRecord::encode(&StripModel {
        params: Params::table_4_2_2006(),
        extensions: Extensions {
            damping_ratio: 0.05,
            ..Extensions::NONE
        },
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    });
    // Not through the counted check: its count spans its first call to
    // its last.
    match Shaper::check(&record, 1e-3) {
        Ok(m) => shaper.install(m),
        Err(_) => ok = false,
    }
    // 0.1 mN at 1 Hz on the held strip, 3 times.
    let force = Motion::Force {
        force_amp_n: 1e-4,
        frequency_hz: 1.0,
        lag_deg_per_segment: 60.0,
    };
    for _ in 0..3 {
        ok &= finrs_shape_force_n3(&shaper, &force).is_ok();
    }
    let step = Motion::Step { tip_m: 1e-3 };
    let mut held = None;
    for _ in 0..10 {
        held = finrs_shape_step_n3(&shaper, &step).ok();
    }
    match held.map(|h| Generator::<N>::new(h.program, h.envelope)) {
        Some(Ok(g)) => {
            let mut sum = 0.0;
            for tick in 0..1000 {
                sum += finrs_held_step_tick_n3(&g, tick)[0];
            }
            // The rise from 0 to above the level: a mean between.
            ok &= sum > 0.0 && sum.is_finite();
        }
        _ => ok = false,
    }
    exit(ok)
}
