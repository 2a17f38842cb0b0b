//! Hybrid superelement reduction (DESIGN.md §2): q = (q_b, q_c) with q_c every DOF of the
//! elements touching a contact surface, kept as finite elements, and q_b = B eta reduced on
//! B = [Phi_b, q0_b] (real modes of the full tangent model and the static shape, restricted
//! to the b DOFs). T = blockdiag(B, I_c); reduced operators T^T A T.
//!
//! B is made M_bb-orthonormal first (eigen-decomposition of its Gram matrix, directions with a
//! negligible b part dropped), so the modal block of the reduced mass is the identity and the
//! reduced system is as well conditioned as the kept zone. Because the kept block is whole,
//! every full real mode in the basis lies in span(T): the reduced model has those modes
//! exactly (Rayleigh-Ritz with an exact subspace).
//!
//! Numbering of the reduced unknowns: the kept DOFs in full-model order, then the modal
//! coordinates. The operators are first assembled in the "natural" layout (every rank owns its
//! own kept DOFs, the last rank also the modal coordinates) and then redistributed so that
//! every rank holds about the same share of the reduced stiffness's entries: the kept zone is
//! a small part of the model that the full model's partition may leave almost all on one rank
//! (3,355 of 3,421 reduced unknowns on one of 2 ranks at 12k DOF), and the time integration
//! works on the reduced operators only. The reduced operators are distributed AIJ matrices:
//! the kept block sparse as in the full model, the modal block dense, the coupling only in the
//! rows and columns of kept DOFs on the border of the kept zone.

use crate::invalid::InvalidSetting;
use crate::measure::nan_max;
use crate::mesh::MeshError;
use std::ops::Range;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::dofmap::DofMap;
use crate::la::Preallocation;
use crate::la::{lapack, LaError, MatrixFormat, Petsc, SparseMatrix, Vector};
use crate::mesh::Mesh;

/// The `[reduction]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReductionSettings {
    /// Add the static shape q0_b to the real modes.
    #[serde(default = "yes")]
    pub static_shape: bool,
    /// Basis directions whose share of the (normalized) Gram matrix is below this are dropped
    /// (modes living almost only in the kept zone carry no independent b part).
    #[serde(default = "default_drop_tolerance")]
    pub drop_tolerance: f64,
}

fn yes() -> bool {
    true
}
fn default_drop_tolerance() -> f64 {
    1e-10
}

impl Default for ReductionSettings {
    fn default() -> Self {
        ReductionSettings {
            static_shape: true,
            drop_tolerance: default_drop_tolerance(),
        }
    }
}

impl ReductionSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if !(self.drop_tolerance > 0.0 && self.drop_tolerance < 1e-2) {
            return Err(InvalidSetting::new(
                "reduction.drop_tolerance",
                format!(" = {}: must be in (0, 0.01)", self.drop_tolerance),
            ));
        }
        Ok(())
    }
}

/// Which full-model DOFs the reduction keeps: every DOF of every element with a face on one of
/// `surfaces` that touches the contact zone, i.e. has a node whose DOFs a contact point
/// couples (`coupled`, indexed by global DOF; None: the whole surfaces). The disc's friction
/// rings are whole annuli, but the contact points sit under the pads (the disc turns through
/// them in this frame): keeping only the elements under the points keeps the superelement's
/// interface to the size of the contact zone. Indexed by global DOF.
pub fn kept_dofs(
    mesh: &Mesh,
    dofs: &DofMap,
    surfaces: &[&str],
    coupled: Option<&[bool]>,
) -> Result<Vec<bool>, MeshError> {
    let mut kept = vec![false; dofs.global_dofs()];
    let touches = |node: usize| {
        coupled.is_none_or(|c| {
            dofs.node_dofs[node]
                .iter()
                .any(|&d| d >= 0 && c[d as usize])
        })
    };
    for name in surfaces {
        for &(element, _) in mesh.surface(name)? {
            let (block, local) = mesh.locate_element(element);
            let nodes = mesh.blocks[block].element(local);
            if !nodes.iter().any(|&n| touches(n)) {
                continue;
            }
            for &node in nodes {
                for &d in &dofs.node_dofs[node] {
                    if d >= 0 {
                        kept[d as usize] = true;
                    }
                }
            }
        }
    }
    Ok(kept)
}

