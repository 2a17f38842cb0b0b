//! Generic assembly of element matrices into a sink (a PETSc matrix, or a dense matrix in
//! tests), and the exact sparsity/preallocation of the distributed matrices.

use super::dofmap::DofMap;
use super::element::{ElementKernel, JacobianError};
use crate::la::Preallocation;
use crate::mesh::Mesh;

/// Receives element matrices at global DOFs (negative = eliminated, skipped).
pub trait MatrixSink {
    type Error;
    fn add(&mut self, dofs: &[i32], values: &[f64]) -> Result<(), Self::Error>;
}

#[derive(Debug, thiserror::Error)]
pub enum AssemblyError<E> {
    #[error("block '{block}': {source}")]
    Element {
        block: String,
        #[source]
        source: JacobianError,
    },
    #[error("point element {element} of '{block}': {message}")]
    Point {
        block: String,
        element: usize,
        message: String,
    },
    #[error(transparent)]
    Sink(E),
}

/// A sink that drops what it is given (the mass of an assembly that wants the stiffness only).
pub struct Discard<E>(std::marker::PhantomData<E>);

impl<E> Default for Discard<E> {
    fn default() -> Self {
        Discard(std::marker::PhantomData)
    }
}

impl<E> MatrixSink for Discard<E> {
    type Error = E;
    fn add(&mut self, _: &[i32], _: &[f64]) -> Result<(), E> {
        Ok(())
    }
}

/// Dense row-major sink for small problems and tests.
pub struct DenseSink {
    pub n: usize,
    pub values: Vec<f64>,
}

impl DenseSink {
    pub fn new(n: usize) -> Self {
        DenseSink {
            n,
            values: vec![0.0; n * n],
        }
    }
}

impl MatrixSink for DenseSink {
    type Error = std::convert::Infallible;
    fn add(&mut self, dofs: &[i32], values: &[f64]) -> Result<(), Self::Error> {
        let m = dofs.len();
        for (i, &r) in dofs.iter().enumerate() {
            if r < 0 {
                continue;
            }
            for (j, &c) in dofs.iter().enumerate() {
                if c >= 0 {
                    self.values[r as usize * self.n + c as usize] += values[i * m + j];
                }
            }
        }
        Ok(())
    }
}

/// Counts of what a rank assembled.
#[derive(Debug, Clone, Copy, Default)]
pub struct AssemblyStats {
    pub elements: usize,
}

/// Assembles stiffness and mass of the elements this rank owns into the two sinks: the
/// solid blocks, then the point elements (masses, springs).
pub fn assemble<S: MatrixSink>(
    mesh: &Mesh,
    dofs: &DofMap,
    stiffness: &mut S,
    mass: &mut S,
) -> Result<AssemblyStats, AssemblyError<S::Error>> {
    let mut stats = assemble_blocks(mesh, dofs, &vec![true; mesh.blocks.len()], stiffness, mass)?;
    let (mut x, mut edofs) = (Vec::new(), Vec::new());
    for block in &mesh.point_blocks {
        for e in 0..block.len() {
            let nodes = block.element(e);
            if dofs.element_owner(nodes) != dofs.rank {
                continue;
            }
            mesh.element_coords(nodes, &mut x);
            let (ke, me) = block.matrices(&x).map_err(|message| AssemblyError::Point {
                block: block.name.clone(),
                element: e + 1,
                message,
            })?;
            dofs.element_dofs(nodes, &mut edofs);
            stiffness.add(&edofs, &ke).map_err(AssemblyError::Sink)?;
            mass.add(&edofs, &me).map_err(AssemblyError::Sink)?;
            stats.elements += 1;
        }
    }
    Ok(stats)
}

