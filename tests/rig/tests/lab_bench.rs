//! The lab-like bench (`finrs_rig::lab`): each artefact present in the
//! written session as docs/rig.md states it, and the sessions without it
//! unchanged byte for byte. Short sessions of the rig's own strip, no
//! diagnosis.

use std::path::{Path, PathBuf};

use finrs_rig::{Bench, Hidden, Sample, Sensors};
use rand::SeedableRng;

fn rng(seed: u64) -> rand::rngs::StdRng {
    rand::rngs::StdRng::seed_from_u64(seed)
}

/// A fresh directory under the system's temporary one.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("finrs-lab-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// FNV-1a over every file of `dir` (names and bytes, in name order): a
/// hash that no Rust release changes, unlike `DefaultHasher`'s.
fn hash_dir(dir: &Path) -> u64 {
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in names {
        eat(p.file_name().unwrap().to_string_lossy().as_bytes());
        eat(&std::fs::read(&p).unwrap());
    }
    h
}

/// The existing rigs' sessions, written by this build: an off-class strip
/// with two departures, mains pickup and every bench imperfection, and an
/// ideal strip with two effects on a perfect bench; a few short runs each.
fn existing_sessions(dir: &Path) -> (u64, u64) {
    let runs = finrs_rig::short_protocol(0.2);
    let pick =
        |idx: &[usize]| -> Vec<finrs_rig::Run> { idx.iter().map(|&i| runs[i].clone()).collect() };
    let mut r = rng(4242);
    let sample = Sample::draw_off_class(&mut r);
    let hidden = Hidden::draw_off_class(
        &["dehydration", "segment-crosstalk", "mains-pickup"],
        &mut r,
    )
    .unwrap();
    let sensors = Sensors::draw(&mut r);
    let bench = Bench::draw(&finrs_rig::IMPERFECTIONS, &mut r).unwrap();
    let off = dir.join("off-class");
    finrs_rig::write_session(
        &off,
        &sample,
        &hidden,
        &sensors,
        &bench,
        &pick(&[0, 3, 8, 9]),
        "HASH-1",
        &mut r,
    )
    .unwrap();
    let mut r = rng(4243);
    let sample = Sample::draw(&mut r);
    let hidden = Hidden::draw(&["large-deflection", "damping"], &mut r).unwrap();
    let sensors = Sensors::draw(&mut r);
    let ideal = dir.join("ideal");
    finrs_rig::write_session(
        &ideal,
        &sample,
        &hidden,
        &sensors,
        &Bench::default(),
        &pick(&[2, 4, 9]),
        "HASH-2",
        &mut r,
    )
    .unwrap();
    (hash_dir(&off), hash_dir(&ideal))
}

#[test]
fn the_existing_sessions_are_unchanged_byte_for_byte() {
    let dir = scratch("existing");
    let (off, ideal) = existing_sessions(&dir);
    std::fs::remove_dir_all(&dir).ok();
    // Written by main's rig (31b57b3) before the lab bench joined.
    assert_eq!(
        (off, ideal),
        (0x506b_16c4_e167_45d7, 0x4561_99bd_82aa_0a72),
        "{off:#x} {ideal:#x}"
    );
}

use finrs::recording::Voltages;
use finrs_rig::lab::{ContactFaults, Dropouts, Quantisation, Readback, ZeroDrift, ADC_STEP_V};
use finrs_rig::lab_session::Written;
use finrs_rig::strip::{run_lab, Lab, BLOCKED_MESH, MESH};
use finrs_rig::{LabBench, LabProtocol, Layout, Run, Tip};

/// A CSV's header and fields (empty ones `None`), read as text: files
/// with the DAQ's rests are checked here without the session reader.
fn table(path: &Path) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|f| (!f.is_empty()).then(|| f.parse::<f64>().unwrap()))
                .collect()
        })
        .collect();
    (header, rows)
}

/// Column `name` of `table`.
fn column(t: &(Vec<String>, Vec<Vec<Option<f64>>>), name: &str) -> Vec<Option<f64>> {
    let j =
        t.0.iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}"));
    t.1.iter().map(|r| r[j]).collect()
}

/// The session's recordings, in order.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut f: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    f.sort();
    f
}

/// A lab bench with nothing on, its streams seeded from `seed`.
fn nothing(seed: u64) -> LabBench {
    LabBench::draw(&[], &mut rng(seed)).unwrap()
}

