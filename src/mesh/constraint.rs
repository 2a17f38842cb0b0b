//! Linear multi-point constraints of an imported model (Abaqus `*EQUATION`, `*TIE`):
//! sum_i a_i u(node_i, dof_i) = 0. They are imposed by a penalty in K (`fem::assembly`):
//! K += k_p a a^T per constraint, k_p = `penalty` x the largest diagonal entry of K, so a
//! constraint holds to about 1/penalty of the deformation it resists and a frequency moves by
//! about 1/penalty relatively (first order in 1/k_p: tests/ccx_reference.rs measures it
//! against CalculiX, which eliminates the dependent DOFs exactly).

/// One linear constraint: terms (node, DOF 0..3, coefficient) and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearConstraint {
    pub terms: Vec<(usize, usize, f64)>,
    pub origin: String,
}

/// The default penalty factor. On the cantilever with two equations against CalculiX
/// (tests/ccx_reference.rs) the frequencies' error is about 1.9e-3 / factor (1.9e-4 at 10,
/// 1.9e-5 at 100), down to the two codes' agreement (3.8e-7) from 1e4 on; 1e5 keeps a decade of margin for models whose
/// constraints carry more of the strain energy, while K's condition number, which grows with
/// the factor, stays within what the factorizations (single-precision ones included) resolve.
pub const DEFAULT_PENALTY: f64 = 1e5;

/// The constraints of a mesh and their penalty factor.
#[derive(Debug, Clone, PartialEq)]
pub struct Constraints {
    pub equations: Vec<LinearConstraint>,
    pub penalty: f64,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            equations: Vec::new(),
            penalty: DEFAULT_PENALTY,
        }
    }
}

impl LinearConstraint {
    /// The distinct nodes of the constraint, in first-seen order.
    pub fn nodes(&self) -> Vec<usize> {
        let mut nodes: Vec<usize> = Vec::new();
        for &(n, _, _) in &self.terms {
            if !nodes.contains(&n) {
                nodes.push(n);
            }
        }
        nodes
    }

    /// k a a^T over the 3 DOFs of each of `nodes` (row-major, 3n x 3n).
    pub fn penalty_matrix(&self, nodes: &[usize], k: f64) -> Vec<f64> {
        let n = 3 * nodes.len();
        let mut a = vec![0.0; n];
        for &(node, dof, c) in &self.terms {
            let at = nodes
                .iter()
                .position(|&m| m == node)
                .expect("node of the constraint");
            a[3 * at + dof] += c;
        }
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                m[i * n + j] = k * a[i] * a[j];
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_penalty_resists_the_constrained_combination_only() {
        // u(3, x) - 0.5 u(7, y) - 0.5 u(7, z) = 0.
        let c = LinearConstraint {
            terms: vec![(3, 0, 1.0), (7, 1, -0.5), (7, 2, -0.5)],
            origin: "test".into(),
        };
        let nodes = c.nodes();
        assert_eq!(nodes, [3, 7]);
        let m = c.penalty_matrix(&nodes, 4.0);
        let energy = |u: [f64; 6]| -> f64 {
            (0..6)
                .map(|i| u[i] * (0..6).map(|j| m[i * 6 + j] * u[j]).sum::<f64>())
                .sum()
        };
        // Satisfied: no energy; violated by 1: k.
        assert!(energy([1.0, 0.0, 0.0, 0.0, 1.0, 1.0]).abs() < 1e-15);
        assert!((energy([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]) - 4.0).abs() < 1e-15);
    }
}
