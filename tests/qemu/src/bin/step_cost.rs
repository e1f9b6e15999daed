//! One `f32` step of the N = 3 model, kept out of line so that its machine
//! code can be counted (`scripts/count-step-cycles`), then run a thousand
//! times in QEMU so that the count can be checked against execution.
#![no_std]
#![no_main]
#![deny(missing_docs)]

use cortex_m_rt::entry;
use finrs_qemu_tests::exit;
use model_core::{Fixture, Params, Strip};

/// The function whose instructions are counted.
#[no_mangle]
#[inline(never)]
pub fn finrs_step_n3(strip: &Strip<f32, 3, 1, 18>, x: &mut [f32; 18], v: &[f32; 3]) {
    strip.step(x, v);
}

#[entry]
fn main() -> ! {
    let ok = match Strip::<f32, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3) {
        Ok(strip) => {
            let mut x = strip.rest();
            for _ in 0..1000 {
                finrs_step_n3(&strip, &mut x, &[2.5; 3]);
            }
            // Defeats dead-code elimination and checks the run is sane.
            let tip = strip.tip_deflection_m(&x);
            tip > 0.0 && tip < 0.05
        }
        Err(_) => false,
    };
    exit(ok)
}
