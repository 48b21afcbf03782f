//! Distributions: histograms, scatters against an input, tornado charts.

use std::path::Path;

use plotters::prelude::*;

use super::{
    atomic_png, bounds, fitted_caption, labels_in_units, mark_labels, tick, xy_chart, Series,
};

/// A histogram of `values` (already in display units) with vertical lines at `marks`
/// (label, x), e.g. P10/P50/P90.
pub fn histogram(
    path: &Path,
    title: &str,
    x_label: &str,
    values: &[f64],
    marks: &[(&str, f64)],
) -> std::io::Result<()> {
    let title = crate::display_units::text(title);
    let (x_label, k) = crate::display_units::axis(x_label);
    let (title, x_label) = (title.as_str(), x_label.as_str());
    let marks: Vec<(&str, f64)> = marks.iter().map(|(l, x)| (*l, x * k)).collect();
    let marks = marks.as_slice();
    let v: Vec<f64> = values
        .iter()
        .map(|x| x * k)
        .filter(|x| x.is_finite())
        .collect();
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1000, 640)).into_drawing_area();
        root.fill(&WHITE)?;
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(*x), b.max(*x))
            });
        let (lo, hi) = if !lo.is_finite() {
            (0.0, 1.0)
        } else if lo == hi {
            (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
        } else {
            (lo, hi)
        };
        // Sturges-like bin count, 10 … 40.
        let bins = ((v.len() as f64).sqrt().ceil() as usize).clamp(10, 40);
        let w = (hi - lo) / bins as f64;
        let mut counts = vec![0usize; bins];
        for x in &v {
            counts[(((x - lo) / w) as usize).min(bins - 1)] += 1;
        }
        let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.1;
        let caption = fitted_caption(&root, title, 24);
        let mut chart = ChartBuilder::on(&root)
            .caption(&caption.0, ("sans-serif", caption.1))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(lo - 0.02 * (hi - lo)..hi + 0.02 * (hi - lo), 0.0..top)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("samples")
            .x_label_formatter(&tick)
            .y_label_formatter(&|y| format!("{y:.0}"))
            .label_style(("sans-serif", 15))
            .draw()?;
        chart.draw_series(counts.iter().enumerate().map(|(k, &c)| {
            let x0 = lo + k as f64 * w;
            Rectangle::new([(x0, 0.0), (x0 + w, c as f64)], BLUE.mix(0.5).filled())
        }))?;
        for (k, (label, x)) in mark_labels(marks).into_iter().enumerate() {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, 0.0), (x, top)],
                RED.stroke_width(2),
            )))?;
            // Labels of nearby marks step down so they do not overprint.
            chart.draw_series(std::iter::once(Text::new(
                label,
                (x, top * (0.97 - 0.06 * k as f64)),
                ("sans-serif", 15).into_font(),
            )))?;
        }
        root.present()?;
        Ok(())
    })
}

/// A scatter plot of `points` (display units).
pub fn scatter(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[(f64, f64)],
) -> std::io::Result<()> {
    let (title, (x_label, kx), (y_label, ky)) = labels_in_units(title, x_label, y_label);
    let (title, x_label, y_label) = (title.as_str(), x_label.as_str(), y_label.as_str());
    let points: Vec<(f64, f64)> = points.iter().map(|(x, y)| (x * kx, y * ky)).collect();
    let points = points.as_slice();
    let series = [Series {
        name: "",
        points: points.to_vec(),
        wide: false,
    }];
    let ((x0, x1), (y0, y1)) = bounds(&series);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 640)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = xy_chart(&root, title, 22, 80, x_label, y_label, (x0, x1), (y0, y1))?;
        chart.draw_series(
            points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|&p| Circle::new(p, 3, BLUE.mix(0.6).filled())),
        )?;
        root.present()?;
        Ok(())
    })
}

/// A tornado chart: one horizontal bar per (label, value) in −1 … 1, largest |value| on top.
pub fn tornado(
    path: &Path,
    title: &str,
    x_label: &str,
    bars: &[(String, f64)],
) -> std::io::Result<()> {
    let mut bars: Vec<(String, f64)> = bars
        .iter()
        .filter(|(_, v)| v.is_finite())
        .cloned()
        .collect();
    bars.sort_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    atomic_png(path, |tmp| {
        let root =
            BitMapBackend::new(tmp, (900, 120 + 50 * bars.len().max(1) as u32)).into_drawing_area();
        root.fill(&WHITE)?;
        let n = bars.len().max(1);
        let caption = fitted_caption(&root, title, 22);
        let mut chart = ChartBuilder::on(&root)
            .caption(&caption.0, ("sans-serif", caption.1))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(160)
            .build_cartesian_2d(-1.0..1.0, 0.0..n as f64)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .x_label_formatter(&|x| format!("{x:.1}"))
            .disable_y_mesh()
            .y_label_formatter(&|_| String::new())
            .label_style(("sans-serif", 15))
            .draw()?;
        chart.draw_series(bars.iter().enumerate().map(|(k, (_, v))| {
            let c = if *v >= 0.0 { BLUE } else { RED };
            Rectangle::new(
                [
                    (0.0f64.min(*v), k as f64 + 0.15),
                    (0.0f64.max(*v), k as f64 + 0.85),
                ],
                c.mix(0.7).filled(),
            )
        }))?;
        // Each bar's input and value, on the side of zero the bar does not take.
        chart.draw_series(bars.iter().enumerate().map(|(k, (name, v))| {
            let x = if *v >= 0.0 { -0.97 } else { 0.03 };
            Text::new(
                format!("{name}  {v:+.2}"),
                (x, k as f64 + 0.6),
                ("sans-serif", 16).into_font(),
            )
        }))?;
        root.present()?;
        Ok(())
    })
}