/// The reduction basis and the numbering of the reduced unknowns.
pub struct Reduction {
    /// Full-model DOF -> reduced index of a kept DOF, or -1 (reduced onto the basis).
    pub map: Vec<i32>,
    /// Kept DOFs (all ranks) and modal coordinates (basis directions kept).
    pub kept: usize,
    pub modal: usize,
    /// Basis vectors offered (modes + static shape) and dropped as dependent.
    pub offered: usize,
    pub dropped: usize,
    /// This rank's reduced unknowns (the balanced layout of the operators and vectors).
    pub columns: Range<usize>,
    /// This rank's reduced unknowns in the natural layout: its own kept DOFs, and on the last
    /// rank the modal coordinates.
    natural: Range<usize>,
    /// Local offsets (in this rank's full DOFs) of its kept and of its reduced DOFs.
    kept_local: Vec<usize>,
    reduced_local: Vec<usize>,
    full_local: usize,
    full_start: usize,
    /// B and M B at this rank's reduced (b) DOFs: reduced_local.len() x modal, column-major.
    basis: Vec<f64>,
    mass_basis: Vec<f64>,
    last_rank: bool,
    /// max |B^T M B - I| after orthonormalization.
    pub orthonormality: f64,
    pub seconds: f64,
}

/// The reduced operators.
pub struct ReducedModel<'p> {
    pub reduction: Reduction,
    pub stiffness: SparseMatrix<'p>,
    pub mass: SparseMatrix<'p>,
}

impl Reduction {
    pub fn size(&self) -> usize {
        self.kept + self.modal
    }

