//! The lining's stiffness in the noise matrix: a point's lining factor e turns K0 into
//! K0 + (e - 1) K_l, K_l the lining blocks' part of K0.

use super::RunError;
use crate::la::{Petsc, SparseMatrix};
use crate::matrix::MatrixSettings;

/// The lining blocks' stiffness K_l on the models a point uses, and the point's K0 + (e - 1)
/// K_l (e the point's lining factor) in a matrix whose pattern holds both.
pub(super) struct LiningParts<'p> {
    /// Phi^T K_l Phi on the projection basis.
    pub projected: Vec<f64>,
    pub full: LiningOperator<'p>,
    pub reduced: Option<LiningOperator<'p>>,
}

pub(super) struct LiningOperator<'p> {
    lining: SparseMatrix<'p>,
    /// K0 + (e - 1) K_l of the last point (pattern: the union of K0's and K_l's).
    point: SparseMatrix<'p>,
}

impl<'p> LiningOperator<'p> {
    /// # Collective
    pub fn new(k0: &SparseMatrix<'p>, lining: SparseMatrix<'p>) -> Result<Self, RunError> {
        let mut point = lining.try_clone()?;
        point.axpy(1.0, k0)?;
        Ok(LiningOperator { lining, point })
    }

    /// K0 + (e - 1) K_l, in `self.point`.
    ///
    /// # Collective
    pub fn at(&mut self, k0: &SparseMatrix<'p>, e: f64) -> Result<&SparseMatrix<'p>, RunError> {
        self.point.zero_entries()?;
        self.point.axpy_subset(1.0, k0)?;
        self.point.axpy_subset(e - 1.0, &self.lining)?;
        Ok(&self.point)
    }
}

/// The lining blocks' part of K0 (`matrix.lining_blocks`), in K0's `format`: what a lining
/// stiffness factor e turns K0 into, K0 + (e - 1) K_l.
///
/// # Collective
pub fn lining_stiffness<'p>(
    petsc: &'p Petsc,
    settings: &MatrixSettings,
    model: &super::model::Model,
    dofs: &crate::fem::dofmap::DofMap,
    format: crate::la::MatrixFormat,
) -> Result<SparseMatrix<'p>, RunError> {
    let blocks = &model.mesh.blocks;
    let mut include = vec![false; blocks.len()];
    for name in settings.lining_block_names() {
        match blocks.iter().position(|b| b.name == name) {
            Some(i) => include[i] = true,
            None => {
                let known: Vec<&str> = blocks.iter().map(|b| b.name.as_str()).collect();
                let message = format!(
                    ": no block '{name}' in the mesh (its blocks: {}); name the lining's blocks in matrix.lining_blocks",
                    known.join(", ")
                );
                return Err(RunError::scene("matrix.lining_blocks", message));
            }
        }
    }
    let mesh = &model.mesh;
    let k_l = crate::fem::petsc::assemble_block_stiffness(petsc, mesh, dofs, &include, format)?;
    Ok(k_l)
}
