//! The study's pictures: the chart of time against error (`study.png`)
//! and the side-by-side picture of a failing case (method | reference |
//! amplified difference).
//!
//! The chart is drawn with `plotters` into an RGB buffer, its text with
//! DejaVu Sans compiled into the binary ([`crate::output::font`]), so it
//! needs no system font and no window: it works in the headless build. The caller saves the image with [`crate::output`].

use super::{FAIL_BELOW, Row};
use image::{Rgb, RgbImage};
use plotters::coord::Shift;
use plotters::element::{DashedPathElement, Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::DrawingErrorKind;
use std::ops::Range;

/// The chart's size in pixels.
pub const CHART_SIZE: (u32, u32) = (1200, 760);

/// How much the difference panel of a failure picture amplifies.
pub const DIFF_GAIN: u16 = 8;

/// The gap between the panels of a failure picture, in pixels.
pub const GAP: u32 = 4;

/// The error plotted: the share of pixels off by more than one level.
/// Exact rows (0) sit on the floor of the log axis, [`ERROR_FLOOR`].
pub fn error(row: &Row) -> f64 {
    (1.0 - row.within1).max(ERROR_FLOOR)
}

/// The bottom of the error axis: exact rows are drawn here.
pub const ERROR_FLOOR: f64 = 1e-5;

/// Why the chart could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw the study chart: {0}")]
pub struct ChartError(String);

fn err<E: std::fmt::Display>(e: E) -> ChartError {
    ChartError(e.to_string())
}

/// The fastest row of each scene that did not fail (ties: the first), in
/// the order the scenes first appear.
pub fn fastest_accurate(rows: &[Row]) -> Vec<&Row> {
    let mut best: Vec<&Row> = Vec::new();
    for row in rows.iter().filter(|r| !r.failed) {
        match best.iter_mut().find(|b| b.scene == row.scene) {
            Some(b) if row.time < b.time => *b = row,
            Some(_) => {}
            None => best.push(row),
        }
    }
    best
}

/// Twelve colours that stay apart (Tableau 10, black and navy): one per
/// study method, so that no two share a colour.
const COLOURS: [RGBColor; 12] = [
    RGBColor(0, 0, 0),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 128),
];

/// The colour of method number `i` (as RGB), the same in the chart and in
/// the app's plot.
pub fn method_colour(i: usize) -> (u8, u8, u8) {
    let RGBColor(r, g, b) = COLOURS[i % COLOURS.len()];
    (r, g, b)
}

/// The marker shape of method number `i` in the chart: 0 circle,
/// 1 square, 2 triangle, 3 cross, 4 diamond.
pub fn method_shape(i: usize) -> usize {
    i % 5
}

/// The marker of method number `i` at `coord`: the colour changes with
/// every method and the shape with every one of five, so that no two of
/// 60 methods look alike.
struct Marker<C> {
    coord: C,
    i: usize,
}

fn marker<C>(i: usize, coord: C) -> Marker<C> {
    Marker { coord, i }
}

impl<'a, C> PointCollection<'a, C> for &'a Marker<C> {
    type Point = &'a C;
    type IntoIter = std::iter::Once<&'a C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.coord)
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for Marker<C> {
    fn draw<I: Iterator<Item = BackendCoordinate>>(
        &self,
        mut points: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = points.next() else {
            return Ok(());
        };
        let colour = COLOURS[self.i % COLOURS.len()];
        let filled = colour.filled();
        match method_shape(self.i) {
            0 => backend.draw_circle((x, y), 5, &filled, true),
            1 => backend.draw_rect((x - 4, y - 4), (x + 4, y + 4), &filled, true),
            2 => backend.fill_polygon([(x, y - 6), (x + 6, y + 5), (x - 6, y + 5)], &filled),
            3 => {
                let line = colour.stroke_width(2);
                backend.draw_line((x - 5, y - 5), (x + 5, y + 5), &line)?;
                backend.draw_line((x - 5, y + 5), (x + 5, y - 5), &line)
            }
            _ => backend.fill_polygon([(x, y - 6), (x + 6, y), (x, y + 6), (x - 6, y)], &filled),
        }
    }
}

/// Pixel coordinates on the backend.
type BackendCoordinate = (i32, i32);

/// The width of the legend column on the right of the chart, in pixels:
/// the legend is drawn there, beside the plotting area, never over it.
pub const LEGEND_WIDTH: u32 = 200;

