//! A lab's exports through `finrs import` and `finrs diagnose`, as a user
//! runs them, with no hand edit between: a session of four LabVIEW-like
//! XLSX exports of one strip (one segment, free; 100 rows/s and no time
//! column; the voltage read back by the DAQ, its rest a few millivolts in
//! 0.3 mV steps; the current in mA rounded to 0.1 mA; a laser's distance
//! with its sentinel -99.9999 over stretches; a derived resistance that
//! is `Inf` where the current reads 0), made by the model itself, one of
//! them with a contact that lifted for 1.3 s at its step. The diagnosis
//! must refuse nothing, name no catalogue effect (the strip is the
//! model's own: `none`), and name the contact fault and the laser's
//! out-of-range stretches as the bench's.

use std::path::{Path, PathBuf};
use std::process::Command;

use finrs::analysis::fit::FIT_ELEMENTS;
use finrs::model::params::ModelFile;
use finrs::model::predict::predict;
use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::Fixture;
use finrs::wave::Wave;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rust_xlsxwriter::Workbook;

/// The bench's rate, rows/s (no time column: the row's index is its time).
const RATE_HZ: f64 = 100.0;
/// The DAQ's read-back: its offset at rest, its noise and its step, V.
const OFFSET_V: f64 = 0.002;
const ADC_NOISE_V: f64 = 0.0002;
const ADC_STEP_V: f64 = 0.0003;
/// The shunt's noise, mA, before the export rounds to 0.1 mA.
const SHUNT_NOISE_MA: f64 = 0.04;
/// The laser's distance to the strip at rest and its noise, mm.
const LASER_REST_MM: f64 = 31.4159;
const LASER_NOISE_MM: f64 = 0.003;
/// The laser's sentinel when the spot leaves its range.
const SENTINEL: f64 = -99.9999;

/// One export: a step of `volts` after 1.5 s at rest, held `hold_s`, then
/// 2.5 s off.
struct Export {
    name: &'static str,
    volts: f64,
    hold_s: f64,
    /// Rows where the laser lost the spot, `(first, end)`, the end not
    /// included.
    lost: &'static [(usize, usize)],
    /// Rows after the step over which the contact was open.
    open_rows: usize,
}

const EXPORTS: [Export; 4] = [
    Export {
        name: "01_step_1V",
        volts: 1.0,
        hold_s: 4.0,
        // 0.25 s lost as the tip moves, and two readings (no stretch).
        lost: &[(250, 275), (600, 602)],
        open_rows: 0,
    },
    Export {
        name: "02_step_2V",
        volts: 2.0,
        hold_s: 4.0,
        lost: &[],
        open_rows: 0,
    },
    Export {
        name: "03_step_2.5V",
        volts: 2.5,
        hold_s: 4.0,
        lost: &[],
        // The clamp's contact lifted: 1.3 s with no voltage on the strip.
        open_rows: 130,
    },
    Export {
        name: "04_step_1.5V",
        volts: 1.5,
        hold_s: 3.0,
        lost: &[(500, 540)],
        open_rows: 0,
    },
];

/// Rounds `x` to a multiple of `step`, as the export writes it (0, not
/// -0).
fn round_to(x: f64, step: f64) -> f64 {
    let digits = (-step.log10()).ceil().max(0.0) as usize + 1;
    let y: f64 = format!("{:.*}", digits, (x / step).round() * step)
        .parse()
        .unwrap();
    y + 0.0
}