/// [`assemble`] over the blocks flagged in `include` only (one flag per mesh block).
pub fn assemble_blocks<S: MatrixSink, T: MatrixSink<Error = S::Error>>(
    mesh: &Mesh,
    dofs: &DofMap,
    include: &[bool],
    stiffness: &mut S,
    mass: &mut T,
) -> Result<AssemblyStats, AssemblyError<S::Error>> {
    let mut stats = AssemblyStats::default();
    let mut x = Vec::new();
    let mut edofs = Vec::new();
    let mut offset = 0;
    for (block, &included) in mesh.blocks.iter().zip(include) {
        if !included {
            offset += block.len();
            continue;
        }
        let orientation = block.orientation.map(|o| &mesh.orientations[o]);
        let material = &mesh.materials[block.material];
        let mut kernel = ElementKernel::oriented(block.kind, material, orientation);
        let n = kernel.order();
        let (mut ke, mut me) = (vec![0.0; n * n], vec![0.0; n * n]);
        for e in 0..block.len() {
            let nodes = block.element(e);
            if dofs.element_owner(nodes) != dofs.rank {
                continue;
            }
            mesh.element_coords(nodes, &mut x);
            let err = |source| AssemblyError::Element {
                block: block.name.clone(),
                source: JacobianError {
                    element: offset + e,
                    ..source
                },
            };
            kernel.stiffness(e, &x, &mut ke).map_err(err)?;
            kernel.mass(e, &x, &mut me).map_err(err)?;
            dofs.element_dofs(nodes, &mut edofs);
            stiffness.add(&edofs, &ke).map_err(AssemblyError::Sink)?;
            mass.add(&edofs, &me).map_err(AssemblyError::Sink)?;
            stats.elements += 1;
        }
        offset += block.len();
    }
    Ok(stats)
}

/// Exact preallocation of this rank's rows (per block row in block mode, per row otherwise),
/// the point elements included.
pub fn preallocation(mesh: &Mesh, dofs: &DofMap) -> Preallocation {
    let mut groups: Vec<Vec<usize>> = mesh
        .point_blocks
        .iter()
        .flat_map(|b| (0..b.len()).map(move |e| b.element(e).to_vec()))
        .collect();
    groups.extend(mesh.constraints.equations.iter().map(|c| c.nodes()));
    pattern(
        mesh,
        dofs,
        &vec![true; mesh.blocks.len()],
        groups.iter().map(Vec::as_slice),
    )
}

/// Adds the penalty k_p a a^T of every constraint this rank owns (the owner of its nodes, as
/// for an element) into `stiffness`; `k_p` from the assembled K (`mesh::constraint`).
pub fn assemble_constraints<S: MatrixSink>(
    mesh: &Mesh,
    dofs: &DofMap,
    k_p: f64,
    stiffness: &mut S,
) -> Result<usize, S::Error> {
    let mut edofs = Vec::new();
    let mut added = 0;
    for c in &mesh.constraints.equations {
        let nodes = c.nodes();
        if dofs.element_owner(&nodes) != dofs.rank {
            continue;
        }
        dofs.element_dofs(&nodes, &mut edofs);
        stiffness.add(&edofs, &c.penalty_matrix(&nodes, k_p))?;
        added += 1;
    }
    Ok(added)
}

/// [`preallocation`] of the solid blocks flagged in `include` only.
pub fn preallocation_of_blocks(mesh: &Mesh, dofs: &DofMap, include: &[bool]) -> Preallocation {
    pattern(mesh, dofs, include, std::iter::empty())
}

