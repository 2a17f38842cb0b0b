//! Point elements of an imported model: lumped masses and linear springs between nodes or to
//! ground (Abaqus MASS, SPRING1, SPRING2, SPRINGA). They add to K and M at the nodes they
//! join (`fem::assembly`), so every later stage sees them as it sees the solid elements.

/// What a block of point elements is, with its DOFs (0..3: x, y, z in global axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PointKind {
    /// A mass at one node, the same in x, y and z (MASS).
    Mass,
    /// A spring from one DOF of a node to ground (SPRING1).
    Grounded { dof: usize },
    /// A spring between DOF `dofs[0]` of the first node and `dofs[1]` of the second (SPRING2).
    Between { dofs: [usize; 2] },
    /// A spring along the line joining two nodes, in the reference configuration (SPRINGA;
    /// the small-displacement axial stiffness, as the linear eigenproblem uses it).
    Axial,
}

impl PointKind {
    pub fn nodes(self) -> usize {
        match self {
            PointKind::Mass | PointKind::Grounded { .. } => 1,
            PointKind::Between { .. } | PointKind::Axial => 2,
        }
    }

    /// The Abaqus element type.
    pub fn abaqus(self) -> &'static str {
        match self {
            PointKind::Mass => "MASS",
            PointKind::Grounded { .. } => "SPRING1",
            PointKind::Between { .. } => "SPRING2",
            PointKind::Axial => "SPRINGA",
        }
    }
}

/// Point elements of one kind and value: `value` is the mass (kg) or the stiffness (N/m).
#[derive(Debug, Clone, PartialEq)]
pub struct PointBlock {
    pub name: String,
    pub kind: PointKind,
    pub value: f64,
    /// `kind.nodes()` node indices per element.
    pub connectivity: Vec<usize>,
}

impl PointBlock {
    pub fn len(&self) -> usize {
        self.connectivity.len() / self.kind.nodes()
    }

    pub fn is_empty(&self) -> bool {
        self.connectivity.is_empty()
    }

    pub fn element(&self, e: usize) -> &[usize] {
        let n = self.kind.nodes();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// Element `e`'s stiffness and mass, row-major over its nodes' 3 DOFs each (3n x 3n), at
    /// the nodes' coordinates `x`. Err: the two nodes of an axial spring coincide.
    pub fn matrices(&self, x: &[[f64; 3]]) -> Result<(Vec<f64>, Vec<f64>), String> {
        let n = 3 * self.kind.nodes();
        let mut k = vec![0.0; n * n];
        let mut m = vec![0.0; n * n];
        let v = self.value;
        match self.kind {
            PointKind::Mass => (0..3).for_each(|i| m[i * n + i] = v),
            PointKind::Grounded { dof } => k[dof * n + dof] = v,
            PointKind::Between { dofs: [i, j] } => {
                let j = 3 + j;
                k[i * n + i] += v;
                k[j * n + j] += v;
                k[i * n + j] -= v;
                k[j * n + i] -= v;
            }
            PointKind::Axial => {
                let d = crate::dense::sub(x[1], x[0]);
                let length = crate::dense::norm(d);
                if length.is_nan() || length <= 0.0 {
                    return Err("its two nodes are at the same place (no axis)".into());
                }
                let e = crate::dense::scale(d, 1.0 / length);
                for a in 0..3 {
                    for b in 0..3 {
                        let s = v * e[a] * e[b];
                        k[a * n + b] += s;
                        k[(3 + a) * n + 3 + b] += s;
                        k[a * n + 3 + b] -= s;
                        k[(3 + a) * n + b] -= s;
                    }
                }
            }
        }
        Ok((k, m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(kind: PointKind, value: f64) -> PointBlock {
        PointBlock {
            name: "p".into(),
            kind,
            value,
            connectivity: (0..kind.nodes()).collect(),
        }
    }

    #[test]
    fn an_axial_spring_resists_stretch_only() {
        let b = block(PointKind::Axial, 2.0);
        let x = [[0.0, 0.0, 0.0], [3.0, 4.0, 0.0]];
        let (k, m) = b.matrices(&x).unwrap();
        assert!(m.iter().all(|&v| v == 0.0));
        // Stretch along the axis (0.6, 0.8, 0): force k per unit; sliding across: none;
        // rigid translation: none.
        let apply = |u: [f64; 6]| -> f64 {
            (0..6)
                .map(|i| u[i] * (0..6).map(|j| k[i * 6 + j] * u[j]).sum::<f64>())
                .sum()
        };
        assert!((apply([0.0, 0.0, 0.0, 0.6, 0.8, 0.0]) - 2.0).abs() < 1e-14);
        assert!(apply([0.0, 0.0, 0.0, -0.8, 0.6, 0.0]).abs() < 1e-14);
        assert!(apply([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]).abs() < 1e-14);
        assert!(apply([1.0, 2.0, 3.0, 1.0, 2.0, 3.0]).abs() < 1e-13);
        assert!(b.matrices(&[[1.0, 1.0, 1.0]; 2]).is_err());
    }

    #[test]
    fn dof_springs_and_masses_sit_where_their_dofs_say() {
        let (k, _) = block(PointKind::Grounded { dof: 2 }, 5.0)
            .matrices(&[[0.0; 3]])
            .unwrap();
        assert_eq!(k[2 * 3 + 2], 5.0);
        assert_eq!(k.iter().filter(|&&v| v != 0.0).count(), 1);
        let (k, _) = block(PointKind::Between { dofs: [0, 1] }, 3.0)
            .matrices(&[[0.0; 3]; 2])
            .unwrap();
        assert_eq!((k[0], k[4 * 6 + 4], k[4], k[4 * 6]), (3.0, 3.0, -3.0, -3.0));
        let (_, m) = block(PointKind::Mass, 0.5).matrices(&[[0.0; 3]]).unwrap();
        assert_eq!((m[0], m[4], m[8], m[1]), (0.5, 0.5, 0.5, 0.0));
    }
}
