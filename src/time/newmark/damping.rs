//! The damping of the equation of motion: Rayleigh (never assembled), an assembled matrix, and
//! modal damping over a band applied as a force.

use crate::la::{LaError, SparseMatrix, Vector};

/// The damping operator C.
#[derive(Clone, Copy)]
pub enum Damping<'a, 'p> {
    None,
    /// C = alpha M + beta K, never assembled: M a + C v + K q = M (a + alpha v) + K (q + beta v).
    Rayleigh {
        alpha: f64,
        beta: f64,
    },
    Matrix(&'a SparseMatrix<'p>),
}

/// Modal damping over a band: C_m = (M Phi) diag(c) (M Phi)^T for M-orthonormal modes Phi,
/// c_i = 2 zeta omega_i. Low rank and dense, so it is applied as a force (f -= C_m v at every
/// force evaluation) and kept out of J: its share of J, gamma / (beta h) c_i against the mass
/// term 1 / (beta h^2), is gamma h c_i ~ 1e-6 for a 1 us step, zeta = 0.01 and 10 kHz, far
/// below what slows the fixed-Jacobian iterations.
pub struct ModalDamping<'p> {
    mass_shapes: Vec<Vector<'p>>,
    coefficients: Vec<f64>,
}

impl<'p> ModalDamping<'p> {
    /// `mass_shapes`: M phi_i of M-orthonormal modes; `coefficients`: 2 zeta_i omega_i.
    pub fn new(mass_shapes: Vec<Vector<'p>>, coefficients: Vec<f64>) -> Self {
        debug_assert_eq!(mass_shapes.len(), coefficients.len());
        ModalDamping {
            mass_shapes,
            coefficients,
        }
    }

    pub fn modes(&self) -> usize {
        self.coefficients.len()
    }

    /// `f -= C_m v`
    ///
    /// # Collective
    pub fn subtract_force(&self, v: &Vector<'p>, f: &mut Vector<'p>) -> Result<(), LaError> {
        let shapes: Vec<&Vector> = self.mass_shapes.iter().collect();
        let projections = v.mdot(&shapes)?;
        let alphas: Vec<f64> = projections
            .iter()
            .zip(&self.coefficients)
            .map(|(p, c)| -p * c)
            .collect();
        f.maxpy(&alphas, &shapes)
    }
}
