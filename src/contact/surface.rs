//! Element faces as 2D isoparametric surfaces: shape functions, quadrature, geometry.

use crate::fem::quadrature::gauss_legendre;
use crate::mesh::Mesh;

/// The shape of an element face, by node count (corners counter-clockwise seen from outside,
/// then mid-edge nodes in edge order, as `ElementKind::face_local_nodes` gives them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceShape {
    Tri3,
    Tri6,
    Quad4,
    Quad8,
}

impl FaceShape {
    pub fn from_nodes(n: usize) -> FaceShape {
        match n {
            3 => FaceShape::Tri3,
            6 => FaceShape::Tri6,
            4 => FaceShape::Quad4,
            8 => FaceShape::Quad8,
            _ => panic!("a face has 3, 4, 6 or 8 nodes, not {n}"),
        }
    }

    pub fn is_triangle(self) -> bool {
        matches!(self, FaceShape::Tri3 | FaceShape::Tri6)
    }

    /// Whether (xi, eta) lies in the reference face, up to `tol`.
    pub fn contains(self, xi: [f64; 2], tol: f64) -> bool {
        if self.is_triangle() {
            xi[0] >= -tol && xi[1] >= -tol && xi[0] + xi[1] <= 1.0 + tol
        } else {
            xi[0].abs() <= 1.0 + tol && xi[1].abs() <= 1.0 + tol
        }
    }

    /// The nearest point of the reference face.
    pub fn clamp(self, xi: [f64; 2]) -> [f64; 2] {
        if self.is_triangle() {
            let (mut a, mut b) = (xi[0].max(0.0), xi[1].max(0.0));
            let s = a + b;
            if s > 1.0 {
                a /= s;
                b /= s;
            }
            [a, b]
        } else {
            [xi[0].clamp(-1.0, 1.0), xi[1].clamp(-1.0, 1.0)]
        }
    }

    /// The centre of the reference face.
    pub fn centre(self) -> [f64; 2] {
        if self.is_triangle() {
            [1.0 / 3.0, 1.0 / 3.0]
        } else {
            [0.0, 0.0]
        }
    }

    /// Shape functions and their derivatives with respect to (xi, eta).
    pub fn eval(self, xi: [f64; 2], n: &mut [f64], dn: &mut [[f64; 2]]) {
        let (x, y) = (xi[0], xi[1]);
        match self {
            FaceShape::Tri3 => {
                n[..3].copy_from_slice(&[1.0 - x - y, x, y]);
                dn[..3].copy_from_slice(&[[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]);
            }
            FaceShape::Tri6 => {
                let l = [1.0 - x - y, x, y];
                let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
                for i in 0..3 {
                    n[i] = l[i] * (2.0 * l[i] - 1.0);
                    for d in 0..2 {
                        dn[i][d] = (4.0 * l[i] - 1.0) * dl[i][d];
                    }
                }
                for (k, (i, j)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                    n[3 + k] = 4.0 * l[i] * l[j];
                    for d in 0..2 {
                        dn[3 + k][d] = 4.0 * (dl[i][d] * l[j] + l[i] * dl[j][d]);
                    }
                }
            }
            FaceShape::Quad4 => {
                for (i, c) in QUAD_CORNERS.iter().enumerate() {
                    n[i] = 0.25 * (1.0 + c[0] * x) * (1.0 + c[1] * y);
                    dn[i] = [
                        0.25 * c[0] * (1.0 + c[1] * y),
                        0.25 * c[1] * (1.0 + c[0] * x),
                    ];
                }
            }
            FaceShape::Quad8 => {
                for (i, c) in QUAD_CORNERS.iter().enumerate() {
                    let (a, b) = (1.0 + c[0] * x, 1.0 + c[1] * y);
                    let s = c[0] * x + c[1] * y - 1.0;
                    n[i] = 0.25 * a * b * s;
                    dn[i] = [0.25 * c[0] * b * (s + a), 0.25 * c[1] * a * (s + b)];
                }
                // Mid-edge nodes of edges (0,1), (1,2), (2,3), (3,0).
                for (k, m) in [[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]]
                    .iter()
                    .enumerate()
                {
                    if m[0] == 0.0 {
                        n[4 + k] = 0.5 * (1.0 - x * x) * (1.0 + m[1] * y);
                        dn[4 + k] = [-x * (1.0 + m[1] * y), 0.5 * m[1] * (1.0 - x * x)];
                    } else {
                        n[4 + k] = 0.5 * (1.0 + m[0] * x) * (1.0 - y * y);
                        dn[4 + k] = [0.5 * m[0] * (1.0 - y * y), -y * (1.0 + m[0] * x)];
                    }
                }
            }
        }
    }

    /// Quadrature points and weights on the reference face: n x n Gauss for quadrilaterals;
    /// 1, 3 or 6 points (degree 1, 2, 4) for triangles.
    pub fn rule(self, n: usize) -> Vec<([f64; 2], f64)> {
        if self.is_triangle() {
            match n {
                1 => vec![([1.0 / 3.0, 1.0 / 3.0], 0.5)],
                2 => vec![
                    ([1.0 / 6.0, 1.0 / 6.0], 1.0 / 6.0),
                    ([2.0 / 3.0, 1.0 / 6.0], 1.0 / 6.0),
                    ([1.0 / 6.0, 2.0 / 3.0], 1.0 / 6.0),
                ],
                _ => {
                    // Dunavant's degree-4 rule.
                    let (a, wa) = (0.445_948_490_915_965, 0.5 * 0.223_381_589_678_011);
                    let (b, wb) = (0.091_576_213_509_771, 0.5 * 0.109_951_743_655_322);
                    vec![
                        ([a, a], wa),
                        ([1.0 - 2.0 * a, a], wa),
                        ([a, 1.0 - 2.0 * a], wa),
                        ([b, b], wb),
                        ([1.0 - 2.0 * b, b], wb),
                        ([b, 1.0 - 2.0 * b], wb),
                    ]
                }
            }
        } else {
            let (p, w) = gauss_legendre(n.clamp(1, 4));
            let mut out = Vec::with_capacity(p.len() * p.len());
            for j in 0..p.len() {
                for i in 0..p.len() {
                    out.push(([p[i], p[j]], w[i] * w[j]));
                }
            }
            out
        }
    }
}

const QUAD_CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// One element face with its node coordinates.
#[derive(Debug, Clone)]
pub struct Face {
    pub element: usize,
    pub face: u8,
    pub shape: FaceShape,
    pub nodes: Vec<usize>,
    pub coords: Vec<[f64; 3]>,
}

/// Position, tangents, shape functions at a point of a face.
#[derive(Debug, Clone)]
pub struct FacePoint {
    pub x: [f64; 3],
    pub dxi: [f64; 3],
    pub deta: [f64; 3],
    pub n: Vec<f64>,
    pub dn: Vec<[f64; 2]>,
}

impl FacePoint {
    /// Unit outward normal and area Jacobian |x_xi x x_eta|.
    pub fn normal(&self) -> ([f64; 3], f64) {
        let c = cross(self.dxi, self.deta);
        let j = norm(c);
        ([c[0] / j, c[1] / j, c[2] / j], j)
    }
}

impl Face {
    pub fn new(mesh: &Mesh, element: usize, face: u8) -> Face {
        let nodes = mesh.face_nodes(element, face);
        let coords = nodes.iter().map(|&n| mesh.coords[n]).collect();
        Face {
            element,
            face,
            shape: FaceShape::from_nodes(nodes.len()),
            nodes,
            coords,
        }
    }

