//! The 20 s, 1 kHz, N = 3 run of `scripts/bench-vs-scipy`: writes the
//! discrete system and the input for scipy, times our own run, and writes
//! its tip output so the two can be checked against each other.
//!
//! `cargo run --release -p model-core --example bench_run -- DIR`
#![deny(missing_docs, unsafe_code)]

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

use model_core::{Fixture, Params, Strip};

fn matrix<const R: usize, const C: usize>(m: &[[f64; C]; R]) -> String {
    let mut s = String::new();
    for row in m {
        let cells: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
        let _ = writeln!(s, "{}", cells.join(" "));
    }
    s
}

fn main() -> std::io::Result<()> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| ".".to_string());
    let dir = std::path::Path::new(&dir);
    let strip = Strip::<f64, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3)
        .expect("the seed's parameters are valid");
    let input: Vec<[f64; 3]> = (0..20_000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            core::array::from_fn(|i| 2.5 * (2.0 * PI * t - i as f64 * 2.0 * PI / 3.0).sin())
        })
        .collect();
    // The tip row, read off the model by unit states.
    let tip_row: [[f64; 18]; 1] = [core::array::from_fn(|j| {
        let mut e = [0.0; 18];
        e[j] = 1.0;
        strip.tip_deflection_m(&e)
    })];
    std::fs::write(dir.join("phi.txt"), matrix(&strip.phi()))?;
    std::fs::write(dir.join("gamma.txt"), matrix(&strip.gamma()))?;
    std::fs::write(dir.join("c.txt"), matrix(&tip_row))?;
    let mut u = String::new();
    for v in &input {
        let _ = writeln!(u, "{:e} {:e} {:e}", v[0], v[1], v[2]);
    }
    std::fs::write(dir.join("input.txt"), u)?;

    // As dlsim: y[k] = C x[k], then x[k+1] = Φ x[k] + Γ u[k].
    let mut tip = vec![0.0; input.len()];
    let mut best = f64::INFINITY;
    for _ in 0..50 {
        let start = Instant::now();
        let mut x = strip.rest();
        for (v, y) in input.iter().zip(tip.iter_mut()) {
            *y = strip.tip_deflection_m(&x);
            strip.step(&mut x, v);
        }
        black_box(&tip);
        best = best.min(start.elapsed().as_secs_f64());
    }
    let mut t = String::new();
    for y in &tip {
        let _ = writeln!(t, "{y:e}");
    }
    std::fs::write(dir.join("tip_finrs.txt"), t)?;
    println!("{:.3}", best / input.len() as f64 * 1e9);
    Ok(())
}
