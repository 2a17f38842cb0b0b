//! A shaded preview of a mesh as PNG: the boundary faces seen from an oblique outboard view,
//! one colour per element block (component), Lambert shading, z-buffered, element edges
//! drawn where faces are large enough on screen to show them.

use crate::dense::{cross, dot, normalize, sub};
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
    render_with(mesh, None, width, height)
}

/// The mesh moved by a nodal displacement `u` and coloured by |u|, dark blue (still) to
/// yellow (the 95th percentile of |u| and beyond), as an RGB image. A field that is zero, or
/// holds a NaN or inf, leaves the mesh undeformed in its component colours.
pub fn render_deformed(mesh: &Mesh, u: &[[f64; 3]], width: usize, height: usize) -> Vec<u8> {
    let usable = u.len() == mesh.coords.len()
        && u.iter().flatten().all(|v| v.is_finite())
        && u.iter().flatten().any(|&v| v != 0.0);
    render_with(mesh, Some(u).filter(|_| usable), width, height)
}

fn render_with(mesh: &Mesh, field: Option<&[[f64; 3]]>, width: usize, height: usize) -> Vec<u8> {
    let eye = normalize([0.55, -0.75, 0.85]);
    let right = normalize(cross([0.0, 0.0, 1.0], eye));
    let up = cross(eye, right);
    let light = normalize([0.3, -0.4, 1.0]);
    let faces = boundary_faces(mesh);
    let size = |u: &[f64; 3]| dot(*u, *u).sqrt();
    // The reference size: the 95th percentile of the nodes' displacements, so that a small
    // part moving far (a loose ear, a finger tip) does not hide how the rest moves. It moves
    // 5 % of the model's size on the picture; larger ones are drawn at most twice as far and
    // take the top colour.
    let reference = field.map_or(0.0, |u| {
        let mut sizes: Vec<f64> = u.iter().map(size).collect();
        sizes.sort_by(f64::total_cmp);
        sizes[(0.95 * (sizes.len() - 1) as f64) as usize]
    });
    let (lo, hi) = bounding_box(&mesh.coords);
    let scale_u = if reference > 0.0 {
        0.05 * size(&sub(hi, lo)) / reference
    } else {
        0.0
    };
    let coords: Vec<[f64; 3]> = match field {
        Some(u) => (mesh.coords.iter().zip(u))
            .map(|(x, u)| {
                let shorten = (2.0 * reference / size(u)).min(1.0);
                [0, 1, 2].map(|d| x[d] + scale_u * shorten * u[d])
            })
            .collect(),
        None => mesh.coords.clone(),
    };
    // Fit the projected bounding box into the image with a margin.
    let project = |x: [f64; 3]| [dot(x, right), dot(x, up), dot(x, eye)];
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for x in &coords {
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
    let colour_of = |node: usize, block: usize| match field {
        Some(u) => {
            crate::io::figure::colormap(size(&u[node]) / reference).map(|c| c as f64 / 255.0)
        }
        None => PALETTE[block % PALETTE.len()],
    };
    let mut rgb = vec![255u8; width * height * 3];
    let mut depth = vec![f64::NEG_INFINITY; width * height];
    for (nodes, block) in &faces {
        let x: Vec<[f64; 3]> = nodes.iter().map(|&n| coords[n]).collect();
        let normal = normalize(cross(sub(x[1], x[0]), sub(x[x.len() - 1], x[0])));
        if dot(normal, eye).is_nan() || dot(normal, eye) <= 0.0 {
            continue;
        }
        let shade = 0.35 + 0.65 * dot(normal, light).abs();
        let colours: Vec<[f64; 3]> = nodes
            .iter()
            .map(|&n| colour_of(n, *block).map(|c| c * shade))
            .collect();
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
            let colour = [colours[0], colours[t], colours[t + 1]];
            let image = Image {
                width,
                height,
                rgb: &mut rgb,
                depth: &mut depth,
            };
            fill_triangle(&tri, outer, edges, colour, image);
        }
    }
    rgb
}

fn bounding_box(coords: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in coords {
        for d in 0..3 {
            lo[d] = lo[d].min(x[d]);
            hi[d] = hi[d].max(x[d]);
        }
    }
    (lo, hi)
}

/// The pixels and depths drawn into.
struct Image<'a> {
    width: usize,
    height: usize,
    rgb: &'a mut [u8],
    depth: &'a mut [f64],
}

/// Fills a triangle with z-buffering, its vertices' colours interpolated; `outer[k]` marks the
/// edge opposite vertex k as a face edge, darkened within a pixel when `edges`.
fn fill_triangle(
    t: &[[f64; 3]; 3],
    outer: [bool; 3],
    edges: bool,
    colour: [[f64; 3]; 3],
    image: Image,
) {
    let Image {
        width,
        height,
        rgb,
        depth,
    } = image;
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
                let v = w0 * colour[0][c] + w1 * colour[1][c] + w2 * colour[2][c];
                rgb[3 * i + c] = (255.0 * (v * k).clamp(0.0, 1.0)) as u8;
            }
        }
    }
}

/// Writes the preview as a PNG file.
pub fn write_png(path: &Path, mesh: &Mesh, width: usize, height: usize) -> std::io::Result<()> {
    save(path, &render(mesh, width, height), width, height)
}

/// Writes an RGB image as a PNG file.
pub fn save(path: &Path, rgb: &[u8], width: usize, height: usize) -> std::io::Result<()> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut encoder = png::Encoder::new(file, width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    Ok(())
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::mesh::material::Material;
    use crate::mesh::structured::block;
    use crate::mesh::ElementKind;

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

    #[test]
    fn a_deformation_is_coloured_from_dark_where_still_to_yellow_where_largest() {
        let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0);
        let mesh = block([1.0, 1.0, 1.0], [4, 4, 4], ElementKind::Hex8, steel);
        // Bending in z growing with x: still at x = 0, largest at x = 1.
        let u: Vec<[f64; 3]> = mesh
            .coords
            .iter()
            .map(|x| [0.0, 0.0, x[0] * x[0]])
            .collect();
        let img = render_deformed(&mesh, &u, 160, 120);
        let yellowish = img
            .chunks(3)
            .filter(|p| p[0] > 180 && p[1] > 160 && p[2] < 90)
            .count();
        let dark = img
            .chunks(3)
            .filter(|p| p[2] > p[1] && p[0] < 90 && p != &[255, 255, 255])
            .count();
        assert!(
            yellowish > 20 && dark > 20,
            "{yellowish} yellow, {dark} dark pixels"
        );
        // A field with a NaN draws the undeformed preview, not garbage.
        let mut nan = u.clone();
        nan[3][1] = f64::NAN;
        assert!(render_deformed(&mesh, &nan, 64, 48) == render(&mesh, 64, 48));
    }
}
