//! Convergence and error-against-time plots (benchmarks, Monte Carlo estimates).

use std::path::Path;

use plotters::prelude::*;

use super::*;

/// Estimates against the number of samples, each with its 95 % band: (name, points).
pub fn convergence_plot(
    path: &Path,
    title: &str,
    y_label: &str,
    estimates: &[(&str, Vec<BandPoint>)],
) -> std::io::Result<()> {
    let all: Vec<(f64, f64)> = estimates
        .iter()
        .flat_map(|(_, p)| p.iter().flat_map(|&(n, v, a, b)| [(n, v), (n, a), (n, b)]))
        .collect();
    let ((x0, x1), (y0, y1)) = point_bounds(all);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1000, 640)).into_drawing_area();
        root.fill(&WHITE)?;
        let caption = fitted_caption(&root, title, 22);
        let mut chart = ChartBuilder::on(&root)
            .caption(&caption.0, ("sans-serif", caption.1))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x0.max(0.0)..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("samples")
            .y_desc(y_label)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 15))
            .draw()?;
        let colours = [BLUE, RED, GREEN, MAGENTA];
        for (k, (name, pts)) in estimates.iter().enumerate() {
            let c = colours[k % colours.len()];
            let line: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
            chart
                .draw_series(LineSeries::new(line, c.stroke_width(3)))?
                .label(format!("{name} (band: 95 %)"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                });
            for side in [2usize, 3] {
                let band: Vec<(f64, f64)> = pts
                    .iter()
                    .map(|p| (p.0, if side == 2 { p.2 } else { p.3 }))
                    .filter(|(_, y)| y.is_finite())
                    .collect();
                chart.draw_series(LineSeries::new(band, c.mix(0.4).stroke_width(1)))?;
            }
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

/// Ticks of a log axis over `lo … hi`: every decade, and 2 and 5 times each where fewer
/// than three decades fall inside (a range within one decade still gets ticks).
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let inside = |v: &f64| *v >= lo && *v <= hi;
    let decades: Vec<f64> = (a..=b).map(|k| 10f64.powi(k)).filter(inside).collect();
    if decades.len() >= 3 {
        return decades;
    }
    (a..=b)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
        .filter(inside)
        .collect()
}

/// A log–log plot of `series` (name, points (x, y), all > 0), markers on the points, and a
/// dashed horizontal line at `y_line` (a tolerance).
pub fn loglog_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    y_line: f64,
) -> std::io::Result<()> {
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(_, p)| p.iter().copied())
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .chain(std::iter::once((f64::NAN, y_line)))
        .collect();
    let fold = |f: &dyn Fn(&(f64, f64)) -> f64| {
        pts.iter()
            .map(f)
            .filter(|v| v.is_finite() && *v > 0.0)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (mut x0, mut x1) = fold(&|p| p.0);
    let (mut y0, mut y1) = fold(&|p| p.1);
    if !x0.is_finite() {
        (x0, x1) = (0.1, 10.0);
    }
    if !y0.is_finite() {
        (y0, y1) = (1e-6, 1.0);
    }
    let (x0, x1) = (x0 / 1.5, x1 * 1.5);
    let (y0, y1) = (y0 / 3.0, y1 * 3.0);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1000, 680)).into_drawing_area();
        let mut chart = loglog_chart(&root, title, (x0, x1, x_label), (y0, y1, y_label), &|y| {
            format!("{y:.0e}")
        })?;
        let colours = [BLUE, RED, GREEN, MAGENTA];
        for (k, (name, p)) in series.iter().enumerate() {
            let c = colours[k % colours.len()];
            let mut p = p.clone();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(p.clone(), c.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart.draw_series(p.iter().map(|&q| Circle::new(q, 5, c.filled())))?;
        }
        let dashes: Vec<f64> = (0..=40)
            .map(|k| x0 * (x1 / x0).powf(k as f64 / 40.0))
            .collect();
        for w in dashes.chunks(2) {
            if let [a, b] = w {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(*a, y_line), (*b, y_line)],
                    BLACK.stroke_width(1),
                )))?;
            }
        }
        chart.draw_series(std::iter::once(Text::new(
            format!("tolerance {y_line:.0e}"),
            (x0 * 1.1, y_line * 1.3),
            ("sans-serif", 15).into_font(),
        )))?;
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    })
}