/// Where [`draw`] put the plotting area and the legend box, in pixels of
/// the picture: `(x range, y range)` each.
#[derive(Debug, Clone, PartialEq)]
struct Layout {
    plot: (Range<i32>, Range<i32>),
    legend: (Range<i32>, Range<i32>),
}

/// Draws the chart of `rows`: median time (ms, log) against the share of
/// pixels off by more than one level (log, exact rows on the floor), one
/// mark per scene and method, methods told apart by colour and shape, the
/// fail threshold dashed, and the fastest accurate method of each scene
/// circled and labelled with the scene's name. The legend stands in a
/// column on the right, outside the plotting area.
pub fn chart(rows: &[Row]) -> Result<RgbImage, ChartError> {
    render(rows).map(|(image, _)| image)
}

/// [`chart`], and where it put the plotting area and the legend.
fn render(rows: &[Row]) -> Result<(RgbImage, Layout), ChartError> {
    crate::output::font::register().map_err(err)?;
    let (w, h) = CHART_SIZE;
    let mut buffer = vec![0u8; w as usize * h as usize * 3];
    let layout = {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        let layout = draw(&root, rows)?;
        root.present().map_err(err)?;
        layout
    };
    let image = RgbImage::from_raw(w, h, buffer).ok_or_else(|| ChartError("buffer size".into()))?;
    Ok((image, layout))
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rows: &[Row],
) -> Result<Layout, ChartError> {
    root.fill(&WHITE).map_err(err)?;
    let times = rows.iter().map(|r| r.time.as_secs_f64() * 1e3);
    let (lo, hi) = times.fold((f64::INFINITY, 0.0f64), |(lo, hi), t| {
        (lo.min(t), hi.max(t))
    });
    let (lo, hi) = if lo.is_finite() && lo > 0.0 {
        (lo / 1.6, hi * 1.6)
    } else {
        (0.01, 10.0)
    };
    // The title over the whole width, then the chart on the left and the
    // legend's column on the right.
    let titled = root
        .margin(12, 12, 12, 12)
        .titled(
            "RayOfLight study: speed against accuracy (circled: fastest method that passes, per scene)",
            ("sans-serif", 20),
        )
        .map_err(err)?;
    let (width, _) = titled.dim_in_pixel();
    let (left, right) = titled.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
    let mut chart = ChartBuilder::on(&left)
        .margin_top(8)
        .x_label_area_size(48)
        .y_label_area_size(90)
        .build_cartesian_2d((lo..hi).log_scale(), (ERROR_FLOOR / 1.5..1.5).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("median render time, ms (log)")
        .y_desc("pixels off by more than 1 level (1 − within1, log; bottom: exact)")
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|t| format_number(*t))
        .y_label_formatter(&|e| {
            if *e <= ERROR_FLOOR * 1.01 {
                "exact".to_owned()
            } else {
                format!("{}%", format_number(*e * 100.0))
            }
        })
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;

    // The fail threshold.
    let threshold = 1.0 - FAIL_BELOW;
    let dashed = RED.mix(0.6).stroke_width(2);
    chart
        .draw_series(DashedLineSeries::new(
            [(lo, threshold), (hi, threshold)],
            8,
            6,
            dashed,
        ))
        .map_err(err)?;

    // One series per method, in the order the rows name them.
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method);
        }
    }
    for (i, method) in methods.iter().enumerate() {
        let points = rows
            .iter()
            .filter(|r| r.method == *method)
            .map(move |r| marker(i, (r.time.as_secs_f64() * 1e3, error(r))));
        chart.draw_series(points).map_err(err)?;
    }

    // The fastest accurate choice of each scene: circled and named.
    // Names of scenes whose marks nearly coincide are stacked upwards.
    let mut best = fastest_accurate(rows);
    best.sort_by_key(|r| r.time);
    let at = |r: &Row| (r.time.as_secs_f64() * 1e3, error(r));
    // Each label takes the lowest line that no nearby label holds.
    let mut placed: Vec<(f64, f64, i32)> = Vec::new();
    let mut labels = Vec::new();
    for r in &best {
        let (t, e) = at(r);
        let taken: Vec<i32> = placed
            .iter()
            .filter(|(pt, pe, _)| (t / pt).max(pt / t) < 2.5 && (e / pe).max(pe / e) < 3.0)
            .map(|&(_, _, line)| line)
            .collect();
        let line = (0..).find(|l| !taken.contains(l)).unwrap_or(0);
        placed.push((t, e, line));
        labels.push(-26 - 16 * line);
    }
    chart
        .draw_series(best.iter().zip(labels).map(|(r, dy)| {
            EmptyElement::at(at(r))
                + Circle::new((0, 0), 11, BLACK.stroke_width(2))
                + Text::new(r.scene.clone(), (8, dy), ("sans-serif", 14))
        }))
        .map_err(err)?;

    let plot = chart.plotting_area().get_pixel_range();
    let legend = draw_legend(
        &right,
        &methods,
        plot.1.start,
        &format!("fails above {}%", format_number(threshold * 100.0)),
    )?;
    Ok(Layout { plot, legend })
}

