//! Speed of the model core: one step, a 20 s run, and the discretisation.
//!
//! `cargo bench -p model-core`; the numbers we measured are in docs/speed.md.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use model_core::{state_len, Extensions, Fixture, Params, Real, Strip};

fn step_one<T: Real, const N: usize, const S: usize>(c: &mut Criterion, label: &str) {
    let strip = Strip::<T, N, 1, S>::new(&Params::main_m_2006(), Fixture::Free, 1e-3).unwrap();
    let mut x = strip.rest();
    let v = [T::from_f64(2.5); N];
    c.bench_with_input(BenchmarkId::new("step", label), &v, |b, v| {
        b.iter(|| strip.step(black_box(&mut x), black_box(v)))
    });
}

fn steps(c: &mut Criterion) {
    step_one::<f32, 1, { state_len(1, 1) }>(c, "N=1 f32");
    step_one::<f64, 1, { state_len(1, 1) }>(c, "N=1 f64");
    step_one::<f32, 3, { state_len(3, 1) }>(c, "N=3 f32");
    step_one::<f64, 3, { state_len(3, 1) }>(c, "N=3 f64");
    step_one::<f32, 8, { state_len(8, 1) }>(c, "N=8 f32");
    step_one::<f64, 8, { state_len(8, 1) }>(c, "N=8 f64");
}

/// One step of the fit's mesh (`E = 4`) in water, without and with the
/// quadratic drag (its implicit step on the lowest four modes), from a
/// swinging state.
fn step_in_water(c: &mut Criterion) {
    const S: usize = state_len(3, 4);
    let p = Params::main_m_2006();
    for (label, c2) in [
        ("N=3 E=4 f64 water", 0.0),
        ("N=3 E=4 f64 water, drag", 10.0),
    ] {
        let ext = Extensions {
            added_mass_kg_per_m: 0.06,
            drag_quadratic_n_s2_per_m3: c2,
            ..Extensions::NONE
        };
        let strip = Strip::<f64, 3, 4, S>::with_extensions(&p, &ext, Fixture::Free, 1e-3).unwrap();
        let mut x = strip.rest();
        for _ in 0..50 {
            strip.step(&mut x, &[2.5; 3]);
        }
        let v = [2.5; 3];
        c.bench_with_input(BenchmarkId::new("step", label), &v, |b, v| {
            b.iter(|| strip.step(black_box(&mut x), black_box(v)))
        });
    }
}

/// The 1 Hz travelling sine of the example session, 20 s at 1 kHz.
pub fn travelling_sine_20s() -> Vec<[f64; 3]> {
    (0..20_000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            core::array::from_fn(|i| 2.5 * (2.0 * PI * t - i as f64 * 2.0 * PI / 3.0).sin())
        })
        .collect()
}

fn run_20s(c: &mut Criterion) {
    let strip = Strip::<f64, 3, 1, 18>::new(&Params::main_m_2006(), Fixture::Free, 1e-3).unwrap();
    let input = travelling_sine_20s();
    let mut tip = vec![0.0; input.len()];
    c.bench_function("run 20 s at 1 kHz, N=3 f64", |b| {
        b.iter(|| {
            let mut x = strip.rest();
            for (v, y) in input.iter().zip(tip.iter_mut()) {
                strip.step(&mut x, v);
                *y = strip.tip_deflection_m(&x);
            }
            black_box(&tip);
        })
    });
}

/// The same run with a reaction behind each double layer whose onset
/// the sine's 2.5 V crosses (1.5 V, 50 mV a Tafel voltage, the leak's
/// current there): the layer's implicit solve at every step.
fn run_20s_reaction(c: &mut Criterion) {
    let ext = Extensions {
        reaction_ratio: 1.0,
        reaction_ref_v: 1.5,
        reaction_tafel_v: 0.05,
        ..Extensions::NONE
    };
    let strip =
        Strip::<f64, 3, 1, 18>::with_extensions(&Params::main_m_2006(), &ext, Fixture::Free, 1e-3)
            .unwrap();
    let input = travelling_sine_20s();
    let mut tip = vec![0.0; input.len()];
    c.bench_function("run 20 s at 1 kHz, N=3 f64, reaction", |b| {
        b.iter(|| {
            let mut x = strip.rest();
            for (v, y) in input.iter().zip(tip.iter_mut()) {
                strip.step(&mut x, v);
                *y = strip.tip_deflection_m(&x);
            }
            black_box(&tip);
        })
    });
}

fn discretise(c: &mut Criterion) {
    let p = Params::main_m_2006();
    c.bench_function("discretise N=3 E=1", |b| {
        b.iter(|| Strip::<f64, 3, 1, 18>::new(black_box(&p), Fixture::Free, 1e-3).unwrap())
    });
    c.bench_function("discretise N=3 E=4", |b| {
        b.iter(|| {
            Strip::<f64, 3, 4, { state_len(3, 4) }>::new(black_box(&p), Fixture::Free, 1e-3)
                .unwrap()
        })
    });
    c.bench_function("discretise N=8 E=1", |b| {
        b.iter(|| {
            Strip::<f64, 8, 1, { state_len(8, 1) }>::new(black_box(&p), Fixture::Free, 1e-3)
                .unwrap()
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = steps, step_in_water, run_20s, run_20s_reaction, discretise
}
criterion_main!(benches);