    /// A new full-model vector (this rank's layout).
    pub fn full_vector<'p>(&self, petsc: &'p Petsc) -> Result<Vector<'p>, LaError> {
        Vector::new(petsc, self.full_local)
    }

    /// A new reduced vector (this rank's layout).
    pub fn new_vector<'p>(&self, petsc: &'p Petsc) -> Result<Vector<'p>, LaError> {
        Vector::new(petsc, self.columns.len())
    }

    /// T^T f: the reduced force of a full-model force vector.
    ///
    /// # Collective
    pub fn project_force<'p>(
        &self,
        petsc: &'p Petsc,
        f: &Vector<'p>,
    ) -> Result<Vector<'p>, LaError> {
        let local = f.local()?;
        let fb: Vec<f64> = self.reduced_local.iter().map(|&i| local[i]).collect();
        let mut eta = lapack::gemm_tn(self.reduced_local.len(), self.modal, 1, &self.basis, &fb);
        crate::parallel::sum_in_place(petsc.world(), &mut eta);
        let kept: Vec<f64> = self.kept_local.iter().map(|&i| local[i]).collect();
        drop(local);
        self.assemble_reduced(petsc, &kept, &eta)
    }

    /// The reduced coordinates of a full-model displacement: kept DOFs as they are, and the
    /// M_bb-projection on the basis, eta = B^T M_bb q_b (exact for q in span(T)).
    ///
    /// # Collective
    pub fn restrict<'p>(&self, petsc: &'p Petsc, q: &Vector<'p>) -> Result<Vector<'p>, LaError> {
        let local = q.local()?;
        let qb: Vec<f64> = self.reduced_local.iter().map(|&i| local[i]).collect();
        let mut eta = lapack::gemm_tn(
            self.reduced_local.len(),
            self.modal,
            1,
            &self.mass_basis,
            &qb,
        );
        crate::parallel::sum_in_place(petsc.world(), &mut eta);
        let kept: Vec<f64> = self.kept_local.iter().map(|&i| local[i]).collect();
        drop(local);
        self.assemble_reduced(petsc, &kept, &eta)
    }

    fn assemble_reduced<'p>(
        &self,
        petsc: &'p Petsc,
        kept: &[f64],
        eta: &[f64],
    ) -> Result<Vector<'p>, LaError> {
        let mut x = Vector::new(petsc, self.natural.len())?;
        {
            let mut out = x.local_mut()?;
            out[..kept.len()].copy_from_slice(kept);
            if self.last_rank {
                out[kept.len()..].copy_from_slice(eta);
            }
        }
        relayout(petsc, &x, self.columns.len())
    }

    /// The modal coordinates of a reduced vector, on every rank.
    ///
    /// # Collective
    pub fn modal_coordinates(&self, petsc: &Petsc, x: &Vector) -> Result<Vec<f64>, LaError> {
        let mut eta = vec![0.0; self.modal];
        let local = x.local()?;
        for (i, &v) in local.iter().enumerate() {
            if let Some(j) = (self.columns.start + i).checked_sub(self.kept) {
                eta[j] = v;
            }
        }
        drop(local);
        crate::parallel::sum_in_place(petsc.world(), &mut eta);
        Ok(eta)
    }

    /// Recovery: the full-model field T x of a reduced vector, written into `q`.
    ///
    /// # Collective
    pub fn recover(&self, petsc: &Petsc, x: &Vector, q: &mut Vector) -> Result<(), LaError> {
        let eta = self.modal_coordinates(petsc, x)?;
        let qb = lapack::gemm_nn(self.reduced_local.len(), self.modal, 1, &self.basis, &eta);
        let natural = relayout(petsc, x, self.natural.len())?;
        let xl = natural.local()?;
        let mut out = q.local_mut()?;
        for (k, &i) in self.kept_local.iter().enumerate() {
            out[i] = xl[k];
        }
        for (k, &i) in self.reduced_local.iter().enumerate() {
            out[i] = qb[k];
        }
        Ok(())
    }

    /// The row of T for a full-model DOF this rank owns: (reduced column, value) pairs — the
    /// kept DOF itself, or the basis at that DOF over the modal coordinates.
    pub fn recovery_row(&self, dof: usize) -> Vec<(i32, f64)> {
        if self.map[dof] >= 0 {
            return vec![(self.map[dof], 1.0)];
        }
        let local = dof - self.full_start;
        let nb = self.reduced_local.len();
        match self.reduced_local.binary_search(&local) {
            Ok(k) => (0..self.modal)
                .map(|j| ((self.kept + j) as i32, self.basis[j * nb + k]))
                .collect(),
            Err(_) => Vec::new(),
        }
    }

    /// T^T A T of another operator of the full model (one block's stiffness, say), in the
    /// reduced operators' balanced layout.
    ///
    /// # Collective
    pub fn project_operator<'p>(
        &self,
        petsc: &'p Petsc,
        a: &SparseMatrix<'p>,
    ) -> Result<SparseMatrix<'p>, LaError> {
        let mut work = a.new_vector()?;
        let mut product = work.duplicate()?;
        let a_basis = products(self, a, &mut work, &mut product)?;
        let reduced = reduced_operators(petsc, self, &[(a, &a_basis)])?
            .pop()
            .expect("one operator reduced, one returned");
        reduced.redistributed(petsc, self.columns.clone())
    }

    /// The b rows of `cols` full local columns (column-major).
    fn at_reduced_rows(&self, w: &[f64], cols: usize) -> Vec<f64> {
        let n = self.full_local;
        let mut out = Vec::with_capacity(self.reduced_local.len() * cols);
        for j in 0..cols {
            out.extend(self.reduced_local.iter().map(|&i| w[j * n + i]));
        }
        out
    }

    /// A full-model vector holding basis column j on the b DOFs, zero on the kept ones.
    fn basis_vector(&self, j: usize, out: &mut Vector) -> Result<(), LaError> {
        let n = self.reduced_local.len();
        let mut v = out.local_mut()?;
        v.iter_mut().for_each(|x| *x = 0.0);
        for (k, &i) in self.reduced_local.iter().enumerate() {
            v[i] = self.basis[j * n + k];
        }
        Ok(())
    }
}

