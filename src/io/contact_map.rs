//! Contact maps: a per-point field of one interface drawn in the disc plane as a PNG, each
//! master face split into the parametric cells of its Gauss points and filled with the
//! point's value (colour bar on the right, range in the file's text chunk).

use std::path::Path;

use crate::contact::pairing::{Axis, ContactPoint};
use crate::contact::surface::{cross, dot, sub, Face};
use crate::fem::quadrature::gauss_legendre;
use crate::mesh::Mesh;

/// A rendered map: RGB pixels (row-major) with the colour bar on the right, and the value
/// range of the bar (bottom, top).
pub struct MapImage {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
    pub range: (f64, f64),
}

/// Width of the colour bar at the right of a map (pixels, with its margin).
pub const BAR: usize = 60;

/// Draws `values` (one per point, point-id order) of the points of `interface` into a PNG,
/// its title and range in the file's text chunks.
#[allow(clippy::too_many_arguments)]
pub fn write_map(
    path: &Path,
    mesh: &Mesh,
    points: &[ContactPoint],
    values: &[f64],
    interface: usize,
    gauss: usize,
    axis: Axis,
    label: &str,
) -> std::io::Result<()> {
    let Some(map) = render_map(
        mesh,
        points,
        values,
        interface,
        gauss,
        axis,
        None,
        (900, 700),
    ) else {
        return Ok(());
    };
    let (width, height, rgb, (lo_v, hi_v)) = (map.width, map.height, map.rgb, map.range);
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .add_text_chunk("Title".into(), label.into())
        .map_err(std::io::Error::other)?;
    encoder
        .add_text_chunk(
            "Range".into(),
            format!("{lo_v:.6e} (bottom of bar) .. {hi_v:.6e} (top)"),
        )
        .map_err(std::io::Error::other)?;
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(&rgb).map_err(std::io::Error::other)
}

