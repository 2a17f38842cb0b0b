//! Partitioning by recursive coordinate bisection. Ranks own contiguous, balanced ranges of
//! nodes (`fem::dofmap`), so the partition is a node numbering: nodes are ordered by
//! recursive bisection at the median of the longest extent, down to small leaves. Any
//! contiguous range of that order is then a compact region, for every rank count; and the
//! numbering does not depend on the rank count, so 1 and 2 ranks assemble the same matrices.

use std::collections::BTreeMap;

use super::Mesh;

/// Leaves of the bisection tree: this many nodes or fewer keep their input order.
const LEAF: usize = 32;

/// The recursive-bisection order of `coords`: `order[new] = old`.
pub fn bisection_order(coords: &[[f64; 3]]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..coords.len()).collect();
    bisect(coords, &mut order);
    order
}

fn bisect(coords: &[[f64; 3]], nodes: &mut [usize]) {
    if nodes.len() <= LEAF {
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &n in nodes.iter() {
        for d in 0..3 {
            lo[d] = lo[d].min(coords[n][d]);
            hi[d] = hi[d].max(coords[n][d]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = nodes.len() / 2;
    // Ties (many nodes share a coordinate in structured meshes) are broken by node index,
    // so the order is deterministic.
    nodes.select_nth_unstable_by(mid, |&a, &b| {
        coords[a][axis].total_cmp(&coords[b][axis]).then(a.cmp(&b))
    });
    let (left, right) = nodes.split_at_mut(mid);
    bisect(coords, left);
    bisect(coords, right);
}

/// Renumbers the nodes of a mesh: node `order[new]` becomes `new`. Node sets stay sorted.
pub fn renumber(mesh: &mut Mesh, order: &[usize]) {
    assert_eq!(order.len(), mesh.node_count());
    let mut new_of = vec![usize::MAX; order.len()];
    for (new, &old) in order.iter().enumerate() {
        new_of[old] = new;
    }
    mesh.coords = order.iter().map(|&old| mesh.coords[old]).collect();
    for block in &mut mesh.blocks {
        for n in &mut block.connectivity {
            *n = new_of[*n];
        }
    }
    for points in &mut mesh.point_blocks {
        for n in &mut points.connectivity {
            *n = new_of[*n];
        }
    }
    for c in &mut mesh.constraints.equations {
        for t in &mut c.terms {
            t.0 = new_of[t.0];
        }
    }
    let sets: BTreeMap<String, Vec<usize>> = std::mem::take(&mut mesh.node_sets)
        .into_iter()
        .map(|(name, nodes)| {
            let mut renumbered: Vec<usize> = nodes.iter().map(|&n| new_of[n]).collect();
            renumbered.sort_unstable();
            (name, renumbered)
        })
        .collect();
    mesh.node_sets = sets;
}

/// Load balance of a distribution: (max / mean) of per-rank counts; 1 is perfect.
pub fn imbalance(per_rank: &[usize]) -> f64 {
    let total: usize = per_rank.iter().sum();
    if total == 0 {
        return 1.0;
    }
    let mean = total as f64 / per_rank.len() as f64;
    *per_rank.iter().max().unwrap_or(&0) as f64 / mean
}

/// Connected parts of a mesh (nodes linked by elements): the part of every node.
pub fn connected_parts(mesh: &Mesh) -> (usize, Vec<usize>) {
    let n = mesh.node_count();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    // Springs between two nodes and constraints join parts too.
    let solids = mesh
        .blocks
        .iter()
        .flat_map(|b| (0..b.len()).map(move |e| b.element(e)));
    let points = mesh
        .point_blocks
        .iter()
        .flat_map(|b| (0..b.len()).map(move |e| b.element(e)));
    let tied: Vec<Vec<usize>> = mesh
        .constraints
        .equations
        .iter()
        .map(|c| c.nodes())
        .collect();
    for nodes in solids.chain(points).chain(tied.iter().map(Vec::as_slice)) {
        let r0 = find(&mut parent, nodes[0]);
        for &m in &nodes[1..] {
            let r = find(&mut parent, m);
            if r != r0 {
                parent[r] = r0;
            }
        }
    }
    let mut id = vec![usize::MAX; n];
    let mut part = vec![0; n];
    let mut count = 0;
    for a in 0..n {
        let r = find(&mut parent, a);
        if id[r] == usize::MAX {
            id[r] = count;
            count += 1;
        }
        part[a] = id[r];
    }
    (count, part)
}

/// Names of the blocks of every connected part that the constraints do not hold against all
/// six rigid-body motions (fewer than three fully fixed nodes, which is what a statically
/// determinate support needs at least): such parts give zero eigenvalues of K.
pub fn unsupported_parts(mesh: &Mesh, fixed: &[[bool; 3]]) -> Vec<String> {
    let (count, part) = connected_parts(mesh);
    let mut held = vec![0usize; count];
    for (node, f) in fixed.iter().enumerate() {
        if f.iter().all(|&c| c) {
            held[part[node]] += 1;
        }
    }
    let mut names: Vec<String> = Vec::new();
    for block in &mesh.blocks {
        if let Some(&first) = block.connectivity.first() {
            if held[part[first]] < 3 && !names.contains(&block.name) {
                names.push(block.name.clone());
            }
        }
    }
    names
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::measure::nan_max;
    use crate::mesh::material::Material;
    use crate::mesh::structured::block;
    use crate::mesh::ElementKind;

    #[test]
    fn halves_of_the_order_are_the_halves_of_a_bar() {
        let steel = Material::isotropic("steel", 210e9, 0.3, 7850.0);
        let mut mesh = block([8.0, 1.0, 1.0], [32, 2, 2], ElementKind::Hex8, steel);
        let order = bisection_order(&mesh.coords);
        renumber(&mut mesh, &order);
        let n = mesh.node_count();
        let max_x_first_half = mesh.coords[..n / 2].iter().map(|x| x[0]).fold(0.0, nan_max);
        assert!(max_x_first_half <= 4.0 + 1e-12, "{max_x_first_half}");
        // Node sets follow their nodes.
        for &i in &mesh.node_sets["u0"] {
            assert_eq!(mesh.coords[i][0], 0.0);
        }
        let (parts, _) = connected_parts(&mesh);
        assert_eq!(parts, 1);
        assert!((imbalance(&[5, 5]) - 1.0).abs() < 1e-15);
        assert!((imbalance(&[6, 4]) - 1.2).abs() < 1e-15);
    }
}
