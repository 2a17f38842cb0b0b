//! The drawing of a [`Figure`] by plotters, on any backend (the PNG's bitmap, the SVG).

use plotters::coord::Shift;
use plotters::prelude::*;

use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{colormap, tick, Figure, Layer, Layout, Rgb, TextPlace, FONT, MAX_CELLS};

/// A failure of the drawing backend (plotters' error, with the backend's as its source).
#[derive(Debug, thiserror::Error)]
#[error("drawing the figure: {0}")]
pub struct DrawError(Box<dyn std::error::Error + Send + Sync>);

fn text_error<E: std::error::Error + Send + Sync + 'static>(e: E) -> DrawError {
    DrawError(Box::new(e))
}

pub(super) fn draw_panels<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    figures: &[&Figure],
    layout: Layout,
) -> Result<(), DrawError> {
    root.fill(&WHITE).map_err(text_error)?;
    let mut rest = root.clone();
    for f in figures {
        let (here, next) = match layout {
            Layout::Column => rest.split_vertically(f.size.1),
            Layout::Row => rest.split_horizontally(f.size.0),
        };
        draw(f, &here)?;
        rest = next;
    }
    Ok(())
}

fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Pixel sizes of the chart's furniture.
const MARGIN: u32 = 12;
const X_AREA: u32 = 48;
const Y_AREA: u32 = 78;
const CAPTION: u32 = 34;
const BAR: u32 = 140;

fn draw<DB: DrawingBackend<ErrorType: 'static>>(
    f: &Figure,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), DrawError> {
    let (w, h) = area.dim_in_pixel();
    let (main, bar) = if f.colour_bar.is_some() {
        let (m, b) = area.split_horizontally(w.saturating_sub(BAR));
        (m, Some(b))
    } else {
        (area.clone(), None)
    };
    let plot_w = main.dim_in_pixel().0 as f64 - (Y_AREA + 2 * MARGIN) as f64;
    let plot_h = h as f64 - (X_AREA + CAPTION + 2 * MARGIN) as f64;
    let (x, y) = f.ranges((plot_w, plot_h));
    let mut chart = ChartBuilder::on(&main)
        .caption(&f.title, (FONT, 19))
        .margin(MARGIN)
        .x_label_area_size(X_AREA)
        .y_label_area_size(Y_AREA)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(text_error)?;
    let format = |log: bool, span: f64| {
        move |v: &f64| {
            if log {
                // Decades only: the grid lines between them carry no label.
                let decade = v.round();
                if (v - decade).abs() < 1e-6 {
                    tick(10f64.powf(decade))
                } else {
                    String::new()
                }
            } else if v.abs() < 1e-9 * span {
                "0".into() // round-off of a tick at zero
            } else {
                tick(*v)
            }
        }
    };
    let (x_format, y_format) = (format(f.log_x, x.1 - x.0), format(f.log_y, y.1 - y.0));
    chart
        .configure_mesh()
        .x_desc(f.x_label.as_str())
        .y_desc(f.y_label.as_str())
        .x_label_formatter(&x_format)
        .y_label_formatter(&y_format)
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(text_error)?;
    let mut legend = false;
    for layer in &f.layers {
        legend |= draw_layer(f, &mut chart, layer, (x, y))?;
    }
    if legend {
        let corner = emptiest_corner(f, (x, y), (plot_w, plot_h));
        chart
            .configure_series_labels()
            .position(corner)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(0, 0, 0))
            .label_font((FONT, 13))
            .draw()
            .map_err(text_error)?;
    }
    if let (Some(bar), Some((label, range))) = (bar, &f.colour_bar) {
        draw_colour_bar(&bar, label, *range)?;
    }
    Ok(())
}

