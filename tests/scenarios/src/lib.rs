//! Scenarios that run the same model core on x86 and on the Cortex-M4F (in
//! QEMU), printing their outputs as text so that the two can be compared.
//!
//! Each scenario prints one line every [`EVERY`] samples:
//! `name k tip_m force_n u1.. i1..`, numbers in Rust's shortest round-trip
//! form. The inputs are computed in `f64` with `libm` on both targets, so a
//! difference can only come from the model's own arithmetic.
//!
//! ```
//! let mut out = String::new();
//! finrs_tests::run_scenario::<f64, _>(&finrs_tests::SCENARIOS[0], &mut out).unwrap();
//! assert!(out.lines().count() > 100);
//! ```
#![no_std]
#![deny(missing_docs, unsafe_code)]

use core::f64::consts::PI;
use core::fmt::{self, Write};

use model_core::{state_len, Fixture, Params, Real, Strip};

/// Sample time of every scenario, s.
pub const DT_S: f64 = 1e-3;

/// Samples between printed lines.
pub const EVERY: usize = 50;

/// What drives the segments.
#[derive(Clone, Copy, Debug)]
pub enum Drive {
    /// Voltages per segment (the first `N` are used), from `t = 0`.
    Steps([f64; 3]),
    /// The same step on every segment after `rest_s`.
    Step {
        /// Level, V.
        level_v: f64,
        /// Rest before, s.
        rest_s: f64,
    },
    /// Travelling sine, segment `k` lagging by `k · lag_deg`.
    Sine {
        /// Amplitude, V.
        amplitude_v: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Lag per segment, degrees.
        lag_deg: f64,
    },
}

impl Drive {
    /// Voltage on `segment` at sample `k`.
    pub fn voltage_v(&self, segment: usize, k: usize) -> f64 {
        let t = k as f64 * DT_S;
        match *self {
            Drive::Steps(levels) => levels[segment.min(2)],
            Drive::Step { level_v, rest_s } => {
                if t >= rest_s {
                    level_v
                } else {
                    0.0
                }
            }
            Drive::Sine {
                amplitude_v,
                frequency_hz,
                lag_deg,
            } => {
                amplitude_v
                    * libm::sin(2.0 * PI * frequency_hz * t - segment as f64 * lag_deg * PI / 180.0)
            }
        }
    }
}

/// One scenario: segments, fixture, drive, length.
#[derive(Clone, Copy, Debug)]
pub struct Scenario {
    /// Name printed at the start of its lines.
    pub name: &'static str,
    /// Segments (1, 3 or 5 here: larger models need more RAM than the
    /// discretisation has on a 128 KiB part).
    pub segments: usize,
    /// How the tip is held.
    pub fixture: Fixture,
    /// The drive.
    pub drive: Drive,
    /// Samples.
    pub samples: usize,
}

/// The scenarios both targets run.
pub const SCENARIOS: [Scenario; 6] = [
    // The seed's section 4.2: steps of 2, 1 and -2 V.
    Scenario {
        name: "seed_4_2",
        segments: 3,
        fixture: Fixture::Free,
        drive: Drive::Steps([2.0, 1.0, -2.0]),
        samples: 10_000,
    },
    Scenario {
        name: "free_step",
        segments: 3,
        fixture: Fixture::Free,
        drive: Drive::Step {
            level_v: 2.5,
            rest_s: 0.5,
        },
        samples: 5_000,
    },
    Scenario {
        name: "blocked_step",
        segments: 3,
        fixture: Fixture::Blocked,
        drive: Drive::Step {
            level_v: 2.0,
            rest_s: 0.5,
        },
        samples: 5_000,
    },
    Scenario {
        name: "travelling_sine",
        segments: 3,
        fixture: Fixture::Free,
        drive: Drive::Sine {
            amplitude_v: 2.5,
            frequency_hz: 1.0,
            lag_deg: 120.0,
        },
        samples: 5_000,
    },
    Scenario {
        name: "one_segment",
        segments: 1,
        fixture: Fixture::Free,
        drive: Drive::Step {
            level_v: 4.0,
            rest_s: 0.1,
        },
        samples: 2_000,
    },
    Scenario {
        name: "five_segments_blocked",
        segments: 5,
        fixture: Fixture::Blocked,
        drive: Drive::Sine {
            amplitude_v: 3.0,
            frequency_hz: 2.0,
            lag_deg: 72.0,
        },
        samples: 2_000,
    },
];

/// Runs one scenario in precision `T`, writing its lines to `w`.
pub fn run_scenario<T: Real + fmt::LowerExp, W: Write>(sc: &Scenario, w: &mut W) -> fmt::Result {
    match sc.segments {
        1 => run::<T, W, 1, { state_len(1, 1) }>(sc, w),
        3 => run::<T, W, 3, { state_len(3, 1) }>(sc, w),
        5 => run::<T, W, 5, { state_len(5, 1) }>(sc, w),
        n => writeln!(w, "{} error unsupported segment count {n}", sc.name),
    }
}

/// Runs every scenario in precision `T`.
pub fn run_all<T: Real + fmt::LowerExp, W: Write>(w: &mut W) -> fmt::Result {
    for sc in &SCENARIOS {
        run_scenario::<T, W>(sc, w)?;
    }
    Ok(())
}

fn run<T: Real + fmt::LowerExp, W: Write, const N: usize, const S: usize>(
    sc: &Scenario,
    w: &mut W,
) -> fmt::Result {
    let strip = match Strip::<T, N, 1, S>::new(&Params::main_m_2006(), sc.fixture, DT_S) {
        Ok(s) => s,
        Err(e) => return writeln!(w, "{} error {e}", sc.name),
    };
    let mut x = strip.rest();
    for k in 0..=sc.samples {
        let mut v = [T::ZERO; N];
        for (i, vi) in v.iter_mut().enumerate() {
            *vi = T::from_f64(sc.drive.voltage_v(i, k));
        }
        if k % EVERY == 0 {
            write!(
                w,
                "{} {k} {:e} {:e}",
                sc.name,
                strip.tip_deflection_m(&x),
                strip.blocking_force_n(&x)
            )?;
            for u in strip.moments_nm(&x) {
                write!(w, " {u:e}")?;
            }
            for i in strip.currents_a(&x, &v) {
                write!(w, " {i:e}")?;
            }
            writeln!(w)?;
        }
        strip.step(&mut x, &v);
    }
    Ok(())
}
