//! DOF numbering with Dirichlet constraints eliminated, and the row distribution over ranks.
//!
//! Free DOFs are numbered node by node, so each rank owns a contiguous range of nodes and of
//! DOFs. When every node is either fully free or fully fixed, DOF = 3 x block + component and
//! the matrices are assembled blockwise (block size 3, SBAIJ); otherwise scalar (AIJ).

use crate::mesh::MeshError;

/// Global DOF numbers per node (-1 where eliminated) and the ownership ranges.
#[derive(Debug, Clone)]
pub struct DofMap {
    pub node_dofs: Vec<[i32; 3]>,
    /// Nodes [node_ranges[r], node_ranges[r+1]) belong to rank r.
    pub node_ranges: Vec<usize>,
    /// DOFs [dof_ranges[r], dof_ranges[r+1]) belong to rank r.
    pub dof_ranges: Vec<usize>,
    pub block_mode: bool,
    pub rank: usize,
}

impl DofMap {
    /// `fixed[n][c]` is true when component c of node n is constrained to zero.
    pub fn new(fixed: &[[bool; 3]], ranks: usize, rank: usize) -> Self {
        let n = fixed.len();
        let block_mode = fixed
            .iter()
            .all(|f| f.iter().all(|&x| x) || f.iter().all(|&x| !x));
        let free_per_node: Vec<usize> = fixed
            .iter()
            .map(|f| f.iter().filter(|&&x| !x).count())
            .collect();
        let total: usize = free_per_node.iter().sum();
        // Balanced contiguous node ranges by free-DOF count.
        let mut node_ranges = vec![0usize; ranks + 1];
        let mut acc = 0usize;
        let mut r = 1;
        for (node, f) in free_per_node.iter().enumerate() {
            acc += f;
            while r < ranks && acc * ranks >= r * total && acc > 0 {
                node_ranges[r] = node + 1;
                r += 1;
            }
        }
        while r <= ranks {
            node_ranges[r] = n;
            r += 1;
        }
        node_ranges[ranks] = n;
        let mut node_dofs = vec![[-1i32; 3]; n];
        let mut next = 0i32;
        for (node, f) in fixed.iter().enumerate() {
            for c in 0..3 {
                if !f[c] {
                    node_dofs[node][c] = next;
                    next += 1;
                }
            }
        }
        let dof_ranges = node_ranges
            .iter()
            .map(|&nr| free_per_node[..nr].iter().sum())
            .collect();
        DofMap {
            node_dofs,
            node_ranges,
            dof_ranges,
            block_mode,
            rank,
        }
    }

    pub fn global_dofs(&self) -> usize {
        *self.dof_ranges.last().unwrap()
    }

    pub fn local_dofs(&self) -> usize {
        self.dof_ranges[self.rank + 1] - self.dof_ranges[self.rank]
    }

    pub fn owned_nodes(&self) -> std::ops::Range<usize> {
        self.node_ranges[self.rank]..self.node_ranges[self.rank + 1]
    }

    pub fn owned_dofs(&self) -> std::ops::Range<usize> {
        self.dof_ranges[self.rank]..self.dof_ranges[self.rank + 1]
    }

    pub fn owner_of_node(&self, node: usize) -> usize {
        self.node_ranges.partition_point(|&start| start <= node) - 1
    }

    /// The rank that assembles an element: the owner of its lowest-numbered node.
    pub fn element_owner(&self, nodes: &[usize]) -> usize {
        self.owner_of_node(*nodes.iter().min().expect("element with nodes"))
    }

    /// DOFs of an element's nodes, 3 per node (-1 where eliminated).
    pub fn element_dofs(&self, nodes: &[usize], out: &mut Vec<i32>) {
        out.clear();
        for &n in nodes {
            out.extend_from_slice(&self.node_dofs[n]);
        }
    }

    /// Expands this rank's part of a DOF vector into a nodal field over its owned nodes
    /// (3 values per node, zero where constrained).
    pub fn to_nodal(&self, local: &[f64]) -> Vec<[f64; 3]> {
        let first = self.dof_ranges[self.rank] as i32;
        self.owned_nodes()
            .map(|n| {
                self.node_dofs[n].map(|d| {
                    if d < 0 {
                        0.0
                    } else {
                        local[(d - first) as usize]
                    }
                })
            })
            .collect()
    }
}

/// The DOF map of a mesh with the given clamps on `ranks` ranks; the error names the node set.
pub fn dof_map(
    mesh: &crate::mesh::Mesh,
    clamps: &[crate::mesh::Clamp],
    ranks: usize,
    rank: usize,
) -> Result<DofMap, MeshError> {
    let mut fixed = vec![[false; 3]; mesh.node_count()];
    for clamp in clamps {
        let set = mesh.node_set(&clamp.node_set)?;
        if set.is_empty() {
            return Err(MeshError::EmptyClamp(clamp.node_set.clone()));
        }
        for &n in set {
            for c in 0..3 {
                fixed[n][c] |= clamp.components[c];
            }
        }
    }
    Ok(DofMap::new(&fixed, ranks, rank))
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn ranges_are_balanced_and_cover_all_dofs() {
        let mut fixed = vec![[false; 3]; 101];
        fixed[0] = [true; 3];
        fixed[50] = [true, false, true];
        for ranks in 1..5 {
            let maps: Vec<DofMap> = (0..ranks).map(|r| DofMap::new(&fixed, ranks, r)).collect();
            let total: usize = maps.iter().map(DofMap::local_dofs).sum();
            assert_eq!(total, 3 * 101 - 5);
            assert!(!maps[0].block_mode);
            let sizes: Vec<usize> = maps.iter().map(DofMap::local_dofs).collect();
            let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            // Cuts fall between nodes: each side can be off by up to one node (3 DOF).
            assert!(hi - lo <= 6, "{sizes:?}");
        }
    }
}
