//! The Study window's interactive chart and its legend.
//!
//! Time against error, both log10 (egui_plot): one mark per row, in the
//! colours and shapes of `study.png` (`study::chart::method_colour` and
//! `method_shape`), exact rows on the floor, the fail threshold dashed,
//! hover for a row's figures. The legend is a column beside the plot, not
//! over it: each method that has rows, with the very marker its points
//! have, and the threshold's dashed line.

use crate::study::{self, Row};
use egui::{Color32, Pos2, Sense, Shape, Stroke, pos2, vec2};
use egui_plot::{HLine, LineStyle, MarkerShape, Plot, PlotPoints, Points};

/// The marks' radius, in points (the legend's markers too).
const RADIUS: f32 = 5.0;

/// The width of the legend column, in points.
const LEGEND_WIDTH: f32 = 150.0;

/// The colour of the fail threshold.
const THRESHOLD: Color32 = Color32::from_rgb(230, 60, 60);

/// The threshold's name, in the legend and on hover.
const THRESHOLD_NAME: &str = "fails above 1 %";

/// The marks of one method: how they look and where they are.
#[derive(Debug, Clone, PartialEq)]
struct Series {
    name: &'static str,
    colour: Color32,
    shape: MarkerShape,
    /// (log10 ms, log10 error) per row.
    marks: Vec<[f64; 2]>,
}

/// One series per study method that has rows, in the study's order of
/// methods (so that a method keeps its colour and shape whatever ran).
fn series(rows: &[Row]) -> Vec<Series> {
    crate::render::methods()
        .iter()
        .enumerate()
        .filter_map(|(i, method)| {
            let marks: Vec<[f64; 2]> = rows
                .iter()
                .filter(|r| r.method == method.name)
                .map(|r| [log_ms(r), study::chart::error(r).log10()])
                .collect();
            if marks.is_empty() {
                return None;
            }
            let (r, g, b) = study::chart::method_colour(i);
            // Black reads badly on the dark theme: a light grey.
            let colour = if (r, g, b) == (0, 0, 0) {
                Color32::from_gray(220)
            } else {
                Color32::from_rgb(r, g, b)
            };
            let shape = match study::chart::method_shape(i) {
                0 => MarkerShape::Circle,
                1 => MarkerShape::Square,
                2 => MarkerShape::Up,
                3 => MarkerShape::Cross,
                _ => MarkerShape::Diamond,
            };
            Some(Series {
                name: method.name,
                colour,
                shape,
                marks,
            })
        })
        .collect()
}

fn log_ms(row: &Row) -> f64 {
    (row.time.as_secs_f64() * 1e3).max(1e-6).log10()
}

/// The chart of `rows` with its legend on the right (nothing without rows).
pub(super) fn plot(ui: &mut egui::Ui, rows: &[Row]) {
    if rows.is_empty() {
        return;
    }
    ui.separator();
    let series = series(rows);
    ui.horizontal_top(|ui| {
        let gap = ui.spacing().item_spacing.x;
        let width = (ui.available_width() - LEGEND_WIDTH - gap).max(200.0);
        chart(ui, rows, &series, width);
        ui.vertical(|ui| {
            ui.set_width(LEGEND_WIDTH);
            legend(ui, &series);
        });
    });
}

fn chart(ui: &mut egui::Ui, rows: &[Row], series: &[Series], width: f32) {
    let floor = study::chart::ERROR_FLOOR.log10();
    let (lo, hi) = rows
        .iter()
        .map(log_ms)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(t), hi.max(t))
        });
    let response = Plot::new("study-plot")
        // A little room around the marks, above for the worst rows.
        .include_x(lo - 0.1)
        .include_x(hi + 0.1)
        .include_y(0.0)
        .include_y(floor - 0.2)
        .width(width)
        .height(340.0)
        // The wheel scrolls the window, not the plot (drag pans it,
        // double-click resets it).
        .allow_scroll(false)
        .x_axis_label("median render time, ms (log)")
        .y_axis_label("pixels off by more than 1 level (log; bottom: exact)")
        .x_axis_formatter(|mark, _| number(10f64.powf(mark.value)))
        .y_axis_formatter(move |mark, _| {
            if mark.value <= floor {
                "exact".into()
            } else {
                format!("{}%", number(100.0 * 10f64.powf(mark.value)))
            }
        })
        .label_formatter(|position| match position {
            egui_plot::HoverPosition::NearDataPoint {
                plot_name,
                position,
                ..
            } => Some(format!(
                "{plot_name}\n{} ms\n{}",
                number(10f64.powf(position.x)),
                if position.y <= floor {
                    "exact to one level".to_owned()
                } else {
                    format!("{}% off", number(100.0 * 10f64.powf(position.y)))
                }
            )),
            _ => None,
        })
        .show(ui, |plot| {
            plot.hline(
                HLine::new(THRESHOLD_NAME, (1.0 - study::FAIL_BELOW).log10())
                    .color(THRESHOLD)
                    .width(1.0)
                    .style(LineStyle::dashed_loose()),
            );
            for s in series {
                plot.points(
                    Points::new(s.name, PlotPoints::from(s.marks.clone()))
                        .shape(s.shape)
                        .color(s.colour)
                        .filled(true)
                        .radius(RADIUS),
                );
            }
        });
    response
        .response
        .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, "study chart"));
}

