//! Line plots (PNG) of profiles along the string, written atomically.

use std::path::Path;

use plotters::prelude::*;

/// One line of a plot.
pub struct Series<'a> {
    /// Legend name.
    pub name: &'a str,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Drawn first as a wide, pale band, so a thin line on top of it stays visible where
    /// the two coincide (a reference curve: the soft string under the FE).
    pub wide: bool,
}

/// Series in the output units ([`crate::display_units`]): names through `text`, points
/// scaled by the axes' factors.
struct InUnits {
    names: Vec<String>,
    points: Vec<Vec<(f64, f64)>>,
    wide: Vec<bool>,
}

impl InUnits {
    fn new(series: &[Series], kx: f64, ky: f64) -> Self {
        InUnits {
            names: series
                .iter()
                .map(|s| crate::display_units::text(s.name))
                .collect(),
            points: series
                .iter()
                .map(|s| s.points.iter().map(|(x, y)| (x * kx, y * ky)).collect())
                .collect(),
            wide: series.iter().map(|s| s.wide).collect(),
        }
    }

    fn series(&self) -> Vec<Series<'_>> {
        self.names
            .iter()
            .zip(&self.points)
            .zip(&self.wide)
            .map(|((name, points), wide)| Series {
                name,
                points: points.clone(),
                wide: *wide,
            })
            .collect()
    }
}

/// Markers' labels in the output units.
fn marker_labels(markers: &[Marker]) -> Vec<String> {
    markers
        .iter()
        .map(|m| crate::display_units::text(m.label))
        .collect()
}

/// Markers at their points scaled by the axes' factors, with `labels` ([`marker_labels`]).
fn scaled_markers<'a>(
    markers: &[Marker],
    labels: &'a [String],
    kx: f64,
    ky: f64,
) -> Vec<Marker<'a>> {
    markers
        .iter()
        .zip(labels)
        .map(|(m, label)| Marker {
            label,
            x: m.x * kx,
            y: m.y * ky,
        })
        .collect()
}

/// Title and axis labels in the output units, and the axes' factors.
fn labels_in_units(
    title: &str,
    x_label: &str,
    y_label: &str,
) -> (String, (String, f64), (String, f64)) {
    (
        crate::display_units::text(title),
        crate::display_units::axis(x_label),
        crate::display_units::axis(y_label),
    )
}

/// A marked point with a label (e.g. the neutral point).
pub struct Marker<'a> {
    /// Label.
    pub label: &'a str,
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
}

fn bounds(series: &[Series]) -> ((f64, f64), (f64, f64)) {
    bounds_of(&series.iter().collect::<Vec<_>>())
}

fn bounds_of(series: &[&Series]) -> ((f64, f64), (f64, f64)) {
    let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
    let mut yr = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(x, y) in &s.points {
            if x.is_finite() && y.is_finite() {
                xr = (xr.0.min(x), xr.1.max(x));
                yr = (yr.0.min(y), yr.1.max(y));
            }
        }
    }
    let pad = |(a, b): (f64, f64)| {
        if !a.is_finite() {
            (0.0, 1.0)
        } else if a == b {
            (a - 1.0, b + 1.0)
        } else {
            let p = 0.05 * (b - a);
            (a - p, b + p)
        }
    };
    (pad(xr), pad(yr))
}

/// Draws `series` (and `markers`) into a PNG at `path`.
pub fn line_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    markers: &[Marker],
) -> std::io::Result<()> {
    let (title, (xl, kx), (yl, ky)) = labels_in_units(title, x_label, y_label);
    let lines = InUnits::new(series, kx, ky);
    let labels = marker_labels(markers);
    let markers = scaled_markers(markers, &labels, kx, ky);
    atomic_png(path, |tmp| {
        draw(tmp, &title, &xl, &yl, &lines.series(), &markers, &[])
    })
}

/// Lines with measured points over them: point set `k` takes line `k`'s colour (a mode's
/// measurements over its modelled curve), drawn as filled circles with their own legend
/// entries.
pub fn lines_and_points(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    points: &[Series],
) -> std::io::Result<()> {
    let (title, (xl, kx), (yl, ky)) = labels_in_units(title, x_label, y_label);
    let (lines, dots) = (InUnits::new(series, kx, ky), InUnits::new(points, kx, ky));
    atomic_png(path, |tmp| {
        draw(tmp, &title, &xl, &yl, &lines.series(), &[], &dots.series())
    })
}