/// The height of one legend entry, in pixels.
const LEGEND_LINE: i32 = 22;

/// The legend in `area` (the column right of the chart), its top at the
/// picture's row `top`: the dashed threshold, then each method's marker
/// (the same [`marker`] as the points) and name. Returns the box it drew,
/// in pixels of the picture.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    methods: &[&str],
    top: i32,
    threshold: &str,
) -> Result<(Range<i32>, Range<i32>), ChartError> {
    let (base_x, base_y) = area.get_base_pixel();
    let (width, height) = area.dim_in_pixel();
    // In the area's own pixels: a gap on the left, the box to the right edge.
    let (x0, x1) = (12, width as i32);
    let y0 = (top - base_y).max(0);
    let entries = methods.len() as i32 + 1;
    let y1 = (y0 + 8 + entries * LEGEND_LINE).min(height as i32);
    area.draw(&Rectangle::new(
        [(x0, y0), (x1 - 1, y1 - 1)],
        BLACK.mix(0.4),
    ))
    .map_err(err)?;
    let font = ("sans-serif", 14).into_font();
    let text = |i: i32| (x0 + 36, y0 + 4 + i * LEGEND_LINE + LEGEND_LINE / 2);
    let centre = |i: i32| (x0 + 18, y0 + 4 + i * LEGEND_LINE + LEGEND_LINE / 2);
    let (cx, cy) = centre(0);
    area.draw(&DashedPathElement::new(
        [(cx - 12, cy), (cx + 12, cy)],
        8,
        6,
        RED.mix(0.6).stroke_width(2),
    ))
    .map_err(err)?;
    let style = font.color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(threshold.to_owned(), text(0), style.clone()))
        .map_err(err)?;
    for (i, method) in methods.iter().enumerate() {
        let line = i as i32 + 1;
        area.draw(&marker(i, centre(line))).map_err(err)?;
        area.draw(&Text::new((*method).to_owned(), text(line), style.clone()))
            .map_err(err)?;
    }
    Ok((base_x + x0..base_x + x1, base_y + y0..base_y + y1))
}

/// A number for a tick label: no trailing zeros, no exponent for the
/// ranges the study meets.
fn format_number(x: f64) -> String {
    let text = if x >= 1.0 {
        format!("{x:.0}")
    } else {
        let digits = (-x.log10()).ceil().max(1.0) as usize;
        format!("{x:.digits$}")
    };
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        text
    }
}

/// A failing case side by side: `image` | `reference` | their absolute
/// difference times [`DIFF_GAIN`] (clamped), on a grey background with a
/// [`GAP`]-pixel gap between the panels.
///
/// # Panics
/// If the two images differ in size.
pub fn side_by_side(image: &RgbImage, reference: &RgbImage) -> RgbImage {
    assert_eq!(image.dimensions(), reference.dimensions());
    let (w, h) = image.dimensions();
    let mut out = RgbImage::from_pixel(3 * w + 2 * GAP, h, Rgb([128, 128, 128]));
    for (x, y, a) in image.enumerate_pixels() {
        let b = reference.get_pixel(x, y);
        out.put_pixel(x, y, *a);
        out.put_pixel(w + GAP + x, y, *b);
        let diff = |c: usize| (u16::from(a[c].abs_diff(b[c])) * DIFF_GAIN).min(255) as u8;
        out.put_pixel(2 * (w + GAP) + x, y, Rgb([diff(0), diff(1), diff(2)]));
    }
    out
}