/// The legend: the threshold's dashed line, then each series' marker and
/// name.
fn legend(ui: &mut egui::Ui, series: &[Series]) {
    let swatch = vec2(3.0 * RADIUS + 8.0, 2.0 * RADIUS + 6.0);
    ui.horizontal(|ui| {
        let (rect, _) = ui.allocate_exact_size(swatch, Sense::hover());
        let y = rect.center().y;
        ui.painter().extend(Shape::dashed_line(
            &[pos2(rect.left(), y), pos2(rect.right(), y)],
            Stroke::new(1.0, THRESHOLD),
            5.0,
            3.0,
        ));
        ui.label(THRESHOLD_NAME);
    });
    for s in series {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(swatch, Sense::hover());
            ui.painter()
                .extend(marker(rect.center(), RADIUS, s.shape, s.colour));
            ui.label(s.name);
        });
    }
}

/// The shapes egui_plot draws for a filled mark of `shape` at `center`
/// (its geometry, `Points::shapes`), so that the legend shows the marks.
fn marker(center: Pos2, radius: f32, shape: MarkerShape, colour: Color32) -> Vec<Shape> {
    let at = |dx: f32, dy: f32| center + radius * vec2(dx, dy);
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let s3 = 3f32.sqrt() / 2.0;
    match shape {
        MarkerShape::Circle => vec![Shape::circle_filled(center, radius, colour)],
        MarkerShape::Square => vec![Shape::convex_polygon(
            vec![
                at(-half, half),
                at(-half, -half),
                at(half, -half),
                at(half, half),
            ],
            colour,
            Stroke::NONE,
        )],
        MarkerShape::Up => vec![Shape::convex_polygon(
            vec![at(0.0, -1.0), at(s3, 0.5), at(-s3, 0.5)],
            colour,
            Stroke::NONE,
        )],
        MarkerShape::Cross => {
            let stroke = Stroke::new(radius / 5.0, colour);
            vec![
                Shape::line_segment([at(-half, -half), at(half, half)], stroke),
                Shape::line_segment([at(half, -half), at(-half, half)], stroke),
            ]
        }
        _ => vec![Shape::convex_polygon(
            vec![at(0.0, 1.0), at(-1.0, 0.0), at(0.0, -1.0), at(1.0, 0.0)],
            colour,
            Stroke::NONE,
        )],
    }
}

/// A plot figure: 3 significant digits, no exponent in the usual range.
fn number(x: f64) -> String {
    if (0.01..1e5).contains(&x) {
        let digits = (2 - x.log10().floor() as i32).clamp(0, 4) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.0e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn row(method: &'static str, within1: f64) -> Row {
        Row {
            scene: "a".into(),
            method,
            time: Duration::from_millis(3),
            rays: 1,
            max_diff: 0,
            mean_diff: 0.0,
            within1,
            failed: within1 < study::FAIL_BELOW,
        }
    }

    #[test]
    fn the_legend_lists_the_methods_that_have_rows_as_they_are_drawn() {
        let rows = [row("draft", 0.5), row("default", 1.0), row("draft", 0.9)];
        let series = series(&rows);
        let names: Vec<_> = series.iter().map(|s| s.name).collect();
        assert_eq!(names, ["default", "draft"], "the study's order");
        assert_eq!(series[1].marks.len(), 2);
        // A method's look is its number in the study, whatever else ran.
        let i = crate::render::methods()
            .iter()
            .position(|m| m.name == "draft")
            .unwrap();
        let (r, g, b) = study::chart::method_colour(i);
        assert_eq!(series[1].colour, Color32::from_rgb(r, g, b));
    }

    #[test]
    fn no_two_methods_look_alike() {
        let rows: Vec<Row> = crate::render::methods()
            .iter()
            .map(|m| row(m.name, 1.0))
            .collect();
        let series = series(&rows);
        assert_eq!(series.len(), crate::render::methods().len());
        for (i, a) in series.iter().enumerate() {
            for b in &series[i + 1..] {
                assert_ne!(a.colour, b.colour, "{} and {}", a.name, b.name);
            }
        }
    }

    #[test]
    fn the_legend_marker_has_the_shape_of_the_marks() {
        let c = Color32::RED;
        let o = pos2(0.0, 0.0);
        assert!(matches!(
            marker(o, 5.0, MarkerShape::Circle, c)[..],
            [Shape::Circle(_)]
        ));
        assert!(matches!(
            marker(o, 5.0, MarkerShape::Cross, c)[..],
            [Shape::LineSegment { .. }, Shape::LineSegment { .. }]
        ));
        let corners = |shape| match &marker(o, 5.0, shape, c)[..] {
            [Shape::Path(path)] => path.points.len(),
            other => panic!("{other:?}"),
        };
        assert_eq!(corners(MarkerShape::Up), 3);
        assert_eq!(corners(MarkerShape::Square), 4);
        assert_eq!(corners(MarkerShape::Diamond), 4);
    }

    #[test]
    fn figures_are_short() {
        assert_eq!(number(12.345), "12.3");
        assert_eq!(number(0.5), "0.500");
    }
}
