//! An elimination's unknowns b split into independent parts, and the parts shared out over
//! the ranks. Two unknowns of b belong to one part when L_bb couples them or one contact
//! point's rows hold both; the residual's rows of a part then depend on its own unknowns
//! alone (the others held), so each part is a nonlinear system of its own, solved on one
//! rank, and the parts' moves are exactly the whole system's. At 600k the 256 eliminated
//! points' ~1,000 unknowns fall into 2-12 parts, the largest 40-80 % of them (the pads'
//! leading and trailing edges, the two pads apart): every rank solving all of them, as
//! before, did the same work twice on 2 ranks.

use crate::la::local_lu::Csr;

/// The parts of b: each a list of positions in b (ascending), the parts ordered by their
/// first position; and for every point, the part its unknowns in b belong to.
///
/// `linear` is L_bb (positions in b); `point_unknowns[p]` the positions in b of point p's
/// unknowns (every point has at least one).
pub(super) fn split(linear: &Csr, point_unknowns: &[Vec<usize>]) -> (Vec<Vec<usize>>, Vec<usize>) {
    let n = linear.n;
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let join = |parent: &mut Vec<usize>, i: usize, j: usize| {
        let (a, b) = (root(parent, i), root(parent, j));
        if a != b {
            // The smaller position as the root: the parts come out the same whatever the order.
            parent[a.max(b)] = a.min(b);
        }
    };
    for i in 0..n {
        for &j in &linear.columns[linear.row_start[i]..linear.row_start[i + 1]] {
            join(&mut parent, i, j);
        }
    }
    for unknowns in point_unknowns {
        for &j in &unknowns[1..] {
            join(&mut parent, unknowns[0], j);
        }
    }
    let mut part_of_root = vec![usize::MAX; n];
    let mut parts: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let r = root(&mut parent, i);
        if part_of_root[r] == usize::MAX {
            part_of_root[r] = parts.len();
            parts.push(Vec::new());
        }
        parts[part_of_root[r]].push(i);
    }
    let point_part = point_unknowns
        .iter()
        .map(|u| part_of_root[root(&mut parent, u[0])])
        .collect();
    (parts, point_part)
}

/// The block of `a` on the rows and columns `members` (ascending), which no entry of a
/// couples with the rest (a part of [`split`]).
pub(super) fn block(a: &Csr, members: &[usize]) -> Csr {
    let mut local = vec![usize::MAX; a.n];
    for (i, &m) in members.iter().enumerate() {
        local[m] = i;
    }
    let mut out = Csr {
        n: members.len(),
        row_start: Vec::with_capacity(members.len() + 1),
        columns: Vec::new(),
        values: Vec::new(),
    };
    out.row_start.push(0);
    for &m in members {
        for k in a.row_start[m]..a.row_start[m + 1] {
            out.columns.push(local[a.columns[k]]);
            out.values.push(a.values[k]);
        }
        out.row_start.push(out.columns.len());
    }
    out
}

/// The rank that solves each part: `fixed[p]` where given (a part on the same unknowns as
/// one of the last elimination's stays where its factor is), the others the largest first,
/// each to the rank with the least work so far (the lowest rank among equals), the work of a
/// part of m unknowns taken as m^1.5 (a sparse LU under nested dissection on a surface mesh).
/// Every rank computes the same, and which parts keep their factor does not depend on the
/// number of ranks.
pub(super) fn share_out(parts: &[Vec<usize>], ranks: usize, fixed: &[Option<usize>]) -> Vec<usize> {
    let work = |p: &Vec<usize>| (p.len() as f64).powf(1.5);
    let mut load = vec![0.0; ranks.max(1)];
    let mut owner = vec![0; parts.len()];
    for (p, f) in fixed.iter().enumerate() {
        if let Some(rank) = *f {
            owner[p] = rank;
            load[rank] += work(&parts[p]);
        }
    }
    let mut order: Vec<usize> = (0..parts.len()).filter(|&p| fixed[p].is_none()).collect();
    order.sort_by(|&a, &b| parts[b].len().cmp(&parts[a].len()).then(a.cmp(&b)));
    for p in order {
        let (rank, _) = load
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (r, &l)| {
                    if l < best.1 {
                        (r, l)
                    } else {
                        best
                    }
                },
            );
        owner[p] = rank;
        load[rank] += work(&parts[p]);
    }
    owner
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    /// A chain 0-1-2 coupled by the operator, 3-4 by a point, 5 alone.
    #[test]
    fn unknowns_coupled_by_the_operator_or_a_point_share_a_part() {
        let linear = Csr::from_triplets(
            6,
            (0..6)
                .map(|i| (i, i, 4.0))
                .chain([(0, 1, 1.0), (2, 1, -1.0)])
                .collect(),
        );
        let points = vec![vec![3, 4], vec![5]];
        let (parts, point_part) = split(&linear, &points);
        assert_eq!(parts, vec![vec![0, 1, 2], vec![3, 4], vec![5]]);
        assert_eq!(point_part, vec![1, 2]);
        let first = block(&linear, &parts[0]);
        assert_eq!(first.row_start, vec![0, 2, 3, 5]);
        assert_eq!(first.columns, vec![0, 1, 1, 1, 2]);
        assert_eq!(first.values, vec![4.0, 1.0, 4.0, -1.0, 4.0]);
        let second = block(&linear, &parts[1]);
        assert_eq!(
            (second.columns, second.values),
            (vec![0, 1], vec![4.0, 4.0])
        );
    }

    #[test]
    fn parts_are_shared_out_largest_first_to_the_least_loaded_rank() {
        let part = |m: usize| (0..m).collect::<Vec<_>>();
        let parts = vec![part(100), part(460), part(130), part(60), part(40)];
        let free = vec![None; 5];
        let owner = share_out(&parts, 2, &free);
        // 460 alone outweighs the rest (460^1.5 = 9,866 > 1,482 + 1,000 + 465 + 253).
        assert_eq!(owner, vec![1, 0, 1, 1, 1]);
        assert_eq!(share_out(&parts, 1, &free), vec![0; 5]);
        let even = vec![part(50), part(50), part(50), part(50)];
        assert_eq!(share_out(&even, 2, &[None; 4]), vec![0, 1, 0, 1]);
        // The 100 and 60 stay on rank 0 with their factors; the rest balance around them.
        let fixed = [Some(0), None, None, Some(0), None];
        assert_eq!(share_out(&parts, 2, &fixed), vec![0, 1, 0, 0, 0]);
    }
}