    pub fn at(&self, xi: [f64; 2]) -> FacePoint {
        let k = self.nodes.len();
        let mut n = vec![0.0; k];
        let mut dn = vec![[0.0; 2]; k];
        self.shape.eval(xi, &mut n, &mut dn);
        let mut p = FacePoint {
            x: [0.0; 3],
            dxi: [0.0; 3],
            deta: [0.0; 3],
            n,
            dn,
        };
        for a in 0..k {
            for d in 0..3 {
                p.x[d] += p.n[a] * self.coords[a][d];
                p.dxi[d] += p.dn[a][0] * self.coords[a][d];
                p.deta[d] += p.dn[a][1] * self.coords[a][d];
            }
        }
        p
    }

    /// Axis-aligned bounding box (min, max) of the nodes.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for c in &self.coords {
            for d in 0..3 {
                lo[d] = lo[d].min(c[d]);
                hi[d] = hi[d].max(c[d]);
            }
        }
        (lo, hi)
    }

    /// Area by the given rule.
    pub fn area(&self, points: usize) -> f64 {
        self.shape
            .rule(points)
            .iter()
            .map(|&(xi, w)| w * self.at(xi).normal().1)
            .sum()
    }

    /// Surface derivatives of the shape functions along a tangent vector v:
    /// dN/ds = N_xi a + N_eta b where x_xi a + x_eta b is the projection of v on the tangent
    /// plane (least squares on the 2x2 metric).
    pub fn directional_derivative(&self, p: &FacePoint, v: [f64; 3]) -> Vec<f64> {
        let g11 = dot(p.dxi, p.dxi);
        let g12 = dot(p.dxi, p.deta);
        let g22 = dot(p.deta, p.deta);
        let (r1, r2) = (dot(p.dxi, v), dot(p.deta, v));
        let det = g11 * g22 - g12 * g12;
        let a = (g22 * r1 - g12 * r2) / det;
        let b = (g11 * r2 - g12 * r1) / det;
        p.dn.iter().map(|d| d[0] * a + d[1] * b).collect()
    }
}

// The 3-vector helpers live in `dense`; re-exported for the contact code that uses them.
pub use crate::dense::{cross, dot, norm, normalize, scale, sub};

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    /// Partition of unity, derivatives against central differences, and node interpolation.
    #[test]
    fn face_shape_functions_are_consistent() {
        for shape in [
            FaceShape::Tri3,
            FaceShape::Tri6,
            FaceShape::Quad4,
            FaceShape::Quad8,
        ] {
            let k = match shape {
                FaceShape::Tri3 => 3,
                FaceShape::Tri6 => 6,
                FaceShape::Quad4 => 4,
                FaceShape::Quad8 => 8,
            };
            let xi = [0.21, 0.13];
            let (mut n, mut dn) = (vec![0.0; k], vec![[0.0; 2]; k]);
            shape.eval(xi, &mut n, &mut dn);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let h = 1e-6;
            for d in 0..2 {
                let (mut np, mut nm, mut scratch) = (vec![0.0; k], vec![0.0; k], vec![[0.0; 2]; k]);
                let mut xp = xi;
                xp[d] += h;
                let mut xm = xi;
                xm[d] -= h;
                shape.eval(xp, &mut np, &mut scratch);
                shape.eval(xm, &mut nm, &mut scratch);
                for a in 0..k {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!((fd - dn[a][d]).abs() < 1e-8, "{shape:?} node {a} d{d}");
                }
            }
            // Rules integrate the area of the reference face.
            let area: f64 = shape.rule(2).iter().map(|r| r.1).sum();
            let expected = if shape.is_triangle() { 0.5 } else { 4.0 };
            assert!((area - expected).abs() < 1e-14);
        }
    }
}