fn draw(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    markers: &[Marker],
    points: &[Series],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::new(path, (1000, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let all: Vec<&Series> = series.iter().chain(points).collect();
    let ((x0, x1), (y0, mut y1)) = bounds_of(&all);
    if !markers.is_empty() {
        // Head room for the markers' labels above their points.
        y1 += 0.1 * (y1 - y0);
    }
    let mut chart = xy_chart(&root, title, 24, 90, x_label, y_label, (x0, x1), (y0, y1))?;
    let colours = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
    let colour = |k: usize| -> RGBColor {
        // Six strong colours, then plotters' palette of 99 distinct ones.
        if series.len() <= colours.len() {
            colours[k]
        } else {
            let (r, g, b) = Palette99::pick(k).to_rgba().rgb();
            RGBColor(r, g, b)
        }
    };
    // Wide (reference) series first, thin ones on top of them.
    let order = (0..series.len())
        .filter(|&k| series[k].wide)
        .chain((0..series.len()).filter(|&k| !series[k].wide));
    for k in order {
        let s = &series[k];
        let c = colour(k);
        let style = if s.wide {
            c.mix(0.35).stroke_width(9)
        } else {
            c.stroke_width(2)
        };
        // Segment by segment: a thick polyline's miter joins spike far past a sharp turn
        // (a side-force peak at a stabilizer drew a line below zero at the bit).
        chart
            .draw_series(
                s.points
                    .windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], style)),
            )?
            .label(s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    }
    for (k, p) in points.iter().enumerate() {
        let c = colour(k);
        chart
            .draw_series(
                p.points
                    .iter()
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .map(move |&q| Circle::new(q, 5, c.filled())),
            )?
            .label(p.name)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    for m in markers {
        // The label beside the point, up and to the left, on a white box: it neither
        // covers the point nor the curve through it.
        let label = m.label.to_string();
        chart.draw_series(std::iter::once(
            EmptyElement::at((m.x, m.y))
                + Circle::new((0, 0), 6, RED.filled())
                + Rectangle::new(
                    [(-12 - 8 * label.chars().count() as i32, -34), (-8, -12)],
                    WHITE.mix(0.85).filled(),
                )
                + Text::new(
                    label.clone(),
                    (-10 - 8 * label.chars().count() as i32, -32),
                    ("sans-serif", 16).into_font(),
                ),
        ))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// An orbit: the lateral displacement `points` (x, y, in mm) inside the clearance circle of
/// radius `clearance_mm`, on equal axes. A string that never left the hole axis gets a
/// frame that says so rather than an empty one.
pub fn orbit_plot(
    path: &Path,
    title: &str,
    points: &[(f64, f64)],
    clearance_mm: f64,
) -> std::io::Result<()> {
    // In field units the axes are in inches: every length scaled, the labels' "mm" too.
    let (x_desc, k) = crate::display_units::axis("lateral x (mm)");
    let (y_desc, _) = crate::display_units::axis("lateral y (mm)");
    let title = crate::display_units::text(title);
    let title = title.as_str();
    let points: Vec<(f64, f64)> = points.iter().map(|(x, y)| (x * k, y * k)).collect();
    let points = points.as_slice();
    let clearance_mm = clearance_mm * k;
    let extent = points
        .iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .fold(0.0f64, |m, (x, y)| m.max(x.hypot(*y)));
    let r = 1.1 * clearance_mm.max(extent).max(1e-9);
    atomic_png(path, |tmp| {
        let root = BitMapBackend::new(tmp, (760, 760)).into_drawing_area();
        root.fill(&WHITE)?;
        let caption = fitted_caption(&root, title, 20);
        let mut chart = ChartBuilder::on(&root)
            .caption(&caption.0, ("sans-serif", caption.1))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(-r..r, -r..r)?;
        chart
            .configure_mesh()
            .x_desc(x_desc.as_str())
            .y_desc(y_desc.as_str())
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 15))
            .draw()?;
        if clearance_mm > 0.0 {
            let circle: Vec<(f64, f64)> = (0..=360)
                .map(|k| {
                    let a = (k as f64).to_radians();
                    (clearance_mm * a.cos(), clearance_mm * a.sin())
                })
                .collect();
            chart
                .draw_series(LineSeries::new(circle, BLACK.stroke_width(2)))?
                .label(format!(
                    "clearance {} {}",
                    tick(&clearance_mm),
                    if k == 1.0 { "mm" } else { "in" }
                ))
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2))
                });
        }
        // Motion below a micrometre (or a millionth of the clearance) is no motion.
        if extent <= (1e-3 * k).max(1e-6 * clearance_mm) {
            chart.draw_series(std::iter::once(Text::new(
                format!(
                    "no lateral motion: the string stayed on the hole axis (largest |r| = {} {})",
                    tick(&extent),
                    if k == 1.0 { "mm" } else { "in" }
                ),
                (-0.95 * r, 0.5 * r),
                ("sans-serif", 17).into_font(),
            )))?;
        } else {
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    BLUE.stroke_width(1),
                ))?
                .label("orbit")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
            if let Some(&last) = points.last() {
                chart.draw_series(std::iter::once(Circle::new(last, 5, RED.filled())))?;
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

/// A caption that fits the width of `root`: the preferred font size, smaller (to 11 px) for a
/// long title, and cut with "…" if even that does not fit (a case's long title would
/// otherwise run off both edges).
fn fitted_caption<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    preferred: u32,
) -> (String, u32) {
    // DejaVu Sans averages ≈ 0.55 em per character.
    let width = root.dim_in_pixel().0 as f64 * 0.96;
    let chars = title.chars().count().max(1) as f64;
    let size = (width / (0.55 * chars))
        .floor()
        .min(preferred as f64)
        .max(11.0) as u32;
    let fits = (width / (0.55 * size as f64)) as usize;
    if title.chars().count() <= fits {
        (title.to_string(), size)
    } else {
        let cut: String = title.chars().take(fits.saturating_sub(1)).collect();
        (format!("{cut}…"), size)
    }
}