/// A scene or method name made safe for a file name: letters, digits,
/// `-`, `_` and `.` kept, anything else `_`.
pub fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The failure picture's file name for a row: `fail-<scene>-<method>.png`.
pub fn failure_file_name(row: &Row) -> String {
    format!(
        "fail-{}-{}.png",
        file_safe(&row.scene),
        file_safe(row.method)
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn no_two_methods_share_a_colour() {
        let n = crate::render::methods().len();
        let colours: std::collections::HashSet<_> = (0..n).map(method_colour).collect();
        assert_eq!(colours.len(), n, "{n} methods");
    }

    fn row(scene: &str, method: &'static str, ms: u64, within1: f64) -> Row {
        Row {
            scene: scene.into(),
            method,
            time: Duration::from_millis(ms),
            rays: 1,
            max_diff: 0,
            mean_diff: 0.0,
            within1,
            failed: within1 < FAIL_BELOW,
        }
    }

    #[test]
    fn fastest_accurate_skips_failures() {
        let rows = [
            row("a", "default", 10, 1.0),
            row("a", "draft", 2, 0.5),
            row("a", "textbook", 8, 1.0),
            row("b", "default", 5, 1.0),
        ];
        let best: Vec<_> = fastest_accurate(&rows)
            .iter()
            .map(|r| (r.scene.as_str(), r.method))
            .collect();
        assert_eq!(best, [("a", "textbook"), ("b", "default")]);
    }

    #[test]
    fn chart_draws_text_and_marks() {
        let rows = [
            row("a", "default", 10, 1.0),
            row("a", "f32", 3, 0.9),
            row("b", "default", 100, 1.0),
        ];
        let image = chart(&rows).unwrap();
        assert_eq!(image.dimensions(), CHART_SIZE);
        // Not blank: text, axes and marks in several colours.
        let dark = image.pixels().filter(|p| p[0] < 64 && p[1] < 64).count();
        assert!(dark > 1000, "{dark} dark pixels");
        // The chart of no rows still draws (empty axes).
        chart(&[]).unwrap();
    }

    #[test]
    fn the_legend_is_beside_the_plotting_area() {
        // Twelve methods, the slowest and worst at the top right corner,
        // where a legend inside the plot would stand.
        let names = [
            "default", "auto", "f32", "textbook", "draft", "aa2", "aa4", "depth-1", "m8", "m9",
            "m10", "m11",
        ];
        let rows: Vec<Row> = names
            .iter()
            .enumerate()
            .map(|(i, m)| row("a", m, 1 + 30 * i as u64, 1.0 - 0.09 * i as f64))
            .collect();
        let (image, layout) = render(&rows).unwrap();
        let (px, py) = &layout.plot;
        let (lx, ly) = &layout.legend;
        let apart =
            lx.start >= px.end || lx.end <= px.start || ly.start >= py.end || ly.end <= py.start;
        assert!(apart, "the legend {layout:?} overlaps the plotting area");
        assert!(lx.end <= CHART_SIZE.0 as i32 && ly.end <= CHART_SIZE.1 as i32);
        // The legend really is there: every method's colour in its box.
        for i in 0..names.len() {
            let (r, g, b) = method_colour(i);
            let found = lx.clone().any(|x| {
                ly.clone()
                    .any(|y| *image.get_pixel(x as u32, y as u32) == Rgb([r, g, b]))
            });
            assert!(found, "no marker of method {i} in the legend {layout:?}");
        }
        // …and the top right point is not covered: its colour is in the
        // plotting area's top right quarter.
        let (r, g, b) = method_colour(names.len() - 1);
        let (xm, ym) = ((px.start + px.end) / 2, (py.start + py.end) / 2);
        let seen = (xm..px.end).any(|x| {
            (py.start..ym).any(|y| *image.get_pixel(x as u32, y as u32) == Rgb([r, g, b]))
        });
        assert!(seen, "the slowest, worst point is hidden");
    }

    #[test]
    fn side_by_side_amplifies_the_difference() {
        let a = RgbImage::from_pixel(2, 1, Rgb([10, 20, 30]));
        let b = RgbImage::from_pixel(2, 1, Rgb([12, 20, 100]));
        let s = side_by_side(&a, &b);
        assert_eq!(s.dimensions(), (6 + 2 * GAP, 1));
        assert_eq!(*s.get_pixel(0, 0), Rgb([10, 20, 30]));
        assert_eq!(*s.get_pixel(2 + GAP, 0), Rgb([12, 20, 100]));
        assert_eq!(*s.get_pixel(2 * (2 + GAP), 0), Rgb([16, 0, 255]));
    }

    #[test]
    fn file_names_are_safe() {
        assert_eq!(file_safe("a b/c..d-1e7"), "a_b_c..d-1e7");
        let r = row("x/y", "f32", 1, 0.5);
        assert_eq!(failure_file_name(&r), "fail-x_y-f32.png");
    }

    #[test]
    fn tick_numbers_are_short() {
        assert_eq!(format_number(100.0), "100");
        assert_eq!(format_number(0.1), "0.1");
        assert_eq!(format_number(0.001), "0.001");
        assert_eq!(format_number(1.0), "1");
    }
}
