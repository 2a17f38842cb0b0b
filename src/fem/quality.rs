//! Mesh quality: the Jacobian determinant at every integration point (must be positive),
//! the scaled Jacobian det J / (|J_1| |J_2| |J_3|) (1 for a perfect cube, -> 0 when
//! degenerate), the aspect ratio (longest / shortest corner edge) and face warping (angle
//! between the normals of the two triangles of a quadrilateral face, worst of both
//! diagonals), reported per element block.

use crate::fem::element::jacobian;
use crate::mesh::element::{
    ElementKind, HEX_EDGES, HEX_FACES, TET_EDGES, WEDGE_EDGES, WEDGE_FACES,
};
use crate::mesh::Mesh;

/// Quality statistics of one element block.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockQuality {
    pub block: String,
    pub elements: usize,
    pub min_scaled_jacobian: f64,
    pub max_aspect_ratio: f64,
    pub mean_aspect_ratio: f64,
    /// Degrees.
    pub max_warping_deg: f64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mesh quality: element {element} (block '{block}', element {local} of the block) has Jacobian determinant {det:.3e} at integration point {point} (at x = {at:?}): it is inverted or degenerate; fix its node order or coordinates")]
pub struct QualityError {
    pub block: String,
    /// Global element index (0-based; the .inp writer numbers it element + 1).
    pub element: usize,
    pub local: usize,
    pub point: usize,
    pub det: f64,
    pub at: [f64; 3],
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
    let na = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let nb = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    let c = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (na * nb);
    c.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Warping of a quadrilateral face (corners in order), degrees.
fn warping(p: [[f64; 3]; 4]) -> f64 {
    let n = |a: usize, b: usize, c: usize| cross(sub(p[b], p[a]), sub(p[c], p[a]));
    let d1 = angle_deg(n(0, 1, 2), n(0, 2, 3));
    let d2 = angle_deg(n(1, 2, 3), n(1, 3, 0));
    d1.max(d2)
}

/// Checks every element; the first element with a non-positive Jacobian determinant is an
/// error that names it.
pub fn check(mesh: &Mesh) -> Result<Vec<BlockQuality>, QualityError> {
    let mut out = Vec::new();
    let mut global = 0;
    let mut x = Vec::new();
    for block in &mesh.blocks {
        let kind = block.kind;
        let rule = kind.stiffness_rule();
        let nn = kind.nodes();
        let mut n = vec![0.0; nn];
        let tabulated: Vec<Vec<[f64; 3]>> = rule
            .points
            .iter()
            .map(|&xi| {
                let mut dn = vec![[0.0; 3]; nn];
                kind.eval(xi, &mut n, &mut dn);
                dn
            })
            .collect();
        let edges: &[[usize; 2]] = match kind {
            ElementKind::Tet4 | ElementKind::Tet10 => &TET_EDGES,
            ElementKind::Wedge6 | ElementKind::Wedge15 => &WEDGE_EDGES,
            _ => &HEX_EDGES,
        };
        let mut q = BlockQuality {
            block: block.name.clone(),
            elements: block.len(),
            min_scaled_jacobian: f64::INFINITY,
            max_aspect_ratio: 0.0,
            mean_aspect_ratio: 0.0,
            max_warping_deg: 0.0,
        };
        for e in 0..block.len() {
            mesh.element_coords(block.element(e), &mut x);
            for (p, dn) in tabulated.iter().enumerate() {
                let j = jacobian(&x, dn);
                let col = |c: usize| [j[0][c], j[1][c], j[2][c]];
                let det = crate::dense::inverse3(&j).1;
                if det <= 0.0 || !det.is_finite() {
                    let mut at = [0.0; 3];
                    kind.eval(rule.points[p], &mut n, &mut vec![[0.0; 3]; nn]);
                    for (xa, na) in x.iter().zip(&n) {
                        for d in 0..3 {
                            at[d] += na * xa[d];
                        }
                    }
                    return Err(QualityError {
                        block: block.name.clone(),
                        element: global + e,
                        local: e,
                        point: p,
                        det,
                        at,
                    });
                }
                let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                let scaled = det / (norm(col(0)) * norm(col(1)) * norm(col(2)));
                q.min_scaled_jacobian = q.min_scaled_jacobian.min(scaled);
            }
            let lengths = edges.iter().map(|&[a, b]| dist(x[a], x[b]));
            let (lo, hi) = lengths.fold((f64::INFINITY, 0.0_f64), |(lo, hi), l| {
                (lo.min(l), hi.max(l))
            });
            let aspect = hi / lo;
            q.max_aspect_ratio = q.max_aspect_ratio.max(aspect);
            q.mean_aspect_ratio += aspect;
            match kind {
                ElementKind::Tet4 | ElementKind::Tet10 => {}
                // The wedge's three quadrilateral faces.
                ElementKind::Wedge6 | ElementKind::Wedge15 => {
                    for f in &WEDGE_FACES[2..] {
                        let corners = [x[f[0]], x[f[1]], x[f[2]], x[f[3]]];
                        q.max_warping_deg = q.max_warping_deg.max(warping(corners));
                    }
                }
                _ => {
                    for f in HEX_FACES {
                        q.max_warping_deg = q.max_warping_deg.max(warping(f.map(|c| x[c])));
                    }
                }
            }
        }
        q.mean_aspect_ratio /= block.len().max(1) as f64;
        global += block.len();
        out.push(q);
    }
    Ok(out)
}

/// A table of the statistics, one line per block.
pub fn table(stats: &[BlockQuality]) -> String {
    let mut s = format!(
        "{:<18} {:>9} {:>10} {:>10} {:>10} {:>10}\n",
        "block", "elements", "min sJ", "max AR", "mean AR", "warp deg"
    );
    for q in stats {
        s += &format!(
            "{:<18} {:>9} {:>10.3} {:>10.2} {:>10.2} {:>10.2}\n",
            q.block,
            q.elements,
            q.min_scaled_jacobian,
            q.max_aspect_ratio,
            q.mean_aspect_ratio,
            q.max_warping_deg
        );
    }
    s
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::mesh::material::Material;
    use crate::mesh::structured::block;

    #[test]
    fn a_cube_is_perfect_and_an_inverted_element_is_named() {
        let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0);
        let mut mesh = block([1.0, 1.0, 1.0], [2, 1, 1], ElementKind::Hex8, steel);
        let stats = check(&mesh).unwrap();
        assert!((stats[0].min_scaled_jacobian - 1.0).abs() < 1e-12);
        assert!((stats[0].max_aspect_ratio - 2.0).abs() < 1e-12);
        assert!(stats[0].max_warping_deg < 1e-9);
        // Swap top and bottom of the second element: inverted.
        let conn = &mut mesh.blocks[0].connectivity;
        for i in 0..4 {
            conn.swap(8 + i, 12 + i);
        }
        let e = check(&mesh).unwrap_err();
        assert_eq!(e.element, 1);
        assert!(e.to_string().contains("block 'solid'"), "{e}");
    }
}
