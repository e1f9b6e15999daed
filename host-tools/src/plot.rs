//! PNG plots of recordings: the drive, each measured mechanical channel
//! (camera dots, tip, load cell) under its own name, and the currents, one
//! panel each, measured and simulated together when both are given; and
//! residual autocorrelations.
//!
//! Read at a glance: measured samples are black, each model keeps one
//! colour ([`model_colour`]) in every plot, camera frames (sampled on a
//! few rows only) are drawn as points with the models both as lines and
//! at the same frames, and the whiteness band is a dashed red, not the
//! grid's grey.

use std::path::Path;
use std::sync::OnceLock;

use plotters::drawing::DrawingAreaErrorKind;
use plotters::prelude::*;
use plotters::style::register_font;

use crate::recording::{Channel, Fixture, Recording};

/// Why a plot was not drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No model was given.
    #[error("nothing to plot")]
    Nothing,
    /// plotters failed to draw or to write the PNG.
    #[error("drawing the plot")]
    Draw(#[source] Box<dyn std::error::Error + Send + Sync>),
    /// The embedded font did not load (a broken build, not bad input).
    #[error("the plots' embedded font (DejaVu Sans) does not load")]
    Font,
}

/// The one typeface of every plot, embedded so that no run loads the
/// system's font libraries (fontconfig, freetype): DejaVu Sans, licence in
/// `assets/fonts/DejaVuSans.LICENSE`.
const SANS_TTF: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers [`SANS_TTF`] as plotters' `sans-serif` (the family its axes,
/// legends and our titles ask for) once, before the first text is drawn;
/// every crate of ours that draws with plotters calls it.
pub fn register_fonts() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| register_font("sans-serif", FontStyle::Normal, SANS_TTF).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

impl<E: std::error::Error + Send + Sync + 'static> From<DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        PlotError::Draw(Box::new(e))
    }
}

/// Measured samples, in every plot.
pub const MEASURED_COLOUR: RGBColor = RGBColor(0, 0, 0);

/// The 99 % band of a white residual's autocorrelation.
pub const BAND_COLOUR: RGBColor = RGBColor(214, 39, 40);

/// The grid's major and minor lines, as drawn (plotters' default, black at
/// 20 % and 10 % on white, made explicit so the band can be kept apart).
pub const GRID_COLOURS: [RGBColor; 2] = [RGBColor(204, 204, 204), RGBColor(230, 230, 230)];

/// The models' colours in the order they are given (blue, orange, green,
/// purple), the same in every plot.
const MODEL_COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// The drive voltages' colours per segment: hues no model uses.
const SEGMENT_COLOURS: [RGBColor; 8] = [
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(90, 50, 40),
    RGBColor(150, 60, 120),
    RGBColor(110, 110, 20),
    RGBColor(15, 110, 120),
];

/// The colour of the `j`th model given to a plot (0-based); the report
/// gives its models in one order, so each keeps its colour everywhere.
pub fn model_colour(j: usize) -> RGBColor {
    MODEL_COLOURS[j % MODEL_COLOURS.len()]
}

/// `colour` lightened for segment `k`, so that segments of one model stay
/// in that model's hue.
fn shade(colour: RGBColor, k: usize) -> RGBColor {
    let f = [0.0, 0.4, 0.6, 0.7][k.min(3)];
    let mix = |c: u8| (f64::from(c) + (255.0 - f64::from(c)) * f) as u8;
    RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
}

/// How a trace is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Style {
    /// A line through the points.
    Line,
    /// A dot per point: sparse samples (camera frames).
    Points,
    /// A dashed line: a reference, not data.
    Dashed,
}

/// One trace: a label (empty: none in the legend), a colour, a style and
/// its points.
#[derive(Debug)]
struct Trace {
    label: String,
    colour: RGBColor,
    style: Style,
    points: Vec<(f64, f64)>,
}

/// Writes a PNG of `simulated`, with `measured` beneath it
/// ([`plot_models`]).
pub fn plot(
    path: &Path,
    title: &str,
    measured: Option<&Recording>,
    simulated: &Recording,
) -> Result<(), PlotError> {
    plot_models(path, title, measured, &[("model", simulated)])
}

