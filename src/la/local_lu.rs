//! A sparse LU of a small matrix this process holds whole: PETSc's sequential AIJ on
//! MPI_COMM_SELF and PETSc's own LU under a nested-dissection ordering. For a nonlinear
//! elimination's local Jacobian (`time::transient`'s eliminate.rs): 4-6 unknowns per contact
//! point, coupled as the contact surface's mesh couples them, where a dense LU's cost grows
//! as the cube of the points (256 points of the 600k brake, 1,088 unknowns: 0.86 GFLOP per
//! dense factorization; sparse, 79,489 entries).
//!
//! No pivoting beyond the diagonal (PETSc's LU): for matrices whose diagonal dominates, such
//! as M / (beta h^2) + c1 C + K plus a contact tangent. A zero pivot is reported
//! ([`LocalLu::new`] returns `None`), never a silent result: the caller then needs a pivoted
//! (dense) LU.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::{cconst, report_destroy, Petsc};

/// A square sparse matrix in compressed rows, columns ascending within a row.
#[derive(Debug, Clone, PartialEq)]
pub struct Csr {
    pub n: usize,
    /// Row i's entries are `columns[row_start[i]..row_start[i + 1]]`.
    pub row_start: Vec<usize>,
    pub columns: Vec<usize>,
    pub values: Vec<f64>,
}

impl Csr {
    /// From (row, column, value) triplets in any order, duplicates summed in the triplets'
    /// order. Bucketed by row first, then each row's distinct columns sorted: one sort of all
    /// the triplets by (row, column) took a third of the 600k brake's eliminated iterations
    /// (perf; ~150,000 triplets per local Jacobian at 256 points).
    pub fn from_triplets(n: usize, triplets: Vec<(usize, usize, f64)>) -> Csr {
        Csr::from_triplets_with_slots(n, triplets).0
    }

    /// [`Csr::from_triplets`], and for every triplet the position of its entry in `values`:
    /// triplets of the same (row, column) sequence then assemble by `values[slot] += value`,
    /// without sorting again.
    pub fn from_triplets_with_slots(
        n: usize,
        triplets: Vec<(usize, usize, f64)>,
    ) -> (Csr, Vec<usize>) {
        let mut start = vec![0usize; n + 1];
        for &(i, _, _) in &triplets {
            start[i + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut next = start.clone();
        let mut bucketed = vec![(0usize, 0.0f64, 0usize); triplets.len()];
        for (t, (i, j, v)) in triplets.into_iter().enumerate() {
            bucketed[next[i]] = (j, v, t);
            next[i] += 1;
        }
        let mut slots = vec![0usize; bucketed.len()];
        let mut out = Csr {
            n,
            row_start: vec![0; n + 1],
            columns: Vec::with_capacity(bucketed.len()),
            values: Vec::with_capacity(bucketed.len()),
        };
        // Each row's distinct columns found with a marker (a row of a local Jacobian holds
        // ~10 triplets per distinct entry), only those sorted; duplicates summed in the
        // triplets' order.
        let mut marker = RowMarker::new(n);
        for i in 0..n {
            let row = &bucketed[start[i]..start[i + 1]];
            marker.push_row(row.iter().map(|&(j, _, _)| j), &mut out.columns);
            out.values.resize(out.columns.len(), 0.0);
            for &(j, v, t) in row {
                out.values[marker.slot(j)] += v;
                slots[t] = marker.slot(j);
            }
            marker.clear(&out.columns);
            out.row_start[i + 1] = out.columns.len();
        }
        (out, slots)
    }

    /// The entries as triplets (for a sum of several matrices).
    pub fn triplets(&self, scale: f64) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.n).flat_map(move |i| {
            (self.row_start[i]..self.row_start[i + 1])
                .map(move |k| (i, self.columns[k], scale * self.values[k]))
        })
    }

