//! `finrs import` on exports built here as labs write them: a
//! LabVIEW-like XLSX (pairs of columns, no time column, 100 rows/s, a
//! laser's distance with `-99.9999` stretches, `Inf` in a derived column
//! nobody maps, currents rounded to 0.1 mA, rests of 0.3 to 1.1 mV), CSV
//! and TSV with decimal commas and time in ms; each refusal names the
//! file, the place and the rule; the command line over a session; the
//! example in `examples/lab-export/`.

use std::path::{Path, PathBuf};
use std::process::Command;

use finrs::import::{import, import_file, Mapping};
use finrs::recording::{Channel, Recording, MEASURED_QUANTUM};
use rust_xlsxwriter::{Format, Formula, Workbook};

/// A fresh folder for one test, removed after it.
struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        let dir = std::env::temp_dir().join(format!("finrs-import-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Dir(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.path(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, text).unwrap();
        path
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A cell of a fixture.
#[derive(Clone, Debug, PartialEq)]
enum Cell {
    N(f64),
    S(String),
    Blank,
    /// A formula and the result the spreadsheet cached for it.
    Formula(&'static str, &'static str),
}

/// A sheet: a header row, then the data.
#[derive(Clone)]
struct Sheet {
    header: Vec<&'static str>,
    rows: Vec<Vec<Cell>>,
    /// Merged blocks: first row, first column, last row, last column
    /// (0-based, as rust_xlsxwriter counts).
    merged: Vec<(u32, u16, u32, u16)>,
}

impl Sheet {
    /// Writes the workbook: this sheet, named `name`.
    fn save(&self, path: &Path, name: &str) {
        let mut book = Workbook::new();
        let ws = book.add_worksheet();
        ws.set_name(name).unwrap();
        for (c, h) in self.header.iter().enumerate() {
            ws.write_string(0, c as u16, *h).unwrap();
        }
        for (r, row) in self.rows.iter().enumerate() {
            let r = r as u32 + 1;
            for (c, cell) in row.iter().enumerate() {
                let c = c as u16;
                match cell {
                    Cell::N(x) => ws.write_number(r, c, *x).map(|_| ()),
                    Cell::S(s) => ws.write_string(r, c, s).map(|_| ()),
                    Cell::Blank => Ok(()),
                    Cell::Formula(f, result) => ws
                        .write_formula(r, c, Formula::new(*f).set_result(*result))
                        .map(|_| ()),
                }
                .unwrap();
            }
        }
        for &(r0, c0, r1, c1) in &self.merged {
            ws.merge_range(r0, c0, r1, c1, "", &Format::new()).unwrap();
        }
        book.save(path).unwrap();
    }

    /// The cell at a spreadsheet's row (1-based, the header is row 1)
    /// and column letter.
    fn set(&mut self, row: usize, col: char, cell: Cell) {
        let c = (col as u8 - b'A') as usize;
        self.rows[row - 2][c] = cell;
    }
}

/// What the LabVIEW-like export holds, for the assertions.
struct Lab {
    sheet: Sheet,
    v: Vec<f64>,
    i_ma: Vec<f64>,
    distance_mm: Vec<f64>,
}

const SENTINEL: f64 = -99.9999;
/// Rows of the LabVIEW-like export where the laser lost the spot.
const LOST: [std::ops::Range<usize>; 2] = [250..270, 400..405];

/// A LabVIEW graph exported to XLSX: 100 rows/s for 6 s (1.5 s at rest,
/// 3 s at 2 V, 1.5 s off), pairs of "Time Point" (the row's index) and
/// "Y axis" columns, an unused load cell, a laser's distance in mm and a
/// derived resistance that is `Inf` where the current reads 0.
fn labview() -> Lab {
    let header = vec![
        "Time Point - Current",
        "Y axis - Current",
        "Time Point - Voltage",
        "Y axis - Voltage",
        "Time Point - Load Cell",
        "Y axis - Load Cell",
        "Time Point - Distance",
        "Y axis - Distance",
        "Resistance (Ohm)",
    ];
    // A fixed sequence in place of noise: the same file every run.
    let wobble = |i: usize, k: usize| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5;
    let round = |x: f64, digits: i32| {
        let m = 10f64.powi(digits);
        format!("{:.*}", digits as usize, (x * m).round() / m)
            .parse::<f64>()
            .unwrap()
    };
    let (mut v, mut i_ma, mut distance_mm, mut rows) = (vec![], vec![], vec![], vec![]);
    for i in 0..600 {
        let t = i as f64 / 100.0;
        let on = (1.5..4.5).contains(&t);
        // The read-back's rest: 0.3 to 1.1 mV.
        let volts = if on { 2.0 } else { 0.0 } + round(0.0007 + 0.0008 * wobble(i, 1), 4);
        let current = if on {
            25.0 * (-(t - 1.5) / 0.4).exp() + 1.5
        } else if t >= 4.5 {
            -20.0 * (-(t - 4.5) / 0.4).exp()
        } else {
            0.0
        } + 0.08 * wobble(i, 2);
        let current = round(current, 1);
        let tip_mm = if on {
            2.0 * (1.0 - (-(t - 1.5) / 0.5).exp())
        } else if t >= 4.5 {
            1.9 * (-(t - 4.5) / 0.5).exp()
        } else {
            0.0
        };
        let distance = if LOST.iter().any(|r| r.contains(&i)) {
            SENTINEL
        } else {
            round(30.0 - tip_mm + 0.004 * wobble(i, 3), 4)
        };
        let point = Cell::N(i as f64);
        rows.push(vec![
            point.clone(),
            Cell::N(current),
            point.clone(),
            Cell::N(volts),
            point.clone(),
            Cell::N(round(0.01 * wobble(i, 4), 3)),
            point,
            Cell::N(distance),
            if current == 0.0 {
                Cell::S("Inf".into())
            } else {
                Cell::N(round(volts / (current * 1e-3), 2))
            },
        ]);
        v.push(volts);
        i_ma.push(current);
        distance_mm.push(distance);
    }
    Lab {
        sheet: Sheet {
            header,
            rows,
            merged: vec![],
        },
        v,
        i_ma,
        distance_mm,
    }
}

const LABVIEW_MAPPING: &str = r#"
format = "finrs-import/1"
[time]
rate_hz = 100
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
out_of_range = [-99.9999]
[metadata]
segments = 1
length_m = 0.025
width_m = 0.005
thickness_m = 0.0002
fixture = "free"
medium = "water"
sample = "LV-1"
"#;

fn mapping(text: &str) -> Mapping {
    Mapping::parse("lab.toml", text).unwrap()
}

/// Whether two measured values agree to what the format writes.
fn close(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= MEASURED_QUANTUM,
        (a, b) => a == b,
    }
}

#[test]
fn a_labview_export_becomes_a_recording_that_reads_back() {
    let dir = Dir::new("labview");
    let lab = labview();
    let path = dir.path("02_step.xlsx");
    lab.sheet.save(&path, "Sheet1");
    let m = mapping(LABVIEW_MAPPING);
    let imported = import(&path, &m).unwrap();
    let rec = &imported.recording;
    assert_eq!(rec.t_s.len(), 600);
    for (i, &t) in rec.t_s.iter().enumerate() {
        assert_eq!(t, i as f64 / 100.0);
    }
    // Voltages as the export holds them: the rests' millivolts kept.
    for (i, &v) in lab.v.iter().enumerate() {
        assert_eq!(rec.v_v[i][0], v, "row {i}");
    }
    assert!(lab.v[..150].iter().all(|v| (0.0003..=0.0011).contains(v)));
    let current = rec.channel(Channel::Current(0)).unwrap();
    for (i, &ma) in lab.i_ma.iter().enumerate() {
        assert!(close(current[i], Some(ma / 1000.0)), "row {i}");
    }
    // The tip: the laser's distance from its first second's mean, turned
    // about; the sentinels empty, nothing else.
    let opening: Vec<f64> = lab.distance_mm[..100].to_vec();
    let zero = opening.iter().sum::<f64>() / 100.0;
    let tip = rec.channel(Channel::TipY).unwrap();
    for (i, &d) in lab.distance_mm.iter().enumerate() {
        let want = (d != SENTINEL).then(|| -(d - zero) / 1000.0);
        assert!(close(tip[i], want), "row {i}: {:?} {want:?}", tip[i]);
    }
    let report = &imported.channels[2];
    assert_eq!((report.sentinels, report.empty_cells), (25, 0));
    assert!((report.zero_raw - zero).abs() < 1e-12);
    assert_eq!(report.column, "column H (\"Y axis - Distance\")");
    // The unmapped derived column holds `Inf`: not read, so not refused.
    assert!(lab.sheet.rows.iter().any(|r| r[8] == Cell::S("Inf".into())));

    let out = dir.path("02_step.csv");
    rec.write(&out).unwrap();
    let back = Recording::read(&out).unwrap();
    assert_eq!(back.t_s, rec.t_s);
    assert_eq!(back.v_v, rec.v_v);
    assert_eq!(back.meta.sample.as_deref(), Some("LV-1"));
    assert_eq!(
        back.meta.notes.as_deref(),
        Some("imported by finrs import from 02_step.xlsx (sheet \"Sheet1\") with lab.toml")
    );
    for ((c, a), (d, b)) in rec.channels.iter().zip(&back.channels) {
        assert_eq!(c, d);
        assert!(a.iter().zip(b).all(|(a, b)| close(*a, *b)), "{c:?}");
    }
}

#[test]
fn csv_and_tsv_with_decimal_commas_and_time_in_ms() {
    let dir = Dir::new("text");
    // A blocked run at 1 kHz: two segments, mV, mA (clipped at the
    // amplifier's 50 mA), mN; decimal commas, fields by `;`.
    let mut csv =
        String::from("Zeit [ms];U1 [mV];U2 [mV];I1 [mA];I2 [mA];Kraft [mN];Temp [°C]\r\n");
    for i in 0..1500 {
        let on = i >= 1000;
        let (u1, u2) = if on {
            ("2000,1", "-1500,0")
        } else {
            ("0,4", "-0,6")
        };
        let i1 = if i == 1001 {
            "50,0".to_string()
        } else {
            format!("{},{}", i % 7, i % 10)
        };
        let f = if on { "1,25" } else { "0,00" };
        csv.push_str(&format!(
            "{},{};{u1};{u2};{i1};-0,1;{f};21,5\r\n",
            i,
            i % 2 * 5
        ));
    }
    let csv_path = dir.write("blocked run.csv", &csv);
    let csv_mapping = mapping(
        r#"
        format = "finrs-import/1"
        [source]
        delimiter = ";"
        decimal_comma = true
        [time]
        column = "Zeit [ms]"
        scale = 0.001
        [[channel]]
        to = "v1_V"
        column = "U1 [mV]"
        scale = 0.001
        [[channel]]
        to = "v2_V"
        column = "U2 [mV]"
        scale = 0.001
        [[channel]]
        to = "i1_A"
        column = "I1 [mA]"
        scale = 0.001
        valid = [-49.9, 49.9]
        [[channel]]
        to = "i2_A"
        letter = "E"
        scale = 0.001
        [[channel]]
        to = "force_N"
        column = "Kraft [mN]"
        scale = 0.001
        [metadata]
        segments = 2
        length_m = 0.03
        width_m = 0.005
        thickness_m = 0.0002
        fixture = "blocked"
        medium = "air"
    "#,
    );
    let imported = import(&csv_path, &csv_mapping).unwrap();
    let rec = &imported.recording;
    assert_eq!(rec.t_s.len(), 1500);
    assert_eq!((rec.t_s[0], rec.t_s[1], rec.t_s[2]), (0.0, 0.0015, 0.002));
    assert_eq!(rec.v_v[1200], [2.0001, -1.5]);
    assert_eq!(rec.v_v[3], [0.0004, -0.0006]);
    assert_eq!(rec.channel(Channel::Current(0)).unwrap()[1001], None);
    assert_eq!(imported.channels[2].outside_valid, 1);
    assert!(close(
        rec.channel(Channel::Force).unwrap()[1200],
        Some(0.00125)
    ));
    rec.write(&dir.path("out.csv")).unwrap();

    // TSV: the tab from the extension, time in ms from 100 ms on.
    let mut tsv = String::from("time (ms)\tV\tcurrent (mA)\n");
    for i in 0..300 {
        tsv.push_str(&format!(
            "{},5\t{}\t{}\n",
            100 + 10 * i,
            if i > 150 { "1,5" } else { "0" },
            "0,3"
        ));
    }
    let tsv_path = dir.write("run.tsv", &tsv);
    let tsv_mapping = mapping(
        r#"
        format = "finrs-import/1"
        [source]
        decimal_comma = true
        [time]
        column = "time (ms)"
        scale = 0.001
        zero = "first"
        [[channel]]
        to = "v1_V"
        column = "V"
        [[channel]]
        to = "i1_A"
        column = "current (mA)"
        scale = 0.001
        [metadata]
        segments = 1
        length_m = 0.03
        width_m = 0.005
        thickness_m = 0.0002
        fixture = "free"
        medium = "air"
    "#,
    );
    let rec = import_file(&tsv_path, &tsv_mapping).unwrap();
    assert_eq!(&rec.t_s[..3], &[0.0, 0.01, 0.02]);
    assert_eq!(rec.v_v[200], [1.5]);
}

/// `import` of `path` by `mapping` is refused, and the message names the
/// file, then `place` (if any), and says `rule`.
fn refused(path: &Path, m: &Mapping, place: &str, rule: &str) {
    let err = import(path, m).unwrap_err().to_string();
    let file = path.display().to_string();
    assert!(err.starts_with(&format!("{file}: {place}")), "{err}");
    assert!(err.contains(rule), "{err}");
}

#[test]
fn broken_workbooks_are_refused_at_the_cell_with_the_rule() {
    let dir = Dir::new("refusals");
    let m = mapping(LABVIEW_MAPPING);
    let case = |name: &str, change: &dyn Fn(&mut Sheet)| {
        let mut sheet = labview().sheet;
        change(&mut sheet);
        let path = dir.path(&format!("{name}.xlsx"));
        sheet.save(&path, "Sheet1");
        path
    };
    let p = case("text", &|s| s.set(57, 'D', Cell::S("n/a".into())));
    refused(
        &p,
        &m,
        "Sheet1!D57: ",
        "v1_V: holds the text `n/a`, not a number",
    );
    let p = case("decimal_comma", &|s| s.set(57, 'B', Cell::S("12,5".into())));
    refused(&p, &m, "Sheet1!B57: ", "set source.decimal_comma = true");
    let p = case("div0", &|s| {
        s.set(20, 'H', Cell::Formula("=1/0", "#DIV/0!"))
    });
    refused(
        &p,
        &m,
        "Sheet1!H20: ",
        "tip_y_m: holds the formula error #DIV/0!",
    );
    let p = case("empty_voltage", &|s| s.set(30, 'D', Cell::Blank));
    refused(
        &p,
        &m,
        "Sheet1!D30: ",
        "v1_V: an empty cell; a voltage is never empty",
    );
    let p = case("sentinel_voltage", &|s| s.set(30, 'D', Cell::N(SENTINEL)));
    let with_sentinel = mapping(&LABVIEW_MAPPING.replace(
        "column = \"Y axis - Voltage\"",
        "column = \"Y axis - Voltage\"\nout_of_range = [-99.9999]",
    ));
    refused(
        &p,
        &with_sentinel,
        "Sheet1!D30: ",
        "the sentinel -99.9999 (out_of_range); a voltage is never empty",
    );
    let p = case("inf", &|s| s.set(40, 'B', Cell::S("Inf".into())));
    refused(&p, &m, "Sheet1!B40: ", "i1_A: holds inf, not a measurement");
    let p = case("beyond", &|s| s.set(100, 'D', Cell::N(4.5)));
    refused(&p, &m, "Sheet1!D100: ", "v1_V");
    let p = case("missing", &|s| s.header[7] = "Y axis - Distance (mm)");
    refused(&p, &m, "Sheet1 row 1 (header row): ", "no column named \"Y axis - Distance\" (lab.toml channel[3].column); it holds A \"Time Point - Current\"");
    let p = case("twice", &|s| s.header[5] = "Y axis - Current");
    refused(
        &p,
        &m,
        "Sheet1 row 1 (header row): ",
        "\"Y axis - Current\" (lab.toml channel[2].column) heads columns B and F",
    );
    let p = case("blank_row", &|s| s.rows[298] = vec![Cell::Blank; 9]);
    refused(&p, &m, "Sheet1 row 300: ", "a blank row inside the data");
    let p = case("merged", &|s| s.merged.push((9, 7, 10, 7)));
    refused(
        &p,
        &m,
        "Sheet1!H10:H11: ",
        "merged cells over column H (tip_y_m)",
    );
    let p = case("lost_opening", &|s| {
        for r in 2..102 {
            s.set(r, 'H', Cell::N(SENTINEL));
        }
    });
    refused(
        &p,
        &m,
        "Sheet1!H2 to Sheet1!H101: ",
        "tip_y_m: zero = \"opening\"",
    );

    // A workbook whose only sheet is empty; one with another sheet's name.
    let empty = dir.path("empty.xlsx");
    let mut book = Workbook::new();
    book.add_worksheet();
    book.save(&empty).unwrap();
    refused(&empty, &m, "", "the sheet \"Sheet1\" is empty");
    let other = case("named", &|_| {});
    let named = mapping(&format!("{LABVIEW_MAPPING}\n[source]\nsheet = \"Data\"\n"));
    refused(
        &other,
        &named,
        "",
        "no sheet named \"Data\" (source.sheet); the workbook has \"Sheet1\"",
    );
    // Not a workbook at all.
    let fake = dir.write("fake.xlsx", "Y axis - Voltage\n1\n");
    refused(&fake, &m, "", "cannot read as an XLSX workbook");
    refused(&dir.path("absent.xlsx"), &m, "", "cannot read");
}

#[test]
fn broken_text_exports_are_refused_at_the_line() {
    let dir = Dir::new("text-refusals");
    let m = mapping(
        r#"
        format = "finrs-import/1"
        [time]
        column = "t"
        [[channel]]
        to = "v1_V"
        column = "v"
        [metadata]
        segments = 1
        length_m = 0.03
        width_m = 0.005
        thickness_m = 0.0002
        fixture = "free"
        medium = "air"
    "#,
    );
    for (name, text, place, rule) in [
        (
            "back.csv",
            "t,v\n0,0\n0.2,0\n0.1,0\n",
            "line 4, field 1 (A): ",
            "time must be strictly increasing",
        ),
        (
            "negative.csv",
            "t,v\n-1,0\n",
            "line 2, field 1 (A): ",
            "time must start at or after 0",
        ),
        (
            "no_time.csv",
            "t,v\n0,0\n,0\n",
            "line 3, field 1 (A): ",
            "t_s: an empty cell; time is never empty",
        ),
        (
            "blank.csv",
            "t,v\n0,0\n\n1,0\n",
            "line 3: ",
            "a blank row inside the data",
        ),
        ("header_only.csv", "t,v\n", "", "no data: from line 2"),
        ("empty.csv", "", "", "the file is empty"),
        // An unclosed quote runs to the end of the file: one field.
        (
            "quote.csv",
            "t,v\n0,\"1\n1,2\n",
            "line 2, field 2 (B): ",
            "v1_V: holds the text `1\\n1,2`",
        ),
    ] {
        let path = dir.write(name, text);
        refused(&path, &m, place, rule);
    }
}

fn finrs(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_finrs"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_command_imports_a_session_whole_or_not_at_all() {
    let dir = Dir::new("cli");
    let exports = dir.path("exports");
    std::fs::create_dir_all(&exports).unwrap();
    let lab = labview();
    lab.sheet.save(&exports.join("01_rest.xlsx"), "Sheet1");
    lab.sheet.save(&exports.join("02_step.xlsx"), "Sheet1");
    std::fs::write(exports.join("notes.md"), "not an export").unwrap();
    let mapping_path = dir.write(
        "lab.toml",
        &format!("{LABVIEW_MAPPING}\n[files.\"02_step.xlsx\"]\nt_session_start_s = 95.0\n"),
    );
    let m = mapping_path.to_str().unwrap();
    let session = dir.path("session");
    let s = session.to_str().unwrap();
    // A folder of exports: a recording per export, by name.
    let (ok, err) = finrs(&[
        "import",
        exports.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        s,
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("tip_y_m from column H (\"Y axis - Distance\")"),
        "{err}"
    );
    assert!(err.contains("25 sentinels"), "{err}");
    let one = Recording::read(&session.join("01_rest.csv")).unwrap();
    let two = Recording::read(&session.join("02_step.csv")).unwrap();
    assert_eq!(one.meta.t_session_start_s, None);
    assert_eq!(two.meta.t_session_start_s, Some(95.0));
    assert_eq!(std::fs::read_dir(&session).unwrap().count(), 2);

    // One export to one file.
    let file = dir.path("one/step.csv");
    let x = exports.join("02_step.xlsx");
    let (ok, err) = finrs(&[
        "import",
        x.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(Recording::read(&file).unwrap().t_s.len(), 600);
    // Two exports cannot go to one file.
    let a = exports.join("01_rest.xlsx");
    let (ok, err) = finrs(&[
        "import",
        a.to_str().unwrap(),
        x.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("names one recording, but 2 exports are given"),
        "{err}"
    );

    // One bad export of two: nothing written, no folder left, each
    // refusal told.
    let mut bad = labview().sheet;
    bad.set(57, 'D', Cell::S("n/a".into()));
    let b = dir.path("03_bad.xlsx");
    bad.save(&b, "Sheet1");
    let fresh = dir.path("fresh/session");
    let (ok, err) = finrs(&[
        "import",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        fresh.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("1 of 2 exports refused, nothing written"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "{}: Sheet1!D57: v1_V: holds the text `n/a`",
            b.display()
        )),
        "{err}"
    );
    assert!(!dir.path("fresh").exists());
    let (ok, err) = finrs(&[
        "import",
        b.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        fresh.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.starts_with(&format!("error: {}: Sheet1!D57", b.display())),
        "{err}"
    );

    // A mapping with an unknown key: the file, the line and the key.
    let typo = dir.write(
        "typo.toml",
        &LABVIEW_MAPPING.replace("sign = -1", "sing = -1"),
    );
    let (ok, err) = finrs(&[
        "import",
        a.to_str().unwrap(),
        "--mapping",
        typo.to_str().unwrap(),
        "--out",
        s,
    ]);
    assert!(!ok, "{err}");
    let line = LABVIEW_MAPPING[..LABVIEW_MAPPING.find("sign = -1").unwrap()]
        .matches('\n')
        .count()
        + 1;
    let says = format!("{}:{line}: unknown field `sing`", typo.display());
    assert!(err.contains(&says), "{err}");
    // An export written over itself.
    let csv = dir.write("exports2/run.csv", "");
    let (ok, err) = finrs(&[
        "import",
        csv.to_str().unwrap(),
        "--mapping",
        m,
        "--out",
        dir.path("exports2").to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("over its own export"), "{err}");
}

#[test]
fn the_example_lab_export_imports_and_reads_back() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/lab-export");
    let m = Mapping::read(&root.join("mapping.toml")).unwrap();
    let imported = import(&root.join("step_2V.xlsx"), &m).unwrap();
    let dir = Dir::new("example");
    let out = dir.path("step_2V.csv");
    imported.recording.write(&out).unwrap();
    let rec = Recording::read(&out).unwrap();
    // 27 s at 100 rows/s, both ends.
    assert_eq!(rec.t_s.len(), 2701);
    assert_eq!(rec.t_s[2700], 27.0);
    // The rests read the ADC's 0.3 to 1.1 mV; the step 2 V and a little.
    let rest = (0..200).chain(1800..2701).map(|i| rec.v_v[i][0]);
    assert!(rest.clone().all(|v| (0.0003..=0.0011).contains(&v)));
    assert!((300..1600).all(|i| (2.0003..=2.0011).contains(&rec.v_v[i][0])));
    // The laser's lost stretches are empty; the tip bends positive.
    let tip = rec.channel(Channel::TipY).unwrap();
    assert_eq!(tip.iter().filter(|x| x.is_none()).count(), 68);
    assert_eq!(imported.channels[2].sentinels, 68);
    let peak = tip.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    assert!((0.005..0.02).contains(&peak), "{peak}");
    // Currents in whole tenths of a milliamp.
    let current = rec.channel(Channel::Current(0)).unwrap();
    assert!(current
        .iter()
        .flatten()
        .all(|i| (i * 1e4 - (i * 1e4).round()).abs() < 1e-6));
    assert!(rec.meta.notes.as_deref().unwrap().contains("synthetic"));
}
