//! The stack the board's shaper needs at N = 6, the most segments whose
//! model the board checks (`MAX_SHAPED_SEGMENTS`): the free stack is
//! painted below the caller's frame, each call made, and the lowest word
//! it touched found (`finrs_firmware_support::watermark`'s pattern and
//! scan). A SetModel's check, a travelling wave's program, a force wave's
//! (which builds the model's held strip inside the program) and a held
//! step's, each printed in bytes on the host's stdout. Exits with failure
//! if a call fails or a motion needs more than the check plus 16 KiB (the
//! held strip's build nests in the force wave's program).
//!
//! Run: `cargo build --release -p finrs-qemu-tests --target
//! thumbv7em-none-eabihf --bin shape_stack`, then `qemu-system-arm -cpu
//! cortex-m4 -machine netduinoplus2 -nographic -semihosting-config
//! enable=on,target=native -kernel
//! target/thumbv7em-none-eabihf/release/shape_stack`.
#![no_std]
#![no_main]
#![deny(missing_docs)]

use core::fmt::Write;

use cortex_m_rt::entry;
use cortex_m_semihosting::hio;
use finrs_controller::shaper::{Shaper, ELEMENTS};
use finrs_drive::Envelope;
use finrs_firmware_support::watermark::{used_bytes, PAINT};
use finrs_frames::{ModelRecord, Motion, StripModel};
use finrs_qemu_tests::exit;
use model_core::{state_len, Extensions, Params};

const N: usize = 6;
const S: usize = state_len(N, ELEMENTS);
type BoardShaper = Shaper<N, ELEMENTS, S>;

extern "C" {
    /// The end of the statics: the stack may grow down to it.
    static __sheap: u32;
}

/// Bytes of stack `f` uses below the caller's frame (less 256 bytes kept
/// for this function's own).
#[inline(never)]
#[allow(unsafe_code)] // painting and reading free stack by address
fn stack_of(f: impl FnOnce() -> bool) -> Option<usize> {
    let sp = cortex_m::register::msp::read() as usize - 256;
    // The words from the statics' end to below this frame are free stack
    // that nothing else uses (no interrupts run here).
    let bottom = core::ptr::addr_of!(__sheap) as usize;
    let len = (sp - bottom) / 4;
    let word = |i: usize| (bottom + 4 * i) as *mut u32;
    for i in 0..len {
        // SAFETY: within the free stack, aligned (both ends are).
        unsafe { word(i).write_volatile(PAINT) };
    }
    // SAFETY: as above, read back.
    f().then(|| used_bytes(len, |i| unsafe { word(i).read_volatile() }))
}

#[entry]
fn main() -> ! {
    let record = ModelRecord::encode(&StripModel {
        params: Params::baseline_air_example(),
        extensions: Extensions {
            damping_ratio: 0.05,
            crosstalk: 0.1,
            ..Extensions::NONE
        },
        dehydration_per_s: 0.0,
        dehydration_curvature: 0.0,
    });
    let mut shaper = BoardShaper::new();
    let check = stack_of(|| match BoardShaper::check(&record, 1e-3) {
        Ok(m) => {
            shaper.install(m);
            true
        }
        Err(_) => false,
    });
    let steady = Envelope::STEADY;
    let rising = Envelope {
        ramp_in_s: 1.0,
        ..steady
    };
    let motions = [
        (
            "travelling wave",
            Motion::Travelling {
                tip_amp_m: 1e-4,
                frequency_hz: 1.0,
                lag_deg_per_segment: 60.0,
            },
            steady,
        ),
        (
            "force wave",
            Motion::Force {
                force_amp_n: 1e-4,
                frequency_hz: 1.0,
                lag_deg_per_segment: 60.0,
            },
            steady,
        ),
        ("held step", Motion::Step { tip_m: 1e-4 }, rising),
    ];
    let mut out = hio::hstdout().ok();
    let mut say = |what: &str, bytes: Option<usize>| {
        if let Some(o) = out.as_mut() {
            let _ = writeln!(o, "N = {N}, {what}: {bytes:?} B of stack");
        }
    };
    say("a SetModel's check", check);
    let mut ok = check.is_some();
    for (what, motion, envelope) in motions {
        let used = stack_of(|| shaper.program(&motion, envelope, 4.0, f32::NAN).is_ok());
        say(what, used);
        ok &= matches!((used, check), (Some(u), Some(c)) if u <= c + 16 * 1024);
    }
    exit(ok)
}
