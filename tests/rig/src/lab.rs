//! The lab-like bench (#48): what real benches add to a session that the
//! rig's other benches lack, each at a strength drawn per session from a
//! range (docs/rig.md, "A lab-like bench", says each range and why; none is
//! any one lab's number), and the lab's own protocol.
//!
//! | artefact (`--lab` name) | what it is |
//! |---|---|
//! | `curl` | the strip curls by itself: a uniform curvature that wanders over minutes (so `w(s) ∝ s²`), a moment `EI κ` on the whole strip |
//! | `zero-drift` | the zeros of the camera or laser, the load cell and each current channel wander over minutes |
//! | `dropouts` | the tracker loses the strip for stretches; the laser reads nothing beyond its range; the camera drops frames |
//! | `quantisation` | currents in ADC steps, the load cell in counts |
//! | `readback` | the voltage columns are what a DAQ reads back: an offset, noise and a 16-bit ADC's step |
//! | `contact-faults` | a contact open for a while after a voltage step: the voltage reads, no current flows |
//! | `carry-over` | a recording starts from the state the last one left, after a 10 s pause |
//! | `asymmetry` | the moment per charge differs by sign |
//!
//! Every parameter is drawn whether its artefact is on or not, and each
//! artefact's noise comes from a random stream of its own ([`LabBench::seed`]),
//! so that switching one artefact off (`--lab-without readback`) leaves the
//! rest of the session as it was.

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::beam::{Beam, Tip};
use crate::sample::{Hidden, Sample};
use crate::session::Run;
use crate::strip::section;

/// The artefacts of the lab-like bench, as `--lab` and
/// [`LabBench::draw`] name them.
pub const LAB_ARTEFACTS: [&str; 8] = [
    "curl",
    "zero-drift",
    "dropouts",
    "quantisation",
    "readback",
    "contact-faults",
    "carry-over",
    "asymmetry",
];

/// Drift alone: the strip's curl and the sensors' wandering zeros.
pub const DRIFT: [&str; 2] = ["curl", "zero-drift"];

/// The strip's own curl: its free tip's displacement from the rest shape
/// calibrated before the session is a smooth Gauss–Markov process of
/// second order (critically damped), so that it wanders by millimetres
/// over minutes, either way, and is continuous with a continuous rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curl {
    /// Stationary standard deviation of the free tip's displacement, m.
    pub sigma_m: f64,
    /// Time constant, s.
    pub tau_s: f64,
}

/// The zeros of every sensor wander: each a first-order Gauss–Markov
/// process (a random walk over times shorter than its time constant).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZeroDrift {
    /// Stationary standard deviation, in units of each channel's noise.
    pub sigma_noise: f64,
    /// Time constant, s.
    pub tau_s: f64,
}

/// Where the tracker reads nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dropouts {
    /// Stretches of a lost spot or lost tracking, per minute.
    pub per_min: f64,
    /// The longest stretch, s (each is drawn from 0.05 s to this).
    pub max_s: f64,
    /// Share of camera frames dropped one by one.
    pub frame_loss: f64,
    /// The laser's measuring range, ± m about its zero.
    pub laser_range_m: f64,
}

/// Steps of the DAQ's channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantisation {
    /// A current's step, A.
    pub current_a: f64,
    /// The load cell's count, N.
    pub force_n: f64,
}

/// What the DAQ reads back of the voltage it applies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readback {
    /// Offset of each voltage channel (segments 1..=8), V.
    pub offsets_v: [f64; 8],
    /// Noise, V rms.
    pub noise_v: f64,
    /// The ADC's step, V.
    pub step_v: f64,
}

/// Contacts that open after a voltage step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactFaults {
    /// Chance that a recording has one.
    pub per_recording: f64,
}

/// A 16-bit ADC over ±10 V: its step, V.
pub const ADC_STEP_V: f64 = 20.0 / 65_536.0;

/// The pieces of a fault: shortest and longest time open, s.
pub const FAULT_S: (f64, f64) = (0.3, 2.0);

/// The lab-like bench of one session; [`LabBench::default`] has nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabBench {
    /// The strip's own curl.
    pub curl: Option<Curl>,
    /// The sensors' wandering zeros.
    pub zeros: Option<ZeroDrift>,
    /// Dropouts and out-of-range stretches of the tracker.
    pub dropouts: Option<Dropouts>,
    /// Quantised currents and load cell.
    pub quantisation: Option<Quantisation>,
    /// The voltage as read back.
    pub readback: Option<Readback>,
    /// Open contacts.
    pub contact: Option<ContactFaults>,
    /// Each recording starts where the last one left the strip.
    pub carry_over: bool,
    /// `a`: the strip bends about `1 + a` times more under a positive
    /// moment than under a negative one ([`crate::strip::Lab::asymmetry`]).
    pub asymmetry: Option<f64>,
    /// Seed of the artefacts' own random streams.
    pub seed: u64,
}

