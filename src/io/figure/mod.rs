//! Figures: a plot described as data (title, axes with units, layers, legend, colour bar) and
//! drawn by `plotters` twice, into `<name>.png` and `<name>.svg`. Text uses the bundled DejaVu
//! Sans (through ab_glyph), so a figure looks the same on every machine and needs no system
//! font. The SVG keeps every text as text: the report's tests read titles and axis labels
//! there.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::prelude::*;

mod draw;
use draw::draw_panels;

pub type Rgb = [u8; 3];
pub const BLACK: Rgb = [0, 0, 0];
pub const GREY: Rgb = [170, 170, 170];
pub const BLUE: Rgb = [31, 119, 180];
pub const RED: Rgb = [214, 39, 40];
/// A cycle of distinguishable colours for series.
pub const PALETTE: [Rgb; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// The family name the bundled font is registered under.
const FONT: &str = "sans-serif";
/// Heat maps are drawn with at most this many cells per direction (largest value of the cells
/// merged): a spectrogram of 10^5 cells would make a 10 MB SVG and no visible difference.
const MAX_CELLS: (usize, usize) = (320, 200);

/// Dark blue -> teal -> yellow for s in [0, 1] (perceptually ordered, like viridis).
pub fn colormap(s: f64) -> Rgb {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    } * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8;
    }
    c
}

/// Widens a degenerate or reversed range and adds a margin of `pad` of its width.
pub fn padded(min: f64, max: f64, pad: f64) -> (f64, f64) {
    if !(min.is_finite() && max.is_finite()) {
        return (0.0, 1.0);
    }
    if max <= min {
        let d = if min == 0.0 { 1.0 } else { 0.1 * min.abs() };
        return (min - d, max + d);
    }
    let d = pad * (max - min);
    (min - d, max + d)
}

/// A tick value with the digits it needs: 2500, 0.25, 1.5e-6.
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a < 1e-300 {
        return "0".into();
    }
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}").replace(".00e", "e").replace("0e", "e");
    }
    let s = format!("{v:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Where a text goes relative to its point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TextPlace {
    RightAbove,
    RightBelow,
    CentredAbove,
}

enum Layer {
    Line(Vec<(f64, f64)>, Rgb, Option<String>),
    Markers(Vec<(f64, f64)>, Rgb, u32),
    /// Markers coloured by value on the colour bar.
    Valued(Vec<(f64, f64)>, Vec<f64>, u32),
    HLine(f64, Rgb),
    VLine(f64, Rgb, Option<String>),
    /// Text at a point: right of it (above or below) or centred above it.
    Text((f64, f64), String, Rgb, TextPlace),
    /// A grid of values (column-major), `columns` across x0..x1 and `rows` across y0..y1.
    Cells {
        columns: usize,
        rows: usize,
        values: Vec<f64>,
        x: (f64, f64),
        y: (f64, f64),
    },
    Polygons(Vec<(Vec<(f64, f64)>, f64)>),
    Segments(Vec<[(f64, f64); 2]>, Rgb),
    Arrow((f64, f64), (f64, f64), Rgb, String),
    Legend(String, Rgb),
}

/// One set of axes with its title, axis labels (with units) and what is drawn on them.
pub struct Figure {
    size: (u32, u32),
    title: String,
    x_label: String,
    y_label: String,
    x: (f64, f64),
    y: (f64, f64),
    log_x: bool,
    log_y: bool,
    equal_aspect: bool,
    colour_bar: Option<(String, (f64, f64))>,
    layers: Vec<Layer>,
}

impl Figure {
    /// A figure `width` x `height` pixels with axes over `x` and `y`.
    pub fn new(
        width: usize,
        height: usize,
        x: (f64, f64),
        y: (f64, f64),
        title: &str,
        x_label: &str,
        y_label: &str,
    ) -> Figure {
        Figure {
            size: (width as u32, height as u32),
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x,
            y,
            log_x: false,
            log_y: false,
            equal_aspect: false,
            colour_bar: None,
            layers: Vec::new(),
        }
    }

