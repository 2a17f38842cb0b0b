//! Element types and their shape functions on the reference element.
//!
//! Node orderings follow Abaqus (C3D8, C3D20, C3D10), which is also VTK's/XDMF's ordering.

use super::quadrature::{hex_rule, tet_rule, Rule};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// Trilinear hexahedron (fully integrated; locks in bending, kept for reference).
    Hex8,
    /// Trilinear hexahedron with Wilson-Taylor incompatible modes, statically condensed:
    /// accurate in bending at linear cost (Abaqus C3D8I).
    #[serde(rename = "hex8i")]
    Hex8I,
    /// Serendipity quadratic hexahedron.
    Hex20,
    /// Quadratic tetrahedron.
    Tet10,
    /// Linear tetrahedron (constant strain; stiff in bending: for imported meshes, C3D4).
    Tet4,
}

/// Corner positions of the reference cube, in C3D8 order.
pub const HEX_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Edges of a hexahedron as corner pairs, in the order of the C3D20 mid-edge nodes 8..19.
pub const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Edges of a tetrahedron as corner pairs, in the order of the C3D10 mid-edge nodes 4..9.
pub const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];

/// Corners of the six faces of a hexahedron (Abaqus faces S1..S6), counter-clockwise seen
/// from outside.
pub const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// Corners of the four faces of a tetrahedron (Abaqus faces S1..S4), counter-clockwise seen
/// from outside.
pub const TET_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];

impl ElementKind {
    /// Element-local nodes of face `face` (1-based, Abaqus numbering): corners in
    /// counter-clockwise order seen from outside, then the mid-edge nodes of quadratic
    /// elements in the order of the face's edges.
    pub fn face_local_nodes(self, face: u8) -> Vec<usize> {
        let f = face as usize - 1;
        let (corners, edges): (Vec<usize>, &[[usize; 2]]) = match self {
            ElementKind::Hex8 | ElementKind::Hex8I => (HEX_FACES[f].to_vec(), &[]),
            ElementKind::Hex20 => (HEX_FACES[f].to_vec(), &HEX_EDGES),
            ElementKind::Tet4 => (TET_FACES[f].to_vec(), &[]),
            ElementKind::Tet10 => (TET_FACES[f].to_vec(), &TET_EDGES),
        };
        let mut out = corners.clone();
        if !edges.is_empty() {
            let first_mid = if matches!(self, ElementKind::Hex20) {
                8
            } else {
                4
            };
            for i in 0..corners.len() {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                let e = edges
                    .iter()
                    .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
                    .expect("face edges are element edges");
                out.push(first_mid + e);
            }
        }
        out
    }

    /// Number of faces (6 for hexahedra, 4 for tetrahedra).
    pub fn faces(self) -> u8 {
        match self {
            ElementKind::Tet4 | ElementKind::Tet10 => 4,
            _ => 6,
        }
    }

