//! Material orientations (Abaqus `*ORIENTATION`): the local axes 1, 2, 3 an orthotropic or
//! anisotropic material's constants refer to, rectangular (the same everywhere) or
//! cylindrical (radial, circumferential, axial at each point: a brake lining's), with an
//! optional extra rotation about one local axis.

/// How the local axes are found.
#[derive(Debug, Clone, PartialEq)]
pub enum System {
    /// Axis 1 along `a - origin`, axis 2 in the plane of `a` and `b` (towards `b`), axis 3
    /// their cross product.
    Rectangular {
        a: [f64; 3],
        b: [f64; 3],
        origin: [f64; 3],
    },
    /// `a` and `b` on the cylinder's axis: axis 3 along `b - a`, axis 1 radial (from the axis
    /// to the point), axis 2 = 3 x 1 (circumferential).
    Cylindrical { a: [f64; 3], b: [f64; 3] },
}

use crate::dense::{cross, dot, scale, sub};

/// An orientation: its system and an extra rotation (local axis 0..3, angle in degrees).
#[derive(Debug, Clone, PartialEq)]
pub struct Orientation {
    pub name: String,
    pub system: System,
    pub extra_rotation: Option<(usize, f64)>,
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

impl Orientation {
    /// Whether the axes are the same everywhere.
    pub fn is_uniform(&self) -> bool {
        matches!(self.system, System::Rectangular { .. })
    }

    /// The local axes at `x` as rows (unit vectors in global coordinates); None where they are
    /// undefined (a point on a cylindrical system's axis, or degenerate points).
    pub fn axes_at(&self, x: [f64; 3]) -> Option<[[f64; 3]; 3]> {
        let (e1, e2, e3) = match self.system {
            System::Rectangular { a, b, origin } => {
                let e1 = unit(sub(a, origin))?;
                let ab = sub(b, origin);
                let e2 = unit(sub(ab, scale(e1, dot(e1, ab))))?;
                (e1, e2, cross(e1, e2))
            }
            System::Cylindrical { a, b } => {
                let e3 = unit(sub(b, a))?;
                let r = sub(x, a);
                let e1 = unit(sub(r, scale(e3, dot(e3, r))))?;
                (e1, cross(e3, e1), e3)
            }
        };
        let mut axes = [e1, e2, e3];
        if let Some((axis, degrees)) = self.extra_rotation {
            // Rotate the two other axes about `axis` by the angle (right-handed).
            let (c, s) = (degrees.to_radians().cos(), degrees.to_radians().sin());
            let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
            let (u, v) = (axes[p], axes[q]);
            axes[p] = [0, 1, 2].map(|i| c * u[i] + s * v[i]);
            axes[q] = [0, 1, 2].map(|i| -s * u[i] + c * v[i]);
        }
        Some(axes)
    }
}

/// D in the global axes from D in the local `axes` (rows: local axes in global coordinates),
/// both in squeal's Voigt order (xx, yy, zz, xy, yz, zx) with engineering shear strains:
/// D_g = M D_l M^T with M the stress transformation (Bond's matrix) of Q = axes^T.
pub fn to_global(d: &[[f64; 6]; 6], axes: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)];
    // Q[i][k]: global i component of local axis k.
    let q = |i: usize, k: usize| axes[k][i];
    let mut m = [[0.0; 6]; 6];
    for (a, &(i, j)) in PAIRS.iter().enumerate() {
        for (b, &(k, l)) in PAIRS.iter().enumerate() {
            m[a][b] = if k == l {
                q(i, k) * q(j, k)
            } else {
                q(i, k) * q(j, l) + q(i, l) * q(j, k)
            };
        }
    }
    let mut md = [[0.0; 6]; 6];
    for a in 0..6 {
        for b in 0..6 {
            md[a][b] = (0..6).map(|c| m[a][c] * d[c][b]).sum();
        }
    }
    let mut out = [[0.0; 6]; 6];
    for a in 0..6 {
        for b in 0..6 {
            out[a][b] = (0..6).map(|c| md[a][c] * m[b][c]).sum();
        }
    }
    out
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn cylindrical_axes_are_radial_circumferential_axial() {
        let o = Orientation {
            name: "pad".into(),
            system: System::Cylindrical {
                a: [0.0; 3],
                b: [0.0, 0.0, 1.0],
            },
            extra_rotation: None,
        };
        let axes = o.axes_at([0.0, 2.0, 5.0]).unwrap();
        assert_eq!(axes, [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
        assert!(o.axes_at([0.0, 0.0, 3.0]).is_none(), "on the axis");
    }

    #[test]
    fn an_extra_rotation_turns_the_other_two_axes() {
        let o = Orientation {
            name: "r".into(),
            system: System::Rectangular {
                a: [1.0, 0.0, 0.0],
                b: [0.0, 1.0, 0.0],
                origin: [0.0; 3],
            },
            extra_rotation: Some((2, 90.0)),
        };
        let axes = o.axes_at([0.0; 3]).unwrap();
        let expect = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        for (r, e) in axes.iter().flatten().zip(expect.iter().flatten()) {
            assert!((r - e).abs() < 1e-15, "{axes:?}");
        }
    }

    /// Swapping the axes 1 and 2 (a rotation by 90 degrees about 3) swaps D11 and D22, the
    /// yz and zx shears, and keeps the xy shear.
    #[test]
    fn bond_matrix_permutes_an_orthotropic_d() {
        let mut d = [[0.0; 6]; 6];
        for (i, v) in [1.0, 2.0, 3.0, 4.0, 5.0, 6.0].into_iter().enumerate() {
            d[i][i] = v;
        }
        d[0][1] = 0.5;
        d[1][0] = 0.5;
        let axes = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let g = to_global(&d, &axes);
        let diag: Vec<f64> = (0..6).map(|i| g[i][i]).collect();
        assert_eq!(diag, [2.0, 1.0, 3.0, 4.0, 6.0, 5.0]);
        assert_eq!(g[0][1], 0.5);
    }
}