/// One kernel's points on a [`roofline_plot`]: its name, its style (colour, shape) and its
/// (intensity, GFLOP/s) points.
pub type RooflineSet = (String, (usize, usize), Vec<(f64, f64)>);

/// A roofline: on log–log axes of arithmetic intensity (FLOP/byte) and GFLOP/s, each `roofs`
/// line (name, its points: the bound `min(peak, bandwidth × intensity)`) and each `kernels`
/// point set (name, its style, (intensity, achieved GFLOP/s)): the style's colour (an index
/// into a palette of 8: a kernel) and shape (0 a circle, 1 a triangle: a precision), so no
/// two sets look alike unless the caller says so.
pub fn roofline_plot(
    path: &Path,
    title: &str,
    roofs: &[(String, Vec<(f64, f64)>)],
    kernels: &[RooflineSet],
) -> std::io::Result<()> {
    let positive = |p: &&(f64, f64)| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
    let all: Vec<(f64, f64)> = roofs
        .iter()
        .map(|(_, p)| p)
        .chain(kernels.iter().map(|(_, _, p)| p))
        .flat_map(|p| p.iter().filter(positive).copied())
        .collect();
    let range = |f: &dyn Fn(&(f64, f64)) -> f64| {
        all.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let ((mut x0, mut x1), (mut y0, mut y1)) = (range(&|p| p.0), range(&|p| p.1));
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.01, 100.0, 0.01, 100.0);
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 2.0, y1 * 2.0);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (1000, 680)).into_drawing_area();
        let mut chart = loglog_chart(
            &root,
            title,
            (x0, x1, "arithmetic intensity (FLOP/byte)"),
            (y0, y1, "GFLOP/s"),
            &tick,
        )?;
        for (k, (name, p)) in roofs.iter().enumerate() {
            let c = [BLACK, RGBColor(120, 120, 120)][k % 2];
            chart
                .draw_series(LineSeries::new(
                    p.iter().filter(positive).copied(),
                    c.stroke_width(3),
                ))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                });
        }
        let colours = [
            BLUE,
            RED,
            GREEN,
            MAGENTA,
            CYAN,
            RGBColor(140, 70, 0),
            RGBColor(90, 0, 120),
            RGBColor(0, 100, 60),
        ];
        for (name, (colour, shape), p) in kernels {
            let c = colours[colour % colours.len()].filled();
            let pts: Vec<(f64, f64)> = p.iter().filter(positive).copied().collect();
            if shape % 2 == 0 {
                chart
                    .draw_series(pts.iter().map(|&q| Circle::new(q, 6, c)))?
                    .label(name.as_str())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 6, c));
            } else {
                chart
                    .draw_series(pts.iter().map(|&q| TriangleMarker::new(q, 8, c)))?
                    .label(name.as_str())
                    .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 8, c));
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    })
}

/// Log–log axes with key points at the decades (and their 2, 5 where few), the title fitted
/// to the width, the mesh drawn: the chart of [`loglog_plot`] and [`roofline_plot`].
#[allow(clippy::type_complexity)]
fn loglog_chart<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    title: &str,
    (x0, x1, x_label): (f64, f64, &str),
    (y0, y1, y_label): (f64, f64, &str),
    y_format: &dyn Fn(&f64) -> String,
) -> Result<
    ChartContext<
        'a,
        BitMapBackend<'b>,
        Cartesian2d<
            plotters::coord::combinators::WithKeyPoints<
                plotters::coord::combinators::LogCoord<f64>,
            >,
            plotters::coord::combinators::WithKeyPoints<
                plotters::coord::combinators::LogCoord<f64>,
            >,
        >,
    >,
    Box<dyn std::error::Error>,
> {
    root.fill(&WHITE)?;
    let caption = fitted_caption(root, title, 20);
    let mut chart = ChartBuilder::on(root)
        .caption(&caption.0, ("sans-serif", caption.1))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(90)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
        )?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&tick)
        .y_label_formatter(y_format)
        .label_style(("sans-serif", 15))
        .draw()?;
    Ok(chart)
}
