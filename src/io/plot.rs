//! Small PNG plots without system fonts: axes with ticks and labels (an 8x8 bitmap font),
//! markers, lines and text. Enough for stability diagrams, parameter sweeps and time signals.

use std::path::Path;

use font8x8::{UnicodeFonts, BASIC_FONTS};

pub type Rgb = [u8; 3];
pub const BLACK: Rgb = [0, 0, 0];
pub const GREY: Rgb = [200, 200, 200];
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

/// A figure with one set of axes.
pub struct Figure {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
    /// Plot area in pixels: left, top, right, bottom.
    area: [f64; 4],
    x: (f64, f64),
    y: (f64, f64),
}

/// Dark blue -> teal -> yellow for s in [0, 1] (perceptually ordered, like viridis).
pub fn colormap(s: f64) -> Rgb {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = s.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8;
    }
    c
}

/// About `n` round tick values covering [min, max].
pub fn nice_ticks(min: f64, max: f64, n: usize) -> Vec<f64> {
    if max.partial_cmp(&min) != Some(std::cmp::Ordering::Greater)
        || !min.is_finite()
        || !max.is_finite()
    {
        return vec![min];
    }
    let raw = (max - min) / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|f| f * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (min / step).ceil() as i64;
    let last = (max / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// A tick label with as many decimals as the tick spacing needs.
fn tick_label(v: f64, step: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
            + usize::from((step / 10f64.powf(step.log10().floor()) - 2.5).abs() < 1e-9)
    };
    format!("{v:.decimals$}")
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

impl Figure {
    /// A white figure with axes over `x` and `y`, a title and axis labels.
    pub fn new(
        width: usize,
        height: usize,
        x: (f64, f64),
        y: (f64, f64),
        title: &str,
        x_label: &str,
        y_label: &str,
    ) -> Figure {
        let mut f = Figure {
            width,
            height,
            rgb: vec![255; width * height * 3],
            area: [90.0, 40.0, width as f64 - 20.0, height as f64 - 60.0],
            x,
            y,
        };
        let [l, t, r, b] = f.area;
        for v in nice_ticks(x.0, x.1, 8) {
            let px = f.px(v, y.0).0;
            f.segment((px, t), (px, b), GREY);
            let label = tick_label(v, nice_step(x));
            f.text(px - 4.0 * label.len() as f64, b + 8.0, &label, BLACK, 1);
        }
        for v in nice_ticks(y.0, y.1, 6) {
            let py = f.px(x.0, v).1;
            f.segment((l, py), (r, py), GREY);
            let label = tick_label(v, nice_step(y));
            f.text(
                l - 8.0 * label.len() as f64 - 6.0,
                py - 4.0,
                &label,
                BLACK,
                1,
            );
        }
        for (a, b2) in [
            ((l, t), (r, t)),
            ((r, t), (r, b)),
            ((r, b), (l, b)),
            ((l, b), (l, t)),
        ] {
            f.segment(a, b2, BLACK);
        }
        let w = width as f64;
        f.text((w - 16.0 * title.len() as f64) / 2.0, 10.0, title, BLACK, 2);
        f.text(
            (l + r) / 2.0 - 4.0 * x_label.len() as f64,
            b + 30.0,
            x_label,
            BLACK,
            1,
        );
        f.vertical_text(
            8.0,
            (t + b) / 2.0 + 4.0 * y_label.len() as f64,
            y_label,
            BLACK,
        );
        f
    }

    /// A white canvas without axes, to compose panels on (`blit`, `text`).
    pub fn canvas(width: usize, height: usize) -> Figure {
        Figure {
            width,
            height,
            rgb: vec![255; width * height * 3],
            area: [0.0, 0.0, width as f64, height as f64],
            x: (0.0, 1.0),
            y: (0.0, 1.0),
        }
    }

    /// Copies an RGB image (row-major, `w` wide) with its top-left corner at pixel (x, y).
    pub fn blit(&mut self, x: usize, y: usize, w: usize, rgb: &[u8]) {
        for (row, line) in rgb.chunks(3 * w).enumerate() {
            for (col, c) in line.chunks(3).enumerate() {
                self.put((x + col) as i64, (y + row) as i64, [c[0], c[1], c[2]]);
            }
        }
    }

    /// Data coordinates to pixels.
    pub fn px(&self, x: f64, y: f64) -> (f64, f64) {
        let [l, t, r, b] = self.area;
        (
            l + (x - self.x.0) / (self.x.1 - self.x.0) * (r - l),
            b - (y - self.y.0) / (self.y.1 - self.y.0) * (b - t),
        )
    }

    fn inside(&self, (px, py): (f64, f64)) -> bool {
        let [l, t, r, b] = self.area;
        px >= l - 0.5 && px <= r + 0.5 && py >= t - 0.5 && py <= b + 0.5
    }

    fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = (y as usize * self.width + x as usize) * 3;
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// A one-pixel segment between pixel positions.
    fn segment(&mut self, a: (f64, f64), b: (f64, f64), c: Rgb) {
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as usize;
        for i in 0..=steps {
            let s = i as f64 / steps as f64;
            let p = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
            self.put(p.0.round() as i64, p.1.round() as i64, c);
        }
    }

    /// A filled square marker of half-width `size` pixels at a data point (clipped).
    pub fn marker(&mut self, x: f64, y: f64, c: Rgb, size: i64) {
        let p = self.px(x, y);
        if !self.inside(p) {
            return;
        }
        let (cx, cy) = (p.0.round() as i64, p.1.round() as i64);
        for dy in -size..=size {
            for dx in -size..=size {
                if dx * dx + dy * dy <= size * size + 1 {
                    self.put(cx + dx, cy + dy, c);
                }
            }
        }
    }

    /// Fills the plot area with a grid of values (column-major: `columns` along x spanning
    /// [x0, x1], `rows` along y spanning [y0, y1]) coloured from dark (lo) to bright (hi).
    #[allow(clippy::too_many_arguments)] // the grid and where it lies
    pub fn heatmap(
        &mut self,
        columns: usize,
        rows: usize,
        values: &[f64],
        (x0, x1): (f64, f64),
        (y0, y1): (f64, f64),
        (lo, hi): (f64, f64),
    ) {
        let [l, t, r, b] = self.area;
        if columns == 0 || rows == 0 {
            return;
        }
        for py in t.ceil() as i64..=b.floor() as i64 {
            for px in l.ceil() as i64..=r.floor() as i64 {
                let x = self.x.0 + (px as f64 - l) / (r - l) * (self.x.1 - self.x.0);
                let y = self.y.0 + (b - py as f64) / (b - t) * (self.y.1 - self.y.0);
                let c = ((x - x0) / (x1 - x0) * columns as f64).floor();
                let k = ((y - y0) / (y1 - y0) * rows as f64).floor();
                if c < 0.0 || k < 0.0 || c >= columns as f64 || k >= rows as f64 {
                    continue;
                }
                let v = values[c as usize * rows + k as usize];
                let s = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
                self.put(px, py, colormap(s));
            }
        }
    }

    /// A polyline through data points (segments with an end outside the axes are skipped).
    pub fn line(&mut self, points: &[(f64, f64)], c: Rgb) {
        for w in points.windows(2) {
            let (a, b) = (self.px(w[0].0, w[0].1), self.px(w[1].0, w[1].1));
            if self.inside(a) && self.inside(b) {
                self.segment(a, b, c);
                self.segment((a.0, a.1 + 1.0), (b.0, b.1 + 1.0), c);
            }
        }
    }

    /// A horizontal line across the axes at data height y.
    pub fn hline(&mut self, y: f64, c: Rgb) {
        let [l, _, r, _] = self.area;
        let py = self.px(self.x.0, y).1;
        if self.inside((l, py)) {
            self.segment((l, py), (r, py), c);
        }
    }

    /// Text at pixel position (top-left), scaled `scale` times.
    pub fn text(&mut self, px: f64, py: f64, s: &str, c: Rgb, scale: i64) {
        let (x0, y0) = (px.round() as i64, py.round() as i64);
        for (x, y) in glyph_pixels(s) {
            for sy in 0..scale {
                for sx in 0..scale {
                    self.put(x0 + x * scale + sx, y0 + y * scale + sy, c);
                }
            }
        }
    }

    /// Text next to a data point (right of it, above or below), if the point is inside the
    /// axes.
    pub fn label(&mut self, x: f64, y: f64, s: &str, c: Rgb, below: bool) {
        let p = self.px(x, y);
        if self.inside(p) {
            let dy = if below { 4.0 } else { -12.0 };
            self.text(p.0 + 6.0, p.1 + dy, s, c, 1);
        }
    }

    /// Text rotated 90 degrees (reading upwards), starting at the bottom pixel (px, py).
    fn vertical_text(&mut self, px: f64, py: f64, s: &str, c: Rgb) {
        let (x0, y0) = (px.round() as i64, py.round() as i64);
        for (x, y) in glyph_pixels(s) {
            self.put(x0 + y, y0 - x, c);
        }
    }

    /// A legend entry (marker and text) in the top-left corner of the axes, row `index`.
    pub fn legend(&mut self, index: usize, s: &str, c: Rgb) {
        let [l, t, _, _] = self.area;
        let y = t + 10.0 + 14.0 * index as f64;
        for dy in -3..=3 {
            for dx in -3..=3 {
                self.put(l as i64 + 14 + dx, y as i64 + 4 + dy, c);
            }
        }
        self.text(l + 24.0, y, s, BLACK, 1);
    }

    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let file = std::fs::File::create(path)?;
        let mut encoder = png::Encoder::new(
            std::io::BufWriter::new(file),
            self.width as u32,
            self.height as u32,
        );
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(&self.rgb)
            .map_err(std::io::Error::other)?;
        Ok(())
    }

    /// Figures of equal width stacked top to bottom into one PNG (panels sharing a time axis).
    pub fn save_column(figures: &[&Figure], path: &Path) -> std::io::Result<()> {
        let width = figures.first().map_or(0, |f| f.width);
        assert!(
            figures.iter().all(|f| f.width == width),
            "panels of one width"
        );
        let column = Figure {
            width,
            height: figures.iter().map(|f| f.height).sum(),
            rgb: figures.iter().flat_map(|f| f.rgb.iter().copied()).collect(),
            area: [0.0; 4],
            x: (0.0, 1.0),
            y: (0.0, 1.0),
        };
        column.save(path)
    }

    /// Number of non-white pixels (for tests).
    pub fn inked(&self) -> usize {
        self.rgb.chunks(3).filter(|p| p != &[255, 255, 255]).count()
    }
}

/// The set pixels (x along the line, y down) of a line of text in the 8x8 font.
fn glyph_pixels(s: &str) -> impl Iterator<Item = (i64, i64)> + '_ {
    s.chars().enumerate().flat_map(|(k, ch)| {
        let glyph = BASIC_FONTS.get(ch).unwrap_or([0; 8]);
        (0..8i64).flat_map(move |row| {
            (0..8i64)
                .filter(move |&col| glyph[row as usize] >> col & 1 == 1)
                .map(move |col| (k as i64 * 8 + col, row))
        })
    })
}

fn nice_step(range: (f64, f64)) -> f64 {
    let t = nice_ticks(range.0, range.1, 8);
    if t.len() >= 2 {
        t[1] - t[0]
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(
            nice_ticks(0.0, 10.0, 5),
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
        );
        let t = nice_ticks(-0.013, 0.021, 6);
        assert!(t.first().unwrap() >= &-0.013 && t.last().unwrap() <= &0.021);
        assert!(t.len() >= 4);
        assert_eq!(tick_label(2500.0, 500.0), "2500");
        assert_eq!(tick_label(0.25, 0.05), "0.25");
    }

    #[test]
    fn a_figure_draws_markers_inside_and_clips_outside() {
        let mut f = Figure::new(400, 300, (0.0, 1.0), (0.0, 1.0), "t", "x", "y");
        let before = f.inked();
        f.marker(0.5, 0.5, RED, 3);
        let after = f.inked();
        assert!(after > before);
        f.marker(5.0, 5.0, RED, 3);
        assert_eq!(f.inked(), after);
    }
}