/// Writes a PNG of one or more models' predictions for the same drive,
/// with `measured` beneath them: a panel for the drive, one for each
/// mechanical channel `measured` samples (camera dots, tip, load cell),
/// labelled by its own name, and one for the currents. Without a measured
/// mechanical channel, the models' tip (free) or force (blocked) is drawn.
pub fn plot_models(
    path: &Path,
    title: &str,
    measured: Option<&Recording>,
    models: &[(&str, &Recording)],
) -> Result<(), PlotError> {
    let Some(&(_, first)) = models.first() else {
        return Err(PlotError::Nothing);
    };
    register_fonts()?;
    let mechanical = mechanical_channels(measured, first);
    let panels_n = 2 + mechanical.len();
    // Each panel keeps the height it had when there were three.
    let root = BitMapBackend::new(path, (1200, 300 * panels_n as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 22))?;
    let panels = root.split_evenly((panels_n, 1));

    let voltages: Vec<Trace> = (0..first.meta.segments)
        .map(|k| Trace {
            label: format!("v{}", k + 1),
            colour: SEGMENT_COLOURS[k % SEGMENT_COLOURS.len()],
            style: Style::Line,
            points: first
                .t_s
                .iter()
                .zip(&first.v_v)
                .map(|(&t, v)| (t, v[k]))
                .collect(),
        })
        .collect();
    panel(&panels[0], "voltage (V)", &voltages)?;

    for (area, &channel) in panels[1..].iter().zip(&mechanical) {
        panel(
            area,
            &axis_label(channel, first),
            &channel_traces(measured, models, channel, 1e3, 0, ""),
        )?;
    }

    let mut currents = Vec::new();
    for k in 0..first.meta.segments {
        let prefix = format!("i{} ", k + 1);
        currents.extend(channel_traces(
            measured,
            models,
            Channel::Current(k),
            1e3,
            k,
            &prefix,
        ));
    }
    panel(&panels[panels_n - 1], "current (mA)", &currents)?;
    root.present()?;
    Ok(())
}

/// The mechanical channels to draw: every one `measured` samples at some
/// row, in its header's order; none sampled, the models' tip (free) or
/// force (blocked).
fn mechanical_channels(measured: Option<&Recording>, first: &Recording) -> Vec<Channel> {
    let sampled: Vec<Channel> = measured
        .map(|m| {
            m.channels
                .iter()
                .filter(|(c, v)| !matches!(c, Channel::Current(_)) && v.iter().any(Option::is_some))
                .map(|(c, _)| *c)
                .collect()
        })
        .unwrap_or_default();
    if !sampled.is_empty() {
        return sampled;
    }
    vec![match first.meta.fixture {
        Fixture::Free => Channel::TipY,
        Fixture::Blocked => Channel::Force,
    }]
}

/// A mechanical channel's axis: its own name, a dot's place on the strip,
/// the unit drawn (mm or mN).
fn axis_label(ch: Channel, r: &Recording) -> String {
    let place = match ch {
        Channel::DotY(j) | Channel::DotX(j) => r
            .meta
            .dots_s_m
            .as_ref()
            .and_then(|d| d.get(j))
            .map(|s| format!(", {:.1} mm from the clamp", s * 1e3))
            .unwrap_or_default(),
        _ => String::new(),
    };
    let unit = if ch == Channel::Force { "mN" } else { "mm" };
    format!("{}{place} ({unit})", ch.name())
}

/// The traces of one channel, scaled: each model as a line in its colour,
/// and where the measurement is sparse, also as dots at the measured
/// frames; and the measured samples in black: larger dots on top where
/// sampled on fewer than half the rows (camera frames), else a line
/// beneath the models. `segment` lightens the
/// colours; `prefix` starts every label.
fn channel_traces(
    measured: Option<&Recording>,
    models: &[(&str, &Recording)],
    ch: Channel,
    scale: f64,
    segment: usize,
    prefix: &str,
) -> Vec<Trace> {
    let mut traces = Vec::new();
    let mut frames = None;
    let mut measured_trace = None;
    // A drive alone (`simulate` of a file without measurements) has no
    // measured samples: no legend entry for them either.
    if let Some((m, points)) = measured
        .map(|m| (m, points(m, ch, scale)))
        .filter(|(_, p)| !p.is_empty())
    {
        let sparse = 2 * points.len() < m.t_s.len();
        if sparse {
            frames = m.channel(ch);
        }
        measured_trace = Some(Trace {
            label: format!("{prefix}measured"),
            colour: shade(MEASURED_COLOUR, segment),
            style: if sparse { Style::Points } else { Style::Line },
            points,
        });
    }
    for (j, (name, sim)) in models.iter().enumerate() {
        let colour = shade(model_colour(j), segment);
        // A model without the channel (what a motion asked has no
        // currents) draws nothing and takes no legend entry.
        let line = points(sim, ch, scale);
        if !line.is_empty() {
            traces.push(Trace {
                label: format!("{prefix}{name}"),
                colour,
                style: Style::Line,
                points: line,
            });
        }
        if let (Some(frames), Some(values)) = (frames, sim.channel(ch)) {
            traces.push(Trace {
                label: String::new(),
                colour,
                style: Style::Points,
                points: sim
                    .t_s
                    .iter()
                    .zip(values)
                    .zip(frames)
                    .filter_map(|((&t, v), f)| f.and(*v).map(|v| (t, v * scale)))
                    .collect(),
            });
        }
    }
    // Dots go on top of the models; a dense line beneath them.
    match measured_trace {
        Some(m) if m.style == Style::Line => traces.insert(0, m),
        m => traces.extend(m),
    }
    traces
}