/// A value drawn between `lo` and `hi`, of either sign.
fn either_sign(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    let m = rng.gen_range(lo..hi);
    if rng.gen_bool(0.5) {
        m
    } else {
        -m
    }
}

impl LabBench {
    /// A lab bench with the artefacts `names` (from [`LAB_ARTEFACTS`]), each
    /// drawn from its range; an unknown name is refused. Every artefact's
    /// parameters are drawn, in one order, whichever are kept.
    pub fn draw(names: &[&str], rng: &mut impl Rng) -> Result<LabBench, String> {
        if let Some(n) = names.iter().find(|n| !LAB_ARTEFACTS.contains(n)) {
            return Err(format!(
                "unknown lab artefact `{n}`: the lab bench has {LAB_ARTEFACTS:?}"
            ));
        }
        let curl = Curl {
            sigma_m: rng.gen_range(1e-3..4e-3),
            tau_s: rng.gen_range(60.0..240.0),
        };
        let zeros = ZeroDrift {
            sigma_noise: rng.gen_range(0.5..2.0),
            tau_s: rng.gen_range(60.0..600.0),
        };
        let dropouts = Dropouts {
            per_min: rng.gen_range(0.5..3.0),
            max_s: rng.gen_range(0.5..2.0),
            frame_loss: rng.gen_range(0.0..0.02),
            laser_range_m: rng.gen_range(4e-3..12e-3),
        };
        let quantisation = Quantisation {
            current_a: rng.gen_range(0.05e-3..0.2e-3),
            force_n: rng.gen_range(10e-6..50e-6),
        };
        let mut offsets_v = [0.0; 8];
        for o in &mut offsets_v {
            *o = either_sign(rng, 0.5e-3, 3e-3);
        }
        let readback = Readback {
            offsets_v,
            noise_v: rng.gen_range(0.1e-3..0.5e-3),
            step_v: ADC_STEP_V,
        };
        let contact = ContactFaults {
            per_recording: rng.gen_range(0.15..0.35),
        };
        let asymmetry = rng.gen_range(-0.2..0.2);
        let seed = rng.gen();
        let on = |name: &str| names.contains(&name);
        Ok(LabBench {
            curl: on("curl").then_some(curl),
            zeros: on("zero-drift").then_some(zeros),
            dropouts: on("dropouts").then_some(dropouts),
            quantisation: on("quantisation").then_some(quantisation),
            readback: on("readback").then_some(readback),
            contact: on("contact-faults").then_some(contact),
            carry_over: on("carry-over"),
            asymmetry: on("asymmetry").then_some(asymmetry),
            seed,
        })
    }

    /// Whether the bench adds anything.
    pub fn is_none(&self) -> bool {
        LabBench {
            seed: self.seed,
            ..LabBench::default()
        } == *self
    }

    /// Whether anything drifts (the strip or a zero).
    pub fn drifts(&self) -> bool {
        self.curl.is_some() || self.zeros.is_some()
    }

    /// The random stream of artefact `which` (its index in
    /// [`LAB_ARTEFACTS`]; higher ones for the sensors' noise).
    pub fn stream(&self, which: u64) -> rand::rngs::StdRng {
        rand::rngs::StdRng::seed_from_u64(
            self.seed ^ which.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        )
    }
}

/// A slow random path on a regular grid, read by linear interpolation.
#[derive(Clone, Debug, PartialEq)]
pub struct SlowPath {
    /// Grid step, s.
    pub dt_s: f64,
    /// Values at `0, dt_s, 2 dt_s, …`.
    pub values: Vec<f64>,
}

/// Grid step of the slow paths, s: a thousandth of their shortest time
/// constant, so the interpolation's corners are far below anything a
/// recording resolves.
pub const PATH_DT_S: f64 = 0.05;

impl SlowPath {
    /// The value at `t_s` (held past either end).
    pub fn at(&self, t_s: f64) -> f64 {
        let x = (t_s / self.dt_s).max(0.0);
        let i = x.floor() as usize;
        match (self.values.get(i), self.values.get(i + 1)) {
            (Some(a), Some(b)) => a + (b - a) * (x - i as f64),
            (Some(a), None) => *a,
            _ => self.values.last().copied().unwrap_or(0.0),
        }
    }

