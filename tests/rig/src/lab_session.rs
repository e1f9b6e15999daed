//! A session on the lab-like bench ([`crate::lab`]): the same strip and
//! sensors as [`crate::session::write`], with the lab's artefacts, on the
//! example's instruments (three segments, 1 kHz, a camera at 30 frames/s)
//! or the lab protocol's (one segment, 100 rows/s, a laser at one point).
//! [`crate::session::write`] is left as it was, so that every session
//! without the lab bench stays the same byte for byte.

use std::f64::consts::PI;
use std::path::Path;

use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::{Channel, Fixture, Medium, Recording, SAFE_VOLTAGE_LIMIT_V};
use finrs::wave::Wave;
use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::bench::{self, Bench};
use crate::lab::{Fault, LabBench, Laser, SlowPath, LAB_RATE_HZ};
use crate::sample::{Hidden, Sample, SEGMENTS};
use crate::session::{
    camera_rows, expose, exposed_rows, load_cell_of, round, Run, Sensors, CAMERA_HZ, DAQ_HZ,
    DOTS_S_M, PAUSE_S,
};
use crate::strip::{pause, run_lab, Lab, Mesh, State, Truth, BLOCKED_MESH, MESH};

/// What follows the strip's shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tracker {
    /// The example's camera: [`DOTS_S_M`] at [`CAMERA_HZ`], across and along.
    Camera,
    /// A laser at one point, across, on every DAQ row.
    Laser(Laser),
}

/// The instruments of a session.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// Segments driven.
    pub segments: usize,
    /// DAQ rate, rows/s.
    pub rate_hz: f64,
    /// What tracks the strip in free runs.
    pub tracker: Tracker,
}

impl Layout {
    /// The example's: three segments, 1 kHz, the camera.
    pub fn camera() -> Layout {
        Layout {
            segments: SEGMENTS,
            rate_hz: DAQ_HZ,
            tracker: Tracker::Camera,
        }
    }

    /// The lab protocol's: one segment, 100 rows/s, `laser`.
    pub fn laser(laser: Laser) -> Layout {
        Layout {
            segments: 1,
            rate_hz: LAB_RATE_HZ,
            tracker: Tracker::Laser(laser),
        }
    }

    /// Arc lengths tracked, m.
    fn dots(&self) -> Vec<f64> {
        match self.tracker {
            Tracker::Camera => DOTS_S_M.to_vec(),
            Tracker::Laser(l) => vec![l.s_m],
        }
    }

    /// The free strip's mesh: as fine as the example's strip (24
    /// elements) whatever the segments.
    fn free_mesh(&self) -> Mesh {
        Mesh {
            per_segment: (MESH.per_segment * SEGMENTS / self.segments).max(MESH.per_segment),
            ..MESH
        }
    }
}

/// What a lab session held beyond its files: for tests and reports.
#[derive(Clone, Debug, Default)]
pub struct Written {
    /// Each recording's open contact, if it had one.
    pub faults: Vec<Option<Fault>>,
    /// Each recording's opening state (at rest without carry-over).
    pub opening: Vec<State>,
    /// Each recording's start on the session's clock, s.
    pub starts_s: Vec<f64>,
    /// The free tip's curl over the session, m (none without `curl`).
    pub curl_tip_m: Option<SlowPath>,
}

/// Random streams of [`LabBench::stream`], one per use.
mod streams {
    pub const CURL: u64 = 0;
    pub const ZEROS: u64 = 1;
    pub const DROPOUTS: u64 = 2;
    pub const READBACK: u64 = 4;
    pub const CONTACT: u64 = 5;
}

/// The sensors' wandering zeros over the session, one path per channel.
struct Zeros {
    currents: Vec<SlowPath>,
    across: SlowPath,
    along: SlowPath,
    force: SlowPath,
}