fn sensors() -> Sensors {
    Sensors {
        current_a: 1e-4,
        camera_m: 5e-5,
        pixel_m: 1.09e-4,
        force_n: 2e-5,
        daq_step: 1e-6,
        rest_offset_m: 2e-4,
    }
}

/// The off-class strip of `seed` on the lab protocol with `lab`, into
/// `dir`.
fn lab_protocol_session(seed: u64, lab: &LabBench, dir: &Path) -> (Sample, Written) {
    let mut r = rng(seed);
    let mut sample = Sample::draw_off_class(&mut r);
    let hidden = Hidden::draw_off_class(&[], &mut r).unwrap();
    let p = LabProtocol::draw(&mut sample, &hidden, &mut r);
    let written = finrs_rig::write_lab(
        dir,
        &sample,
        &hidden,
        &sensors(),
        &Bench::default(),
        lab,
        &p.runs,
        &Layout::laser(p.laser),
        "LAB",
        &mut r,
    )
    .unwrap();
    (sample, written)
}

/// The off-class strip of `seed` on the short protocol's runs `pick`
/// (0.6 of the holds) with `lab`, into `dir`.
fn short_session(seed: u64, pick: &[usize], lab: &LabBench, dir: &Path) -> Written {
    let runs = finrs_rig::short_protocol(0.6);
    let runs: Vec<Run> = pick.iter().map(|&i| runs[i].clone()).collect();
    let mut r = rng(seed);
    let sample = Sample::draw_off_class(&mut r);
    let hidden = Hidden::draw_off_class(&[], &mut r).unwrap();
    finrs_rig::write_lab(
        dir,
        &sample,
        &hidden,
        &sensors(),
        &Bench::default(),
        lab,
        &runs,
        &Layout::camera(),
        "LAB",
        &mut r,
    )
    .unwrap()
}