    /// The x values given are log10 of the quantity; ticks show the quantity.
    pub fn log_x(mut self) -> Figure {
        self.log_x = true;
        self
    }

    /// The y values given are log10 of the quantity; ticks show the quantity (1e-6, ...).
    pub fn log_y(mut self) -> Figure {
        self.log_y = true;
        self
    }

    /// One unit of x is as long as one unit of y (maps in a plane).
    pub fn equal_aspect(mut self) -> Figure {
        self.equal_aspect = true;
        self
    }

    /// A colour bar over `range` labelled `label` (with units), for `valued`, `cells` and
    /// `polygons`.
    pub fn colour_bar(mut self, label: &str, range: (f64, f64)) -> Figure {
        let range = if range.0.is_finite() && range.1.is_finite() && range.1 > range.0 {
            range
        } else {
            padded(range.0, range.1, 0.0)
        };
        self.colour_bar = Some((label.into(), range));
        self
    }

    pub fn title(&self) -> &str {
        &self.title
    }

    pub fn marker(&mut self, x: f64, y: f64, c: Rgb, size: u32) {
        self.markers(vec![(x, y)], c, size);
    }

    pub fn markers(&mut self, points: Vec<(f64, f64)>, c: Rgb, size: u32) {
        self.layers.push(Layer::Markers(points, c, size.max(1)));
    }

    pub fn valued(&mut self, points: Vec<(f64, f64)>, values: Vec<f64>, size: u32) {
        self.layers.push(Layer::Valued(points, values, size.max(1)));
    }

    pub fn line(&mut self, points: &[(f64, f64)], c: Rgb) {
        self.layers.push(Layer::Line(points.to_vec(), c, None));
    }

    /// A line with a legend entry.
    pub fn series(&mut self, points: &[(f64, f64)], c: Rgb, label: &str) {
        self.layers
            .push(Layer::Line(points.to_vec(), c, Some(label.into())));
    }

    pub fn hline(&mut self, y: f64, c: Rgb) {
        self.layers.push(Layer::HLine(y, c));
    }

    /// A vertical line, with a legend entry when `label` is given.
    pub fn vline(&mut self, x: f64, c: Rgb, label: Option<&str>) {
        self.layers.push(Layer::VLine(x, c, label.map(Into::into)));
    }

    /// Text next to a data point (right of it, above or below).
    pub fn label(&mut self, x: f64, y: f64, s: &str, c: Rgb, below: bool) {
        let place = if below {
            TextPlace::RightBelow
        } else {
            TextPlace::RightAbove
        };
        self.layers.push(Layer::Text((x, y), s.into(), c, place));
    }

    /// Text centred above a point (a bar's count: it stays over its own bar).
    pub fn label_centred(&mut self, x: f64, y: f64, s: &str, c: Rgb) {
        self.layers
            .push(Layer::Text((x, y), s.into(), c, TextPlace::CentredAbove));
    }

    /// A legend entry (the `index` of the old API is the order of the calls).
    pub fn legend(&mut self, _index: usize, s: &str, c: Rgb) {
        self.layers.push(Layer::Legend(s.into(), c));
    }

    /// A heat map of `values` (column-major) coloured on the colour bar.
    pub fn cells(
        &mut self,
        (columns, rows): (usize, usize),
        values: Vec<f64>,
        x: (f64, f64),
        y: (f64, f64),
    ) {
        self.layers.push(Layer::Cells {
            columns,
            rows,
            values,
            x,
            y,
        });
    }

    /// Filled polygons coloured by their value on the colour bar.
    pub fn polygons(&mut self, polygons: Vec<(Vec<(f64, f64)>, f64)>) {
        self.layers.push(Layer::Polygons(polygons));
    }

    pub fn segments(&mut self, segments: Vec<[(f64, f64); 2]>, c: Rgb) {
        self.layers.push(Layer::Segments(segments, c));
    }