/// The preallocation of the included blocks' elements and of `extra` node groups (each one
/// couples all its nodes).
fn pattern<'a>(
    mesh: &'a Mesh,
    dofs: &DofMap,
    include: &[bool],
    extra: impl Iterator<Item = &'a [usize]>,
) -> Preallocation {
    let owned = dofs.owned_nodes();
    let start = owned.start;
    // Neighbour nodes of each owned node, through the elements it belongs to.
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); owned.len()];
    let solids = mesh
        .blocks
        .iter()
        .zip(include)
        .filter(|(_, &i)| i)
        .flat_map(|(b, _)| (0..b.len()).map(move |e| b.element(e)));
    for nodes in solids.chain(extra) {
        for &n in nodes {
            if owned.contains(&n) {
                neighbours[n - start].extend(nodes.iter().map(|&m| m as u32));
            }
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    let own_dofs = dofs.owned_dofs();
    let mut p = Preallocation::default();
    // One preallocation row: its columns split by owner, and the upper-triangle part.
    let mut push_row = |row: i32, cols: &mut dyn Iterator<Item = i32>| {
        let (mut d, mut o, mut du, mut ou) = (0, 0, 0, 0);
        for col in cols {
            let local = own_dofs.contains(&(col as usize));
            let upper = col >= row;
            match (local, upper) {
                (true, true) => (d, du) = (d + 1, du + 1),
                (true, false) => d += 1,
                (false, true) => (o, ou) = (o + 1, ou + 1),
                (false, false) => o += 1,
            }
        }
        p.diag.push(d);
        p.off.push(o);
        p.diag_upper.push(du);
        p.off_upper.push(ou);
    };
    for (i, list) in neighbours.iter().enumerate() {
        let row_dofs = dofs.node_dofs[start + i];
        if dofs.block_mode {
            // Block rows and columns: a node's first DOF stands for its block.
            if row_dofs[0] >= 0 {
                let mut cols = list
                    .iter()
                    .map(|&m| dofs.node_dofs[m as usize][0])
                    .filter(|&c| c >= 0);
                push_row(row_dofs[0], &mut cols);
            }
        } else {
            for &row in row_dofs.iter().filter(|&&r| r >= 0) {
                let mut cols = list
                    .iter()
                    .flat_map(|&m| dofs.node_dofs[m as usize])
                    .filter(|&c| c >= 0);
                push_row(row, &mut cols);
            }
        }
    }
    p
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml)
mod tests {
    use super::*;
    use crate::mesh::material::Material;
    use crate::mesh::point::{PointBlock, PointKind};
    use crate::mesh::structured::block;
    use crate::mesh::ElementKind;

    /// A rigid translation's kinetic energy counts the solid's mass and the point mass once
    /// each; a spring to ground adds its stiffness to the translation along its DOF.
    #[test]
    fn point_masses_and_springs_add_once_to_m_and_k() {
        let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
        let mut mesh = block([0.2, 0.04, 0.02], [2, 1, 1], ElementKind::Hex8, steel);
        mesh.point_blocks = vec![
            PointBlock {
                name: "m".into(),
                kind: PointKind::Mass,
                value: 0.3,
                connectivity: vec![3],
            },
            PointBlock {
                name: "k".into(),
                kind: PointKind::Grounded { dof: 1 },
                value: 1e6,
                connectivity: vec![5],
            },
        ];
        let dofs = crate::fem::dofmap::dof_map(&mesh, &[], 1, 0).unwrap();
        let n = dofs.global_dofs();
        let (mut k, mut m) = (DenseSink::new(n), DenseSink::new(n));
        assemble(&mesh, &dofs, &mut k, &mut m).unwrap();
        let quadratic = |a: &DenseSink, dir: usize| -> f64 {
            let u: Vec<f64> = (0..n)
                .map(|i| if i % 3 == dir { 1.0 } else { 0.0 })
                .collect();
            (0..n)
                .map(|i| u[i] * (0..n).map(|j| a.values[i * n + j] * u[j]).sum::<f64>())
                .sum()
        };
        let solid = 0.2 * 0.04 * 0.02 * 7850.0;
        for dir in 0..3 {
            let mass = quadratic(&m, dir);
            assert!((mass - solid - 0.3).abs() < 1e-12, "{dir}: {mass}");
        }
        assert!(
            (quadratic(&k, 1) - 1e6).abs() < 1e-4,
            "{}",
            quadratic(&k, 1)
        );
        assert!(quadratic(&k, 0).abs() < 1e-3, "{}", quadratic(&k, 0));
    }
}