/// Writes the session of `runs` from `sample` with `hidden` on `bench` and
/// the lab bench `lab`, recorded with `layout`'s instruments, into `dir`;
/// `label` goes into each file's notes. With `lab`'s readback the voltage
/// columns are what a DAQ reads, whose rests are not 0 V and whose 4 V
/// may read past the safe limit: those files are written unchecked.
#[allow(clippy::too_many_arguments)]
pub fn write_lab(
    dir: &Path,
    sample: &Sample,
    hidden: &Hidden,
    sensors: &Sensors,
    bench: &Bench,
    lab: &LabBench,
    runs: &[Run],
    layout: &Layout,
    label: &str,
    rng: &mut impl Rng,
) -> anyhow::Result<Written> {
    std::fs::create_dir_all(dir)?;
    let dt_s = 1.0 / layout.rate_hz;
    let session_s: f64 = runs
        .iter()
        .map(|r| r.rest_s + r.hold_s + r.off_s + dt_s + PAUSE_S)
        .sum::<f64>()
        + 60.0;
    let (ei, _) = crate::strip::section(sample, hidden);
    let curl_tip = lab.curl.map(|c| {
        SlowPath::second_order(
            c.sigma_m,
            c.tau_s,
            session_s,
            &mut lab.stream(streams::CURL),
        )
    });
    // A uniform curvature κ bends the free tip by κ L²/2: κ = 2 d / L².
    let length = sample.length_m;
    let curl_moment = curl_tip
        .clone()
        .map(|p| move |t: f64| ei * 2.0 * p.at(t) / (length * length));
    let tracker_noise = match layout.tracker {
        Tracker::Camera => sensors.camera_m,
        Tracker::Laser(l) => l.noise_m,
    };
    let zeros = lab.zeros.map(|z| {
        let mut r = lab.stream(streams::ZEROS);
        let mut path =
            |noise: f64| SlowPath::first_order(z.sigma_noise * noise, z.tau_s, session_s, &mut r);
        Zeros {
            currents: (0..layout.segments)
                .map(|_| path(sensors.current_a))
                .collect(),
            across: path(tracker_noise),
            along: path(tracker_noise),
            force: path(sensors.force_n),
        }
    });
    let mut dropout_rng = lab.stream(streams::DROPOUTS);
    let mut readback_rng = lab.stream(streams::READBACK);
    let mut contact_rng = lab.stream(streams::CONTACT);
    let mut written = Written {
        curl_tip_m: curl_tip.clone(),
        ..Written::default()
    };
    let mut state = State::default();
    let mut t_session = 0.0;
    for (index, r) in runs.iter().enumerate() {
        let wave = Wave::parse(&r.wave).map_err(anyhow::Error::msg)?;
        let drive = Drive {
            segments: layout.segments,
            fixture: r.fixture,
            rest_s: r.rest_s,
            duration_s: r.hold_s,
            off_s: r.off_s,
            rate_hz: layout.rate_hz,
        };
        let mut rec = drive_recording(&wave, &drive)?;
        rec.meta.sample = Some(label.to_string());
        rec.meta.thickness_m = sample.thickness_m();
        rec.meta.length_m = sample.length_m;
        rec.meta.width_m = sample.width_m;
        rec.meta.medium = if hidden.water.is_some() {
            Medium::Water
        } else {
            Medium::Air
        };
        let dots = layout.dots();
        rec.meta.dots_s_m = Some(dots.clone());
        rec.meta.t_session_start_s = Some(round(t_session, 1e-3) + 0.0);
        rec.meta.notes = Some(format!(
            "t_session_start_s = {t_session:.3}; run {} of {}; {} ({} s rest, {} s drive, {} s off); finrs-rig, lab bench",
            index + 1,
            runs.len(),
            r.description,
            r.rest_s,
            r.hold_s,
            r.off_s
        ));
        let rows = rec.t_s.len();
        let fault = lab.contact.and_then(|c| {
            contact_rng
                .gen_bool(c.per_recording)
                .then(|| Fault::draw(&rec.v_v, layout.rate_hz, &mut contact_rng))
                .flatten()
        });
        let open = fault.map(|f| f.mask(layout.segments, rows));
        let blocked = r.fixture == Fixture::Blocked;
        let tracked: Vec<bool> = match (blocked, layout.tracker) {
            (true, _) => vec![false; rows],
            (false, Tracker::Camera) => camera_rows(rows),
            (false, Tracker::Laser(_)) => vec![true; rows],
        };
        let exposure_rows = match layout.tracker {
            Tracker::Camera => bench
                .exposure_s
                .map_or(1, |e| ((e * layout.rate_hz).round() as usize).max(1)),
            Tracker::Laser(_) => 1,
        };
        let (mesh, tip) = if blocked {
            (
                BLOCKED_MESH,
                load_cell_of(sample, hidden, bench, layout.segments),
            )
        } else {
            (layout.free_mesh(), crate::beam::Tip::Free)
        };
        written.opening.push(state.clone());
        written.starts_s.push(t_session);
        written.faults.push(fault);
        let strip_lab = Lab {
            start: lab.carry_over.then_some(&state),
            curl_nm: curl_moment.as_ref().map(|c| c as &dyn Fn(f64) -> f64),
            open: open.as_deref(),
            asymmetry: lab.asymmetry.unwrap_or(0.0),
        };
        let (mut truth, end) = run_lab(
            sample,
            hidden,
            mesh,
            tip,
            &rec.v_v,
            dt_s,
            t_session,
            &exposed_rows(&tracked, exposure_rows),
            &dots,
            &strip_lab,
        );
        if exposure_rows > 1 {
            expose(&mut truth, &tracked, exposure_rows);
        }
        // The load cell is tared before each blocked recording: what the
        // strip pressed on it at the start (its curl, a carried charge) is
        // the preload that `force_N` leaves out.
        if let Some(&f0) = truth.force_n.first() {
            truth.force_n.iter_mut().for_each(|f| *f -= f0);
        }
        let lost = lab.dropouts.map(|d| {
            lost_rows(
                rows,
                layout.rate_hz,
                d.per_min,
                d.max_s,
                match layout.tracker {
                    Tracker::Camera => d.frame_loss,
                    Tracker::Laser(_) => 0.0,
                },
                &mut dropout_rng,
            )
        });
        let context = Context {
            hidden,
            sensors,
            bench,
            lab,
            zeros: zeros.as_ref(),
            layout,
            t0_s: t_session,
            lost: lost.as_deref(),
        };
        measure_lab(&mut rec, &truth, &tracked, &context, rng);
        let path = dir.join(format!("{}.csv", r.name));
        if let Some(rb) = lab.readback {
            let noise = Normal::new(0.0, rb.noise_v).expect("positive noise");
            for row in rec.v_v.as_flat_mut().chunks_mut(layout.segments) {
                for (k, v) in row.iter_mut().enumerate() {
                    let read = *v + rb.offsets_v[k] + noise.sample(&mut readback_rng);
                    // The ADC's count, exported in microvolts (divided, so
                    // that the number is the decimal's nearest and reads
                    // back as written).
                    *v = (round(read, rb.step_v) * 1e6).round() / 1e6 + 0.0;
                }
            }
            // Unchecked: a rest of a few millivolts and a 4 V step read a
            // hair past 4 V are what the DAQ wrote.
            std::fs::write(&path, rec.to_csv_string())?;
        } else {
            debug_assert!(rec
                .v_v
                .as_flat()
                .iter()
                .all(|v| v.abs() <= SAFE_VOLTAGE_LIMIT_V));
            rec.write(&path)?;
        }
        state = if lab.carry_over {
            let mut s = end;
            // The next recording starts PAUSE_S after this one's last row;
            // the strip has run a row past it.
            pause(sample, hidden, &mut s, PAUSE_S - dt_s, dt_s);
            s
        } else {
            State::default()
        };
        t_session += rec.t_s.last().copied().unwrap_or(0.0) + PAUSE_S;
    }
    Ok(written)
}