/// Builds the reduction of the full model (stiffness `k0`, mass `m`, both AIJ) that keeps the
/// DOFs flagged in `kept` and reduces the rest onto `shapes` (M-normalized real modes of the
/// tangent state) and `static_shapes` (the static state, static shapes of parameters).
///
/// # Collective
pub fn reduce<'p>(
    petsc: &'p Petsc,
    k0: &SparseMatrix<'p>,
    m: &SparseMatrix<'p>,
    kept: &[bool],
    shapes: &[Vector<'p>],
    static_shapes: &[&Vector<'p>],
    settings: &ReductionSettings,
) -> Result<ReducedModel<'p>, LaError> {
    let start = Instant::now();
    let world = petsc.world();
    let own = m.ownership();
    assert_eq!(
        kept.len(),
        m.global_rows(),
        "reduction: one kept flag per DOF"
    );
    // Numbering: kept DOFs in full order; modal coordinates after them on the last rank.
    let mut map = vec![-1i32; kept.len()];
    let mut n_kept = 0usize;
    let mut first_kept = 0usize;
    for (d, &k) in kept.iter().enumerate() {
        if d == own.start {
            first_kept = n_kept;
        }
        if k {
            map[d] = n_kept as i32;
            n_kept += 1;
        }
    }
    let (kept_local, reduced_local): (Vec<usize>, Vec<usize>) =
        (0..own.len()).partition(|&i| kept[own.start + i]);
    let nb = reduced_local.len();
    let last_rank = petsc.rank() == petsc.size() - 1;

    // The raw basis at the b DOFs, each column scaled to unit M_bb norm below.
    let mut work = m.new_vector()?;
    let mut product = work.duplicate()?;
    let mut raw: Vec<&Vector> = shapes.iter().collect();
    raw.extend(static_shapes);
    let offered = raw.len();
    let mut basis = Vec::with_capacity(nb * offered);
    for v in &raw {
        let local = v.local()?;
        basis.extend(reduced_local.iter().map(|&i| local[i]));
    }
    let mut partial = Reduction {
        map,
        kept: n_kept,
        modal: offered,
        offered,
        dropped: 0,
        columns: 0..0,
        natural: 0..0,
        kept_local,
        reduced_local,
        full_local: own.len(),
        full_start: own.start,
        basis,
        mass_basis: Vec::new(),
        last_rank,
        orthonormality: 0.0,
        seconds: 0.0,
    };
    let mass_products = products(&partial, m, &mut work, &mut product)?;
    let mut gram = lapack::gemm_tn(
        nb,
        offered,
        offered,
        &partial.basis,
        &partial.at_reduced_rows(&mass_products, offered),
    );
    crate::parallel::sum_in_place(world, &mut gram);
    // Orthonormalize: scale to unit diagonal, eigen-decompose, keep the directions above the
    // drop tolerance: S = D V_k Lambda_k^-1/2, B <- B S, M B <- (M B) S.
    let largest = (0..offered)
        .map(|j| gram[j * offered + j])
        .fold(0.0, nan_max);
    let scale: Vec<f64> = (0..offered)
        .map(|j| {
            let d = gram[j * offered + j];
            if d > 1e-24 * largest.max(f64::MIN_POSITIVE) {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let mut normalized = gram.clone();
    for i in 0..offered {
        for j in 0..offered {
            normalized[j * offered + i] *= scale[i] * scale[j];
        }
    }
    let (values, vectors) = lapack::eigen_symmetric(offered, normalized)?;
    let top = values.iter().copied().fold(0.0, nan_max);
    let keep: Vec<usize> = (0..offered)
        .filter(|&j| values[j] > settings.drop_tolerance * top)
        .collect();
    let modal = keep.len();
    let mut s = vec![0.0; offered * modal];
    for (c, &j) in keep.iter().enumerate() {
        let f = 1.0 / values[j].sqrt();
        for i in 0..offered {
            s[c * offered + i] = scale[i] * vectors[j * offered + i] * f;
        }
    }
    partial.basis = lapack::gemm_nn(nb, offered, modal, &partial.basis, &s);
    let mass_products = lapack::gemm_nn(partial.full_local, offered, modal, &mass_products, &s);
    partial.modal = modal;
    partial.dropped = offered - modal;
    partial.mass_basis = partial.at_reduced_rows(&mass_products, modal);
    let mut identity = lapack::gemm_tn(nb, modal, modal, &partial.basis, &partial.mass_basis);
    crate::parallel::sum_in_place(world, &mut identity);
    partial.orthonormality = (0..modal * modal)
        .map(|k| (identity[k] - if k % (modal + 1) == 0 { 1.0 } else { 0.0 }).abs())
        .fold(0.0, nan_max);
    let stiffness_products = products(&partial, k0, &mut work, &mut product)?;

    let local_reduced = partial.kept_local.len() + if last_rank { modal } else { 0 };
    partial.natural = first_kept..first_kept + local_reduced;
    let operators = reduced_operators(
        petsc,
        &partial,
        &[(k0, &stiffness_products), (m, &mass_products)],
    )?;
    let [stiffness, mass]: [SparseMatrix<'p>; 2] = operators
        .try_into()
        .unwrap_or_else(|_| unreachable!("two operators reduced, two returned"));
    partial.columns = balanced_rows(petsc, &stiffness, partial.natural.clone())?;
    let stiffness = stiffness.redistributed(petsc, partial.columns.clone())?;
    let mass = mass.redistributed(petsc, partial.columns.clone())?;
    partial.seconds = start.elapsed().as_secs_f64();
    Ok(ReducedModel {
        reduction: partial,
        stiffness,
        mass,
    })
}

/// Extra weight of a row (in stored entries) for the vector work that comes with it.
const ROW_WEIGHT: f64 = 30.0;

/// A contiguous split of the reduced unknowns with about the same stored entries of `a` (plus
/// ROW_WEIGHT per row) on every rank: this rank's range. `a` is in the natural layout.
///
/// # Collective
fn balanced_rows(
    petsc: &Petsc,
    a: &SparseMatrix,
    natural: Range<usize>,
) -> Result<Range<usize>, LaError> {
    let world = petsc.world();
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let mut weights = Vec::with_capacity(natural.len());
    a.for_each_local_row(|_, cols, _| weights.push(cols.len() as f64 + ROW_WEIGHT))?;
    let mut totals = vec![0.0; size];
    totals[rank] = weights.iter().sum();
    crate::parallel::sum_in_place(world, &mut totals);
    let total: f64 = totals.iter().sum();
    let mut at: f64 = totals[..rank].iter().sum();
    // Each row goes to the rank whose share of the total holds the row's middle: monotone in
    // the row number, so every rank's rows stay contiguous.
    let mut counts = vec![0.0; size];
    for w in weights {
        let middle = at + 0.5 * w;
        let target = ((middle / total.max(f64::MIN_POSITIVE)) * size as f64) as usize;
        counts[target.min(size - 1)] += 1.0;
        at += w;
    }
    crate::parallel::sum_in_place(world, &mut counts);
    let start = counts[..rank].iter().sum::<f64>() as usize;
    Ok(start..start + counts[rank] as usize)
}

/// The same global vector with `local` entries on this rank (a contiguous relayout).
///
/// # Collective
fn relayout<'p>(petsc: &'p Petsc, x: &Vector<'p>, local: usize) -> Result<Vector<'p>, LaError> {
    let mut y = Vector::new(petsc, local)?;
    y.set_all(0.0)?;
    let indices: Vec<i32> = x.ownership().map(|i| i as i32).collect();
    y.add_values(&indices, &x.local()?)?;
    y.assemble()?;
    Ok(y)
}

/// A B for every basis column (full local rows x modal, column-major).
fn products(
    r: &Reduction,
    a: &SparseMatrix,
    work: &mut Vector,
    out: &mut Vector,
) -> Result<Vec<f64>, LaError> {
    let mut w = Vec::with_capacity(r.full_local * r.modal);
    for j in 0..r.modal {
        r.basis_vector(j, work)?;
        a.mult(work, out)?;
        w.extend_from_slice(&out.local()?);
    }
    Ok(w)
}

/// T^T A T for each (A, A B) on one shared pattern: the kept block of A (renumbered), the
/// coupling (A B at kept rows, and its transpose), the modal block B^T (A B) symmetrized.
fn reduced_operators<'p>(
    petsc: &'p Petsc,
    r: &Reduction,
    operators: &[(&SparseMatrix<'p>, &Vec<f64>)],
) -> Result<Vec<SparseMatrix<'p>>, LaError> {
    let world = petsc.world();
    let n = r.full_local;
    let nb = r.reduced_local.len();
    let nk = r.kept_local.len();
    let modal_start = r.kept;
    let cols = &r.natural;
    // Coupling pattern: kept rows where any operator's A B is nonzero.
    let coupled: Vec<usize> = (0..nk)
        .filter(|&k| {
            let i = r.kept_local[k];
            operators
                .iter()
                .any(|(_, w)| (0..r.modal).any(|j| w[j * n + i] != 0.0))
        })
        .collect();
    // Kept block rows: the union of the operators' kept columns.
    let mut kept_rows: Vec<Vec<i32>> = vec![Vec::new(); nk];
    let position: std::collections::HashMap<usize, usize> = r
        .kept_local
        .iter()
        .enumerate()
        .map(|(k, &i)| (i, k))
        .collect();
    let full_start = r.full_start;
    for (a, _) in operators {
        a.for_each_local_row(|row, cs, _| {
            if let Some(&k) = row.checked_sub(full_start).and_then(|l| position.get(&l)) {
                kept_rows[k].extend(cs.iter().filter_map(|&c| {
                    let m = r.map[c as usize];
                    (m >= 0).then_some(m)
                }));
            }
        })?;
    }
    for row in &mut kept_rows {
        row.sort_unstable();
        row.dedup();
    }
    // Modal rows: counts of coupled kept columns per modal row, split by owner (the last rank
    // owns the modal rows, so its own kept columns are "diagonal").
    let coupled_count = coupled.len() as f64;
    let mut counts = [coupled_count, 0.0];
    if r.last_rank {
        counts = [0.0, coupled_count];
    }
    crate::parallel::sum_in_place(world, &mut counts);
    let (coupled_off, coupled_diag) = (counts[0] as i32, counts[1] as i32);
    let local_rows = cols.len();
    let mut pre = Preallocation {
        diag: vec![0; local_rows],
        off: vec![0; local_rows],
        diag_upper: vec![0; local_rows],
        off_upper: vec![0; local_rows],
    };
    let is_coupled: Vec<bool> = {
        let mut f = vec![false; nk];
        for &k in &coupled {
            f[k] = true;
        }
        f
    };
    for k in 0..nk {
        let d = kept_rows[k]
            .iter()
            .filter(|&&c| cols.contains(&(c as usize)))
            .count();
        let mut diag = d as i32;
        let mut off = (kept_rows[k].len() - d) as i32;
        if is_coupled[k] {
            if r.last_rank {
                diag += r.modal as i32;
            } else {
                off += r.modal as i32;
            }
        }
        pre.diag[k] = diag;
        pre.off[k] = off;
    }
    if r.last_rank {
        for j in 0..r.modal {
            pre.diag[nk + j] = r.modal as i32 + coupled_diag;
            pre.off[nk + j] = coupled_off;
        }
    }
    pre.diag_upper.clone_from(&pre.diag);
    pre.off_upper.clone_from(&pre.off);

    let mut out = Vec::with_capacity(operators.len());
    for (a, w) in operators {
        let mut reduced = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, local_rows, &pre)?;
        // Explicit zeros make every operator's pattern the shared one.
        let mut failed = Ok(());
        for (k, row) in kept_rows.iter().enumerate() {
            let zeros = vec![0.0; row.len()];
            if failed.is_ok() {
                failed = reduced.add_values(&[(cols.start + k) as i32], row, &zeros);
            }
        }
        failed?;
        let mut failed = Ok(());
        a.for_each_local_row(|row, cs, vs| {
            let Some(&k) = row.checked_sub(full_start).and_then(|l| position.get(&l)) else {
                return;
            };
            let (mut c2, mut v2) = (Vec::new(), Vec::new());
            for (&c, &v) in cs.iter().zip(vs) {
                let m = r.map[c as usize];
                if m >= 0 {
                    c2.push(m);
                    v2.push(v);
                }
            }
            if failed.is_ok() {
                failed = reduced.add_values(&[(cols.start + k) as i32], &c2, &v2);
            }
        })?;
        failed?;
        // Coupling A_cb B and its transpose.
        let modal_cols: Vec<i32> = (0..r.modal).map(|j| (modal_start + j) as i32).collect();
        for &k in &coupled {
            let i = r.kept_local[k];
            let row: Vec<f64> = (0..r.modal).map(|j| w[j * n + i]).collect();
            let g = (cols.start + k) as i32;
            reduced.add_values(&[g], &modal_cols, &row)?;
            reduced.add_values(&modal_cols, &[g], &row)?;
        }
        // Modal block B^T A B, symmetrized (A symmetric; removes round-off asymmetry).
        let wb = r.at_reduced_rows(w, r.modal);
        let mut block = lapack::gemm_tn(nb, r.modal, r.modal, &r.basis, &wb);
        crate::parallel::sum_in_place(world, &mut block);
        if r.last_rank {
            let mut sym = vec![0.0; r.modal * r.modal];
            for i in 0..r.modal {
                for j in 0..r.modal {
                    sym[j * r.modal + i] = 0.5 * (block[j * r.modal + i] + block[i * r.modal + j]);
                }
            }
            // add_values takes row-major values; the symmetric block is its own transpose.
            reduced.add_values(&modal_cols, &modal_cols, &sym)?;
        }
        reduced.assemble()?;
        out.push(reduced);
    }
    Ok(out)
}