/// Renders `values` of the points of `interface` in the disc plane (`range`: of the colour
/// bar; None: the values' own), or None when the interface has no point.
#[allow(clippy::too_many_arguments)] // the field, where it lives and how to draw it
pub fn render_map(
    mesh: &Mesh,
    points: &[ContactPoint],
    values: &[f64],
    interface: usize,
    gauss: usize,
    axis: Axis,
    range: Option<(f64, f64)>,
    (width, height): (usize, usize),
) -> Option<MapImage> {
    let bar = BAR;
    // In-plane frame: e1 = any direction normal to the axis, e2 = axis x e1.
    let a = axis.direction;
    let seed = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = {
        let t = sub(seed, crate::contact::surface::scale(a, dot(seed, a)));
        crate::contact::surface::normalize(t)
    };
    let e2 = cross(a, e1);
    let plane = |x: [f64; 3]| [dot(x, e1), dot(x, e2)];
    let mine: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].interface == interface)
        .collect();
    if mine.is_empty() {
        return None;
    }
    let (lo_v, hi_v) = range.unwrap_or_else(|| {
        mine.iter()
            .filter(|&&i| values[i].is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &i| {
                (l.min(values[i]), h.max(values[i]))
            })
    });
    // Polygons (in the plane) with their values.
    let (gp, _) = gauss_legendre(gauss.clamp(1, 4));
    let mut bounds = vec![-1.0];
    bounds.extend(gp.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    bounds.push(1.0);
    let cell = |x: f64| gp.iter().position(|&g| (g - x).abs() < 1e-9);
    let mut polys: Vec<(Vec<[f64; 2]>, f64)> = Vec::new();
    for &i in &mine {
        let p = &points[i];
        let face = Face::new(mesh, p.master_face.0, p.master_face.1);
        let corners: Vec<[f64; 2]> = match (
            face.shape.is_triangle(),
            cell(p.master_xi[0]),
            cell(p.master_xi[1]),
        ) {
            (false, Some(ci), Some(cj)) => [
                [bounds[ci], bounds[cj]],
                [bounds[ci + 1], bounds[cj]],
                [bounds[ci + 1], bounds[cj + 1]],
                [bounds[ci], bounds[cj + 1]],
            ]
            .iter()
            .map(|&xi| plane(face.at(xi).x))
            .collect(),
            // Triangles: the point's share of the face, drawn as the whole face.
            _ => face
                .coords
                .iter()
                .take(if face.shape.is_triangle() { 3 } else { 4 })
                .map(|&x| plane(x))
                .collect(),
        };
        polys.push((corners, values[i]));
    }
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (c, _) in &polys {
        for q in c {
            for d in 0..2 {
                min[d] = min[d].min(q[d]);
                max[d] = max[d].max(q[d]);
            }
        }
    }
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(1e-300);
    let draw_w = (width - bar - 30) as f64;
    let draw_h = (height - 20) as f64;
    let s = (draw_w / (max[0] - min[0]).max(1e-300 * span))
        .min(draw_h / (max[1] - min[1]).max(1e-300 * span));
    let to_px = |q: [f64; 2]| {
        [
            10.0 + (q[0] - min[0]) * s,
            height as f64 - 10.0 - (q[1] - min[1]) * s,
        ]
    };
    let mut rgb = vec![255u8; width * height * 3];
    let colour = |v: f64| -> [u8; 3] {
        let t = if hi_v > lo_v {
            ((v - lo_v) / (hi_v - lo_v)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        ramp(t)
    };
    for (c, v) in &polys {
        let px: Vec<[f64; 2]> = c.iter().map(|&q| to_px(q)).collect();
        let col = colour(*v);
        for t in 1..px.len() - 1 {
            fill_triangle(&mut rgb, width, height, [px[0], px[t], px[t + 1]], col);
        }
    }
    // Colour bar: bottom = minimum, top = maximum.
    for y in 10..height - 10 {
        let t = 1.0 - (y - 10) as f64 / (height - 21) as f64;
        let c = ramp(t);
        for x in width - bar..width - 20 {
            rgb[3 * (y * width + x)..3 * (y * width + x) + 3].copy_from_slice(&c);
        }
    }
    Some(MapImage {
        width,
        height,
        rgb,
        range: (lo_v, hi_v),
    })
}

/// Blue - cyan - green - yellow - red.
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [0.10, 0.15, 0.60],
        [0.10, 0.65, 0.85],
        [0.20, 0.75, 0.30],
        [0.95, 0.85, 0.15],
        [0.80, 0.10, 0.10],
    ];
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (255.0 * (STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f)) as u8;
    }
    c
}

fn fill_triangle(rgb: &mut [u8], w: usize, h: usize, p: [[f64; 2]; 3], c: [u8; 3]) {
    let xmin = p
        .iter()
        .map(|q| q[0])
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let xmax = p
        .iter()
        .map(|q| q[0])
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(w as f64 - 1.0);
    let ymin = p
        .iter()
        .map(|q| q[1])
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let ymax = p
        .iter()
        .map(|q| q[1])
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(h as f64 - 1.0);
    if xmax < 0.0 || ymax < 0.0 {
        return;
    }
    let edge = |a: [f64; 2], b: [f64; 2], x: f64, y: f64| {
        (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
    };
    let area = edge(p[0], p[1], p[2][0], p[2][1]);
    if area.abs() < 1e-12 {
        return;
    }
    for y in ymin..=ymax as usize {
        for x in xmin..=xmax as usize {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = edge(p[1], p[2], fx, fy) / area;
            let w1 = edge(p[2], p[0], fx, fy) / area;
            let w2 = edge(p[0], p[1], fx, fy) / area;
            if w0 >= -1e-9 && w1 >= -1e-9 && w2 >= -1e-9 {
                rgb[3 * (y * w + x)..3 * (y * w + x) + 3].copy_from_slice(&c);
            }
        }
    }
}
