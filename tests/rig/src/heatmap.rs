//! The sweep's confusion matrix as a picture: one cell per hidden row and
//! named column, shaded by the share of the row's sessions.

use std::path::Path;

use plotters::prelude::*;

use crate::sweep::{columns, matrix, Outcome};

/// Draws the matrix of `outcomes` into the PNG at `path`.
pub fn draw(outcomes: &[Outcome], path: &Path) -> anyhow::Result<()> {
    finrs::plot::register_fonts()?;
    let rows = matrix(outcomes);
    let columns = columns();
    let (label_w, cell_w, cell_h, head_h) = (330i32, 72i32, 26i32, 240i32);
    let width = (label_w + cell_w * columns.len() as i32 + 20) as u32;
    let height = (head_h + cell_h * rows.len() as i32 + 20) as u32;
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE)?;
    let text = ("sans-serif", 15).into_font();
    for (j, c) in columns.iter().enumerate() {
        let x = label_w + cell_w * j as i32 + cell_w / 2;
        root.draw(&Text::new(
            c.to_string(),
            (x, head_h - 8),
            text.clone().transform(FontTransform::Rotate270),
        ))?;
    }
    for (i, (key, r)) in rows.iter().enumerate() {
        let y = head_h + cell_h * i as i32;
        root.draw(&Text::new(
            format!("{key} ({})", r.sessions),
            (6, y + 6),
            text.clone(),
        ))?;
        for (j, c) in columns.iter().enumerate() {
            let share = r.named.get(c).copied().unwrap_or(0) as f64 / r.sessions.max(1) as f64;
            let x = label_w + cell_w * j as i32;
            // White (never) to dark blue (every session).
            let shade = (255.0 * (1.0 - 0.85 * share)) as u8;
            let fill = RGBColor(shade, shade, 255);
            root.draw(&Rectangle::new(
                [(x, y), (x + cell_w - 1, y + cell_h - 1)],
                fill.filled(),
            ))?;
            root.draw(&Rectangle::new(
                [(x, y), (x + cell_w - 1, y + cell_h - 1)],
                RGBColor(200, 200, 200),
            ))?;
            if share > 0.0 {
                let colour = if share > 0.6 { WHITE } else { BLACK };
                root.draw(&Text::new(
                    format!("{:.0}", 100.0 * share),
                    (x + cell_w / 2 - 10, y + 6),
                    text.clone().color(&colour),
                ))?;
            }
        }
    }
    root.present()?;
    Ok(())
}