    /// A first-order Gauss–Markov (Ornstein–Uhlenbeck) path over
    /// `duration_s` of standard deviation `sigma` and time constant
    /// `tau_s`, started from its stationary law, stepped exactly.
    pub fn first_order(sigma: f64, tau_s: f64, duration_s: f64, rng: &mut impl Rng) -> SlowPath {
        let n = (duration_s / PATH_DT_S).ceil() as usize + 2;
        let a = (-PATH_DT_S / tau_s).exp();
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        let mut x = sigma * unit.sample(rng);
        let values = (0..n)
            .map(|_| {
                let now = x;
                x = a * x + sigma * (1.0 - a * a).sqrt() * unit.sample(rng);
                now
            })
            .collect();
        SlowPath {
            dt_s: PATH_DT_S,
            values,
        }
    }

    /// A critically damped second-order Gauss–Markov path,
    /// `x'' = -2x'/τ - x/τ² + noise`, of stationary standard deviation
    /// `sigma`, started at 0 (the rest calibrated before the session) with
    /// its rate drawn from its stationary law (`sigma/τ` rms).
    pub fn second_order(sigma: f64, tau_s: f64, duration_s: f64, rng: &mut impl Rng) -> SlowPath {
        let n = (duration_s / PATH_DT_S).ceil() as usize + 2;
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        // Stationary: var(x) = q τ³/4 for white noise of intensity q.
        let q = 4.0 * sigma * sigma / tau_s.powi(3);
        let (mut x, mut v) = (0.0, sigma / tau_s * unit.sample(rng));
        // Ten sub-steps a grid step (semi-implicit Euler–Maruyama): τ is
        // more than a thousand grid steps.
        let sub = 10;
        let h = PATH_DT_S / sub as f64;
        let kick = (q * h).sqrt();
        let values = (0..n)
            .map(|_| {
                let now = x;
                for _ in 0..sub {
                    v += (-2.0 * v / tau_s - x / (tau_s * tau_s)) * h + kick * unit.sample(rng);
                    x += v * h;
                }
                now
            })
            .collect();
        SlowPath {
            dt_s: PATH_DT_S,
            values,
        }
    }
}

/// One segment's electrode contact open from `from_row` for `rows` rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fault {
    /// Segment, 0-based.
    pub segment: usize,
    /// First row open.
    pub from_row: usize,
    /// Rows open.
    pub rows: usize,
}

impl Fault {
    /// A fault in a recording of voltages `v_v` at `rate_hz`: at one of the
    /// steps that apply a voltage (a segment's voltage rising in size by
    /// more than 0.5 V from one row to the next, or its first row off
    /// 0 V), drawn at random, for [`FAULT_S`]. `None` if nothing is ever
    /// applied.
    pub fn draw(
        v_v: &finrs::recording::Voltages,
        rate_hz: f64,
        rng: &mut impl Rng,
    ) -> Option<Fault> {
        let segments = v_v.segments();
        let mut edges = Vec::new();
        for k in 0..segments {
            let mut before = 0.0;
            let mut driven = false;
            for (r, row) in v_v.rows().enumerate() {
                let v = row[k];
                if v.abs() - f64::abs(before) > 0.5 || (!driven && v != 0.0) {
                    edges.push((k, r));
                }
                driven |= v != 0.0;
                before = v;
            }
        }
        if edges.is_empty() {
            return None;
        }
        let (segment, from_row) = edges[rng.gen_range(0..edges.len())];
        let seconds = rng.gen_range(FAULT_S.0..FAULT_S.1);
        Some(Fault {
            segment,
            from_row,
            rows: (seconds * rate_hz).round() as usize,
        })
    }

    /// `open[segment][row]` for a recording of `segments` × `rows`.
    pub fn mask(&self, segments: usize, rows: usize) -> Vec<Vec<bool>> {
        let mut open = vec![vec![false; rows]; segments];
        let end = (self.from_row + self.rows).min(rows);
        for o in &mut open[self.segment][self.from_row.min(end)..end] {
            *o = true;
        }
        open
    }
}

/// The laser of the lab protocol: one point of the strip, across.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Laser {
    /// Where it points, m from the clamp.
    pub s_m: f64,
    /// Noise, m rms.
    pub noise_m: f64,
    /// Resolution, m.
    pub step_m: f64,
}

/// The lab protocol's DAQ rate, rows/s.
pub const LAB_RATE_HZ: f64 = 100.0;

/// Recordings of a lab session.
pub const LAB_RECORDINGS: usize = 5;

/// The voltage held in a lab session, minutes in all (spread over its
/// recordings): with the rests, offs and pauses, about 20 minutes.
pub const LAB_HELD_MIN: f64 = 17.5;