/// The corner of the axes where the legend hides the fewest data points (upper right on a
/// tie): the legend's size is estimated from its labels' widths in the legend font.
fn emptiest_corner(
    f: &Figure,
    (x, y): ((f64, f64), (f64, f64)),
    (plot_w, plot_h): (f64, f64),
) -> SeriesLabelPosition {
    let font = (FONT, 13).into_font();
    let labels: Vec<&str> = (f.layers.iter())
        .filter_map(|l| match l {
            Layer::Line(_, _, Some(s)) | Layer::VLine(_, _, Some(s)) => Some(s.as_str()),
            Layer::Arrow(_, _, _, s) | Layer::Legend(s, _) => Some(s.as_str()),
            _ => None,
        })
        .collect();
    let widest = labels
        .iter()
        .map(|s| font.box_size(s).map_or(8 * s.len() as u32, |b| b.0))
        .max()
        .unwrap_or(0);
    // The legend: its symbol area (30), margins (2 x 10) and one line of ~16 px per entry,
    // as a fraction of the axes.
    let fx = ((widest + 50) as f64 / plot_w.max(1.0)).min(1.0);
    let fy = ((16 * labels.len() + 24) as f64 / plot_h.max(1.0)).min(1.0);
    let inside = |p: &(f64, f64), right: bool, upper: bool| {
        let u = (p.0 - x.0) / (x.1 - x.0);
        let v = (p.1 - y.0) / (y.1 - y.0);
        let in_x = if right { u >= 1.0 - fx } else { u <= fx };
        let in_y = if upper { v >= 1.0 - fy } else { v <= fy };
        in_x && in_y && u.is_finite() && v.is_finite()
    };
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let hidden = |right: bool, upper: bool| -> usize {
        (f.layers.iter())
            .map(|l| match l {
                Layer::Line(p, _, _) | Layer::Markers(p, _, _) | Layer::Valued(p, _, _) => {
                    p.iter().filter(|p| inside(p, right, upper)).count()
                }
                _ => 0,
            })
            .sum()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (corner, right, upper) in corners {
        let n = hidden(right, upper);
        if n < best.0 {
            best = (n, corner);
        }
    }
    best.1
}

type Chart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// Draws one layer; true when it added a legend entry.
fn draw_layer<DB: DrawingBackend<ErrorType: 'static>>(
    f: &Figure,
    chart: &mut Chart<'_, DB>,
    layer: &Layer,
    (x, y): ((f64, f64), (f64, f64)),
) -> Result<bool, DrawError> {
    let inside = |p: &(f64, f64)| {
        p.0.is_finite()
            && p.1.is_finite()
            && (x.0..=x.1).contains(&p.0)
            && (y.0..=y.1).contains(&p.1)
    };
    let fill = |v: f64| rgb(colormap(f.fraction(v))).filled();
    match layer {
        Layer::Line(points, c, label) => {
            // A NaN breaks the line; points outside the axes are clipped by plotters.
            let colour = rgb(*c);
            for run in points.split(|p| !(p.0.is_finite() && p.1.is_finite())) {
                // A zigzag (the min/max of each bucket of a long signal) drawn 2 px wide gets
                // miter spikes far beyond its points, out of the axes (plotters issue 549):
                // such a run is drawn 1 px wide.
                let width = if run.len() > 2 * LINE_BUCKETS { 1 } else { 2 };
                let run = decimated(run);
                let s = chart
                    .draw_series(LineSeries::new(
                        run.iter().copied(),
                        colour.stroke_width(width),
                    ))
                    .map_err(text_error)?;
                if let (Some(label), false) = (label, run.is_empty()) {
                    s.label(label.as_str()).legend(move |(px, py)| {
                        PathElement::new(vec![(px, py), (px + 18, py)], colour.stroke_width(2))
                    });
                    return Ok(true);
                }
            }
            Ok(false)
        }
        Layer::Markers(points, c, size) => {
            let style = rgb(*c).filled();
            chart
                .draw_series(
                    points
                        .iter()
                        .filter(|p| inside(p))
                        .map(|&p| Circle::new(p, *size, style)),
                )
                .map_err(text_error)?;
            Ok(false)
        }
        Layer::Valued(points, values, size) => {
            let shapes = points
                .iter()
                .zip(values)
                .filter(|(p, v)| inside(p) && v.is_finite())
                .map(|(&p, &v)| Circle::new(p, *size, fill(v)));
            chart.draw_series(shapes).map_err(text_error)?;
            Ok(false)
        }
        Layer::HLine(v, c) => {
            let line = LineSeries::new([(x.0, *v), (x.1, *v)], rgb(*c).stroke_width(1));
            chart.draw_series(line).map_err(text_error)?;
            Ok(false)
        }
        Layer::VLine(v, c, label) => {
            let colour = rgb(*c);
            let s = chart
                .draw_series(LineSeries::new(
                    [(*v, y.0), (*v, y.1)],
                    colour.stroke_width(2),
                ))
                .map_err(text_error)?;
            if let Some(label) = label {
                s.label(label.as_str()).legend(move |(px, py)| {
                    PathElement::new(vec![(px, py), (px + 18, py)], colour.stroke_width(2))
                });
            }
            Ok(label.is_some())
        }
        Layer::Text(at, s, c, place) => {
            if inside(at) {
                draw_text(chart, *at, s, *c, *place)?;
            }
            Ok(false)
        }
        Layer::Cells {
            columns,
            rows,
            values,
            x: cx,
            y: cy,
        } => {
            draw_cells(f, chart, (*columns, *rows), values, (*cx, *cy))?;
            Ok(false)
        }
        Layer::Polygons(polygons) => {
            let shapes = polygons
                .iter()
                .filter(|(_, v)| v.is_finite())
                .map(|(p, v)| Polygon::new(p.clone(), fill(*v)));
            chart.draw_series(shapes).map_err(text_error)?;
            Ok(false)
        }
        Layer::Segments(segments, c) => {
            let style = rgb(*c).stroke_width(2);
            let paths = segments.iter().map(|s| PathElement::new(s.to_vec(), style));
            chart.draw_series(paths).map_err(text_error)?;
            Ok(false)
        }
        Layer::Arrow(a, b, c, label) => {
            let colour = rgb(*c);
            let (ux, uy) = (b.0 - a.0, b.1 - a.1);
            let head = |sign: f64| {
                let (cs, sn) = (0.93f64, sign * 0.36);
                (
                    b.0 - 0.3 * (cs * ux - sn * uy),
                    b.1 - 0.3 * (sn * ux + cs * uy),
                )
            };
            let path = vec![*a, *b, head(1.0), *b, head(-1.0)];
            chart
                .draw_series(std::iter::once(PathElement::new(
                    path,
                    colour.stroke_width(3),
                )))
                .map_err(text_error)?
                .label(label.as_str())
                .legend(move |(px, py)| {
                    PathElement::new(vec![(px, py), (px + 18, py)], colour.stroke_width(3))
                });
            Ok(true)
        }
        Layer::Legend(s, c) => {
            let colour = rgb(*c);
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), u32>>())
                .map_err(text_error)?
                .label(s.as_str())
                .legend(move |(px, py)| Circle::new((px + 9, py), 5, colour.filled()));
            Ok(true)
        }
    }
}