    /// y += A x.
    pub fn mult_add(&self, x: &[f64], y: &mut [f64]) {
        for (i, y) in y.iter_mut().enumerate().take(self.n) {
            let range = self.row_start[i]..self.row_start[i + 1];
            *y += self.columns[range.clone()]
                .iter()
                .zip(&self.values[range])
                .map(|(&j, a)| a * x[j])
                .sum::<f64>();
        }
    }

    /// The matrix dense, column-major (LAPACK's layout).
    pub fn dense_columns(&self) -> Vec<f64> {
        let mut a = vec![0.0; self.n * self.n];
        for (i, j, v) in self.triplets(1.0) {
            a[j * self.n + i] += v;
        }
        a
    }
}

/// One row of a compressed-row pattern at a time: its distinct columns, found with a marker
/// over all columns (no sort of the repeated ones), appended sorted to the pattern's columns,
/// and each one's position there.
pub(crate) struct RowMarker {
    slot_of: Vec<usize>,
    first: usize,
}

impl RowMarker {
    const UNSEEN: usize = usize::MAX;

    pub fn new(n: usize) -> RowMarker {
        RowMarker {
            slot_of: vec![Self::UNSEEN; n],
            first: 0,
        }
    }

    /// Appends the distinct values of `row` (columns below n, repeats allowed), sorted, to
    /// `columns`.
    pub fn push_row(&mut self, row: impl Iterator<Item = usize>, columns: &mut Vec<usize>) {
        self.first = columns.len();
        for j in row {
            if self.slot_of[j] == Self::UNSEEN {
                self.slot_of[j] = self.first;
                columns.push(j);
            }
        }
        columns[self.first..].sort_unstable();
        for (offset, &j) in columns[self.first..].iter().enumerate() {
            self.slot_of[j] = self.first + offset;
        }
    }

    /// The position in `columns` of column j of the last row pushed.
    pub fn slot(&self, j: usize) -> usize {
        self.slot_of[j]
    }

    /// Unmarks the last row pushed (`columns` as `push_row` left it).
    pub fn clear(&mut self, columns: &[usize]) {
        for &j in &columns[self.first..] {
            self.slot_of[j] = Self::UNSEEN;
        }
    }
}

