//! The PETSc adapter of `fem`'s generic assembly: distributed K and M of a mesh with its
//! Dirichlet constraints eliminated (as dolfinx's fem/petsc; the kernels never see PETSc).

use std::time::Instant;

use super::assembly::{assemble, preallocation, AssemblyError, MatrixSink};
use super::dofmap::{dof_map, DofMap};
use crate::la::{LaError, MatrixFormat, Petsc, SparseMatrix};
use crate::mesh::{Clamp, Mesh};

#[derive(Debug, thiserror::Error)]
pub enum SystemError {
    #[error("constraint: {0}")]
    Constraint(crate::mesh::MeshError),
    #[error("constraint: {0:?} storage needs every node fully free or fully clamped; use AIJ")]
    BlockStorage(MatrixFormat),
    #[error("assembly failed on another rank (see its message)")]
    OtherRank,
    #[error("assembly: {0}")]
    Assembly(#[from] AssemblyError<LaError>),
    #[error(transparent)]
    La(#[from] LaError),
}

/// Assembled stiffness and mass with their DOF map.
pub struct AssembledSystem<'p> {
    pub stiffness: SparseMatrix<'p>,
    pub mass: SparseMatrix<'p>,
    pub dofs: DofMap,
    /// Seconds spent in element kernels + insertion, and in PETSc's final assembly.
    pub seconds: f64,
    pub elements_on_rank: usize,
}

impl AssembledSystem<'_> {
    /// No DOF is constrained: K has rigid-body modes.
    pub fn is_free_free(&self) -> bool {
        self.dofs.global_dofs() == 3 * self.dofs.node_dofs.len()
    }
}

/// Assembles K and M in parallel: each rank computes its own elements; PETSc sends the
/// entries of rows owned elsewhere. Block mode gives SBAIJ (block size 3), else symmetric AIJ.
///
/// # Collective
pub fn assemble_system<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    clamps: &[Clamp],
) -> Result<AssembledSystem<'p>, SystemError> {
    assemble_system_as(petsc, mesh, clamps, None)
}

/// As [`assemble_system`], with a chosen storage format (block formats need every node fully
/// free or fully clamped). LU factorizations want AIJ or BAIJ; Cholesky wants SBAIJ.
///
/// # Collective
pub fn assemble_system_as<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    clamps: &[Clamp],
    format: Option<MatrixFormat>,
) -> Result<AssembledSystem<'p>, SystemError> {
    let start = Instant::now();
    let dofs = dof_map(mesh, clamps, petsc.size() as usize, petsc.rank() as usize)
        .map_err(SystemError::Constraint)?;
    let prealloc = preallocation(mesh, &dofs);
    let format = format.unwrap_or(if dofs.block_mode {
        MatrixFormat::Sbaij
    } else {
        MatrixFormat::Aij
    });
    if format != MatrixFormat::Aij && !dofs.block_mode {
        return Err(SystemError::BlockStorage(format));
    }
    // In block mode the preallocation counts 3x3 blocks, also for AIJ (PETSc expands them).
    let bs = if dofs.block_mode { 3 } else { 1 };
    let mut k = SparseMatrix::new(petsc, format, bs, dofs.local_dofs(), &prealloc)?;
    let mut m = SparseMatrix::new(petsc, format, bs, dofs.local_dofs(), &prealloc)?;
    // A rank-local element failure must not leave the other ranks waiting in assembly.
    let local = assemble(mesh, &dofs, &mut k, &mut m);
    let stats = agreed(petsc, local)?;
    // The constraints' entries as zeros first: the final assembly squeezes out preallocated
    // entries nothing was added to, and their values need K's diagonal.
    if !mesh.constraints.equations.is_empty() {
        let local = super::assembly::assemble_constraints(mesh, &dofs, 0.0, &mut k);
        agreed(petsc, local)?;
    }
    k.assemble()?;
    m.assemble()?;
    if !mesh.constraints.equations.is_empty() {
        add_constraints(petsc, mesh, &dofs, &mut k)?;
    }
    k.set_symmetric(true)?;
    m.set_symmetric(true)?;
    Ok(AssembledSystem {
        stiffness: k,
        mass: m,
        dofs,
        seconds: start.elapsed().as_secs_f64(),
        elements_on_rank: stats.elements,
    })
}

/// A rank-local assembly result agreed on by every rank (a failure on one is an error on all),
/// so that no rank is left waiting in the final assembly.
///
/// # Collective
fn agreed<T, E>(petsc: &Petsc, local: Result<T, E>) -> Result<T, SystemError>
where
    SystemError: From<E>,
{
    let failed = crate::parallel::any_rank(petsc.world(), local.is_err());
    match local {
        Ok(v) if !failed => Ok(v),
        Ok(_) => Err(SystemError::OtherRank),
        Err(e) => Err(e.into()),
    }
}

/// The constraints' penalty into the assembled K: k_p = penalty x the largest diagonal entry
/// of K (`mesh::constraint`).
///
/// # Collective
fn add_constraints(
    petsc: &Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    k: &mut SparseMatrix,
) -> Result<(), SystemError> {
    let mut diagonal = k.new_vector()?;
    k.diagonal(&mut diagonal)?;
    let k_p = mesh.constraints.penalty * diagonal.norm_inf()?;
    let local = super::assembly::assemble_constraints(mesh, dofs, k_p, k);
    agreed(petsc, local)?;
    k.assemble()?;
    Ok(())
}

/// The stiffness of the blocks flagged in `include` alone, on the DOF map and in the storage
/// format of the whole model's (`format`), so that its pattern is a subset of K0's: the part
/// of K0 a change of those blocks' elastic constants scales.
///
/// # Collective
pub fn assemble_block_stiffness<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    include: &[bool],
    format: MatrixFormat,
) -> Result<SparseMatrix<'p>, SystemError> {
    use super::assembly::{assemble_blocks, preallocation_of_blocks, Discard};
    let prealloc = preallocation_of_blocks(mesh, dofs, include);
    let bs = if dofs.block_mode { 3 } else { 1 };
    let mut k = SparseMatrix::new(petsc, format, bs, dofs.local_dofs(), &prealloc)?;
    let local = assemble_blocks(mesh, dofs, include, &mut k, &mut Discard::default());
    agreed(petsc, local)?;
    k.assemble()?;
    k.set_symmetric(true)?;
    Ok(k)
}

impl MatrixSink for SparseMatrix<'_> {
    type Error = LaError;

    /// Element matrices at scalar DOFs; in block mode (block size 3, every node fully free or
    /// fully eliminated) inserted blockwise, which SBAIJ assembles several times faster.
    fn add(&mut self, dofs: &[i32], values: &[f64]) -> Result<(), LaError> {
        if self.block_size() == 3 {
            let blocks: Vec<i32> = dofs
                .chunks(3)
                .map(|d| if d[0] < 0 { -1 } else { d[0] / 3 })
                .collect();
            self.add_blocked(&blocks, &blocks, values)
        } else {
            self.add_values(dofs, dofs, values)
        }
    }
}