/// A text at a data point, placed as `place` says.
fn draw_text<DB: DrawingBackend<ErrorType: 'static>>(
    chart: &mut Chart<'_, DB>,
    at: (f64, f64),
    s: &str,
    c: Rgb,
    place: TextPlace,
) -> Result<(), DrawError> {
    let colour = rgb(c);
    let style = TextStyle::from((FONT, 13).into_font()).color(&colour);
    let (style, offset) = match place {
        TextPlace::RightAbove => (style, (6, -16)),
        TextPlace::RightBelow => (style, (6, 4)),
        TextPlace::CentredAbove => (style.pos(Pos::new(HPos::Center, VPos::Bottom)), (0, -3)),
    };
    // A label beside a point gets a white backing, so markers drawn under it do not hide it.
    if place != TextPlace::CentredAbove {
        let (w, h) = style.font.box_size(s).unwrap_or((8 * s.len() as u32, 13));
        let corner = (offset.0 - 2, offset.1 - 1);
        let far = (offset.0 + w as i32 + 2, offset.1 + h as i32 + 4);
        let backing = EmptyElement::at(at) + Rectangle::new([corner, far], WHITE.mix(0.8).filled());
        chart
            .draw_series(std::iter::once(backing))
            .map_err(text_error)?;
    }
    let text = EmptyElement::at(at) + plotters::element::Text::new(s.to_string(), offset, style);
    chart
        .draw_series(std::iter::once(text))
        .map_err(text_error)?;
    Ok(())
}

