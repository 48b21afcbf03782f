//! Line plots (PNG) of profiles along the string, written atomically.

use std::path::Path;

use plotters::prelude::*;

mod convergence;
mod distributions;
mod maps;
pub use convergence::{convergence_plot, log_ticks, loglog_plot, roofline_plot, RooflineSet};
pub use distributions::{histogram, scatter, tornado};
pub use maps::{class_scatter, heat_map, tile_map, Tile};

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

/// [`bounds`] of bare points.
fn point_bounds(points: Vec<(f64, f64)>) -> ((f64, f64), (f64, f64)) {
    bounds(&[Series {
        name: "",
        points,
        wide: false,
    }])
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

/// Thin lines (or point sets) from named point lists.
pub fn named_series(sets: &[(String, Vec<(f64, f64)>)]) -> Vec<Series<'_>> {
    sets.iter()
        .map(|(name, points)| Series {
            name,
            points: points.clone(),
            wide: false,
        })
        .collect()
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
        draw(
            tmp,
            &title,
            &xl,
            &yl,
            &lines.series(),
            &markers,
            (&[], Dots::LineColours),
        )
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
    lines_with_dots(
        path,
        (title, x_label, y_label),
        series,
        points,
        Dots::LineColours,
    )
}

/// [`lines_and_points`] and [`lines_and_measured`]: lines, then point sets coloured by `dots`.
fn lines_with_dots(
    path: &Path,
    (title, x_label, y_label): (&str, &str, &str),
    series: &[Series],
    points: &[Series],
    dots: Dots,
) -> std::io::Result<()> {
    let (title, (xl, kx), (yl, ky)) = labels_in_units(title, x_label, y_label);
    let (lines, pts) = (InUnits::new(series, kx, ky), InUnits::new(points, kx, ky));
    atomic_png(path, |tmp| {
        draw(
            tmp,
            &title,
            &xl,
            &yl,
            &lines.series(),
            &[],
            (&pts.series(), dots),
        )
    })
}

/// Lines with measured points over them where the points do not belong to one line each
/// (an ensemble's broomstick: many lines per mode, one point set per mode): each point set
/// gets its own dark colour and shape (filled circle, triangle, square, …) so it reads apart
/// from the lines.
pub fn lines_and_measured(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    points: &[Series],
) -> std::io::Result<()> {
    lines_with_dots(path, (title, x_label, y_label), series, points, Dots::Own)
}

/// How point sets are coloured.
#[derive(Clone, Copy, PartialEq)]
enum Dots {
    /// Point set `k` in line `k`'s colour, filled circles.
    LineColours,
    /// Their own dark colours and shapes.
    Own,
}

fn draw(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    markers: &[Marker],
    (points, dots): (&[Series], Dots),
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
        let pts = p
            .points
            .iter()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .copied();
        let shape = if dots == Dots::Own { k % 3 } else { 0 };
        let c = match dots {
            Dots::LineColours => colour(k),
            Dots::Own => [
                BLACK,
                RGBColor(140, 70, 0),
                RGBColor(90, 0, 120),
                RGBColor(0, 100, 60),
                RGBColor(110, 110, 110),
            ][k % 5],
        };
        let style = c.filled();
        let name = p.name;
        match shape {
            0 => {
                chart
                    .draw_series(pts.map(move |q| Circle::new(q, 5, style)))?
                    .label(name)
                    .legend(move |(x, y)| Circle::new((x + 10, y), 5, style));
            }
            1 => {
                chart
                    .draw_series(pts.map(move |q| TriangleMarker::new(q, 7, style)))?
                    .label(name)
                    .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 7, style));
            }
            _ => {
                let square = move |q: (i32, i32)| {
                    Rectangle::new([(q.0 - 5, q.1 - 5), (q.0 + 5, q.1 + 5)], style)
                };
                chart
                    .draw_series(pts.map(move |q| {
                        EmptyElement::at(q) + Rectangle::new([(-5, -5), (5, 5)], style)
                    }))?
                    .label(name)
                    .legend(move |(x, y)| square((x + 10, y)));
            }
        }
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
        .position(legend_corner(&all, (x0, x1), (y0, y1)))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// The corner of the plot whose quarter (the outer 45 % of each axis) holds the fewest
/// points of `series` (lines sampled at their points): where the legend covers least.
/// Upper right wins ties, then upper left.
fn legend_corner(
    series: &[&Series],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> SeriesLabelPosition {
    let (wx, wy) = (0.45 * (x1 - x0), 0.45 * (y1 - y0));
    let corners = [
        (SeriesLabelPosition::UpperRight, x1 - wx..=x1, y1 - wy..=y1),
        (SeriesLabelPosition::UpperLeft, x0..=x0 + wx, y1 - wy..=y1),
        (SeriesLabelPosition::LowerRight, x1 - wx..=x1, y0..=y0 + wy),
        (SeriesLabelPosition::LowerLeft, x0..=x0 + wx, y0..=y0 + wy),
    ];
    let count = |xr: &std::ops::RangeInclusive<f64>, yr: &std::ops::RangeInclusive<f64>| {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|(x, y)| xr.contains(x) && yr.contains(y))
            .count()
    };
    corners
        .into_iter()
        .min_by_key(|(_, xr, yr)| count(xr, yr))
        .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
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
        let mut chart = xy_chart(&root, title, 20, 70, &x_desc, &y_desc, (-r, r), (-r, r))?;
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

/// The plots' one typeface, DejaVu Sans (licence beside it), carried in the binary so that
/// PNG text needs no font installed on the machine: registered once as "sans-serif", the
/// family every plot names.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font (the test `the_carried_font_draws_text`).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Writes a PNG through a temporary file and a rename (never half-written).
fn atomic_png(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), Box<dyn std::error::Error>>,
) -> std::io::Result<()> {
    register_font();
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

/// One point of an estimate's convergence: samples, value, 95 % low and high (NaN where no
/// bound exists).
pub type BandPoint = (f64, f64, f64, f64);

#[cfg(test)]
mod tests {
    #[test]
    fn the_carried_font_draws_text() {
        use plotters::prelude::*;
        assert!(
            plotters::style::register_font("sans-serif", FontStyle::Normal, super::FONT).is_ok()
        );
        super::register_font();
        let (w, h) = ("sans-serif", 15)
            .into_font()
            .box_size("kN·m, °/30 m, λ")
            .expect("text measured with the carried font");
        assert!(w > 50 && h > 5, "{w}×{h}");
    }

    #[test]
    fn the_legend_goes_where_the_data_are_not() {
        use plotters::prelude::SeriesLabelPosition as P;
        let at = |pts: Vec<(f64, f64)>| {
            let s = super::Series {
                name: "s",
                points: pts,
                wide: false,
            };
            super::legend_corner(&[&s], (0.0, 10.0), (0.0, 10.0))
        };
        // A broomstick low across the plot: upper right is free.
        assert!(matches!(at(vec![(1.0, 1.0), (9.0, 2.0)]), P::UpperRight));
        // Data in the upper right and along the bottom: upper left.
        assert!(matches!(
            at(vec![(9.0, 9.0), (8.0, 8.0), (1.0, 1.0), (9.0, 1.0)]),
            P::UpperLeft
        ));
        // Everything in the upper half: the lower right.
        assert!(matches!(
            at(vec![(1.0, 9.0), (9.0, 9.0), (2.0, 8.0)]),
            P::LowerRight
        ));
    }

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