    /// An arrow from `a` to `b` with a legend entry.
    pub fn arrow(&mut self, a: (f64, f64), b: (f64, f64), c: Rgb, label: &str) {
        self.layers.push(Layer::Arrow(a, b, c, label.into()));
    }

    /// Writes `path` (a .png) and the same figure as SVG beside it.
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        save_panels(&[self], path, Layout::Column)
    }

    /// Figures of one width stacked top to bottom (panels sharing a time axis).
    pub fn save_column(figures: &[&Figure], path: &Path) -> std::io::Result<()> {
        save_panels(figures, path, Layout::Column)
    }

    /// Figures of one height side by side.
    pub fn save_row(figures: &[&Figure], path: &Path) -> std::io::Result<()> {
        save_panels(figures, path, Layout::Row)
    }

    fn fraction(&self, v: f64) -> f64 {
        let (lo, hi) = self.colour_bar.as_ref().map_or((0.0, 1.0), |c| c.1);
        (v - lo) / (hi - lo)
    }

    /// The axes' ranges, widened along one direction for an equal aspect in `pixels` of plot
    /// area.
    fn ranges(&self, pixels: (f64, f64)) -> ((f64, f64), (f64, f64)) {
        let (mut x, mut y) = (self.x, self.y);
        if self.equal_aspect && pixels.0 > 0.0 && pixels.1 > 0.0 {
            let scale = ((x.1 - x.0) / pixels.0).max((y.1 - y.0) / pixels.1);
            let widen = |r: (f64, f64), span: f64| {
                let c = 0.5 * (r.0 + r.1);
                (c - 0.5 * span, c + 0.5 * span)
            };
            x = widen(x, scale * pixels.0);
            y = widen(y, scale * pixels.1);
        }
        (x, y)
    }
}

#[derive(Clone, Copy)]
enum Layout {
    Column,
    Row,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("font/DejaVuSans.ttf");
        // The bundled file is a valid TrueType font; a failure here is a build defect.
        plotters::style::register_font(FONT, FontStyle::Normal, bytes)
            .unwrap_or_else(|_| panic!("the bundled DejaVu Sans does not load"));
    });
}

fn save_panels(figures: &[&Figure], png: &Path, layout: Layout) -> std::io::Result<()> {
    register_font();
    let sizes = figures.iter().map(|f| f.size);
    let size = match layout {
        Layout::Column => sizes.fold((0, 0), |(w, h), (fw, fh)| (w.max(fw), h + fh)),
        Layout::Row => sizes.fold((0, 0), |(w, h), (fw, fh)| (w + fw, h.max(fh))),
    };
    let svg: PathBuf = png.with_extension("svg");
    // Drawn into memory and encoded by the `png` crate the preview already uses (plotters'
    // own encoder would bring the `image` crate and its decoders into the build).
    let mut rgb = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_panels(&root, figures, layout).map_err(std::io::Error::other)?;
        root.present()
            .map_err(|e| std::io::Error::other(e.to_string()))?;
    }
    write_png(png, size, &rgb)?;
    let root = SVGBackend::new(&svg, size).into_drawing_area();
    draw_panels(&root, figures, layout).map_err(std::io::Error::other)?;
    root.present()
        .map_err(|e| std::io::Error::other(e.to_string()))
}