/// A cartesian chart on `root` with the house style: caption, label areas, engineering tick
/// labels on both axes, the mesh drawn.
type XyChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

#[allow(clippy::too_many_arguments)]
fn xy_chart<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    title: &str,
    caption_size: u32,
    y_area: u32,
    x_label: &str,
    y_label: &str,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<XyChart<'a, 'b>, Box<dyn std::error::Error>> {
    let caption = fitted_caption(root, title, caption_size);
    let mut chart = ChartBuilder::on(root)
        .caption(&caption.0, ("sans-serif", caption.1))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(y_area)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style(("sans-serif", 15))
        .draw()?;
    Ok(chart)
}

/// Writes a PNG through a temporary file and a rename (never half-written).
fn atomic_png(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), Box<dyn std::error::Error>>,
) -> std::io::Result<()> {
    let tmp = path.with_extension(format!("{}.tmp.png", std::process::id()));
    match draw(&tmp) {
        Ok(()) => std::fs::rename(&tmp, path),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(std::io::Error::other(format!(
                "plot {}: {e}",
                path.display()
            )))
        }
    }
}

/// Tick labels of an axis in engineering style: at most 4 significant digits, no
/// trailing zeros, exponent only beyond 1e6 or below 1e-3.
pub fn tick(x: &f64) -> String {
    let a = x.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e6).contains(&a) {
        format!("{x:.2e}")
    } else {
        let s = format!("{:.*}", (3 - a.log10().floor() as i32).max(0) as usize, x);
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

/// The labels of a histogram's marks (`P10 12.3`): marks at the same value share one
/// label (`P10 = P50 12.3`); finite marks only, in the order given.
pub fn mark_labels(marks: &[(&str, f64)]) -> Vec<(String, f64)> {
    let mut out: Vec<(Vec<&str>, f64)> = Vec::new();
    for (label, x) in marks.iter().filter(|m| m.1.is_finite()) {
        match out.iter_mut().find(|(_, y)| tick(y) == tick(x)) {
            Some((names, _)) => names.push(label),
            None => out.push((vec![label], *x)),
        }
    }
    out.into_iter()
        .map(|(names, x)| (format!("{} {}", names.join(" = "), tick(&x)), x))
        .collect()
}

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

/// One point of an estimate's convergence: samples, value, 95 % low and high (NaN where no
/// bound exists).
pub type BandPoint = (f64, f64, f64, f64);

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
    let ((x0, x1), (y0, y1)) = bounds(&[Series {
        name: "",
        points: all,
        wide: false,
    }]);
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
        root.fill(&WHITE)?;
        let caption = fitted_caption(&root, title, 20);
        let mut chart = ChartBuilder::on(&root)
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
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .label_style(("sans-serif", 15))
            .draw()?;
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
    let ((x0, x1), (y0, y1)) = bounds(&[Series {
        name: "",
        points: all,
        wide: false,
    }]);
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

#[cfg(test)]
mod tests {
    #[test]
    fn equal_marks_share_a_label_and_log_axes_tick_each_decade() {
        let l = super::mark_labels(&[("P10", 12.0), ("P50", 12.0), ("P90", 15.0)]);
        assert_eq!(l.len(), 2);
        assert!(l[0].0.starts_with("P10 = P50 "), "{l:?}");
        assert!(l[1].0.starts_with("P90 "), "{l:?}");
        // 0.3 … 7 s: one decade inside, so 1, 2, 5 ticks.
        assert_eq!(super::log_ticks(0.3, 7.0), vec![0.5, 1.0, 2.0, 5.0]);
        // 1e-9 … 1e-2: every decade.
        assert_eq!(super::log_ticks(1e-9, 1e-2).len(), 8);
    }
}