/// Rows where the tracker reads nothing: stretches of a lost spot at
/// random times (`per_min` a minute, each 0.05 s to `max_s`) and single
/// camera frames dropped with chance `frame_loss`.
fn lost_rows(
    rows: usize,
    rate_hz: f64,
    per_min: f64,
    max_s: f64,
    frame_loss: f64,
    rng: &mut impl Rng,
) -> Vec<bool> {
    let mut lost = vec![false; rows];
    let duration_s = rows as f64 / rate_hz;
    let gap = rand_distr::Exp::new(per_min / 60.0).expect("positive rate");
    let mut t = gap.sample(rng);
    while t < duration_s {
        let len = rng.gen_range(0.05..max_s);
        let (a, b) = ((t * rate_hz) as usize, ((t + len) * rate_hz) as usize);
        for l in &mut lost[a.min(rows)..b.min(rows)] {
            *l = true;
        }
        t += len + gap.sample(rng);
    }
    if frame_loss > 0.0 {
        for l in &mut lost {
            *l |= rng.gen_bool(frame_loss);
        }
    }
    lost
}

/// What [`measure_lab`] needs of the session.
struct Context<'a> {
    hidden: &'a Hidden,
    sensors: &'a Sensors,
    bench: &'a Bench,
    lab: &'a LabBench,
    zeros: Option<&'a Zeros>,
    layout: &'a Layout,
    /// The recording's start on the session's clock, s.
    t0_s: f64,
    /// Rows the tracker lost.
    lost: Option<&'a [bool]>,
}

