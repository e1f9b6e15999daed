//! `finrs merge-camera` as a user runs it: a DAQ file and a tracker's CSV
//! in, a free recording with the camera's columns out; refusals name the
//! file and the rule.

use std::process::Command;

use finrs::recording::{Channel, Recording};

fn finrs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_finrs"))
}

/// `finrs merge-camera` in `dir` of `daq.csv` and `track.csv` (50
/// frames/s, 1e-4 m per pixel, y flipped) into `out`.
fn merge(dir: &std::path::Path, out: &str) -> std::process::Output {
    finrs()
        .current_dir(dir)
        .args([
            "merge-camera",
            "--daq",
            "daq.csv",
            "--track",
            "track.csv",
            "--fps",
            "50",
            "--m-per-px",
            "1e-4",
            "--flip-y",
            "--out",
            out,
        ])
        .output()
        .unwrap()
}

/// [`merge`] into `out`, which must succeed: the merged tip.
fn merged_tip(dir: &std::path::Path, out: &str) -> Vec<Option<f64>> {
    let run = merge(dir, out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let merged = Recording::read(&dir.join(out)).unwrap();
    merged.channel(Channel::TipY).unwrap().to_vec()
}

#[test]
fn a_track_is_merged_into_the_daq_recording() {
    let dir = std::env::temp_dir().join(format!("finrs-merge-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 2 s at 1 kHz, a 2 V step from 0.5 s.
    let mut daq = String::from(
        "# format = \"ipmc-bench/1\"\n# segments = 3\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0002858\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V,v2_V,v3_V,i1_A\n",
    );
    for i in 0..2000 {
        let v = if i >= 500 { 2 } else { 0 };
        daq.push_str(&format!("{},{v},{v},{v},0.001\n", i as f64 / 1000.0));
    }
    std::fs::write(dir.join("daq.csv"), daq).unwrap();
    // 50 fps, the camera's clock 0.2 s behind; the tip 20 px up from 0.5 s.
    let mut track = String::from("frame,dot,x_px,y_px\n");
    for f in 0..90 {
        let t_daq = f as f64 / 50.0 + 0.2;
        let y = if t_daq >= 0.5 { 280 } else { 300 };
        track.push_str(&format!("{f},tip,640,{y}\n"));
        if f == 15 {
            track.push_str(&format!("{f},sync,,\n"));
        }
    }
    std::fs::write(dir.join("track.csv"), track).unwrap();
    let out = merge(&dir, "free.csv");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("camera clock + 0.2000 s = DAQ clock"),
        "{stderr}"
    );
    let rec = Recording::read(&dir.join("free.csv")).unwrap();
    let tip = rec.channel(Channel::TipY).unwrap();
    // A frame every 20 rows from 0.2 s; 2 mm up once the step is on.
    assert_eq!(tip.iter().flatten().count(), 90);
    assert_eq!(tip[200], Some(0.0));
    assert!((tip[1000].unwrap() - 2e-3).abs() < 1e-9, "{:?}", tip[1000]);
    assert_eq!(tip[1001], None);

    // Into a folder not there yet: made, as every command's outputs are.
    assert_eq!(merged_tip(&dir, "merged/run 1/free.csv"), tip);
    // In place: the DAQ file becomes the merged one.
    assert_eq!(merged_tip(&dir, "daq.csv"), tip);

    // Without --fps a track with no time_s is refused by file and line.
    let out = finrs()
        .current_dir(&dir)
        .args([
            "merge-camera",
            "--daq",
            "daq.csv",
            "--track",
            "track.csv",
            "--m-per-px",
            "1e-4",
            "--out",
            "x.csv",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("track.csv:1: no `time_s` column"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
