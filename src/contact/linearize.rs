//! Linearization of the contact forces at a state (DESIGN.md §2): the tangent parts (normal
//! stiffness, sticking, sliding friction, friction damping) assembled into a matrix on the
//! pattern of K0 joined with the contact couplings, or applied as an operator through the
//! observation rows.

use std::cell::RefCell;
use std::collections::HashMap;

use super::kernel::{self, Channel, Part};
use super::{ContactModel, ContactState};
use crate::la::Preallocation;
use crate::la::{
    BlockAddPlan, ColumnKey, Dominant, LaError, MatrixFormat, Petsc, SparseMatrix, TangentChange,
    Vector,
};

/// What a linearized matrix starts from: a base operator plus the tangent, or only the
/// tangent on the base's pattern (to be combined with matrices of that pattern later).
#[derive(Clone, Copy)]
pub enum Base<'a, 'p> {
    Plus(&'a SparseMatrix<'p>),
    PatternOf(&'a SparseMatrix<'p>),
}

/// A contact tangent sum_points sum_terms coef c_a c_b^T applied as C_a^T diag(coef) C_b x
/// (see [`ContactModel::tangent_operator`]).
pub struct TangentOperator<'c, 'p> {
    contact: &'c ContactModel<'p>,
    world: &'c mpi::topology::SimpleCommunicator,
    /// (a, b, coefficient per local point), sorted by a then b, the same pairs on every rank.
    blocks: Vec<(Channel, Channel, Vec<f64>)>,
    /// C_b x per channel, and the weighted point vector of one channel a.
    work: RefCell<([Vector<'p>; 4], Vector<'p>)>,
}

impl<'p> crate::la::Operator<'p> for TangentOperator<'_, 'p> {
    fn mult_add(&self, x: &Vector<'p>, y: &mut Vector<'p>) -> Result<(), LaError> {
        let mut work = self.work.borrow_mut();
        let (observed, weighted) = &mut *work;
        for b in [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv] {
            if self.blocks.iter().any(|t| t.1 == b) {
                self.contact
                    .observation(b)
                    .mult(x, &mut observed[b as usize])?;
            }
        }
        for a in [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv] {
            if !self.blocks.iter().any(|t| t.0 == a) {
                continue;
            }
            {
                let mut w = weighted.local_mut()?;
                w.iter_mut().for_each(|x| *x = 0.0);
                for (_, b, coef) in self.blocks.iter().filter(|t| t.0 == a) {
                    let o = observed[*b as usize].local()?;
                    for ((w, c), o) in w.iter_mut().zip(coef).zip(o.iter()) {
                        *w += c * o;
                    }
                }
            }
            self.contact
                .observation(a)
                .mult_transpose_add(weighted, y)?;
        }
        Ok(())
    }
}

/// A ranked point's record: its row, the squared norm of its block, the block's 16 entries.
const RECORD: usize = 18;

impl TangentOperator<'_, '_> {
    /// Point p's 4 x 4 channel block D_p, row-major.
    fn block(&self, k: usize) -> [f64; 16] {
        let mut d = [0.0; 16];
        for (a, b, coef) in &self.blocks {
            d[4 * *a as usize + *b as usize] = coef[k];
        }
        d
    }

