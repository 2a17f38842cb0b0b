//! The nonlinear elimination's local Jacobian L_bb + T_bb (eliminate.rs) on a pattern built
//! once per set of unknowns b: where L_bb's entries and every coupling point's tangent block
//! land in it, so that each new local Jacobian on the same b is summed straight into its
//! values (no triplets, no sorting) and refactored numerically.

use crate::contact::kernel::{Channel, PointRows};
use crate::la::local_lu::{Csr, RowMarker};

/// The local Jacobian's pattern on one set of unknowns, and where each term goes in it.
pub(super) struct LocalPattern {
    /// The pattern (its values unused).
    pub jacobian: Csr,
    /// For every entry of L_bb (in its order), its position in the pattern.
    linear_slots: Vec<usize>,
    /// For every coupling point, its entries' positions in the pattern.
    point_slots: Vec<PointSlots>,
}

/// Where one point's tangent block lands in the local Jacobian.
struct PointSlots {
    /// The point's rows' DOFs (their indices in its rows) that are in b, m of them.
    in_b: Vec<usize>,
    /// Row-major m x m: the position in the pattern of (in_b[i], in_b[j]).
    slots: Vec<usize>,
}

/// Work buffers of [`LocalPattern::add_point`], reused from point to point.
#[derive(Default)]
pub(super) struct BlockScratch {
    w: Vec<f64>,
    row: Vec<f64>,
}

/// The observation channels by their index (`Channel as usize`).
const CHANNELS: [Channel; 4] = [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv];

impl LocalPattern {
    /// The pattern of L_bb (`linear`, n x n) plus every point's (row, column) pairs in b,
    /// `at[p][i]` being the position in b of point p's i-th DOF (None: held), whatever the
    /// values (a point's tangent fills different entries as it opens, sticks or slips; the
    /// pattern holds them all). Row by row with a marker: the ~200 pairs per unknown (~24
    /// DOFs per point, ~18 of them in b) are not sorted.
    pub fn new(n: usize, at: &[Vec<Option<usize>>], linear: &Csr) -> LocalPattern {
        let mut point_slots: Vec<PointSlots> = at
            .iter()
            .map(|at| {
                let in_b: Vec<usize> = (0..at.len()).filter(|&i| at[i].is_some()).collect();
                let m = in_b.len();
                PointSlots {
                    in_b,
                    slots: vec![0; m * m],
                }
            })
            .collect();
        // For every unknown of b, the (point, index in the point's in_b) pairs in its row.
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for (p, (at, point)) in at.iter().zip(&point_slots).enumerate() {
            for (ii, &li) in point.in_b.iter().enumerate() {
                rows_of[at[li].expect("in b")].push((p, ii));
            }
        }
        let mut linear_slots = vec![0; linear.values.len()];
        let mut jacobian = Csr {
            n,
            row_start: vec![0; n + 1],
            columns: Vec::with_capacity(linear.values.len() * 2),
            values: Vec::new(),
        };
        let mut marker = RowMarker::new(n);
        for i in 0..n {
            let linear_row = linear.row_start[i]..linear.row_start[i + 1];
            let point_columns = rows_of[i]
                .iter()
                .flat_map(|&(p, _)| at[p].iter().flatten().copied());
            let row = linear.columns[linear_row.clone()].iter().copied();
            marker.push_row(row.chain(point_columns), &mut jacobian.columns);
            for k in linear_row {
                linear_slots[k] = marker.slot(linear.columns[k]);
            }
            for &(p, ii) in &rows_of[i] {
                let point = &mut point_slots[p];
                let m = point.in_b.len();
                for (jj, &lj) in point.in_b.iter().enumerate() {
                    point.slots[ii * m + jj] = marker.slot(at[p][lj].expect("in b"));
                }
            }
            marker.clear(&jacobian.columns);
            jacobian.row_start[i + 1] = jacobian.columns.len();
        }
        jacobian.values = vec![0.0; jacobian.columns.len()];
        LocalPattern {
            jacobian,
            linear_slots,
            point_slots,
        }
    }

    /// L_bb's values (on the pattern `linear` had in [`LocalPattern::new`]) in this pattern.
    pub fn linear_values(&self, linear: &Csr) -> Vec<f64> {
        let mut values = vec![0.0; self.jacobian.values.len()];
        for (&slot, &v) in self.linear_slots.iter().zip(&linear.values) {
            values[slot] += v;
        }
        values
    }

