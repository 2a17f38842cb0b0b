//! A shaded preview of a mesh as PNG: the boundary faces seen from an oblique outboard view,
//! one colour per element block (component), Lambert shading, z-buffered, element edges
//! drawn where faces are large enough on screen to show them.

use std::collections::HashMap;
use std::path::Path;

use crate::measure::{nan_max, nan_min};
use crate::mesh::Mesh;

/// Component colours (RGB), cycled.
const PALETTE: [[f64; 3]; 8] = [
    [0.62, 0.64, 0.68], // disc: cast iron grey
    [0.55, 0.35, 0.20], // lining: brown
    [0.30, 0.45, 0.70], // backplate: steel blue
    [0.55, 0.35, 0.20],
    [0.30, 0.45, 0.70],
    [0.80, 0.75, 0.30], // piston
    [0.75, 0.20, 0.18], // caliper: red
    [0.35, 0.60, 0.35], // anchor: green
];

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

/// Boundary faces (corner nodes, outward order) with their block index.
pub fn boundary_faces(mesh: &Mesh) -> Vec<(Vec<usize>, usize)> {
    let mut seen: HashMap<Vec<usize>, (usize, Vec<usize>, usize)> = HashMap::new();
    let mut global = 0;
    for (b, block) in mesh.blocks.iter().enumerate() {
        let corners = if block.kind.faces() == 6 { 4 } else { 3 };
        for e in 0..block.len() {
            for f in 1..=block.kind.faces() {
                let nodes: Vec<usize> = mesh.face_nodes(global + e, f)[..corners].to_vec();
                let mut key = nodes.clone();
                key.sort_unstable();
                seen.entry(key)
                    .and_modify(|v| v.0 += 1)
                    .or_insert((1, nodes, b));
            }
        }
        global += block.len();
    }
    let mut faces: Vec<(Vec<usize>, usize)> = seen
        .into_values()
        .filter(|(count, _, _)| *count == 1)
        .map(|(_, nodes, b)| (nodes, b))
        .collect();
    faces.sort_unstable();
    faces
}

/// Renders the mesh into an RGB image of `width` x `height`.
pub fn render(mesh: &Mesh, width: usize, height: usize) -> Vec<u8> {
    let eye = normalize([0.55, -0.75, 0.85]);
    let right = normalize(cross([0.0, 0.0, 1.0], eye));
    let up = cross(eye, right);
    let light = normalize([0.3, -0.4, 1.0]);
    let faces = boundary_faces(mesh);
    // Fit the projected bounding box into the image with a margin.
    let project = |x: [f64; 3]| [dot(x, right), dot(x, up), dot(x, eye)];
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for x in &mesh.coords {
        let p = project(*x);
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let scale = 0.9 * (width as f64 / (hi[0] - lo[0])).min(height as f64 / (hi[1] - lo[1]));
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let screen = |x: [f64; 3]| {
        let p = project(x);
        [
            width as f64 / 2.0 + scale * (p[0] - centre[0]),
            height as f64 / 2.0 - scale * (p[1] - centre[1]),
            p[2],
        ]
    };
    let mut rgb = vec![255u8; width * height * 3];
    let mut depth = vec![f64::NEG_INFINITY; width * height];
    for (nodes, block) in &faces {
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let normal = normalize(cross(sub(x[1], x[0]), sub(x[x.len() - 1], x[0])));
        if dot(normal, eye) <= 0.0 {
            continue;
        }
        let shade = 0.35 + 0.65 * dot(normal, light).abs();
        let base = PALETTE[block % PALETTE.len()];
        let s: Vec<[f64; 3]> = x.iter().map(|&p| screen(p)).collect();
        // Draw edges only where an element spans several pixels.
        let size = s
            .iter()
            .zip(s.iter().cycle().skip(1))
            .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
            .fold(f64::INFINITY, nan_min);
        let edges = size > 6.0;
        // Fan triangulation; each triangle draws its outer edges (not the fan diagonals).
        for t in 1..s.len() - 1 {
            let tri = [s[0], s[t], s[t + 1]];
            let outer = [true, t + 1 == s.len() - 1, t == 1];
            fill_triangle(
                &tri,
                outer,
                edges,
                [base[0] * shade, base[1] * shade, base[2] * shade],
                width,
                height,
                &mut rgb,
                &mut depth,
            );
        }
    }
    rgb
}

/// Fills a triangle with z-buffering; `outer[k]` marks the edge opposite vertex k as a
/// face edge, darkened within a pixel when `edges`.
#[allow(clippy::too_many_arguments)]
fn fill_triangle(
    t: &[[f64; 3]; 3],
    outer: [bool; 3],
    edges: bool,
    colour: [f64; 3],
    width: usize,
    height: usize,
    rgb: &mut [u8],
    depth: &mut [f64],
) {
    let area =
        (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
    if area.abs() < 1e-12 {
        return;
    }
    let x0 = t
        .iter()
        .map(|p| p[0])
        .fold(f64::INFINITY, nan_min)
        .floor()
        .max(0.0) as usize;
    let x1 = (t
        .iter()
        .map(|p| p[0])
        .fold(f64::NEG_INFINITY, nan_max)
        .ceil() as usize)
        .min(width - 1);
    let y0 = t
        .iter()
        .map(|p| p[1])
        .fold(f64::INFINITY, nan_min)
        .floor()
        .max(0.0) as usize;
    let y1 = (t
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, nan_max)
        .ceil() as usize)
        .min(height - 1);
    // Heights of the triangle over each edge, in pixels (for the edge distance).
    let len = |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    let heights = [
        area.abs() / len(t[1], t[2]),
        area.abs() / len(t[2], t[0]),
        area.abs() / len(t[0], t[1]),
    ];
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = ((t[1][0] - px) * (t[2][1] - py) - (t[2][0] - px) * (t[1][1] - py)) / area;
            let w1 = ((t[2][0] - px) * (t[0][1] - py) - (t[0][0] - px) * (t[2][1] - py)) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * t[0][2] + w1 * t[1][2] + w2 * t[2][2];
            let i = y * width + x;
            if z <= depth[i] {
                continue;
            }
            depth[i] = z;
            let on_edge = edges
                && [w0, w1, w2]
                    .iter()
                    .zip(heights)
                    .zip(outer)
                    .any(|((w, h), o)| o && w * h < 0.8);
            let k = if on_edge { 0.45 } else { 1.0 };
            for c in 0..3 {
                rgb[3 * i + c] = (255.0 * (colour[c] * k).clamp(0.0, 1.0)) as u8;
            }
        }
    }
}

/// Writes the preview as a PNG file.
pub fn write_png(path: &Path, mesh: &Mesh, width: usize, height: usize) -> std::io::Result<()> {
    let rgb = render(mesh, width, height);
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(&rgb)
        .map_err(std::io::Error::other)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::material::Material;
    use crate::fem::shape::ElementKind;
    use crate::mesh::structured::block;

    #[test]
    fn a_block_has_its_surface_and_is_drawn() {
        let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0);
        let mesh = block([1.0, 1.0, 1.0], [2, 3, 4], ElementKind::Hex8, steel);
        // 2 (2x3 + 3x4 + 2x4) = 52 boundary faces.
        assert_eq!(boundary_faces(&mesh).len(), 52);
        let img = render(&mesh, 64, 48);
        let coloured = img.chunks(3).filter(|p| p != &[255, 255, 255]).count();
        assert!(coloured > 64 * 48 / 10, "{coloured} pixels drawn");
    }
}
