//! Maps: labelled tiles, classified scatters and heat maps.

use std::path::Path;

use plotters::prelude::*;

use super::{
    atomic_png, labels_in_units, marker_labels, point_bounds, scaled_markers, xy_chart, Marker,
};

/// One tile of a [`tile_map`].
pub struct Tile {
    /// Row label.
    pub row: String,
    /// Column label (within its row).
    pub column: String,
    /// 0 green, 1 amber, 2 red.
    pub colour: usize,
    /// Text in the tile.
    pub text: String,
}

/// A map of labelled tiles: one row per distinct `row`, its tiles left to right in order,
/// each coloured and labelled with its column and text.
pub fn tile_map(path: &Path, title: &str, tiles: &[Tile]) -> std::io::Result<()> {
    let mut rows: Vec<&str> = Vec::new();
    for t in tiles {
        if !rows.contains(&t.row.as_str()) {
            rows.push(&t.row);
        }
    }
    let cols = rows
        .iter()
        .map(|r| tiles.iter().filter(|t| t.row == *r).count())
        .max()
        .unwrap_or(1)
        .max(1);
    let (cw, rh, left, top) = (120i32, 44i32, 230i32, 50i32);
    let width = (left + cw * cols as i32 + 20) as u32;
    let height = (top + rh * rows.len().max(1) as i32 + 20) as u32;
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (width.max(600), height)).into_drawing_area();
        root.fill(&WHITE)?;
        root.draw(&Text::new(
            title.to_string(),
            (10, 12),
            ("sans-serif", 18).into_font(),
        ))?;
        let palette = [
            RGBColor(120, 200, 120),
            RGBColor(240, 190, 80),
            RGBColor(230, 100, 90),
        ];
        for (ri, r) in rows.iter().enumerate() {
            let y = top + ri as i32 * rh;
            root.draw(&Text::new(
                r.to_string(),
                (8, y + 14),
                ("sans-serif", 14).into_font(),
            ))?;
            for (ci, t) in tiles.iter().filter(|t| t.row == *r).enumerate() {
                let x = left + ci as i32 * cw;
                root.draw(&Rectangle::new(
                    [(x, y), (x + cw - 4, y + rh - 4)],
                    palette[t.colour.min(2)].filled(),
                ))?;
                root.draw(&Text::new(
                    t.column.clone(),
                    (x + 4, y + 4),
                    ("sans-serif", 12).into_font(),
                ))?;
                root.draw(&Text::new(
                    t.text.clone(),
                    (x + 4, y + 22),
                    ("sans-serif", 12).into_font(),
                ))?;
            }
        }
        root.present()?;
        Ok(())
    })
}

/// A scatter of classified points: (x, y, class) with one colour and legend entry per
/// class name (`classes[class]`), e.g. a whirl map over RPM × WOB.
pub fn class_scatter(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[(f64, f64, usize)],
    classes: &[&str],
) -> std::io::Result<()> {
    let (title, (x_label, kx), (y_label, ky)) = labels_in_units(title, x_label, y_label);
    let (title, x_label, y_label) = (title.as_str(), x_label.as_str(), y_label.as_str());
    let points: Vec<(f64, f64, usize)> = points.iter().map(|p| (p.0 * kx, p.1 * ky, p.2)).collect();
    let points = points.as_slice();
    let all: Vec<(f64, f64)> = points.iter().map(|p| (p.0, p.1)).collect();
    let ((x0, x1), (y0, y1)) = point_bounds(all);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 660)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = xy_chart(&root, title, 20, 80, x_label, y_label, (x0, x1), (y0, y1))?;
        let colours = [RGBColor(150, 150, 150), BLUE, RED, MAGENTA, GREEN, BLACK];
        for (c, name) in classes.iter().enumerate() {
            let colour = colours[c % colours.len()];
            let pts: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.2 == c && p.0.is_finite() && p.1.is_finite())
                .map(|p| (p.0, p.1))
                .collect();
            if pts.is_empty() {
                continue;
            }
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 7, colour.filled())))?
                .label(*name)
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour.filled()));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    })
}

/// A heat map of `values[i][j]` (≥ 0) over the cells centred on `xs[i]` × `ys[j]` (uniform
/// grids), white at 0 to dark blue at the largest value, with `marks` drawn as labelled
/// red points (e.g. a posterior density and its mode).
pub fn heat_map(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    (xs, ys): (&[f64], &[f64]),
    values: &[Vec<f64>],
    marks: &[Marker],
) -> std::io::Result<()> {
    let (title, (x_label, kx), (y_label, ky)) = labels_in_units(title, x_label, y_label);
    let (title, x_label, y_label) = (title.as_str(), x_label.as_str(), y_label.as_str());
    let (xs, ys): (Vec<f64>, Vec<f64>) = (
        xs.iter().map(|x| x * kx).collect(),
        ys.iter().map(|y| y * ky).collect(),
    );
    let (xs, ys) = (xs.as_slice(), ys.as_slice());
    let labels = marker_labels(marks);
    let marks = scaled_markers(marks, &labels, kx, ky);
    let top = values
        .iter()
        .flatten()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let half = |g: &[f64]| {
        if g.len() > 1 {
            0.5 * (g[1] - g[0])
        } else {
            0.5
        }
    };
    let (hx, hy) = (half(xs), half(ys));
    let xr = (xs[0] - hx, xs[xs.len() - 1] + hx);
    let yr = (ys[0] - hy, ys[ys.len() - 1] + hy);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 760)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = xy_chart(&root, title, 22, 80, x_label, y_label, xr, yr)?;
        chart.draw_series(xs.iter().enumerate().flat_map(|(i, &x)| {
            ys.iter().enumerate().map(move |(j, &y)| {
                let t = (values[i][j] / top).clamp(0.0, 1.0);
                let c = RGBColor(
                    (255.0 * (1.0 - 0.9 * t)) as u8,
                    (255.0 * (1.0 - 0.75 * t)) as u8,
                    (255.0 * (1.0 - 0.35 * t)) as u8,
                );
                Rectangle::new([(x - hx, y - hy), (x + hx, y + hy)], c.filled())
            })
        }))?;
        for m in marks {
            chart.draw_series(std::iter::once(
                EmptyElement::at((m.x, m.y))
                    + Circle::new((0, 0), 6, RED.filled())
                    + Text::new(
                        m.label.to_string(),
                        (10, -8),
                        ("sans-serif", 16).into_font(),
                    ),
            ))?;
        }
        root.present()?;
        Ok(())
    })
}
