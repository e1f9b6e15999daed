//! The seed's three-segment simulation (section 4.2): steps of 2, 1 and
//! −2 V on segments 1, 2 and 3, printed every 0.5 s.
#![deny(missing_docs, unsafe_code)]

use model_core::{Fixture, Params, Strip};

fn main() {
    let strip = Strip::<f64, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3)
        .expect("the seed's parameters are valid");
    let v = [2.0, 1.0, -2.0];
    let mut x = strip.rest();
    println!("t_s,node1_mm,node2_mm,tip_mm,u1_uNm,u2_uNm,u3_uNm,i2_mA");
    for k in 0..=10_000 {
        if k % 500 == 0 {
            let u = strip.moments_nm(&x);
            let i = strip.currents_a(&x, &v);
            let w = |n| strip.node_deflection_m(&x, n).unwrap_or_default() * 1e3;
            println!(
                "{:.1},{:.4},{:.4},{:.4},{:.2},{:.2},{:.2},{:.4}",
                k as f64 * 1e-3,
                w(1),
                w(2),
                w(3),
                u[0] * 1e6,
                u[1] * 1e6,
                u[2] * 1e6,
                i[1] * 1e3
            );
        }
        strip.step(&mut x, &v);
    }
}