/// A one-segment session as a lab records it: voltage steps held for
/// minutes, 100 rows/s, a laser at one point, currents.
#[derive(Clone, Debug)]
pub struct LabProtocol {
    /// The recordings, all free.
    pub runs: Vec<Run>,
    /// The laser.
    pub laser: Laser,
}

/// The example strip's segment (50 × 10 mm in three), m²: the area the
/// rig's `R1`, `R2` and `C` are drawn for.
const SEGMENT_AREA_M2: f64 = 0.05 / 3.0 * 0.01;

impl LabProtocol {
    /// Draws a lab's strip into `sample` and the protocol it is recorded
    /// with. The strip: 20–40 mm long, 4–10 mm wide, 0.2–0.6 mm thick;
    /// `C` in proportion to its area against the rig's segment, `R1` and
    /// `R2` in inverse proportion (both are across the same membrane), and
    /// `K` such that a volt bends the free tip 0.5–3 mm before any
    /// relaxation (with `hidden`'s stiffness: K = 2 EI d / (C L²)). The
    /// protocol: [`LAB_RECORDINGS`] recordings, each a rest of 2–5 s, a
    /// step of 1–3 V (the signs alternating from a random one) held 1–6 min
    /// ([`LAB_HELD_MIN`] in all), and 20–40 s at 0 V; a laser at 0.6–0.95
    /// of the length, 2–20 µm of noise in 0.1–1 µm steps.
    pub fn draw(sample: &mut Sample, hidden: &Hidden, rng: &mut impl Rng) -> LabProtocol {
        let length_m = rng.gen_range(0.020..0.040);
        let width_m = rng.gen_range(0.004..0.010);
        let thickness_m = rng.gen_range(0.2e-3..0.6e-3);
        let area = length_m * width_m / SEGMENT_AREA_M2;
        sample.length_m = length_m;
        sample.width_m = width_m;
        sample.core_m = thickness_m - 2.0 * sample.film_m;
        sample.c_f *= area;
        sample.r1_ohm /= area;
        sample.r2_ohm /= area;
        let bend_m_per_v = rng.gen_range(0.5e-3..3e-3);
        let (ei, _) = section(sample, hidden);
        sample.k_nm_per_c = 2.0 * ei * bend_m_per_v / (sample.c_f * length_m * length_m);
        let laser = Laser {
            s_m: length_m * rng.gen_range(0.6..0.95),
            noise_m: rng.gen_range(2e-6..20e-6),
            step_m: rng.gen_range(0.1e-6..1e-6),
        };
        let mut held: Vec<f64> = (0..LAB_RECORDINGS)
            .map(|_| rng.gen_range(60.0..360.0))
            .collect();
        // Scaled to the session's total, each kept within 1–6 min: a few
        // rounds of scaling and clamping settle (the total lies between
        // five minimal and five maximal holds).
        for _ in 0..20 {
            let scale = LAB_HELD_MIN * 60.0 / held.iter().sum::<f64>();
            held.iter_mut()
                .for_each(|h| *h = (*h * scale).clamp(60.0, 360.0));
        }
        let mut sign = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
        let runs = held
            .iter()
            .enumerate()
            .map(|(i, h)| {
                let level = sign * rng.gen_range(1.0..3.0);
                sign = -sign;
                let hold_s = h.round();
                let rest_s = rng.gen_range(2.0..5.0_f64).round();
                let off_s = rng.gen_range(20.0..40.0_f64).round();
                Run {
                    name: format!("{:02}_lab_step_{level:+.2}V", i + 1),
                    wave: format!("step:{level:.3}"),
                    fixture: finrs::recording::Fixture::Free,
                    rest_s,
                    hold_s,
                    off_s,
                    description: format!(
                        "lab step {level:+.3} V held {hold_s} s, laser at {:.1} mm",
                        laser.s_m * 1e3
                    ),
                }
            })
            .collect();
        LabProtocol { runs, laser }
    }

    /// Seconds of data in the session (the recordings, not the pauses).
    pub fn data_s(&self) -> f64 {
        self.runs
            .iter()
            .map(|r| r.rest_s + r.hold_s + r.off_s)
            .sum()
    }
}