/// The LU factors of a [`Csr`] matrix on this process, for solves; renewed for new values in
/// the same pattern by the numerical phase alone ([`LocalLu::refactor`]).
pub struct LocalLu<'p> {
    n: usize,
    matrix: ffi::Mat,
    factor: ffi::Mat,
    rhs: ffi::Vec,
    solution: ffi::Vec,
    entries: f64,
    /// The matrix's compressed rows, which PETSc uses in place (MatCreateSeqAIJWithArrays)
    /// until the matrix is destroyed: kept here, never reallocated.
    _row_start: Vec<ffi::PetscInt>,
    _columns: Vec<ffi::PetscInt>,
    values: Vec<f64>,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> LocalLu<'p> {
    /// Factors `a`; `None` when the LU meets a zero pivot, numerically or for want of a diagonal
    /// entry in the pattern (the matrix needs pivoting). Errs on
    /// non-finite entries or a failed PETSc call. Not collective (MPI_COMM_SELF).
    pub fn new(_petsc: &'p Petsc, a: &Csr) -> Result<Option<Self>> {
        check_finite(&a.values)?;
        let n = a.n;
        let has_diagonal = |i: usize| {
            a.columns[a.row_start[i]..a.row_start[i + 1]]
                .binary_search(&i)
                .is_ok()
        };
        if !(0..n).all(has_diagonal) {
            // A structurally zero pivot (PETSc's LU would refuse the pattern).
            return Ok(None);
        }
        let ni = n as ffi::PetscInt;
        // SAFETY: MPI_COMM_SELF is a valid communicator for the whole run.
        let comm_self = unsafe { ffi::mpi_sys::RSMPI_COMM_SELF };
        let mut lu = LocalLu {
            n,
            matrix: std::ptr::null_mut(),
            factor: std::ptr::null_mut(),
            rhs: std::ptr::null_mut(),
            solution: std::ptr::null_mut(),
            entries: 0.0,
            _row_start: a.row_start.iter().map(|&k| k as ffi::PetscInt).collect(),
            _columns: a.columns.iter().map(|&j| j as ffi::PetscInt).collect(),
            values: a.values.clone(),
            _petsc: PhantomData,
        };
        call!(MatCreateSeqAIJWithArrays(
            comm_self,
            ni,
            ni,
            lu._row_start.as_mut_ptr(),
            lu._columns.as_mut_ptr(),
            lu.values.as_mut_ptr(),
            &mut lu.matrix
        ))?;
        call!(VecCreateSeq(comm_self, ni, &mut lu.rhs))?;
        call!(VecCreateSeq(comm_self, ni, &mut lu.solution))?;
        if n == 0 {
            return Ok(Some(lu));
        }
        let (mut rows, mut columns) = (std::ptr::null_mut(), std::ptr::null_mut());
        call!(MatGetOrdering(
            lu.matrix,
            cconst(ffi::MATORDERINGND),
            &mut rows,
            &mut columns
        ))?;
        let factored = lu.factorize(rows, columns);
        report_destroy(call!(ISDestroy(&mut rows)));
        report_destroy(call!(ISDestroy(&mut columns)));
        Ok(factored?.then_some(lu))
    }

    /// The symbolic and numerical LU under the given ordering; false at a zero pivot.
    fn factorize(&mut self, rows: ffi::IS, columns: ffi::IS) -> Result<bool> {
        call!(MatGetFactor(
            self.matrix,
            cconst(ffi::MATSOLVERPETSC),
            ffi::MAT_FACTOR_LU,
            &mut self.factor
        ))?;
        call!(MatLUFactorSymbolic(
            self.factor,
            self.matrix,
            rows,
            columns,
            &factor_info()?
        ))?;
        self.numeric()
    }

    /// The numerical LU of the matrix's current values; false at a zero pivot.
    fn numeric(&mut self) -> Result<bool> {
        call!(MatLUFactorNumeric(
            self.factor,
            self.matrix,
            &factor_info()?
        ))?;
        let mut error: ffi::MatFactorError = ffi::MAT_FACTOR_NOERROR;
        call!(MatFactorGetError(self.factor, &mut error))?;
        if error != ffi::MAT_FACTOR_NOERROR {
            return Ok(false);
        }
        // SAFETY: MatInfo is plain numbers (PetscLogDouble); all zeros is a valid value.
        let mut stored: ffi::MatInfo = unsafe { std::mem::zeroed() };
        call!(MatGetInfo(self.factor, ffi::MAT_LOCAL, &mut stored))?;
        self.entries = stored.nz_used;
        Ok(true)
    }

    /// The stored entries of the factored matrix (its pattern's length).
    pub fn pattern_len(&self) -> usize {
        self.values.len()
    }

    /// Factors the matrix of the same pattern with new `values` (in the [`Csr`] order of the
    /// matrix given to [`LocalLu::new`]): the ordering and the symbolic factorization are kept,
    /// only the numerical phase runs. False at a zero pivot: the factor is then unusable (drop
    /// it). Errs on non-finite values, a wrong length or a failed PETSc call.
    pub fn refactor(&mut self, values: &[f64]) -> Result<bool> {
        if values.len() != self.values.len() {
            return Err(LaError::Invalid(format!(
                "local sparse LU refactor: {} values for a pattern of {}",
                values.len(),
                self.values.len()
            )));
        }
        check_finite(values)?;
        if self.n == 0 {
            return Ok(true);
        }
        let mut data = std::ptr::null_mut();
        // Through Get/RestoreArray, so PETSc knows the values changed.
        call!(MatSeqAIJGetArray(self.matrix, &mut data))?;
        // SAFETY: the matrix stores exactly `values.len()` entries (its pattern) until
        // MatSeqAIJRestoreArray; they are `self.values`' storage.
        unsafe { std::slice::from_raw_parts_mut(data, values.len()) }.copy_from_slice(values);
        call!(MatSeqAIJRestoreArray(self.matrix, &mut data))?;
        self.numeric()
    }

    /// The factor's stored entries (L and U).
    pub fn factor_entries(&self) -> f64 {
        self.entries
    }

    /// Solves A x = b in place (b of length n). Not collective.
    pub fn solve(&self, b: &mut [f64]) -> Result<()> {
        if b.len() != self.n {
            return Err(LaError::Invalid(format!(
                "local sparse LU solve: {} entries for order {}",
                b.len(),
                self.n
            )));
        }
        if self.n == 0 {
            return Ok(());
        }
        self.copy(self.rhs, b, true)?;
        call!(MatSolve(self.factor, self.rhs, self.solution))?;
        self.copy(self.solution, b, false)
    }

    /// `values` into the sequential vector `v` (`into`), or out of it.
    fn copy(&self, v: ffi::Vec, values: &mut [f64], into: bool) -> Result<()> {
        let mut data = std::ptr::null_mut();
        call!(VecGetArray(v, &mut data))?;
        // SAFETY: the sequential vector holds n entries until VecRestoreArray.
        let whole = unsafe { std::slice::from_raw_parts_mut(data, self.n) };
        if into {
            whole.copy_from_slice(values);
        } else {
            values.copy_from_slice(whole);
        }
        call!(VecRestoreArray(v, &mut data))
    }
}