fn write_png(path: &Path, (width, height): (u32, u32), rgb: &[u8]) -> std::io::Result<()> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // Plots are flat colour: adaptive filtering and the better deflate level make them (and
    // the report, which embeds them) several times smaller for a little time
    // (benches/decisions-results.md, "png-compression").
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    encoder.set_compression(png::Compression::Best);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(rgb).map_err(std::io::Error::other)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::draw::{decimated, merge_cells, LINE_BUCKETS};
    use super::*;

    #[test]
    fn ticks_print_the_digits_they_need() {
        assert_eq!(tick(2500.0), "2500");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(1.5e-6), "1.5e-6");
        assert_eq!(tick(2.0e7), "2e7");
    }

    #[test]
    fn a_figure_writes_a_png_and_an_svg_with_its_title_and_axis_labels() {
        let dir = std::env::temp_dir().join(format!("squeal-figure-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut f = Figure::new(
            500,
            300,
            (0.0, 1.0),
            (-1.0, 1.0),
            "a sine",
            "time (s)",
            "y (m)",
        )
        .colour_bar("value (Pa)", (0.0, 2.0));
        let points: Vec<(f64, f64)> = (0..50)
            .map(|i| (i as f64 / 49.0, (6.0 * i as f64 / 49.0).sin()))
            .collect();
        f.series(&points, BLUE, "sin 6t");
        f.valued(
            points.clone(),
            points.iter().map(|p| p.1 + 1.0).collect(),
            3,
        );
        let png = dir.join("sine.png");
        f.save(&png).unwrap();
        let svg = std::fs::read_to_string(dir.join("sine.svg")).unwrap();
        for text in ["a sine", "time (s)", "y (m)", "value (Pa)", "sin 6t"] {
            assert!(svg.contains(text), "{text} missing from the SVG");
        }
        let decoder = png::Decoder::new(std::fs::File::open(&png).unwrap());
        let info = decoder.read_info().unwrap().info().clone();
        assert_eq!((info.width, info.height), (500, 300));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_decimated_line_keeps_every_extreme_in_order() {
        let n = 100_000;
        let points: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                (
                    i as f64,
                    (i as f64 * 0.0123).sin() * (1.0 + i as f64 / n as f64),
                )
            })
            .collect();
        let d = decimated(&points);
        assert_eq!(d.len(), LINE_BUCKETS);
        let extreme = |v: &[(f64, f64)], max: bool| {
            use crate::measure::nan_max;
            v.iter()
                .map(|p| if max { p.1 } else { -p.1 })
                .fold(f64::NEG_INFINITY, nan_max)
        };
        assert_eq!(extreme(&d, true), extreme(&points, true));
        assert_eq!(extreme(&d, false), extreme(&points, false));
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0), "time order");
    }

    #[test]
    fn a_long_noisy_line_stays_inside_its_axes() {
        // 150,000 samples jumping by up to the whole range from one to the next, like the
        // saturated torque of a 150,000-step run (which drew spikes out through the title).
        let n = 150_000u64;
        let points: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let hash = i.wrapping_mul(2_654_435_761) % 10_007;
                (i as f64, hash as f64 / 10_007.0 - 0.5)
            })
            .collect();
        let (w, h) = (900u32, 400u32);
        let mut f = Figure::new(
            w as usize,
            h as usize,
            (0.0, n as f64),
            padded(-0.5, 0.5, 0.05),
            "noise",
            "i",
            "y",
        );
        f.series(&points, BLUE, "");
        let dir = std::env::temp_dir().join(format!("squeal-noise-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("noise.png");
        f.save(&png).unwrap();
        let mut reader = png::Decoder::new(std::fs::File::open(&png).unwrap())
            .read_info()
            .unwrap();
        let mut rgb = vec![0u8; reader.output_buffer_size()];
        reader.next_frame(&mut rgb).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let blue = |x: u32, y: u32| {
            let k = 3 * (y * w + x) as usize;
            (0..3).all(|c| (rgb[k + c] as i32 - BLUE[c] as i32).abs() < 40)
        };
        // The plot area lies below the top margin and the caption, above the x labels.
        let outside: Vec<(u32, u32)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| y < 20 || y > h - 40 || x < 40)
            .filter(|&(x, y)| blue(x, y))
            .collect();
        assert!(
            outside.is_empty(),
            "line pixels outside the axes: {outside:?}"
        );
        assert!(
            (0..h).any(|y| (0..w).any(|x| blue(x, y))),
            "the line is drawn"
        );
    }

    #[test]
    fn merged_cells_keep_the_largest_value() {
        let values: Vec<f64> = (0..16).map(f64::from).collect();
        assert_eq!(
            merge_cells((4, 4), &values, (2, 2)),
            vec![5.0, 7.0, 13.0, 15.0]
        );
    }
}