    pub fn nodes(self) -> usize {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => 8,
            ElementKind::Hex20 => 20,
            ElementKind::Tet10 => 10,
            ElementKind::Tet4 => 4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Hex8 => "hex8",
            ElementKind::Hex8I => "hex8i",
            ElementKind::Hex20 => "hex20",
            ElementKind::Tet10 => "tet10",
            ElementKind::Tet4 => "tet4",
        }
    }

    /// Rule for the stiffness (exact for affine geometry where possible).
    pub fn stiffness_rule(self) -> Rule {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => hex_rule(2),
            ElementKind::Hex20 => hex_rule(3),
            ElementKind::Tet10 => tet_rule(3),
            ElementKind::Tet4 => tet_rule(2),
        }
    }

    /// Rule for the consistent mass (degree 2p integrand).
    pub fn mass_rule(self) -> Rule {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => hex_rule(2),
            ElementKind::Hex20 => hex_rule(3),
            ElementKind::Tet10 => tet_rule(4),
            ElementKind::Tet4 => tet_rule(3),
        }
    }

    /// Reference coordinates of the nodes.
    pub fn reference_nodes(self) -> Vec<[f64; 3]> {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => HEX_CORNERS.to_vec(),
            ElementKind::Hex20 => {
                let mut v = HEX_CORNERS.to_vec();
                for [a, b] in HEX_EDGES {
                    let (p, q) = (HEX_CORNERS[a], HEX_CORNERS[b]);
                    v.push([
                        0.5 * (p[0] + q[0]),
                        0.5 * (p[1] + q[1]),
                        0.5 * (p[2] + q[2]),
                    ]);
                }
                v
            }
            ElementKind::Tet4 => vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            ElementKind::Tet10 => {
                let c = [
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ];
                let mut v = c.to_vec();
                for [a, b] in TET_EDGES {
                    v.push([
                        0.5 * (c[a][0] + c[b][0]),
                        0.5 * (c[a][1] + c[b][1]),
                        0.5 * (c[a][2] + c[b][2]),
                    ]);
                }
                v
            }
        }
    }

    /// Shape functions `n[a]` and their reference gradients `dn[a]` at `xi`.
    pub fn eval(self, xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
        let [x, y, z] = xi;
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                    n[a] = 0.125 * fx * fy * fz;
                    dn[a] = [
                        0.125 * c[0] * fy * fz,
                        0.125 * fx * c[1] * fz,
                        0.125 * fx * fy * c[2],
                    ];
                }
            }
            ElementKind::Hex20 => {
                for (a, c) in HEX_CORNERS.iter().enumerate() {
                    let (fx, fy, fz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                    let s = c[0] * x + c[1] * y + c[2] * z - 2.0;
                    n[a] = 0.125 * fx * fy * fz * s;
                    dn[a] = [
                        0.125 * c[0] * fy * fz * (s + fx),
                        0.125 * c[1] * fx * fz * (s + fy),
                        0.125 * c[2] * fx * fy * (s + fz),
                    ];
                }
                for (e, [p, q]) in HEX_EDGES.iter().enumerate() {
                    let a = 8 + e;
                    let (cp, cq) = (HEX_CORNERS[*p], HEX_CORNERS[*q]);
                    let c = [
                        0.5 * (cp[0] + cq[0]),
                        0.5 * (cp[1] + cq[1]),
                        0.5 * (cp[2] + cq[2]),
                    ];
                    // One coordinate of a mid-edge node is 0: the bubble runs along that axis.
                    let f = |t: f64, ct: f64| if ct == 0.0 { 1.0 - t * t } else { 1.0 + ct * t };
                    let df = |t: f64, ct: f64| if ct == 0.0 { -2.0 * t } else { ct };
                    let (fx, fy, fz) = (f(x, c[0]), f(y, c[1]), f(z, c[2]));
                    n[a] = 0.25 * fx * fy * fz;
                    dn[a] = [
                        0.25 * df(x, c[0]) * fy * fz,
                        0.25 * fx * df(y, c[1]) * fz,
                        0.25 * fx * fy * df(z, c[2]),
                    ];
                }
            }
            ElementKind::Tet4 => {
                n[..4].copy_from_slice(&[1.0 - x - y - z, x, y, z]);
                dn[..4].copy_from_slice(&[
                    [-1.0, -1.0, -1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ]);
            }
            ElementKind::Tet10 => {
                let l = [1.0 - x - y - z, x, y, z];
                let dl = [
                    [-1.0, -1.0, -1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ];
                for a in 0..4 {
                    n[a] = l[a] * (2.0 * l[a] - 1.0);
                    let g = 4.0 * l[a] - 1.0;
                    dn[a] = [g * dl[a][0], g * dl[a][1], g * dl[a][2]];
                }
                for (e, [p, q]) in TET_EDGES.iter().enumerate() {
                    n[4 + e] = 4.0 * l[*p] * l[*q];
                    dn[4 + e] = [
                        4.0 * (dl[*p][0] * l[*q] + l[*p] * dl[*q][0]),
                        4.0 * (dl[*p][1] * l[*q] + l[*p] * dl[*q][1]),
                        4.0 * (dl[*p][2] * l[*q] + l[*p] * dl[*q][2]),
                    ];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [ElementKind; 4] = [
        ElementKind::Hex8,
        ElementKind::Hex20,
        ElementKind::Tet10,
        ElementKind::Tet4,
    ];

    #[test]
    fn kronecker_delta_and_partition_of_unity() {
        for kind in KINDS {
            let nn = kind.nodes();
            let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
            for (b, xb) in kind.reference_nodes().iter().enumerate() {
                kind.eval(*xb, &mut n, &mut dn);
                for (a, na) in n.iter().enumerate() {
                    let expect = if a == b { 1.0 } else { 0.0 };
                    assert!((na - expect).abs() < 1e-14, "{kind:?} N{a} at node {b}");
                }
                let sum_grad: [f64; 3] = [0, 1, 2].map(|d| dn.iter().map(|g| g[d]).sum());
                assert!(sum_grad.iter().all(|g| g.abs() < 1e-13), "{kind:?}");
            }
        }
    }

    #[test]
    fn gradients_match_finite_differences() {
        let xi = [0.21, -0.37, 0.13];
        for kind in KINDS {
            let nn = kind.nodes();
            let (mut n0, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
            let (mut np, mut nm, mut tmp) = (vec![0.0; nn], vec![0.0; nn], vec![[0.0; 3]; nn]);
            kind.eval(xi, &mut n0, &mut dn);
            for d in 0..3 {
                let h = 1e-6;
                let (mut xp, mut xm) = (xi, xi);
                xp[d] += h;
                xm[d] -= h;
                kind.eval(xp, &mut np, &mut tmp);
                kind.eval(xm, &mut nm, &mut tmp);
                for a in 0..nn {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!((fd - dn[a][d]).abs() < 1e-8, "{kind:?} dN{a}/dxi{d}");
                }
            }
        }
    }
}