fn check_finite(values: &[f64]) -> Result<()> {
    if values.iter().any(|v| !v.is_finite()) {
        return Err(LaError::Invalid(
            "local sparse LU: the matrix has NaN or infinite entries".into(),
        ));
    }
    Ok(())
}

/// PETSc's default factorization controls.
fn factor_info() -> Result<ffi::MatFactorInfo> {
    // SAFETY: MatFactorInfo is plain numbers; MatFactorInfoInitialize sets them all.
    let mut info: ffi::MatFactorInfo = unsafe { std::mem::zeroed() };
    call!(MatFactorInfoInitialize(&mut info))?;
    Ok(info)
}

impl Drop for LocalLu<'_> {
    fn drop(&mut self) {
        for m in [&mut self.factor, &mut self.matrix] {
            if !m.is_null() {
                report_destroy(call!(MatDestroy(m)));
            }
        }
        for v in [&mut self.rhs, &mut self.solution] {
            if !v.is_null() {
                report_destroy(call!(VecDestroy(v)));
            }
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn triplets_are_summed_and_sorted_into_rows() {
        let a = Csr::from_triplets(
            3,
            vec![
                (2, 0, 1.0),
                (0, 1, 2.0),
                (0, 1, 3.0),
                (1, 1, 4.0),
                (0, 0, 5.0),
            ],
        );
        assert_eq!(a.row_start, vec![0, 2, 3, 4]);
        assert_eq!(a.columns, vec![0, 1, 1, 0]);
        assert_eq!(a.values, vec![5.0, 5.0, 4.0, 1.0]);
        let mut y = vec![1.0; 3];
        a.mult_add(&[1.0, 2.0, 3.0], &mut y);
        assert_eq!(y, vec![16.0, 9.0, 2.0]);
        assert_eq!(
            a.dense_columns(),
            vec![5.0, 0.0, 1.0, 5.0, 4.0, 0.0, 0.0, 0.0, 0.0]
        );
    }

    #[test]
    fn slots_assemble_the_same_sequence_without_sorting() {
        let pattern = [(2, 0), (0, 1), (0, 1), (1, 1), (0, 0)];
        let first: Vec<_> = pattern.iter().map(|&(i, j)| (i, j, 1.0)).collect();
        let (a, slots) = Csr::from_triplets_with_slots(3, first);
        assert_eq!(slots, vec![3, 1, 1, 2, 0]);
        let values = [1.0, 2.0, 3.0, 4.0, 5.0];
        let mut assembled = vec![0.0; a.values.len()];
        for (&slot, &v) in slots.iter().zip(&values) {
            assembled[slot] += v;
        }
        let triplets = pattern.iter().zip(values).map(|(&(i, j), v)| (i, j, v));
        assert_eq!(assembled, Csr::from_triplets(3, triplets.collect()).values);
    }
}
