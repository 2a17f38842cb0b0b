//! Element stiffness and consistent mass of 3D solid elements (pure Rust kernels).
//!
//! Stiffness: K_e = sum_gp B^T D B det(J) w, B the strain-displacement matrix (Voigt order
//! xx, yy, zz, xy, yz, zx). Mass: M_e = sum_gp rho N^T N det(J) w (consistent). Matrices are
//! row-major of order 3n, DOF 3a + i for component i of node a.

use super::quadrature::Rule;
use crate::dense::{cholesky, cholesky_solve, inverse3};
use crate::mesh::material::Material;
use crate::mesh::orientation::{to_global, Orientation};
use crate::mesh::ElementKind;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("element {element}: Jacobian determinant {det:.3e} <= 0 at integration point {point} (inverted or degenerate element: check its node order and coordinates)")]
pub struct JacobianError {
    pub element: usize,
    pub point: usize,
    pub det: f64,
}

/// Shape data tabulated at a rule's points.
struct Tabulated {
    rule: Rule,
    n: Vec<Vec<f64>>,
    dn: Vec<Vec<[f64; 3]>>,
}

impl Tabulated {
    fn new(kind: ElementKind, rule: Rule) -> Self {
        let nn = kind.nodes();
        let mut n = Vec::new();
        let mut dn = Vec::new();
        for p in &rule.points {
            let (mut a, mut b) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
            kind.eval(*p, &mut a, &mut b);
            n.push(a);
            dn.push(b);
        }
        Tabulated { rule, n, dn }
    }
}

pub(crate) fn jacobian(x: &[[f64; 3]], dn: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for (xa, da) in x.iter().zip(dn) {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += xa[r] * da[c];
            }
        }
    }
    j
}

/// Inverse and determinant of the Jacobian, or the error naming the element and point.
fn checked_jacobian(
    x: &[[f64; 3]],
    dn: &[[f64; 3]],
    element: usize,
    point: usize,
) -> Result<([[f64; 3]; 3], f64), JacobianError> {
    let (inv, det) = inverse3(&jacobian(x, dn));
    if det <= 0.0 || !det.is_finite() {
        return Err(JacobianError {
            element,
            point,
            det,
        });
    }
    Ok((inv, det))
}

/// Physical gradient from a reference gradient: g_i = sum_j dN/dxi_j (J^-1)_ji.
fn physical(d: &[f64; 3], jinv: &[[f64; 3]; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| d[0] * jinv[0][i] + d[1] * jinv[1][i] + d[2] * jinv[2][i])
}

/// Adds w * B_a^T D B_b for every node pair (upper triangle then mirrored) to `k` of order
/// 3 * g.len().
fn add_btdb(k: &mut [f64], g: &[[f64; 3]], d: &[[f64; 6]; 6], w: f64) {
    let n3 = 3 * g.len();
    for (b, gb) in g.iter().enumerate() {
        let [bx, by, bz] = *gb;
        // X = D B_b (6 x 3)
        let mut x = [[0.0; 3]; 6];
        for r in 0..6 {
            x[r][0] = d[r][0] * bx + d[r][3] * by + d[r][5] * bz;
            x[r][1] = d[r][1] * by + d[r][3] * bx + d[r][4] * bz;
            x[r][2] = d[r][2] * bz + d[r][4] * by + d[r][5] * bx;
        }
        for (a, ga) in g.iter().enumerate().take(b + 1) {
            let [ax, ay, az] = *ga;
            for c in 0..3 {
                let v0 = ax * x[0][c] + ay * x[3][c] + az * x[5][c];
                let v1 = ay * x[1][c] + ax * x[3][c] + az * x[4][c];
                let v2 = az * x[2][c] + ay * x[4][c] + ax * x[5][c];
                k[(3 * a) * n3 + 3 * b + c] += w * v0;
                k[(3 * a + 1) * n3 + 3 * b + c] += w * v1;
                k[(3 * a + 2) * n3 + 3 * b + c] += w * v2;
            }
        }
    }
}

fn mirror_upper(k: &mut [f64], n: usize) {
    // add_btdb fills blocks with a <= b completely; copy them to b < a.
    for i in 0..n {
        for j in 0..n {
            if i / 3 > j / 3 {
                k[i * n + j] = k[j * n + i];
            }
        }
    }
}