    /// The records of the points with the largest squared norm of D_p over all ranks, at
    /// most `max_points`, largest first (ties by row), stopping once they hold `fraction`
    /// of the total; the same on every rank. None: no change anywhere.
    ///
    /// # Collective
    fn ranked(&self, max_points: usize, fraction: f64) -> Result<Option<Vec<f64>>, LaError> {
        let contact = self.contact;
        let mut local: Vec<(f64, usize)> = (0..contact.local.len())
            .map(|k| (self.block(k).iter().map(|x| x * x).sum::<f64>(), k))
            .collect();
        let total = local.iter().map(|x| x.0).sum::<f64>();
        let by_norm = |x: &(f64, usize), y: &(f64, usize)| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1));
        if local.len() > max_points {
            if max_points > 0 {
                local.select_nth_unstable_by(max_points - 1, by_norm);
            }
            local.truncate(max_points);
        }
        local.sort_unstable_by(by_norm);
        // Every rank's candidates in its own slot of one buffer, summed over the ranks.
        use mpi::topology::Communicator;
        let (ranks, rank) = (self.world.size() as usize, self.world.rank() as usize);
        let mut records = vec![0.0; ranks * max_points * RECORD];
        for (slot, &(norm2, k)) in local.iter().enumerate() {
            let r = &mut records[(rank * max_points + slot) * RECORD..][..RECORD];
            r[0] = (contact.first_row + k) as f64;
            r[1] = norm2;
            r[2..].copy_from_slice(&self.block(k));
        }
        crate::parallel::sum_in_place(self.world, &mut records);
        let total = crate::parallel::sum(self.world, total);
        if !(total > 0.0 && total.is_finite()) {
            return Ok(None);
        }
        let mut candidates: Vec<&[f64]> = records.chunks(RECORD).filter(|r| r[1] > 0.0).collect();
        candidates.sort_by(|x, y| y[1].total_cmp(&x[1]).then(x[0].total_cmp(&y[0])));
        let mut held = 0.0;
        let mut chosen = Vec::new();
        for r in candidates.into_iter().take(max_points) {
            if fraction < 1.0 && held >= fraction * total {
                break;
            }
            held += r[1];
            chosen.extend_from_slice(r);
        }
        Ok(Some(chosen))
    }
}

/// Explicit columns of the change for the preconditioner's low-rank update: a point's 4 x 4
/// channel block D_p (rows a, columns b: the coefficient of O_a^T e_p e_p^T O_b), its
/// columns O_a^T e_p.
impl<'p> TangentChange<'p> for TangentOperator<'_, 'p> {
    /// The points with the largest Frobenius norm of D_p (all of them for a fraction of 1).
    fn dominant(&self, max_points: usize, fraction: f64) -> Result<Option<Dominant>, LaError> {
        let Some(chosen) = self.ranked(max_points, fraction)? else {
            return Ok(None);
        };
        // Per point, the channels its block touches.
        let mut keys = Vec::new();
        let mut entries = Vec::new();
        for r in chosen.chunks(RECORD) {
            let d = &r[2..];
            for a in 0..4 {
                if (0..4).any(|b| d[4 * a + b] != 0.0 || d[4 * b + a] != 0.0) {
                    keys.push((r[0] as usize, a as u8));
                    entries.push(d);
                }
            }
        }
        let s = keys.len();
        let mut d = vec![0.0; s * s];
        for i in 0..s {
            for j in 0..s {
                if keys[i].0 == keys[j].0 {
                    d[i * s + j] = entries[i][4 * keys[i].1 as usize + keys[j].1 as usize];
                }
            }
        }
        Ok(Some(Dominant { keys, d }))
    }

    /// The ranked points' rows alone (no coupling block: at 256 points of ~4 channels it
    /// is 1,024^2 entries, most of an elimination's ranking time).
    fn dominant_points(&self, max_points: usize) -> Result<Option<Vec<usize>>, LaError> {
        Ok(self
            .ranked(max_points, 1.0)?
            .map(|chosen| chosen.chunks(RECORD).map(|r| r[0] as usize).collect()))
    }

    fn column(&self, key: ColumnKey, out: &mut Vector<'p>) -> Result<(), LaError> {
        let contact = self.contact;
        let channel = [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv]
            .get(key.1 as usize)
            .copied()
            .expect("a column key names one of the four channels");
        let mut e = contact.c_nor.new_point_vector()?;
        if let Some(k) = key.0.checked_sub(contact.first_row) {
            if k < contact.local.len() {
                e.local_mut()?[k] = 1.0;
            }
        }
        out.set_all(0.0)?;
        contact.observation(channel).mult_transpose_add(&e, out)
    }
}

impl<'p> ContactModel<'p> {
    /// Adds the chosen tangent parts of this rank's points to `matrix` (entries of other
    /// ranks' rows travel at assembly; call `assemble` after).
    pub fn add_tangent(
        &self,
        state: &ContactState,
        parts: &[Part],
        matrix: &mut SparseMatrix,
    ) -> Result<(), LaError> {
        self.add_tangent_terms(state, &[(parts, 1.0)], matrix)
    }

