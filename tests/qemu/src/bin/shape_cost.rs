//! The board's shaper for N = 3, kept out of line so that its machine code
//! can be counted (`scripts/count-step-cycles`): checking a SetModel (the
//! model's strip built in `f32`, and its answer to a 1 Hz sine), then the
//! program of a SetMotion, each run ten times in QEMU.
#![no_std]
#![no_main]
#![deny(missing_docs)]

use cortex_m_rt::entry;
use finrs_controller::shaper::{CheckedModel, ShapeRefused, Shaper, ELEMENTS};
use finrs_drive::Program;
use finrs_frames::{ModelRecord, Motion, StripModel};
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
) -> Result<Program, ShapeRefused> {
    shaper.program(motion, 4.0)
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
            Ok(Program::Harmonic { amplitudes_v, .. }) if amplitudes_v[0] > 1.0 && amplitudes_v[0] < 4.0
        );
    }
    exit(ok)
}