/// Element kernel for one element type and material, with tabulated shape functions and
/// work arrays (one per thread of assembly).
pub struct ElementKernel {
    kind: ElementKind,
    /// D in the global axes (with a uniform orientation, rotated once).
    d: [[f64; 6]; 6],
    /// A cylindrical orientation and the material's local D: D rotated at each point.
    varying: Option<(Orientation, [[f64; 6]; 6])>,
    density: f64,
    stiff: Tabulated,
    mass: Tabulated,
    grads: Vec<[f64; 3]>,
    work: Vec<f64>,
}

impl ElementKernel {
    pub fn new(kind: ElementKind, material: &Material) -> Self {
        Self::oriented(kind, material, None)
    }

    /// The kernel of a material whose constants refer to `orientation`'s local axes. The
    /// reader has checked that the axes are defined at every element's centroid.
    pub fn oriented(
        kind: ElementKind,
        material: &Material,
        orientation: Option<&Orientation>,
    ) -> Self {
        let local = material.stiffness_matrix();
        let (d, varying) = match orientation {
            None => (local, None),
            Some(o) if o.is_uniform() => {
                let axes = o
                    .axes_at([0.0; 3])
                    .expect("a checked rectangular orientation");
                (to_global(&local, &axes), None)
            }
            Some(o) => (local, Some((o.clone(), local))),
        };
        ElementKernel {
            kind,
            d,
            varying,
            density: material.density,
            stiff: Tabulated::new(kind, kind.stiffness_rule()),
            mass: Tabulated::new(kind, kind.mass_rule()),
            grads: Vec::new(),
            work: Vec::new(),
        }
    }

    pub fn kind(&self) -> ElementKind {
        self.kind
    }

    /// Order of the element matrices (3 x nodes).
    pub fn order(&self) -> usize {
        3 * self.kind.nodes()
    }

    /// Stiffness of the element with node coordinates `x` into `k` (overwritten).
    /// `element` is only used to name the element in an error.
    pub fn stiffness(
        &mut self,
        element: usize,
        x: &[[f64; 3]],
        k: &mut [f64],
    ) -> Result<(), JacobianError> {
        let nn = self.kind.nodes();
        let n3 = 3 * nn;
        if self.kind == ElementKind::Hex8I {
            return self.stiffness_incompatible(element, x, k);
        }
        k[..n3 * n3].fill(0.0);
        self.grads.resize(nn, [0.0; 3]);
        for (p, w) in self.stiff.rule.weights.iter().enumerate() {
            let dn = &self.stiff.dn[p];
            let (jinv, det) = checked_jacobian(x, dn, element, p)?;
            for (g, d) in self.grads.iter_mut().zip(dn) {
                *g = physical(d, &jinv);
            }
            let d = self.d_at(&self.stiff.n[p], x);
            add_btdb(k, &self.grads, &d, w * det);
        }
        mirror_upper(k, n3);
        Ok(())
    }

    /// D at the point with shape-function values `n` of the element with nodes `x`: the
    /// global one, or the local one turned into the cylindrical axes there (at the centroid
    /// where the point lies on the axis).
    fn d_at(&self, n: &[f64], x: &[[f64; 3]]) -> [[f64; 6]; 6] {
        let Some((o, local)) = &self.varying else {
            return self.d;
        };
        let at = |w: &dyn Fn(usize) -> f64| {
            let mut p = [0.0; 3];
            for (a, xa) in x.iter().enumerate() {
                for i in 0..3 {
                    p[i] += w(a) * xa[i];
                }
            }
            p
        };
        let axes = o
            .axes_at(at(&|a| n[a]))
            .or_else(|| o.axes_at(at(&|_| 1.0 / x.len() as f64)))
            .expect("a cylindrical orientation checked off its axis at the centroids");
        to_global(local, &axes)
    }