#[test]
fn a_lab_session_is_five_recordings_of_about_twenty_minutes_at_100_rows_a_second() {
    use finrs_rig::sweep::{write_scenario, LabKind, Scenario};
    let s = Scenario {
        seed: 900,
        lab: Some(LabKind::Protocol),
        ..Scenario::default()
    };
    let dir = scratch("size");
    let expected = write_scenario(&s, &dir).unwrap();
    let recordings = files(&dir);
    assert_eq!(recordings.len(), 5);
    let mut seconds = 0.0;
    for f in &recordings {
        let t = table(f);
        assert_eq!(t.0, ["t_s", "v1_V", "i1_A", "dot1_y_m"]);
        let time: Vec<f64> = column(&t, "t_s").into_iter().map(Option::unwrap).collect();
        assert!(time.windows(2).all(|w| ((w[1] - w[0]) - 0.01).abs() < 1e-9));
        seconds += time.last().unwrap();
        let text = std::fs::read_to_string(f).unwrap();
        assert!(text.contains("# segments = 1\n") && text.contains("# dots_s_m = ["));
        assert!(text.contains("# t_session_start_s = "));
    }
    let minutes = seconds / 60.0;
    assert!((17.0..23.0).contains(&minutes), "{minutes} min");
    // The lab's faults allow `unexplained`; drift is never a name.
    assert!(expected.unexplained_ok && expected.allowed.contains(&"bench:drift"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn currents_read_in_steps_a_rest_in_none_or_one_and_the_load_cell_in_counts() {
    let step = 1e-4;
    let mut lab = nothing(1);
    lab.quantisation = Some(Quantisation {
        current_a: step,
        force_n: 2e-5,
    });
    let dir = scratch("steps");
    // A free step and a blocked one.
    short_session(501, &[0, 8], &lab, &dir);
    let on_grid = |v: f64, q: f64| ((v / q) - (v / q).round()).abs() < 1e-6;
    let mut rest_steps = Vec::new();
    for f in files(&dir) {
        let t = table(&f);
        for k in 1..=3 {
            let i = column(&t, &format!("i{k}_A"));
            assert!(
                i.iter().all(|v| on_grid(v.unwrap(), step)),
                "{}",
                f.display()
            );
            // The opening rest (1.2 s): noise of one step's size reads
            // mostly as no step or one.
            rest_steps.extend(i[..1200].iter().map(|v| (v.unwrap() / step).round().abs()));
        }
        if let Some(j) = t.0.iter().position(|h| h == "force_N") {
            assert!(t.1.iter().all(|r| on_grid(r[j].unwrap(), 2e-5)));
        }
    }
    let within_one = rest_steps.iter().filter(|&&s| s <= 1.0).count() as f64;
    let share = within_one / rest_steps.len() as f64;
    assert!(share > 0.8, "{share}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_laser_reads_nothing_out_of_its_range_or_where_it_lost_the_spot() {
    let range = 1.5e-3;
    let mut lab = nothing(2);
    lab.dropouts = Some(Dropouts {
        per_min: 3.0,
        max_s: 1.5,
        frame_loss: 0.0,
        laser_range_m: range,
    });
    let dir = scratch("laser");
    lab_protocol_session(502, &lab, &dir);
    let (mut stretches, mut out_of_range) = (0, 0);
    for f in files(&dir) {
        let t = table(&f);
        let y = column(&t, "dot1_y_m");
        // Never a sentinel: whatever is written lies within the range.
        assert!(y.iter().flatten().all(|v| v.abs() <= range));
        let mut r = 0;
        while r < y.len() {
            if y[r].is_some() {
                r += 1;
                continue;
            }
            let start = r;
            while r < y.len() && y[r].is_none() {
                r += 1;
            }
            stretches += 1;
            // Beside an edge of the range: the strip went out of it.
            let near =
                |v: Option<&Option<f64>>| v.and_then(|v| *v).is_some_and(|v| v.abs() > 0.8 * range);
            if near(y.get(start.wrapping_sub(1))) && near(y.get(r)) {
                out_of_range += 1;
            }
        }
    }
    assert!(
        stretches >= 10 && out_of_range >= 1,
        "{stretches} {out_of_range}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_camera_drops_frames() {
    let mut lab = nothing(3);
    lab.dropouts = Some(Dropouts {
        per_min: 2.0,
        max_s: 1.0,
        frame_loss: 0.02,
        laser_range_m: 5e-3,
    });
    let dir = scratch("camera");
    short_session(503, &[0, 1, 2], &lab, &dir);
    let (mut frames, mut dropped) = (0, 0);
    for f in files(&dir) {
        let t = table(&f);
        let y = column(&t, "tip_y_m");
        for frame in 0.. {
            let row = (frame as f64 / 30.0 * 1000.0).round() as usize;
            if row >= y.len() {
                break;
            }
            frames += 1;
            dropped += usize::from(y[row].is_none());
        }
    }
    let share = dropped as f64 / frames as f64;
    assert!((0.01..0.2).contains(&share), "{dropped} of {frames}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_voltage_reads_back_millivolts_off_and_a_4_v_step_a_hair_past_4_v() {
    let mut lab = nothing(4);
    lab.readback = Some(Readback {
        offsets_v: [1.5e-3; 8],
        noise_v: 0.2e-3,
        step_v: ADC_STEP_V,
    });
    let dir = scratch("readback");
    short_session(504, &[0, 2], &lab, &dir);
    let recordings = files(&dir);
    for f in &recordings {
        let t = table(f);
        for k in 1..=3 {
            let v: Vec<f64> = column(&t, &format!("v{k}_V"))
                .into_iter()
                .flatten()
                .collect();
            let rest = &v[..1200];
            assert!(rest.iter().all(|x| x.abs() < 5e-3) && rest.iter().any(|&x| x != 0.0));
            let mean = rest.iter().sum::<f64>() / rest.len() as f64;
            assert!((mean - 1.5e-3).abs() < 0.3e-3, "{mean}");
            // On the ADC's grid, as exported in microvolts.
            assert!(v
                .iter()
                .all(|x| (x - (x / ADC_STEP_V).round() * ADC_STEP_V).abs() <= 0.5e-6));
        }
    }
    let t = table(&recordings[1]);
    let v1: Vec<f64> = column(&t, "v1_V").into_iter().flatten().collect();
    let held = &v1[1300..3000];
    assert!(
        held.iter().all(|&x| x > 4.0 && x < 4.004),
        "{:?}",
        &held[..5]
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_open_contact_reads_its_voltage_but_passes_no_current_and_leaves_the_strip_still() {
    let mut lab = nothing(5);
    lab.contact = Some(ContactFaults { per_recording: 1.0 });
    let dir = scratch("contact");
    let (_, written) = lab_protocol_session(505, &lab, &dir);
    for (f, fault) in files(&dir).iter().zip(&written.faults) {
        let fault = fault.expect("every recording has one");
        let t = table(f);
        let (v, i, y) = (
            column(&t, "v1_V"),
            column(&t, "i1_A"),
            column(&t, "dot1_y_m"),
        );
        let open = fault.from_row..fault.from_row + fault.rows;
        assert!((30..=200).contains(&fault.rows));
        assert!(open.clone().all(|r| v[r].unwrap().abs() >= 1.0));
        let mean_abs_i = open.clone().map(|r| i[r].unwrap()).sum::<f64>().abs() / fault.rows as f64;
        assert!(mean_abs_i < 0.1e-3, "{mean_abs_i}");
        // The strip stays where it was until the contact closes, then
        // charges: the current's spike comes late.
        let before = y[fault.from_row - 1].unwrap();
        let moved = open
            .clone()
            .map(|r| (y[r].unwrap() - before).abs())
            .fold(0.0, f64::max);
        assert!(moved < 0.1e-3, "{moved}");
        let closed = i[open.end].unwrap().abs();
        assert!(closed > 3e-3, "{closed}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_curl_bends_the_strip_as_the_square_of_the_distance_from_the_clamp_and_loads_the_held_tip() {
    let mut r = rng(6);
    let sample = Sample::draw(&mut r);
    let hidden = Hidden {
        damping_ratio: Some(0.05),
        ..Hidden::default()
    };
    let (ei, _) = finrs_rig::strip::section(&sample, &hidden);
    let length = sample.length_m;
    // The free tip curls 2 mm over 20 s.
    let tip_m = |t: f64| 2e-3 * t / 20.0;
    let curl = move |t: f64| ei * 2.0 * tip_m(t) / (length * length);
    let lab = Lab {
        curl_nm: Some(&curl),
        ..Lab::default()
    };
    let rows = 2000;
    let volts = Voltages::zeros(3, rows);
    let dots = finrs_rig::session::DOTS_S_M;
    let camera = vec![true; rows];
    let (free, _) = run_lab(
        &sample,
        &hidden,
        MESH,
        Tip::Free,
        &volts,
        0.01,
        0.0,
        &camera,
        &dots,
        &lab,
    );
    let tip = free.points_m[4][rows - 1].1;
    let want = tip_m((rows - 1) as f64 * 0.01);
    assert!((tip / want - 1.0).abs() < 0.01, "{tip} {want}");
    for (j, s) in dots.iter().enumerate() {
        let ratio = free.points_m[j][rows - 1].1 / tip;
        let square = (s / length).powi(2);
        assert!(
            (ratio / square - 1.0).abs() < 0.01,
            "dot {j}: {ratio} {square}"
        );
    }
    // Held at the tip, the curl presses on the load cell: 3 EI d / L³.
    let none = vec![false; rows];
    let (held, _) = run_lab(
        &sample,
        &hidden,
        BLOCKED_MESH,
        Tip::Pinned,
        &volts,
        0.01,
        0.0,
        &none,
        &[],
        &lab,
    );
    let force = held.force_n[rows - 1];
    let want = 3.0 * ei * want / length.powi(3);
    assert!((force / want - 1.0).abs() < 0.01, "{force} {want}");
}

#[test]
fn a_drifting_session_follows_its_curl_tip_and_dots() {
    use finrs_rig::lab::Curl;
    let mut lab = nothing(7);
    lab.curl = Some(Curl {
        sigma_m: 3e-3,
        tau_s: 60.0,
    });
    let dir = scratch("drift");
    // Two free steps and a blocked one, with their pauses: about 40 s.
    let written = short_session(507, &[0, 1, 8], &lab, &dir);
    let curl = written.curl_tip_m.unwrap();
    let path = files(&dir);
    for (f, t0) in path.iter().zip(&written.starts_s).take(2) {
        let t = table(f);
        let time = column(&t, "t_s");
        let y = column(&t, "tip_y_m");
        // The opening rest: the tip sits where the curl has it (the rest
        // calibrated at the session's start), give or take the camera's
        // 0.2 mm rest offset and its noise.
        let rest: Vec<(f64, f64)> = (0..1200)
            .filter_map(|r| y[r].map(|v| (v, curl.at(t0 + time[r].unwrap()))))
            .collect();
        let off = rest.iter().map(|(v, c)| v - c).sum::<f64>() / rest.len() as f64;
        assert!(off.abs() < 0.35e-3, "{}: {off}", f.display());
    }
    // Over the session the curl moved by more than the camera resolves.
    let end = *written.starts_s.last().unwrap() + 5.0;
    let moved = (0..=(end as usize))
        .map(|s| curl.at(s as f64).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.3e-3, "{moved}");
    // The blocked recording's force starts tared at 0 and follows the curl.
    let t = table(&path[2]);
    let force: Vec<f64> = column(&t, "force_N").into_iter().flatten().collect();
    let head = force[..100].iter().sum::<f64>() / 100.0;
    assert!(head.abs() < 3e-5, "{head}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_carried_over_recording_opens_where_the_last_one_left_the_strip() {
    let dir_on = scratch("carry-on");
    let dir_off = scratch("carry-off");
    let mut lab = nothing(8);
    lab.carry_over = true;
    // A 2.5 V step, then a 4 V one 10 s later.
    let on = short_session(508, &[1, 2], &lab, &dir_on);
    let off = short_session(508, &[1, 2], &nothing(8), &dir_off);
    assert!(on.opening[0].is_rest() && !on.opening[1].is_rest());
    assert!(off.opening.iter().all(|s| s.is_rest()));
    // The same noise: the difference is what was carried.
    let opening = |dir: &Path| {
        let t = table(&files(dir)[1]);
        column(&t, "tip_y_m")[..1200].iter().flatten().sum::<f64>()
            / column(&t, "tip_y_m")[..1200].iter().flatten().count() as f64
    };
    let carried = opening(&dir_on) - opening(&dir_off);
    assert!(carried.abs() > 0.2e-3, "{carried}");
    std::fs::remove_dir_all(&dir_on).ok();
    std::fs::remove_dir_all(&dir_off).ok();
}

#[test]
fn the_moment_is_larger_one_way_by_its_asymmetry() {
    let mut r = rng(9);
    let sample = Sample::draw(&mut r);
    let hidden = Hidden {
        damping_ratio: Some(0.1),
        ..Hidden::default()
    };
    let a = 0.2;
    let lab = Lab {
        asymmetry: a,
        ..Lab::default()
    };
    let rows = 2000;
    let camera = vec![true; rows];
    let tip = |level: f64| {
        let volts =
            Voltages::from_rows(3, (0..rows).map(|r| [if r < 100 { 0.0 } else { level }; 3]));
        let (t, _) = run_lab(
            &sample,
            &hidden,
            MESH,
            Tip::Free,
            &volts,
            1e-3,
            0.0,
            &camera,
            &[0.05],
            &lab,
        );
        t.points_m[0][rows - 1].1
    };
    let ratio = tip(2.0) / -tip(-2.0);
    let want = (1.0 + a / 2.0) / (1.0 - a / 2.0);
    assert!((ratio / want - 1.0).abs() < 1e-6, "{ratio} {want}");
}

#[test]
fn the_sensors_zeros_wander_between_recordings() {
    let spread = |lab: &LabBench, name: &str| {
        let dir = scratch(name);
        short_session(510, &[0, 1, 5, 6], lab, &dir);
        let means: Vec<f64> = files(&dir)
            .iter()
            .map(|f| {
                let i = column(&table(f), "i1_A");
                i[..1200].iter().flatten().sum::<f64>() / 1200.0
            })
            .collect();
        std::fs::remove_dir_all(&dir).ok();
        means.iter().fold(f64::MIN, |m, &v| m.max(v))
            - means.iter().fold(f64::MAX, |m, &v| m.min(v))
    };
    let mut lab = nothing(10);
    lab.zeros = Some(ZeroDrift {
        sigma_noise: 2.0,
        tau_s: 60.0,
    });
    let (wander, still) = (spread(&lab, "zeros-on"), spread(&nothing(10), "zeros-off"));
    // Without it, the rests' means agree to their noise (0.1 mA over
    // 1200 rows: 3 µA); with it they differ by a good part of the noise.
    assert!(still < 15e-6 && wander > 30e-6, "{still} {wander}");
}