/// The free strip's first mode, Hz, on `segments` segments.
pub fn first_mode_hz(sample: &Sample, hidden: &Hidden, segments: usize) -> f64 {
    let (ei, mass) = section(sample, hidden);
    let beam = Beam::new(sample.length_m, segments, 4, ei, mass, Tip::Free);
    beam.omega[0] / (2.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng() -> rand::rngs::StdRng {
        rand::rngs::StdRng::seed_from_u64(11)
    }

    #[test]
    fn unknown_artefacts_are_refused_and_off_ones_leave_the_others_drawn_alike() {
        let e = LabBench::draw(&["curl", "wobble"], &mut rng()).unwrap_err();
        assert!(e.contains("`wobble`"), "{e}");
        let all = LabBench::draw(&LAB_ARTEFACTS, &mut rng()).unwrap();
        let some = LabBench::draw(&["curl", "asymmetry"], &mut rng()).unwrap();
        assert_eq!(some.curl, all.curl);
        assert_eq!(some.asymmetry, all.asymmetry);
        assert_eq!(some.seed, all.seed);
        assert!(some.readback.is_none() && !some.carry_over);
        assert!(LabBench::default().is_none() && !all.is_none());
        let none = LabBench::draw(&[], &mut rng()).unwrap();
        assert!(none.is_none() && !none.drifts());
    }

    #[test]
    fn the_draws_keep_to_their_ranges() {
        let mut r = rng();
        for _ in 0..200 {
            let b = LabBench::draw(&LAB_ARTEFACTS, &mut r).unwrap();
            let rb = b.readback.unwrap();
            assert!(rb
                .offsets_v
                .iter()
                .all(|o| (0.5e-3..3e-3).contains(&o.abs())));
            let q = b.quantisation.unwrap();
            assert!((0.05e-3..0.2e-3).contains(&q.current_a));
            assert!(b.asymmetry.unwrap().abs() < 0.2);
            let c = b.curl.unwrap();
            assert!((1e-3..4e-3).contains(&c.sigma_m) && (60.0..240.0).contains(&c.tau_s));
        }
    }

    #[test]
    fn slow_paths_have_their_spread_and_the_curl_starts_at_rest() {
        let mut r = rng();
        let sd = |p: &SlowPath| {
            let n = p.values.len() as f64;
            let m = p.values.iter().sum::<f64>() / n;
            (p.values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt()
        };
        // Many time constants long: the spread is the stationary one.
        let p = SlowPath::first_order(2.0, 10.0, 20_000.0, &mut r);
        assert!((sd(&p) / 2.0 - 1.0).abs() < 0.15, "{}", sd(&p));
        let c = SlowPath::second_order(3e-3, 10.0, 20_000.0, &mut r);
        assert_eq!(c.values[0], 0.0);
        assert!((sd(&c) / 3e-3 - 1.0).abs() < 0.2, "{}", sd(&c));
        // Linear between the grid's points, held past its end.
        let p = SlowPath {
            dt_s: 1.0,
            values: vec![0.0, 2.0, 4.0],
        };
        assert_eq!(p.at(0.5), 1.0);
        assert_eq!(p.at(1.25), 2.5);
        assert_eq!(p.at(9.0), 4.0);
    }

    #[test]
    fn a_fault_opens_at_a_step_for_its_time() {
        let v = finrs::recording::Voltages::from_rows(
            2,
            (0..1000).map(|r| if r < 300 { [0.0, 0.0] } else { [2.0, 0.0] }),
        );
        let f = Fault::draw(&v, 1000.0, &mut rng()).unwrap();
        assert_eq!((f.segment, f.from_row), (0, 300));
        assert!((300..=2000).contains(&f.rows), "{}", f.rows);
        let m = f.mask(2, 1000);
        assert!(m[0][300] && !m[0][299] && !m[1].iter().any(|&o| o));
        let rest = finrs::recording::Voltages::zeros(2, 100);
        assert!(Fault::draw(&rest, 1000.0, &mut rng()).is_none());
    }

    #[test]
    fn the_lab_protocol_draws_a_lab_strip_and_about_twenty_minutes() {
        let mut r = rng();
        for _ in 0..50 {
            let mut s = Sample::draw_off_class(&mut r);
            let h = Hidden::draw_off_class(&[], &mut r).unwrap();
            let p = LabProtocol::draw(&mut s, &h, &mut r);
            assert!((0.02..0.04).contains(&s.length_m));
            assert!((0.2e-3..0.6e-3).contains(&s.thickness_m()));
            assert_eq!(p.runs.len(), LAB_RECORDINGS);
            let minutes = p.data_s() / 60.0;
            assert!((17.0..23.0).contains(&minutes), "{minutes}");
            for (a, b) in p.runs.iter().zip(p.runs.iter().skip(1)) {
                // Alternating signs.
                assert_ne!(a.wave.contains('-'), b.wave.contains('-'));
            }
            assert!(p.laser.s_m < s.length_m);
        }
    }
}