/// Writes a PNG of residual autocorrelations (lag in samples), one series
/// per model in the models' colours, with the band `±band` that white
/// residuals stay inside 99 % of the time, dashed in [`BAND_COLOUR`].
pub fn plot_autocorrelation(
    path: &Path,
    title: &str,
    series: &[(&str, Vec<f64>)],
    band: f64,
) -> Result<(), PlotError> {
    let root = BitMapBackend::new(path, (1000, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    panel_x(
        &root,
        "lag (samples)",
        "autocorrelation",
        &autocorrelation_traces(series, band),
    )?;
    root.present()?;
    Ok(())
}

/// The autocorrelation plot's traces: the series, then the two band lines.
fn autocorrelation_traces(series: &[(&str, Vec<f64>)], band: f64) -> Vec<Trace> {
    let mut traces: Vec<Trace> = series
        .iter()
        .enumerate()
        .map(|(j, (name, rho))| Trace {
            label: name.to_string(),
            colour: model_colour(j),
            style: Style::Line,
            points: rho
                .iter()
                .enumerate()
                .map(|(k, &r)| (k as f64, r))
                .collect(),
        })
        .collect();
    let lags = series.iter().map(|s| s.1.len()).max().unwrap_or(1) as f64;
    for sign in [1.0, -1.0] {
        traces.push(Trace {
            label: if sign > 0.0 {
                "±99 % band of white noise".to_string()
            } else {
                String::new()
            },
            colour: BAND_COLOUR,
            style: Style::Dashed,
            points: vec![(0.0, sign * band), (lags, sign * band)],
        });
    }
    traces
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
) -> Result<(), PlotError>
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
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let all = traces.iter().flat_map(|t| t.points.iter());
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
        .bold_line_style(GRID_COLOURS[0])
        .light_line_style(GRID_COLOURS[1])
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()?;
    for trace in traces {
        let colour = trace.colour;
        let pts = trace.points.iter().copied();
        let drawn = match trace.style {
            Style::Line => chart.draw_series(LineSeries::new(pts, colour))?,
            Style::Points => chart.draw_series(pts.map(|p| Circle::new(p, 2, colour.filled())))?,
            Style::Dashed => {
                chart.draw_series(DashedLineSeries::new(pts, 10, 6, colour.stroke_width(2)))?
            }
        };
        if trace.label.is_empty() {
            continue;
        }
        drawn.label(&trace.label).legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (16, 0)], colour.stroke_width(2))
        });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Geometry, Medium, Metadata, Voltages};

    /// Squared distance between two colours in RGB.
    fn distance2(a: RGBColor, b: RGBColor) -> i32 {
        let d = |x: u8, y: u8| (i32::from(x) - i32::from(y)).pow(2);
        d(a.0, b.0) + d(a.1, b.1) + d(a.2, b.2)
    }

    #[test]
    fn every_model_band_and_measurement_stands_apart() {
        // One colour per model, the same on every call.
        assert_eq!(model_colour(1), model_colour(1));
        let mut apart = vec![MEASURED_COLOUR, BAND_COLOUR];
        apart.extend((0..MODEL_COLOURS.len()).map(model_colour));
        apart.extend(GRID_COLOURS);
        apart.extend(SEGMENT_COLOURS);
        for (i, &a) in apart.iter().enumerate() {
            for &b in &apart[i + 1..] {
                assert!(distance2(a, b) > 40 * 40, "{a:?} and {b:?} look alike");
            }
        }
        // The band is far from the grid's greys, not one of them.
        for g in GRID_COLOURS {
            assert!(distance2(BAND_COLOUR, g) > 150 * 150);
        }
    }

    #[test]
    fn the_embedded_font_draws_text() {
        // A title drawn in memory with the embedded font leaves dark
        // pixels in its strip; with no font it would fail to draw at all.
        let (w, h) = (200u32, 40u32);
        let mut pixels = vec![255u8; (w * h * 3) as usize];
        {
            register_fonts().unwrap();
            let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
            root.titled("finrs 0.1 mm", ("sans-serif", 22)).unwrap();
            root.present().unwrap();
        }
        let dark = pixels
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c < 128))
            .count();
        assert!(dark > 50, "{dark} dark pixels");
    }

    fn free(rows: usize, tip: impl Fn(usize) -> Option<f64>) -> Recording {
        Recording {
            meta: Metadata::new(1, Geometry::THESIS_2006, Fixture::Free, Medium::Air),
            t_s: (0..rows).map(|k| k as f64 * 1e-3).collect(),
            v_v: Voltages::from_rows(1, std::iter::repeat_n([1.0], rows)),
            channels: vec![
                (
                    Channel::Current(0),
                    (0..rows).map(|k| Some(k as f64)).collect(),
                ),
                (Channel::TipY, (0..rows).map(tip).collect()),
            ],
        }
    }

    /// A laser at one dot: its channel is drawn as measured, by its own
    /// name and place, and the models' tip (which nothing measured) not.
    #[test]
    fn each_measured_channel_has_a_panel_under_its_own_name() {
        let mut laser = free(10, |_| None);
        laser.meta.dots_s_m = Some(vec![0.015]);
        laser.channels[1] = (Channel::DotY(0), (0..10).map(|k| Some(k as f64)).collect());
        let model = free(10, |_| Some(1.0));
        assert_eq!(
            mechanical_channels(Some(&laser), &model),
            [Channel::DotY(0)]
        );
        assert_eq!(
            axis_label(Channel::DotY(0), &laser),
            "dot1_y_m, 15.0 mm from the clamp (mm)"
        );
        let traces = channel_traces(Some(&laser), &[("m", &laser)], Channel::DotY(0), 1e3, 0, "");
        assert!(traces
            .iter()
            .any(|t| t.label == "measured" && t.points.len() == 10));
        // Nothing measured but currents: the models' tip, as before.
        let drive = free(10, |_| None);
        assert_eq!(mechanical_channels(Some(&drive), &model), [Channel::TipY]);
        assert_eq!(mechanical_channels(None, &model), [Channel::TipY]);
        // Several, in the header's order; a column never sampled is not drawn.
        let mut camera = free(10, |_| Some(0.0));
        camera.channels.push((Channel::TipX, vec![Some(0.0); 10]));
        camera.channels.push((Channel::DotY(1), vec![None; 10]));
        assert_eq!(
            mechanical_channels(Some(&camera), &model),
            [Channel::TipY, Channel::TipX]
        );
        assert_eq!(axis_label(Channel::Force, &camera), "force_N (mN)");
        assert_eq!(axis_label(Channel::TipX, &camera), "tip_x_m (mm)");
    }

    #[test]
    fn camera_frames_are_dots_and_models_keep_their_colour() {
        // Camera every 33rd row: sparse.
        let measured = free(100, |k| (k % 33 == 0).then_some(1e-3));
        let base = free(100, |_| Some(2e-3));
        let fin = free(100, |_| Some(3e-3));
        let models = [("baseline", &base), ("final", &fin)];
        let tip = channel_traces(Some(&measured), &models, Channel::TipY, 1e3, 0, "");
        let styles: Vec<(Style, RGBColor, usize)> = tip
            .iter()
            .map(|t| (t.style, t.colour, t.points.len()))
            .collect();
        assert_eq!(
            styles,
            [
                (Style::Line, model_colour(0), 100),
                (Style::Points, model_colour(0), 4),
                (Style::Line, model_colour(1), 100),
                (Style::Points, model_colour(1), 4),
                (Style::Points, MEASURED_COLOUR, 4),
            ]
        );
        // The models at the frames are their own values there.
        assert_eq!(tip[3].points[1], (33e-3, 3.0));
        // Currents on every row: a line, no frames.
        let i = channel_traces(Some(&measured), &models, Channel::Current(0), 1e3, 0, "i1 ");
        assert_eq!(i.len(), 3);
        assert_eq!((i[0].style, i[0].colour), (Style::Line, MEASURED_COLOUR));
        assert_eq!(i[2].colour, model_colour(1));
        assert_eq!(i[2].label, "i1 final");
        // A drive with nothing measured on the channel: no measured trace
        // and no legend entry for one.
        let unmeasured = free(100, |_| None);
        let tip = channel_traces(Some(&unmeasured), &models, Channel::TipY, 1e3, 0, "");
        assert_eq!(tip.len(), 2);
        assert!(tip
            .iter()
            .all(|t| t.colour != MEASURED_COLOUR && t.points.len() == 100));
        // The same models in the autocorrelation plot: the same colours.
        let rho = autocorrelation_traces(
            &[("baseline", vec![1.0, 0.1]), ("final", vec![1.0, 0.0])],
            0.05,
        );
        assert_eq!(rho[0].colour, model_colour(0));
        assert_eq!(rho[1].colour, model_colour(1));
        assert!(rho[2..]
            .iter()
            .all(|t| t.colour == BAND_COLOUR && t.style == Style::Dashed));
    }
}