/// Writes `e` as LabVIEW exports a graph, the strip the seed's
/// (`main_m_2006`) at session time `t_session_s`; its length, s.
fn write_export(path: &Path, e: &Export, t_session_s: f64, rng: &mut rand::rngs::StdRng) -> f64 {
    let drive = Drive {
        segments: 1,
        fixture: Fixture::Free,
        rest_s: 1.5,
        duration_s: e.hold_s,
        off_s: 2.5,
        rate_hz: RATE_HZ,
    };
    let wave = Wave::parse(&format!("step:{}", e.volts)).unwrap();
    let commanded = drive_recording(&wave, &drive).unwrap();
    let spec = ModelFile::main_m_2006()
        .spec_for(&commanded.meta.geometry())
        .unwrap();
    let adc = Normal::new(0.0, ADC_NOISE_V).unwrap();
    // What the DAQ read back: the drive with its offset and noise, in its
    // steps; a rest is never 0 V.
    let mut read = commanded.clone();
    for row in 0..read.t_s.len() {
        let v = commanded.v_v[row][0] + OFFSET_V + adc.sample(rng);
        read.v_v[row][0] = round_to(v, ADC_STEP_V);
    }
    // What the strip saw: the same, but nothing while the contact was open.
    let mut strip = read.clone();
    let step_row = drive.start_row();
    for row in step_row..step_row + e.open_rows {
        strip.v_v[row][0] = round_to(OFFSET_V + adc.sample(rng), ADC_STEP_V);
    }
    let traces = predict(
        &strip,
        &spec,
        FIT_ELEMENTS,
        1.0 / RATE_HZ,
        t_session_s,
        None,
        &mut |_| {},
    )
    .unwrap();
    let shunt = Normal::new(0.0, SHUNT_NOISE_MA).unwrap();
    let laser = Normal::new(0.0, LASER_NOISE_MM).unwrap();

    let mut book = Workbook::new();
    let sheet = book.add_worksheet();
    sheet.set_name("Sheet1").unwrap();
    let header = [
        "Time Point - Voltage",
        "Y axis - Voltage",
        "Time Point - Current",
        "Y axis - Current",
        "Time Point - Distance",
        "Y axis - Distance",
        "Resistance (Ohm)",
    ];
    for (col, name) in header.iter().enumerate() {
        sheet.write_string(0, col as u16, *name).unwrap();
    }
    for row in 0..read.t_s.len() {
        let v = read.v_v[row][0];
        let i_ma = round_to(traces.currents_a[0][row] * 1e3 + shunt.sample(rng), 0.1);
        // The laser faces the side the strip bends toward.
        let distance_mm = if e.lost.iter().any(|&(a, b)| (a..b).contains(&row)) {
            SENTINEL
        } else {
            round_to(
                LASER_REST_MM - traces.tip_y_m[row] * 1e3 + laser.sample(rng),
                1e-4,
            )
        };
        let point = row as f64;
        let r = row as u32 + 1;
        for (col, x) in [point, v, point, i_ma, point, distance_mm]
            .into_iter()
            .enumerate()
        {
            sheet.write_number(r, col as u16, x).unwrap();
        }
        if i_ma == 0.0 {
            sheet.write_string(r, 6, "Inf").unwrap();
        } else {
            sheet
                .write_number(r, 6, round_to(v / (i_ma * 1e-3), 0.01))
                .unwrap();
        }
    }
    book.save(path).unwrap();
    read.t_s.len() as f64 / RATE_HZ
}

/// The mapping a user writes for these exports (docs/import.md), with
/// each export's session time.
fn mapping(starts: &[(&str, f64)]) -> String {
    let g = finrs::recording::Geometry::THESIS_2006;
    let mut m = format!(
        r#"format = "finrs-import/1"

[time]
rate_hz = {RATE_HZ:?}

[[channel]]
to = "v1_V"
column = "Y axis - Voltage"

[[channel]]
to = "i1_A"
column = "Y axis - Current"
scale = 0.001

[[channel]]
to = "tip_y_m"
column = "Y axis - Distance"
scale = 0.001
sign = -1
zero = "opening"
out_of_range = [{SENTINEL:?}]

[metadata]
segments = 1
length_m = {:?}
width_m = {:?}
thickness_m = {:?}
fixture = "free"
medium = "air"
sample = "SYNTHETIC-E2E"
"#,
        g.length_m, g.width_m, g.thickness_m
    );
    for (name, t) in starts {
        m += &format!("\n[files.\"{name}.xlsx\"]\nt_session_start_s = {t:?}\n");
    }
    m
}

