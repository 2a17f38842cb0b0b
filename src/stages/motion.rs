//! Which components move in a mode: each element block's share of the mode's kinetic energy,
//! psi^H M psi split over the DOFs (sum_i Re(conj(psi_i) (M psi)_i)), a DOF's term given to the
//! blocks of its node (in equal parts where blocks share the node). The shares sum to 1; they
//! name the parts of the brake a mode lives in (the answer's "moving most").
//!
//! Cost: one product with M per mode; computed for the unstable modes only.

use crate::eigen::complex_modes::ComplexModes;
use crate::fem::dofmap::DofMap;
use crate::la::{LaError, Petsc, SparseMatrix, Vector};
use crate::mesh::Mesh;

/// For each node, the blocks whose elements use it.
fn node_blocks(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut of = vec![Vec::new(); mesh.node_count()];
    for (b, block) in mesh.blocks.iter().enumerate() {
        for &n in &block.connectivity {
            if !of[n].contains(&b) {
                of[n].push(b);
            }
        }
    }
    of
}

/// Each block's share of the kinetic energy of the shape (re, im), by block, summing to 1;
/// (name, share) pairs, largest first, blocks without share left out.
///
/// # Collective
pub fn kinetic_shares(
    petsc: &Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    m: &SparseMatrix,
    shape: &(Vector, Vector),
    blocks_of: &[Vec<usize>],
) -> Result<Vec<(String, f64)>, LaError> {
    let mut per_block = vec![0.0; mesh.blocks.len()];
    let owned = dofs.owned_dofs();
    for part in [&shape.0, &shape.1] {
        let mut mx = part.duplicate()?;
        m.mult(part, &mut mx)?;
        let (x, mx) = (part.local()?, mx.local()?);
        for n in dofs.owned_nodes() {
            let blocks = &blocks_of[n];
            if blocks.is_empty() {
                continue;
            }
            let energy: f64 = dofs.node_dofs[n]
                .iter()
                .filter(|&&d| d >= 0)
                .map(|&d| {
                    let i = d as usize - owned.start;
                    x[i] * mx[i]
                })
                .sum();
            let each = energy / blocks.len() as f64;
            for &b in blocks {
                per_block[b] += each;
            }
        }
    }
    crate::parallel::sum_in_place(petsc.world(), &mut per_block);
    let total: f64 = per_block.iter().sum();
    let mut shares: Vec<(String, f64)> = mesh
        .blocks
        .iter()
        .zip(&per_block)
        .map(|(b, &e)| (b.name.clone(), e / total))
        .filter(|(_, s)| *s > 0.0 || s.is_nan())
        .collect();
    shares.sort_by(|a, b| b.1.total_cmp(&a.1));
    Ok(shares)
}

/// Fills `motion` of every unstable mode of each route.
///
/// # Collective
pub fn unstable_mode_motion(
    petsc: &Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    m: &SparseMatrix,
    routes: &mut [ComplexModes],
) -> Result<(), LaError> {
    let blocks_of = node_blocks(mesh);
    for route in routes {
        for (mode, shape) in route.modes.iter_mut().zip(&route.shapes) {
            if mode.unstable {
                mode.motion = kinetic_shares(petsc, mesh, dofs, m, shape, &blocks_of)?;
            }
        }
    }
    Ok(())
}