    /// As [`add_tangent`](Self::add_tangent) with each `(parts, scale)` adding `scale` times
    /// those parts.
    pub fn add_tangent_terms(
        &self,
        state: &ContactState,
        terms: &[(&[Part], f64)],
        matrix: &mut SparseMatrix,
    ) -> Result<(), LaError> {
        let mut dense = Vec::new();
        for (k, rows) in self.rows.iter().enumerate() {
            let n = rows.dofs.len();
            dense.clear();
            dense.resize(n * n, 0.0);
            self.point_tangent(k, state, terms, &mut dense);
            matrix.add_values(&rows.dofs, &rows.dofs, &dense)?;
        }
        Ok(())
    }

    /// A plan for [`add_tangent_planned`](Self::add_tangent_planned) into `matrix` (None when
    /// its pattern lacks a point's couplings: use `add_tangent`).
    ///
    /// # Collective
    pub fn tangent_plan(&self, matrix: &SparseMatrix) -> Result<Option<BlockAddPlan>, LaError> {
        BlockAddPlan::new(matrix, &self.point_dofs())
    }

    /// Whether `plan` is of `matrix` and these points, on every rank.
    ///
    /// # Collective
    pub fn tangent_plan_fits(
        &self,
        plan: &BlockAddPlan,
        matrix: &SparseMatrix,
    ) -> Result<bool, LaError> {
        plan.fits_everywhere(matrix, &self.point_dofs())
    }

    /// As [`add_tangent`](Self::add_tangent) followed by the assembly, through a plan of
    /// where every entry lands (no sort of other ranks' entries; see [`BlockAddPlan`]).
    ///
    /// # Collective
    pub fn add_tangent_planned(
        &self,
        state: &ContactState,
        parts: &[Part],
        matrix: &mut SparseMatrix,
        plan: &mut BlockAddPlan,
    ) -> Result<(), LaError> {
        self.add_tangent_terms_planned(state, &[(parts, 1.0)], matrix, plan)
    }

    /// As [`add_tangent_planned`](Self::add_tangent_planned) with each `(parts, scale)` adding
    /// `scale` times those parts (the transient's Jacobian: the friction damping through
    /// gamma / (beta h)).
    ///
    /// # Collective
    pub fn add_tangent_terms_planned(
        &self,
        state: &ContactState,
        terms: &[(&[Part], f64)],
        matrix: &mut SparseMatrix,
        plan: &mut BlockAddPlan,
    ) -> Result<(), LaError> {
        plan.add(matrix, &self.point_dofs(), |k, dense| {
            self.point_tangent(k, state, terms, dense)
        })
    }

    fn point_dofs(&self) -> Vec<&[i32]> {
        self.rows.iter().map(|r| r.dofs.as_slice()).collect()
    }

    /// Local point k's tangent added to `dense` (its DOFs' square, row-major): each `(parts,
    /// scale)` adds `scale` times those parts (the tangent is linear in the point's weight).
    fn point_tangent(
        &self,
        k: usize,
        state: &ContactState,
        terms: &[(&[Part], f64)],
        dense: &mut [f64],
    ) {
        let id = self.local[k];
        let sliding = self.interfaces[self.points[id].interface]
            .friction
            .is_sliding();
        let omega = if sliding { self.disc_speed } else { 0.0 };
        for &(parts, scale) in terms {
            for &part in parts {
                kernel::add_tangent(
                    &self.rows[k],
                    scale * self.points[id].weight,
                    omega,
                    &state.response[k],
                    part,
                    dense,
                );
            }
        }
    }

    /// The rank-one terms of every local point's tangent `parts` (see
    /// [`kernel::tangent_terms`]), in local point order.
    pub fn tangent_terms(
        &self,
        state: &ContactState,
        parts: &[Part],
    ) -> Vec<Vec<(f64, Channel, Channel)>> {
        self.local
            .iter()
            .enumerate()
            .map(|(k, &id)| {
                let point = &self.points[id];
                let sliding = self.interfaces[point.interface].friction.is_sliding();
                let omega = if sliding { self.disc_speed } else { 0.0 };
                parts
                    .iter()
                    .flat_map(|&part| {
                        kernel::tangent_terms(point.weight, omega, &state.response[k], part)
                    })
                    .collect()
            })
            .collect()
    }

