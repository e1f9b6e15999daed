//! The merge on a synthetic track whose clock offset, frame rate, scale
//! and motion are known.

use super::*;
use crate::camera::track::Track;
use crate::recording::{Geometry, Medium, Metadata, Voltages};

const ONSET_S: f64 = 1.2;
const OFFSET_S: f64 = 0.35;
const FPS: f64 = 60.0;
const M_PER_PX: f64 = 5e-5;

/// The tip's truth: across, along (m) at DAQ time `t`.
fn tip_m(t: f64) -> (f64, f64) {
    if t < ONSET_S {
        return (0.0, 0.0);
    }
    let s = 1.0 - (-(t - ONSET_S) / 0.3).exp();
    (2e-3 * s, -1e-4 * s)
}

fn daq(fixture: Fixture) -> Recording {
    let rows = 6000;
    let t_s: Vec<f64> = (0..rows).map(|i| i as f64 / 1000.0).collect();
    let v: Vec<[f64; 3]> = t_s
        .iter()
        .map(|&t| {
            if (ONSET_S..4.0).contains(&t) {
                [2.0; 3]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    Recording {
        meta: Metadata {
            dots_s_m: Some(vec![0.025, 0.05]),
            notes: Some("from the board".to_string()),
            t_session_start_s: Some(10.0),
            ..Metadata::new(3, Geometry::THESIS_2006, fixture, Medium::Air)
        },
        v_v: Voltages::from_rows(3, &v),
        channels: vec![(Channel::Current(0), vec![Some(0.01); rows])],
        t_s,
    }
}

/// 60 fps from camera time 0 (DAQ time 0.35) for 7 s, the image's y
/// pointing down (flipped), the tip at (400, 300) px at rest and dot 1
/// halfway, the LED on from the frame at the wave's start.
fn track_csv() -> String {
    let mut s = String::from("frame,time_s,dot,x_px,y_px\n");
    for f in 0..(7.0 * FPS) as usize {
        let t_cam = f as f64 / FPS;
        let (y, x) = tip_m(t_cam + OFFSET_S);
        s.push_str(&format!(
            "{f},{t_cam},tip,{},{}\n",
            400.0 + x / M_PER_PX,
            300.0 - y / M_PER_PX
        ));
        s.push_str(&format!(
            "{f},{t_cam},1,{},{}\n",
            200.0 + 0.5 * x / M_PER_PX,
            300.0 - 0.5 * y / M_PER_PX
        ));
        if t_cam + OFFSET_S >= ONSET_S - 1e-9 {
            s.push_str(&format!("{f},{t_cam},sync,,\n"));
        }
    }
    s
}

fn options() -> MergeOptions {
    MergeOptions {
        flip_y: true,
        ..MergeOptions::new(M_PER_PX)
    }
}

#[test]
fn the_track_lands_on_the_daq_rows_in_metres_from_rest() {
    let track = Track::parse("t.csv", &track_csv(), None).unwrap();
    let m = merge(&daq(Fixture::Free), "d.csv", &track, "t.csv", &options()).unwrap();
    assert!((m.offset_s - OFFSET_S).abs() < 1e-9, "{}", m.offset_s);
    // Frames from DAQ time 0.35 to 6 s: (6 − 0.35) · 60 = 339 per mark.
    assert_eq!(m.placed, 2 * 339);
    assert_eq!(m.outside, 2 * (420 - 339));
    let r = &m.recording;
    let tip_y = r.channel(Channel::TipY).unwrap();
    let tip_x = r.channel(Channel::TipX).unwrap();
    let dot_y = r.channel(Channel::DotY(0)).unwrap();
    let mut checked = 0;
    for (row, &t) in r.t_s.iter().enumerate() {
        let Some(y) = tip_y[row] else {
            assert!(tip_x[row].is_none());
            continue;
        };
        // The frame's own time (within the half millisecond of its row).
        let t_frame = ((t - OFFSET_S) * FPS).round() / FPS + OFFSET_S;
        let (want_y, want_x) = tip_m(t_frame);
        assert!((y - want_y).abs() < 1e-9, "row {row}: {y} against {want_y}");
        assert!((tip_x[row].unwrap() - want_x).abs() < 1e-9);
        assert!((dot_y[row].unwrap() - 0.5 * want_y).abs() < 1e-9);
        checked += 1;
    }
    assert_eq!(checked, 339);
    // The rows in between have no position: nothing interpolated.
    assert_eq!(tip_y.iter().filter(|v| v.is_none()).count(), 6000 - 339);
    assert_eq!(r.meta.t_session_start_s, Some(10.0));
    assert!(r
        .meta
        .notes
        .as_deref()
        .unwrap()
        .starts_with("from the board; camera merged by finrs: 678 positions"));
    // Written (7 significant digits) and read back as a valid free
    // recording.
    let path = std::env::temp_dir().join(format!("finrs-merge-{}.csv", std::process::id()));
    r.write(&path).unwrap();
    let back = Recording::read(&path).unwrap();
    let read = back.channel(Channel::TipY).unwrap();
    let same = read.iter().zip(tip_y).all(|(a, b)| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= 1e-6 * b.abs().max(1e-9),
        (None, None) => true,
        _ => false,
    });
    let first = read.iter().zip(tip_y).position(|(a, b)| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() > 1e-6 * b.abs().max(1e-9),
        (None, None) => false,
        _ => true,
    });
    assert!(
        same,
        "the written file holds the same positions and gaps: row {first:?}: {:?} against {:?}",
        first.map(|r| read[r]),
        first.map(|r| tip_y[r])
    );
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn a_given_sync_time_and_an_unflipped_image() {
    let csv: String = track_csv()
        .lines()
        .filter(|l| !l.contains("sync"))
        .map(|l| format!("{l}\n"))
        .collect();
    let track = Track::parse("t.csv", &csv, None).unwrap();
    let e = merge(&daq(Fixture::Free), "d.csv", &track, "t.csv", &options()).unwrap_err();
    assert!(e.to_string().contains("no `sync` row"), "{e}");
    let opts = MergeOptions {
        sync_time_s: Some(ONSET_S - OFFSET_S),
        flip_y: false,
        ..options()
    };
    let m = merge(&daq(Fixture::Free), "d.csv", &track, "t.csv", &opts).unwrap();
    let y = m.recording.channel(Channel::TipY).unwrap();
    let last = y.iter().rev().flatten().next().unwrap();
    assert!(
        *last < -1.9e-3,
        "{last}: unflipped, the image's down is negative"
    );
}

#[test]
fn what_cannot_be_merged_is_refused_by_file_and_rule() {
    let track = Track::parse("t.csv", &track_csv(), None).unwrap();
    let e = merge(&daq(Fixture::Blocked), "d.csv", &track, "t.csv", &options()).unwrap_err();
    assert!(
        e.to_string().starts_with("d.csv: a blocked recording"),
        "{e}"
    );
    let mut one_dot = daq(Fixture::Free);
    one_dot.meta.dots_s_m = None;
    let e = merge(&one_dot, "d.csv", &track, "t.csv", &options()).unwrap_err();
    assert!(
        e.to_string()
            .contains("t.csv: dot 1: the recording's dots_s_m has 0 dots"),
        "{e}"
    );
    let mut idle = daq(Fixture::Free);
    idle.v_v = Voltages::from_rows(3, vec![[0.0; 3]; 6000]);
    let e = merge(&idle, "d.csv", &track, "t.csv", &options()).unwrap_err();
    assert!(e.to_string().contains("no wave start"), "{e}");
    // A camera at 2 kHz against the 1 kHz DAQ.
    let fast = Track::parse(
        "f.csv",
        "frame,time_s,dot,x_px,y_px\n0,0,tip,1,1\n1,0.0005,tip,1,1\n2,0.001,tip,1,1\n3,0.0015,tip,1,1\n",
        None,
    )
    .unwrap();
    let opts = MergeOptions {
        sync_time_s: Some(0.001),
        ..options()
    };
    let mut early = daq(Fixture::Free);
    early.v_v = Voltages::from_rows(3, vec![[1.0; 3]; 6000]);
    let e = merge(&early, "d.csv", &fast, "f.csv", &opts).unwrap_err();
    assert!(e.to_string().contains("faster than the DAQ"), "{e}");
}

#[test]
fn a_track_file_that_breaks_a_rule_names_its_line() {
    for (text, says) in [
        (
            "frame,dot,x_px,y_px\n0,tip,1,1\n",
            "t.csv:1: no `time_s` column",
        ),
        ("frame,time_s,x_px,y_px\n", "t.csv:1: no `dot` column"),
        (
            "frame,time_s,dot,x_px,y_px\n0,0,tip,1,1\n1,0.1,nose,1,1\n",
            "t.csv:3: dot \"nose\"",
        ),
        (
            "frame,time_s,dot,x_px,y_px\n0,0,tip,1,1\n1,0.1,tip,x,1\n",
            "t.csv:3: x_px \"x\"",
        ),
        (
            "frame,time_s,dot,x_px,y_px\n1,0.1,tip,1,1\n0,0,tip,1,1\n",
            "t.csv:3: frame 0 at 0 s after frame 1",
        ),
        (
            "frame,time_s,dot,x_px,y_px\n0,0,tip,1\n",
            "t.csv:2: 4 fields, the header has 5",
        ),
    ] {
        let e = Track::parse("t.csv", text, None).unwrap_err().to_string();
        assert!(e.starts_with(says), "{e}");
    }
    // Frame numbers and a rate stand in for the times; a lost mark is no point.
    let t = Track::parse(
        "t.csv",
        "frame,dot,x_px,y_px\n0,tip,1,1\n30,tip,,\n60,tip,2,2\n",
        Some(30.0),
    )
    .unwrap();
    assert_eq!(t.points.len(), 2);
    assert_eq!(t.points[1].t_s, 2.0);
}
