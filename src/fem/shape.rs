//! Shape functions and quadrature rules on the reference element of each element kind
//! (`mesh::element`: the kinds, their nodes and faces).

use super::quadrature::{hex_rule, tet_rule, wedge_rule, Rule};
use crate::mesh::element::{ElementKind, HEX_CORNERS, HEX_EDGES, TET_EDGES, WEDGE_EDGES};

impl ElementKind {
    /// Rule for the stiffness: the rule Abaqus and CalculiX integrate the same element with
    /// (C3D8, C3D8I: 2x2x2; C3D20: 3x3x3; C3D20R: 2x2x2; C3D10: 4 points; C3D4: exact), so
    /// that an imported deck's K is the one its authors' solver assembles (tests/ccx_reference).
    pub fn stiffness_rule(self) -> Rule {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => hex_rule(2),
            ElementKind::Hex20 => hex_rule(3),
            ElementKind::Hex20R => hex_rule(2),
            ElementKind::Tet10 => super::quadrature::tet_rule_4_points(),
            ElementKind::Tet4 => tet_rule(2),
            ElementKind::Wedge6 => wedge_rule(1, 2),
            ElementKind::Wedge15 => wedge_rule(3, 3),
        }
    }

    /// Rule for the consistent mass, on the stiffness' points where CalculiX takes them
    /// (C3D20R on 2x2x2, C3D10 on 4 points): exact to degree 2p - 2 at least, which keeps
    /// the eigenvalues' O(h^2p) convergence (Strang and Fix, ch. 6.3).
    pub fn mass_rule(self) -> Rule {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => hex_rule(2),
            ElementKind::Hex20 => hex_rule(3),
            ElementKind::Hex20R => hex_rule(2),
            ElementKind::Tet10 => super::quadrature::tet_rule_4_points(),
            ElementKind::Tet4 => tet_rule(3),
            ElementKind::Wedge6 => wedge_rule(1, 2),
            ElementKind::Wedge15 => wedge_rule(3, 3),
        }
    }

    /// The rules in words, for the log.
    pub fn rule_description(self) -> &'static str {
        match self {
            ElementKind::Hex8 => "2x2x2 Gauss points for K and M",
            ElementKind::Hex8I => "2x2x2 Gauss points, 9 incompatible modes condensed",
            ElementKind::Hex20 => "3x3x3 Gauss points for K and M",
            ElementKind::Hex20R => "reduced: 2x2x2 Gauss points for K and M",
            ElementKind::Tet10 => "4 points for K and M",
            ElementKind::Tet4 => "K exact (constant strain), M exact",
            ElementKind::Wedge6 => "2 points (triangle centroid x 2 Gauss) for K and M",
            ElementKind::Wedge15 => "9 points (3 in the triangle x 3 Gauss) for K and M",
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
            ElementKind::Hex20 | ElementKind::Hex20R => {
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
            ElementKind::Wedge6 => {
                let l = [1.0 - x - y, x, y];
                let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
                for a in 0..6 {
                    let (i, c) = (a % 3, if a < 3 { -1.0 } else { 1.0 });
                    let f = 0.5 * (1.0 + c * z);
                    n[a] = l[i] * f;
                    dn[a] = [dl[i][0] * f, dl[i][1] * f, 0.5 * c * l[i]];
                }
            }
            ElementKind::Wedge15 => wedge15(xi, n, dn),
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

/// The 15-node wedge's serendipity functions: corners
/// L (2L - 1)(1 + c zeta)/2 - L (1 - zeta^2)/2, triangle mid-edges 2 L_p L_q (1 + c zeta),
/// vertical mid-edges L (1 - zeta^2) (c = -1 on the bottom, +1 on the top).
fn wedge15(xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    let [x, y, z] = xi;
    let l = [1.0 - x - y, x, y];
    let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    let bubble = 1.0 - z * z;
    for a in 0..6 {
        let (i, c) = (a % 3, if a < 3 { -1.0 } else { 1.0 });
        let f = 1.0 + c * z;
        n[a] = 0.5 * l[i] * (2.0 * l[i] - 1.0) * f - 0.5 * l[i] * bubble;
        let g = 0.5 * (4.0 * l[i] - 1.0) * f - 0.5 * bubble;
        dn[a] = [
            g * dl[i][0],
            g * dl[i][1],
            0.5 * l[i] * (2.0 * l[i] - 1.0) * c + l[i] * z,
        ];
    }
    for (e, [p, q]) in WEDGE_EDGES.iter().enumerate() {
        let a = 6 + e;
        let (i, j) = (p % 3, q % 3);
        if e < 6 {
            let c = if e < 3 { -1.0 } else { 1.0 };
            let f = 1.0 + c * z;
            n[a] = 2.0 * l[i] * l[j] * f;
            dn[a] = [
                2.0 * (dl[i][0] * l[j] + l[i] * dl[j][0]) * f,
                2.0 * (dl[i][1] * l[j] + l[i] * dl[j][1]) * f,
                2.0 * l[i] * l[j] * c,
            ];
        } else {
            n[a] = l[i] * bubble;
            dn[a] = [dl[i][0] * bubble, dl[i][1] * bubble, -2.0 * l[i] * z];
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    const KINDS: [ElementKind; 6] = [
        ElementKind::Hex8,
        ElementKind::Hex20,
        ElementKind::Tet10,
        ElementKind::Tet4,
        ElementKind::Wedge6,
        ElementKind::Wedge15,
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