    /// The chosen tangent parts at `state` as an operator applied through the observation
    /// rows, without assembling it: each `(parts, scale)` adds `scale` times those parts.
    /// Applying it costs four observation products and three transposed ones; an assembled
    /// contact tangent has |point DOFs|^2 entries per point.
    ///
    /// # Collective
    pub fn tangent_operator<'c>(
        &'c self,
        petsc: &'c Petsc,
        state: &ContactState,
        parts: &[(&[Part], f64)],
    ) -> Result<TangentOperator<'c, 'p>, LaError> {
        let terms: Vec<_> = parts.iter().map(|&(p, scale)| (state, p, scale)).collect();
        self.tangent_operator_of(petsc, &terms)
    }

    /// [`Self::tangent_operator`] of a combination of states' tangents, e.g. the change of the
    /// tangent between two states (scales 1 and -1) in one operator: one set of products with
    /// the observation rows instead of one per state.
    ///
    /// # Collective
    pub fn tangent_operator_of<'c>(
        &'c self,
        petsc: &'c Petsc,
        parts: &[(&ContactState, &[Part], f64)],
    ) -> Result<TangentOperator<'c, 'p>, LaError> {
        let n = self.local.len();
        // One coefficient column per (a, b) channel pair that occurs on any rank, found by
        // its slot 4 a + b; the terms of a point appended to one reused buffer (an operator
        // is built per elimination: a Vec per point and a search per term were most of it).
        let mut blocks: Vec<(Channel, Channel, Vec<f64>)> = Vec::new();
        let mut slot_of = [usize::MAX; 16];
        let mut terms = Vec::with_capacity(16);
        for &(state, part_list, scale) in parts {
            for (k, &id) in self.local.iter().enumerate() {
                let point = &self.points[id];
                let sliding = self.interfaces[point.interface].friction.is_sliding();
                let omega = if sliding { self.disc_speed } else { 0.0 };
                terms.clear();
                for &part in part_list {
                    let response = &state.response[k];
                    kernel::push_tangent_terms(
                        point.weight,
                        omega,
                        response,
                        part,
                        1.0,
                        &mut terms,
                    );
                }
                for &(coef, a, b) in &terms {
                    let slot = &mut slot_of[4 * a as usize + b as usize];
                    if *slot == usize::MAX {
                        *slot = blocks.len();
                        blocks.push((a, b, vec![0.0; n]));
                    }
                    blocks[*slot].2[k] += scale * coef;
                }
            }
        }
        // Every rank takes part in the same products (they are collective).
        let mut present = [0.0; 16];
        for (a, b, _) in &blocks {
            present[4 * *a as usize + *b as usize] = 1.0;
        }
        crate::parallel::max_in_place(petsc.world(), &mut present);
        for a in [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv] {
            for b in [Channel::Nor, Channel::Tan, Channel::Tan2, Channel::Conv] {
                let missing = !blocks.iter().any(|x| x.0 == a && x.1 == b);
                if present[4 * a as usize + b as usize] > 0.0 && missing {
                    blocks.push((a, b, vec![0.0; n]));
                }
            }
        }
        blocks.sort_by_key(|x| (x.0 as usize, x.1 as usize));
        let work = [
            self.c_nor.new_point_vector()?,
            self.c_nor.new_point_vector()?,
            self.c_nor.new_point_vector()?,
            self.c_nor.new_point_vector()?,
        ];
        let weighted = self.c_nor.new_point_vector()?;
        Ok(TangentOperator {
            contact: self,
            world: petsc.world(),
            blocks,
            work: RefCell::new((work, weighted)),
        })
    }
    /// Preallocation of a matrix with the pattern of `base` (if any) joined with every
    /// contact point's coupling.
    ///
    /// # Collective (when `base` is given)
    pub fn pattern(&self, base: Option<&SparseMatrix>) -> Result<Preallocation, LaError> {
        let own = self.columns.clone();
        let mut extra: HashMap<usize, Vec<i32>> = HashMap::new();
        let mut d = Vec::new();
        for cols in &self.point_columns {
            d.clear();
            d.extend(cols.iter().copied().filter(|&x| x >= 0));
            for &r in &d {
                if own.contains(&(r as usize)) {
                    extra
                        .entry(r as usize - own.start)
                        .or_default()
                        .extend_from_slice(&d);
                }
            }
        }
        let n = own.len();
        let mut pre = Preallocation {
            diag: vec![0; n],
            off: vec![0; n],
            diag_upper: vec![0; n],
            off_upper: vec![0; n],
        };
        let mut count = |row: usize, cols: &mut Vec<i32>| {
            cols.sort_unstable();
            cols.dedup();
            let dg = cols
                .iter()
                .filter(|&&c| own.contains(&(c as usize)))
                .count();
            pre.diag[row] = dg as i32;
            pre.off[row] = (cols.len() - dg) as i32;
            pre.diag_upper[row] = pre.diag[row];
            pre.off_upper[row] = pre.off[row];
        };
        match base {
            Some(b) => {
                b.for_each_local_row(|row, cols, _| {
                    let local = row - own.start;
                    let mut all = cols.to_vec();
                    if let Some(e) = extra.get(&local) {
                        all.extend_from_slice(e);
                    }
                    count(local, &mut all);
                })?;
            }
            None => {
                for (row, cols) in extra.iter_mut() {
                    count(*row, cols);
                }
            }
        }
        Ok(pre)
    }

    /// A new assembled AIJ matrix with the values of `base` on the pattern of `base` joined
    /// with every contact coupling (explicit zeros there), ready for `copy_values_from(base)`
    /// and `add_tangent` again and again.
    ///
    /// # Collective
    pub fn joined_matrix(
        &self,
        petsc: &'p Petsc,
        base: &SparseMatrix,
    ) -> Result<SparseMatrix<'p>, LaError> {
        let pre = self.pattern(Some(base))?;
        let mut m = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, self.columns.len(), &pre)?;
        let mut failed = Ok(());
        base.for_each_local_row(|row, cols, vals| {
            if failed.is_ok() {
                failed = m.add_values(&[row as i32], cols, vals);
            }
        })?;
        failed?;
        // Every later tangent adds within these blocks: keep this assembly's messages.
        m.fix_off_rank_pattern()?;
        for rows in &self.rows {
            let zeros = vec![0.0; rows.dofs.len() * rows.dofs.len()];
            m.add_values(&rows.dofs, &rows.dofs, &zeros)?;
        }
        m.assemble()?;
        Ok(m)
    }

    /// A new AIJ matrix holding only the given contact tangent parts at `state`.
    ///
    /// # Collective
    pub fn tangent_matrix(
        &self,
        petsc: &'p Petsc,
        state: &ContactState,
        parts: &[Part],
    ) -> Result<SparseMatrix<'p>, LaError> {
        let pre = self.pattern(None)?;
        let mut m = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, self.columns.len(), &pre)?;
        self.add_tangent(state, parts, &mut m)?;
        m.assemble()?;
        Ok(m)
    }

    /// The base (K0, or any operator on its rows) joined with the contact couplings, plus the
    /// chosen tangent parts at `state`, assembled: the one recipe behind every contact
    /// tangent (real modes, complex modes, reduction check, the transient's Jacobian).
    ///
    /// # Collective
    pub fn linearize(
        &self,
        petsc: &'p Petsc,
        base: Base<'_, 'p>,
        state: &ContactState,
        parts: &[Part],
    ) -> Result<SparseMatrix<'p>, LaError> {
        let mut m = match base {
            Base::Plus(b) => self.joined_matrix(petsc, b)?,
            Base::PatternOf(b) => {
                let mut m = self.joined_matrix(petsc, b)?;
                m.zero_entries()?;
                m
            }
        };
        self.add_tangent(state, parts, &mut m)?;
        m.assemble()?;
        Ok(m)
    }
}
