//! PNG plots of recordings: the drive, the mechanical channel (tip or
//! force), and the currents, one panel each, measured and simulated
//! together when both are given.

use std::path::Path;

use plotters::prelude::*;

use crate::recording::{Channel, Fixture, Recording};

/// One trace: a label, a colour and its points.
type Trace = (String, RGBColor, Vec<(f64, f64)>);

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Writes a three-panel PNG of `simulated`, with `measured` beneath it.
pub fn plot(
    path: &Path,
    title: &str,
    measured: Option<&Recording>,
    simulated: &Recording,
) -> anyhow::Result<()> {
    plot_models(path, title, measured, &[("model", simulated)])
}

/// Writes a three-panel PNG (drive, tip or force, currents) of one or more
/// models' predictions for the same drive, with `measured` beneath them.
pub fn plot_models(
    path: &Path,
    title: &str,
    measured: Option<&Recording>,
    models: &[(&str, &Recording)],
) -> anyhow::Result<()> {
    let Some(&(_, first)) = models.first() else {
        anyhow::bail!("nothing to plot");
    };
    let root = BitMapBackend::new(path, (1200, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 22))?;
    let panels = root.split_evenly((3, 1));

    let voltages: Vec<Trace> = (0..first.meta.segments)
        .map(|k| {
            let pts = first
                .t_s
                .iter()
                .zip(&first.v_v)
                .map(|(&t, v)| (t, v[k]))
                .collect();
            (format!("v{}", k + 1), PALETTE[k % 8], pts)
        })
        .collect();
    panel(&panels[0], "voltage (V)", &voltages)?;

    let (channel, label, scale) = match first.meta.fixture {
        Fixture::Free => (Channel::TipY, "tip across (mm)", 1e3),
        Fixture::Blocked => (Channel::Force, "blocking force (mN)", 1e3),
    };
    let mut mech = Vec::new();
    if let Some(m) = measured {
        mech.push((
            "measured".to_string(),
            RGBColor(120, 120, 120),
            points(m, channel, scale),
        ));
    }
    for (j, (name, sim)) in models.iter().enumerate() {
        mech.push((
            name.to_string(),
            PALETTE[j % 8],
            points(sim, channel, scale),
        ));
    }
    panel(&panels[1], label, &mech)?;

    let mut currents = Vec::new();
    for k in 0..first.meta.segments {
        if let Some(m) = measured {
            currents.push((
                format!("i{} measured", k + 1),
                RGBColor(160, 160, 160),
                points(m, Channel::Current(k), 1e3),
            ));
        }
        for (j, (name, sim)) in models.iter().enumerate() {
            currents.push((
                format!("i{} {name}", k + 1),
                PALETTE[(k + j * 3) % 8],
                points(sim, Channel::Current(k), 1e3),
            ));
        }
    }
    panel(&panels[2], "current (mA)", &currents)?;
    root.present()?;
    Ok(())
}

/// Writes a PNG of residual autocorrelations (lag in samples) with the
/// band `±band` that white residuals stay inside 99 % of the time.
pub fn plot_autocorrelation(
    path: &Path,
    title: &str,
    series: &[(&str, Vec<f64>)],
    band: f64,
) -> anyhow::Result<()> {
    let root = BitMapBackend::new(path, (1000, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let mut traces: Vec<Trace> = series
        .iter()
        .enumerate()
        .map(|(j, (name, rho))| {
            let pts = rho
                .iter()
                .enumerate()
                .map(|(k, &r)| (k as f64, r))
                .collect();
            (name.to_string(), PALETTE[j % 8], pts)
        })
        .collect();
    let lags = series.iter().map(|s| s.1.len()).max().unwrap_or(1) as f64;
    for sign in [1.0, -1.0] {
        traces.push((
            format!("{} 99 % band", if sign > 0.0 { "+" } else { "−" }),
            RGBColor(150, 150, 150),
            vec![(0.0, sign * band), (lags, sign * band)],
        ));
    }
    panel_x(&root, "lag (samples)", "autocorrelation", &traces)?;
    root.present()?;
    Ok(())
}

/// The sampled points of a channel, scaled; empty if the channel is absent.
fn points(r: &Recording, ch: Channel, scale: f64) -> Vec<(f64, f64)> {
    r.channel(ch)
        .map(|vals| {
            r.t_s
                .iter()
                .zip(vals)
                .filter_map(|(&t, v)| v.map(|v| (t, v * scale)))
                .collect()
        })
        .unwrap_or_default()
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    y_label: &str,
    traces: &[Trace],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    panel_x(area, "t (s)", y_label, traces)
}

fn panel_x<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    x_label: &str,
    y_label: &str,
    traces: &[Trace],
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let all = traces.iter().flat_map(|t| t.2.iter());
    let (mut t0, mut t1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(t, y) in all {
        t0 = t0.min(t);
        t1 = t1.max(t);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if t0 > t1 {
        (t0, t1, y0, y1) = (0.0, 1.0, -1.0, 1.0);
    }
    let pad = ((y1 - y0) * 0.05).max(1e-9);
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(t0..t1.max(t0 + 1e-9), (y0 - pad)..(y1 + pad))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()?;
    for (label, colour, pts) in traces {
        let colour = *colour;
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