    /// Adds point p's block, the sum of its rank-one terms `coef c_a c_b^T` over its
    /// observation rows `rows`, on the rows and columns in b. Grouped by the row channel a
    /// (w_a = sum over the terms of coef c_b, on the columns in b), every entry is one
    /// scattered add instead of one per term.
    pub fn add_point(
        &self,
        p: usize,
        rows: &PointRows,
        terms: &[(f64, Channel, Channel)],
        values: &mut [f64],
        scratch: &mut BlockScratch,
    ) {
        let point = &self.point_slots[p];
        let m = point.in_b.len();
        let BlockScratch { w, row } = scratch;
        w.clear();
        w.resize(CHANNELS.len() * m, 0.0);
        let mut used = [false; CHANNELS.len()];
        for &(coef, a, b) in terms {
            let column = rows.row(b);
            let wa = &mut w[a as usize * m..(a as usize + 1) * m];
            for (x, &lj) in wa.iter_mut().zip(&point.in_b) {
                *x += coef * column[lj];
            }
            used[a as usize] = true;
        }
        for (ii, &li) in point.in_b.iter().enumerate() {
            row.clear();
            row.resize(m, 0.0);
            for c in (0..CHANNELS.len()).filter(|&c| used[c]) {
                let ci = rows.row(CHANNELS[c])[li];
                if ci != 0.0 {
                    for (x, &wc) in row.iter_mut().zip(&w[c * m..(c + 1) * m]) {
                        *x += ci * wc;
                    }
                }
            }
            for (&slot, &x) in point.slots[ii * m..(ii + 1) * m].iter().zip(row.iter()) {
                values[slot] += x;
            }
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    /// A small generator of reproducible numbers in [-0.5, 0.5).
    struct Numbers(u64);
    impl Numbers {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
        fn below(&mut self, n: usize) -> usize {
            ((self.next() + 0.5) * n as f64) as usize % n
        }
    }

    /// The local Jacobian summed on the pattern equals, entry for entry, the same terms
    /// assembled the plain way: every point's dense k x k block sum_terms coef c_a c_b^T,
    /// its entries on b pushed as triplets beside L_bb's and summed by `Csr::from_triplets`.
    #[test]
    fn pattern_sum_equals_the_triplet_assembly_of_the_dense_blocks() {
        let mut rnd = Numbers(7);
        let (n, k, points) = (40, 8, 30);
        // L_bb: a diagonal and a few random entries.
        let mut linear_triplets: Vec<(usize, usize, f64)> = (0..n).map(|i| (i, i, 10.0)).collect();
        for _ in 0..60 {
            linear_triplets.push((rnd.below(n), rnd.below(n), rnd.next()));
        }
        let linear = Csr::from_triplets(n, linear_triplets.clone());
        // Points over k DOFs, about two thirds of them in b, with four observation rows
        // (some entries exactly zero, as where a row does not see a DOF).
        let mut at = Vec::new();
        let mut rows = Vec::new();
        let mut terms = Vec::new();
        for _ in 0..points {
            at.push(
                (0..k)
                    .map(|_| (rnd.next() < 0.17).then(|| rnd.below(n)))
                    .collect::<Vec<_>>(),
            );
            let mut row = || -> Vec<f64> {
                (0..k)
                    .map(|_| if rnd.next() < -0.3 { 0.0 } else { rnd.next() })
                    .collect()
            };
            rows.push(PointRows {
                dofs: vec![0; k],
                nor: row(),
                tan: row(),
                tan2: row(),
                conv: row(),
            });
            let channel = |x: usize| CHANNELS[x % 4];
            terms.push(
                (0..5)
                    .map(|_| (rnd.next(), channel(rnd.below(3)), channel(rnd.below(4))))
                    .collect::<Vec<_>>(),
            );
        }
        let pattern = LocalPattern::new(n, &at, &linear);
        let mut values = pattern.linear_values(&linear);
        let mut scratch = BlockScratch::default();
        for p in 0..points {
            pattern.add_point(p, &rows[p], &terms[p], &mut values, &mut scratch);
        }
        let mut triplets = linear_triplets;
        for p in 0..points {
            for i in 0..k {
                for j in 0..k {
                    let (Some(pi), Some(pj)) = (at[p][i], at[p][j]) else {
                        continue;
                    };
                    let v: f64 = terms[p]
                        .iter()
                        .map(|&(c, a, b)| c * rows[p].row(a)[i] * rows[p].row(b)[j])
                        .sum();
                    triplets.push((pi, pj, v));
                }
            }
        }
        let reference = Csr::from_triplets(n, triplets);
        assert_eq!(pattern.jacobian.row_start, reference.row_start);
        assert_eq!(pattern.jacobian.columns, reference.columns);
        let scale = crate::measure::largest_abs(&reference.values);
        for (got, want) in values.iter().zip(&reference.values) {
            // Sums of at most ~200 products of numbers below 10 in another order.
            assert!(
                (got - want).abs() <= 1e-13 * scale,
                "entry {got} against {want}"
            );
        }
    }
}