/// A heat map's cells (merged down to at most `MAX_CELLS`), coloured on the colour bar.
fn draw_cells<DB: DrawingBackend<ErrorType: 'static>>(
    f: &Figure,
    chart: &mut Chart<'_, DB>,
    (columns, rows): (usize, usize),
    values: &[f64],
    (cx, cy): ((f64, f64), (f64, f64)),
) -> Result<(), DrawError> {
    let (nx, ny) = (columns.min(MAX_CELLS.0), rows.min(MAX_CELLS.1));
    let merged = merge_cells((columns, rows), values, (nx, ny));
    let (dx, dy) = ((cx.1 - cx.0) / nx as f64, (cy.1 - cy.0) / ny as f64);
    let shapes = (0..nx * ny).filter_map(|k| {
        let (i, j) = (k / ny, k % ny);
        let v = merged[k];
        let a = (cx.0 + i as f64 * dx, cy.0 + j as f64 * dy);
        let fill = rgb(colormap(f.fraction(v))).filled();
        v.is_finite()
            .then(|| Rectangle::new([a, (a.0 + dx, a.1 + dy)], fill))
    });
    chart.draw_series(shapes).map_err(text_error)?;
    Ok(())
}

/// Lines of more points than this are drawn through the lowest and highest point of each of
/// `LINE_BUCKETS / 2` equal runs of points: a signal of 10^5 steps keeps its envelope exactly
/// and draws as a solid band instead of overlapping strokes (and a small SVG).
pub(super) const LINE_BUCKETS: usize = 2400;

pub(super) fn decimated(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    if points.len() <= 2 * LINE_BUCKETS {
        return points.to_vec();
    }
    let buckets = LINE_BUCKETS / 2;
    let mut out = Vec::with_capacity(2 * buckets);
    for b in 0..buckets {
        let run = &points[b * points.len() / buckets..(b + 1) * points.len() / buckets];
        let lowest = run
            .iter()
            .enumerate()
            .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1));
        let highest = run
            .iter()
            .enumerate()
            .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1));
        if let (Some((i, &low)), Some((j, &high))) = (lowest, highest) {
            out.extend(if i <= j { [low, high] } else { [high, low] });
        }
    }
    out
}

/// The largest value of the source cells each of `(nx, ny)` merged cells covers.
pub(super) fn merge_cells(
    (columns, rows): (usize, usize),
    values: &[f64],
    (nx, ny): (usize, usize),
) -> Vec<f64> {
    let mut out = vec![f64::NEG_INFINITY; nx * ny];
    for i in 0..columns {
        for j in 0..rows {
            let v = values[i * rows + j];
            let k = (i * nx / columns) * ny + j * ny / rows;
            if v.is_finite() {
                out[k] = out[k].max(v);
            }
        }
    }
    out.iter()
        .map(|&v| if v == f64::NEG_INFINITY { f64::NAN } else { v })
        .collect()
}

fn draw_colour_bar<DB: DrawingBackend<ErrorType: 'static>>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    (lo, hi): (f64, f64),
) -> Result<(), DrawError> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(MARGIN + CAPTION)
        .margin_bottom(MARGIN + X_AREA)
        .margin_left(8)
        .margin_right(16)
        .set_label_area_size(LabelAreaPosition::Right, 80)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(text_error)?;
    chart
        .configure_mesh()
        .disable_x_axis()
        .disable_x_mesh()
        .disable_y_mesh()
        .y_desc(label)
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(text_error)?;
    let n = 128;
    let step = (hi - lo) / n as f64;
    let bands = (0..n).map(|k| {
        let a = lo + k as f64 * step;
        let c = colormap((k as f64 + 0.5) / n as f64);
        Rectangle::new([(0.0, a), (1.0, a + step)], rgb(c).filled())
    });
    chart.draw_series(bands).map_err(text_error)?;
    Ok(())
}