fn finrs(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn lab_exports_go_through_import_and_diagnose_with_no_hand_edit() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("finrs-import-diagnose-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let exports = dir.join("exports");
    std::fs::create_dir_all(&exports).unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(48);
    let mut starts = Vec::new();
    let mut t_session_s = 0.0;
    for e in &EXPORTS {
        let length_s = write_export(
            &exports.join(format!("{}.xlsx", e.name)),
            e,
            t_session_s,
            &mut rng,
        );
        starts.push((e.name, t_session_s));
        t_session_s += length_s + 20.0;
    }
    let map = dir.join("lab.toml");
    std::fs::write(&map, mapping(&starts)).unwrap();
    let path = |p: &Path| p.to_str().unwrap().to_string();
    let session = dir.join("session");

    let (ok, _, err) = finrs(&[
        "import",
        &path(&exports),
        "--mapping",
        &path(&map),
        "--out",
        &path(&session),
    ]);
    assert!(ok, "import refused: {err}");
    // The laser's sentinels became empty fields.
    assert!(err.contains("sentinels"), "{err}");

    let (json, report) = (dir.join("v.json"), dir.join("report"));
    let (ok, out, err) = finrs(&[
        "diagnose",
        &path(&session),
        "--json",
        &path(&json),
        "--report",
        &path(&report),
    ]);
    assert!(ok, "diagnose refused: {err}");
    eprintln!("{out}{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let md = std::fs::read_to_string(report.join("REPORT.md")).unwrap();
    std::fs::remove_dir_all(&dir).ok();

    // The strip is the model's own: no catalogue effect for the bench's
    // artefacts.
    assert_eq!(v["verdict"], "none", "{out}");
    assert_eq!(v["causes"], serde_json::json!([]), "{out}");
    // Every export gave its session time: drying is testable.
    let untestable: Vec<&str> = v["untestable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["effect"].as_str().unwrap())
        .collect();
    assert!(!untestable.contains(&"dehydration"), "{untestable:?}");

    let faults = v["faults"].as_array().unwrap();
    let kinds: Vec<(&str, &str, &str)> = faults
        .iter()
        .map(|f| {
            (
                f["recording"].as_str().unwrap(),
                f["kind"].as_str().unwrap(),
                f["channel"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        kinds,
        [
            ("01_step_1V.csv", "out-of-range", "tip_y_m"),
            ("03_step_2.5V.csv", "contact-fault", "v1_V"),
            ("04_step_1.5V.csv", "out-of-range", "tip_y_m"),
        ],
        "{out}"
    );
    let seconds = |f: &serde_json::Value, key: &str| f[key].as_f64().unwrap();
    // The contact: from the step to its closing, 1.3 s later.
    assert!(
        (seconds(&faults[1], "from_s") - 1.5).abs() < 1e-6,
        "{}",
        faults[1]
    );
    assert!(
        (seconds(&faults[1], "to_s") - 2.8).abs() < 1e-6,
        "{}",
        faults[1]
    );
    // One stretch each: the laser's 25 and 40 lost readings; two are none.
    for (f, lost_s) in [(&faults[0], 0.25), (&faults[2], 0.40)] {
        assert_eq!(f["stretches"], 1, "{f}");
        assert!((seconds(f, "total_s") - lost_s).abs() < 1e-6, "{f}");
    }
    assert!(
        out.contains("bench, not the strip: 03_step_2.5V.csv: contact fault on segment 1"),
        "{out}"
    );
    assert!(
        out.contains("bench, not the strip: 01_step_1V.csv: tip_y_m out of range"),
        "{out}"
    );
    assert!(
        md.contains("| 03_step_2.5V.csv | contact-fault | v1_V | 1.500 | 2.800 | 1 | 1.300 |"),
        "{md}"
    );
}
