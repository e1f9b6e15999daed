//! Writes the synthetic lab export of `examples/lab-export/`: what
//! `finrs simulate --wave step:2` predicts for the seed's strip (one
//! segment, free, the main_m_2006 parameters), made to look like a
//! LabVIEW graph exported to XLSX by a simple bench: 100 rows/s and no
//! time column, pairs of "Time Point" (the row's index) and "Y axis"
//! columns, the voltage read back by a 16-bit ADC (a rest of 0.3 to 1.1
//! mV, a step of 2.0003 to 2.0011 V), the current in mA rounded to 0.1 mA, an unused
//! load cell, a laser's *distance* to the strip in mm (not a
//! displacement) with its sentinel -99.9999 where the spot was lost, and a
//! derived resistance that is `Inf` where the current reads 0.
//!
//! ```sh
//! cargo run --release -p finrs --example lab_export -- examples/lab-export/step_2V.xlsx
//! ```
//!
//! The data are synthetic: a model's prediction with made-up artefacts,
//! for trying `finrs import`, never evidence about a real strip.

use anyhow::Context as _;
use finrs::model::params::ModelFile;
use finrs::model::simulate::simulate;
use finrs::model::synth::{drive_recording, Drive};
use finrs::recording::{Channel, Fixture};
use finrs::wave::Wave;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rust_xlsxwriter::{DocProperties, ExcelDateTime, Workbook};

/// The model's rate, rows/s, and the export's: every tenth row kept.
const MODEL_HZ: f64 = 1000.0;
const EXPORT_EVERY: usize = 10;
/// The laser's distance to the strip at rest, mm.
const LASER_REST_MM: f64 = 31.4159;
/// The laser's sentinel when the spot leaves its range.
const SENTINEL: f64 = -99.9999;
/// Where the laser lost the spot, s (from, to): a reflection off the
/// wet strip as it bends, and once as it returns.
const LOST_S: [(f64, f64); 3] = [(3.2, 3.45), (9.0, 9.08), (18.6, 18.95)];

fn main() -> anyhow::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "examples/lab-export/step_2V.xlsx".to_string());
    let drive = Drive {
        segments: 1,
        fixture: Fixture::Free,
        rest_s: 2.0,
        duration_s: 15.0,
        off_s: 10.0,
        rate_hz: MODEL_HZ,
    };
    let input = drive_recording(&Wave::parse("step:2")?, &drive)?;
    let model = ModelFile::main_m_2006().spec_for(&input.meta.geometry())?;
    let sim = simulate("step:2", &input, &model, 1, &mut |_| {})?;
    let current = sim.channel(Channel::Current(0)).context("a current")?;
    let tip = sim.channel(Channel::TipY).context("a tip")?;

    let mut rng = rand::rngs::StdRng::seed_from_u64(2026);
    // The ADC's noise, V, within 0.4 mV of the offset.
    let adc = Normal::new(0.0, 0.00015)?;
    let shunt = Normal::new(0.0, 0.00004)?;
    let laser = Normal::new(0.0, 0.003)?;
    // The read-back's offset, V: every rest reads 0.3 to 1.1 mV.
    let offset_v = 0.0007;

    let mut book = Workbook::new();
    book.set_properties(
        &DocProperties::new()
            .set_title("Synthetic lab export for finrs import")
            .set_comment(
                "SYNTHETIC: finrs simulate --wave step:2 (one segment, free, main_m_2006) \
                 with lab artefacts added by host-tools/examples/lab_export.rs; not a measurement",
            )
            .set_creation_datetime(&ExcelDateTime::from_ymd(2026, 11, 28)?),
    );
    let sheet = book.add_worksheet();
    sheet.set_name("Sheet1")?;
    let header = [
        "Time Point - Voltage",
        "Y axis - Voltage",
        "Time Point - Current",
        "Y axis - Current",
        "Time Point - Load Cell",
        "Y axis - Load Cell",
        "Time Point - Distance",
        "Y axis - Distance",
        "Resistance (Ohm)",
    ];
    for (col, name) in header.iter().enumerate() {
        sheet.write_string(0, col as u16, *name)?;
    }
    for (row, i) in (0..sim.t_s.len()).step_by(EXPORT_EVERY).enumerate() {
        let t_s = sim.t_s[i];
        let point = row as f64;
        let noise_v = f64::clamp(adc.sample(&mut rng), -0.0004, 0.0004);
        let v = round_to(sim.v_v[i][0] + offset_v + noise_v, 1e-4);
        let i_ma = round_to(
            (current[i].unwrap_or(0.0) + shunt.sample(&mut rng)) * 1e3,
            0.1,
        );
        let load_mn = round_to(0.02 * rng.gen::<f64>() - 0.01, 0.001);
        let lost = LOST_S.iter().any(|&(a, b)| (a..b).contains(&t_s));
        // The laser faces the side the strip bends toward: the distance
        // shrinks as the tip moves positive.
        let distance_mm = if lost {
            SENTINEL
        } else {
            round_to(
                LASER_REST_MM - tip[i].unwrap_or(0.0) * 1e3 + laser.sample(&mut rng),
                1e-4,
            )
        };
        let r = row as u32 + 1;
        for (col, x) in [point, v, point, i_ma, point, load_mn, point, distance_mm]
            .into_iter()
            .enumerate()
        {
            sheet.write_number(r, col as u16, x)?;
        }
        if i_ma == 0.0 {
            sheet.write_string(r, 8, "Inf")?;
        } else {
            sheet.write_number(r, 8, round_to(v / (i_ma * 1e-3), 0.01))?;
        }
    }
    book.save(&out)?;
    let rows = (0..sim.t_s.len()).step_by(EXPORT_EVERY).count();
    eprintln!("wrote {out} ({rows} rows)");
    Ok(())
}

/// `x` rounded to a multiple of `step`, as the export writes it (0, not
/// -0).
fn round_to(x: f64, step: f64) -> f64 {
    let digits = (-step.log10()).round().max(0.0) as usize;
    let y: f64 = format!("{:.*}", digits, (x / step).round() * step)
        .parse()
        .expect("a formatted number");
    y + 0.0
}