/// The recording's measured channels: [`crate::session`]'s sensors (noise,
/// pickup, the bench's hum and 1/f noise, pixels), then the lab's wandering
/// zeros, steps and lost rows; a laser instead of the camera on the lab
/// protocol.
fn measure_lab(
    rec: &mut Recording,
    truth: &Truth,
    tracked: &[bool],
    c: &Context,
    rng: &mut impl Rng,
) {
    let rows = rec.t_s.len();
    let (hidden, sensors, bench) = (c.hidden, c.sensors, c.bench);
    let at = |p: &SlowPath| -> Vec<f64> { rec.t_s.iter().map(|t| p.at(c.t0_s + t)).collect() };
    // Mains pickup: 50 Hz and a third of it at 150 Hz, phase unknown.
    let pickup = |sigma: f64, rng: &mut dyn rand::RngCore| -> Vec<f64> {
        let Some(a) = hidden.mains_pickup else {
            return vec![0.0; rows];
        };
        let (p1, p3) = (rng.gen_range(0.0..2.0 * PI), rng.gen_range(0.0..2.0 * PI));
        rec.t_s
            .iter()
            .map(|t| {
                a * sigma
                    * ((2.0 * PI * 50.0 * t + p1).sin() + (2.0 * PI * 150.0 * t + p3).sin() / 3.0)
            })
            .collect()
    };
    // White noise keeps what the bench's 1/f noise leaves of the power.
    let white = |sigma: f64| {
        let f = bench.pink_fraction.unwrap_or(0.0);
        Normal::new(0.0, sigma * (1.0 - f).sqrt()).expect("positive noise")
    };
    // A DAQ channel: value, pickup, white noise, the bench's hum and 1/f
    // noise, the wandering zero, in the channel's step.
    let daq =
        |values: &[f64], sigma: f64, zero: Vec<f64>, step: f64, rng: &mut dyn rand::RngCore| {
            let n = white(sigma);
            let p = pickup(sigma, rng);
            let mut out: Vec<f64> = values
                .iter()
                .zip(&p)
                .zip(&zero)
                .map(|((x, p), z)| x + p + z + n.sample(rng))
                .collect();
            if let Some(a) = bench.hum {
                for (o, h) in out.iter_mut().zip(bench::hum(&rec.t_s, a * sigma, rng)) {
                    *o += h;
                }
            }
            if let Some(f) = bench.pink_fraction {
                let pink = bench::pink(rows, sigma * f.sqrt(), c.layout.rate_hz, rng);
                for (o, p) in out.iter_mut().zip(pink) {
                    *o += p;
                }
            }
            out.into_iter()
                .map(|v| Some(round(v, step) + 0.0))
                .collect::<Vec<_>>()
        };
    let quant = c.lab.quantisation;
    let mut channels = Vec::new();
    for (k, i) in truth.currents_a.iter().enumerate() {
        let zero = c.zeros.map_or(vec![0.0; rows], |z| at(&z.currents[k]));
        let step = quant.map_or(sensors.daq_step, |q| q.current_a);
        channels.push((
            Channel::Current(k),
            daq(i, sensors.current_a, zero, step, rng),
        ));
    }
    let lost = |r: usize| c.lost.is_some_and(|l| l[r]);
    if !truth.force_n.is_empty() {
        // The zero too is tared at the start.
        let zero = c.zeros.map_or(vec![0.0; rows], |z| {
            let z0 = z.force.at(c.t0_s);
            at(&z.force).into_iter().map(|v| v - z0).collect()
        });
        let step = quant.map_or(sensors.daq_step, |q| q.force_n);
        channels.push((
            Channel::Force,
            daq(&truth.force_n, sensors.force_n, zero, step, rng),
        ));
    } else {
        let zero_y = c.zeros.map_or(vec![0.0; rows], |z| at(&z.across));
        let zero_x = c.zeros.map_or(vec![0.0; rows], |z| at(&z.along));
        match c.layout.tracker {
            Tracker::Camera => {
                let n = white(sensors.camera_m);
                let frames = tracked.iter().filter(|&&f| f).count();
                let camera_channel =
                    |series: &[(f64, f64)], along: bool, rng: &mut dyn rand::RngCore| {
                        // The rest shape is found to a fraction of a millimetre.
                        let offset = rng.gen_range(-sensors.rest_offset_m..sensors.rest_offset_m);
                        let zero = if along { &zero_x } else { &zero_y };
                        let mut pink = bench
                            .pink_fraction
                            .map(|f| {
                                bench::pink(frames, sensors.camera_m * f.sqrt(), CAMERA_HZ, rng)
                            })
                            .unwrap_or_default()
                            .into_iter();
                        (0..rows)
                            .map(|r| {
                                if !tracked[r] {
                                    return None;
                                }
                                let (x, y) = series[r];
                                let v =
                                    (if along { x } else { y }) + offset + zero[r] + n.sample(rng);
                                let v = pink.next().map_or(v, |p| v + p);
                                (!lost(r)).then(|| round(v, sensors.pixel_m) + 0.0)
                            })
                            .collect::<Vec<_>>()
                    };
                let tip = truth.points_m.last().expect("the tip is tracked");
                let tip_y = camera_channel(tip, false, rng);
                let tip_x = camera_channel(tip, true, rng);
                channels.push((Channel::TipY, tip_y.clone()));
                channels.push((Channel::TipX, tip_x.clone()));
                let last = truth.points_m.len() - 1;
                for (j, p) in truth.points_m.iter().enumerate() {
                    // The last dot is the tip's mark, read once.
                    if j == last {
                        channels.push((Channel::DotY(j), tip_y.clone()));
                        channels.push((Channel::DotX(j), tip_x.clone()));
                    } else {
                        channels.push((Channel::DotY(j), camera_channel(p, false, rng)));
                        channels.push((Channel::DotX(j), camera_channel(p, true, rng)));
                    }
                }
            }
            Tracker::Laser(laser) => {
                let n = white(laser.noise_m);
                let offset = rng.gen_range(-sensors.rest_offset_m..sensors.rest_offset_m);
                let mut pink = bench
                    .pink_fraction
                    .map(|f| bench::pink(rows, laser.noise_m * f.sqrt(), c.layout.rate_hz, rng))
                    .unwrap_or_default()
                    .into_iter();
                let range = c.lab.dropouts.map_or(f64::INFINITY, |d| d.laser_range_m);
                let spot = &truth.points_m[0];
                let y: Vec<Option<f64>> = (0..rows)
                    .map(|r| {
                        let v = spot[r].1 + offset + zero_y[r] + n.sample(rng);
                        let v = pink.next().map_or(v, |p| v + p);
                        // Out of its range the laser reads its sentinel,
                        // which the file leaves empty.
                        (!lost(r) && v.abs() <= range).then(|| round(v, laser.step_m) + 0.0)
                    })
                    .collect();
                channels.push((Channel::DotY(0), y));
            }
        }
    }
    rec.channels = channels;
}