    /// Hex8 with Wilson's incompatible bubbles P_i = 1 - xi_i^2, in Taylor's form (gradients
    /// through the centre Jacobian J0, scaled by det J0 / det J) so that the patch test passes
    /// on distorted meshes; the 9 internal DOFs are condensed statically:
    /// K = K_cc - K_ci K_ii^-1 K_ic.
    fn stiffness_incompatible(
        &mut self,
        element: usize,
        x: &[[f64; 3]],
        k: &mut [f64],
    ) -> Result<(), JacobianError> {
        const N: usize = 11; // 8 nodes + 3 bubbles (each with 3 components)
        const N3: usize = 3 * N;
        self.work.clear();
        self.work.resize(N3 * N3, 0.0);
        self.grads.resize(N, [0.0; 3]);
        let mut dn0 = [[0.0; 3]; 8];
        let mut n0 = [0.0; 8];
        ElementKind::Hex8.eval([0.0; 3], &mut n0, &mut dn0);
        let (j0inv, det0) = checked_jacobian(x, &dn0, element, usize::MAX)?;
        for (p, w) in self.stiff.rule.weights.iter().enumerate() {
            let xi = self.stiff.rule.points[p];
            let dn = &self.stiff.dn[p];
            let (jinv, det) = checked_jacobian(x, dn, element, p)?;
            for (g, d) in self.grads.iter_mut().zip(dn) {
                *g = physical(d, &jinv);
            }
            let scale = det0 / det;
            for i in 0..3 {
                let mut d = [0.0; 3];
                d[i] = -2.0 * xi[i];
                let g = physical(&d, &j0inv);
                self.grads[8 + i] = [g[0] * scale, g[1] * scale, g[2] * scale];
            }
            let d = self.d_at(&self.stiff.n[p][..8], x);
            add_btdb(&mut self.work, &self.grads, &d, w * det);
        }
        mirror_upper(&mut self.work, N3);
        // Condense: rows/cols 0..24 compatible (c), 24..33 incompatible (i).
        let (nc, ni) = (24, 9);
        let mut kii = vec![0.0; ni * ni];
        for r in 0..ni {
            for c in 0..ni {
                kii[r * ni + c] = self.work[(nc + r) * N3 + nc + c];
            }
        }
        cholesky(&mut kii, ni).ok_or(JacobianError {
            element,
            point: usize::MAX,
            det: 0.0,
        })?;
        // Z = K_ii^-1 K_ic (9 x 24), column by column.
        let mut z = vec![0.0; ni * nc];
        let mut col = [0.0; 9];
        for c in 0..nc {
            for r in 0..ni {
                col[r] = self.work[(nc + r) * N3 + c];
            }
            cholesky_solve(&kii, ni, &mut col);
            for r in 0..ni {
                z[r * nc + c] = col[r];
            }
        }
        for r in 0..nc {
            for c in 0..nc {
                let mut s = self.work[r * N3 + c];
                for m in 0..ni {
                    s -= self.work[r * N3 + nc + m] * z[m * nc + c];
                }
                k[r * nc + c] = s;
            }
        }
        // Restore exact symmetry lost to rounding in the condensation.
        for r in 0..nc {
            for c in r + 1..nc {
                let v = 0.5 * (k[r * nc + c] + k[c * nc + r]);
                k[r * nc + c] = v;
                k[c * nc + r] = v;
            }
        }
        Ok(())
    }

    /// Consistent mass of the element into `m` (overwritten).
    pub fn mass(
        &mut self,
        element: usize,
        x: &[[f64; 3]],
        m: &mut [f64],
    ) -> Result<(), JacobianError> {
        let nn = self.kind.nodes();
        let n3 = 3 * nn;
        m[..n3 * n3].fill(0.0);
        for (p, w) in self.mass.rule.weights.iter().enumerate() {
            let (_, det) = checked_jacobian(x, &self.mass.dn[p], element, p)?;
            let f = self.density * det * w;
            let n = &self.mass.n[p];
            for a in 0..nn {
                for b in 0..nn {
                    let v = f * (n[a] * n[b]);
                    for i in 0..3 {
                        m[(3 * a + i) * n3 + 3 * b + i] += v;
                    }
                }
            }
        }
        Ok(())
    }

    /// Volume of the element (sum of det J w over the mass rule).
    pub fn volume(&self, x: &[[f64; 3]]) -> f64 {
        self.mass
            .rule
            .weights
            .iter()
            .enumerate()
            .map(|(p, w)| inverse3(&jacobian(x, &self.mass.dn[p])).1 * w)
            .sum()
    }
}
