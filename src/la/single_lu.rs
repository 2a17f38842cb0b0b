//! A single-precision MUMPS factor (libsmumps, called directly: PETSc hands MUMPS only its
//! own scalar type, double here). For a factor solved very often inside an iteration whose
//! residual stays in double precision (the transient's modified Newton): a solve streams half
//! the bytes of the double-precision factor, and the factor's rounding (~1e-7 relative) only
//! adds to what the fixed Jacobian already leaves for the next iteration to correct.
//!
//! The matrix goes to MUMPS distributed as PETSc holds it (ICNTL(18) = 3, this rank's rows);
//! the right-hand side is gathered to rank 0 and the solution scattered back (ICNTL(20) = 0,
//! ICNTL(21) = 0): at the reduced model's ~35k unknowns that is 140 kB each way, while the
//! distributed-solution layout would need its own permutation back to PETSc's rows.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::csr::max_over_ranks;
use super::error::{call, LaError, Result};
use super::matrix::SparseMatrix;
use super::solver::{mumps_count, FactorizationReport};
use super::vector::Vector;
use super::Petsc;

/// MUMPS' integer types (macros in its header, so bindgen gives the structure's fields their
/// underlying types: a MUMPS built with 64-bit integers fails to compile here, not at run time).
type MumpsInt = std::os::raw::c_int;
type MumpsInt8 = i64;

/// MUMPS' job codes.
const JOB_INIT: i32 = -1;
const JOB_END: i32 = -2;
const JOB_FACTORIZE: i32 = 2;
const JOB_ANALYSE_FACTORIZE: i32 = 4;
const JOB_SOLVE: i32 = 3;

/// A factorized matrix in single precision, with its gather and scatter of vectors.
pub struct SingleLu<'p> {
    /// Boxed: MUMPS keeps pointers into the structure between calls.
    id: Box<ffi::SMUMPS_STRUC_C>,
    /// This rank's entries (1-based, MUMPS' layout), kept while MUMPS may read them.
    _rows: Vec<MumpsInt>,
    _cols: Vec<MumpsInt>,
    _values: Vec<f32>,
    /// The right-hand side and solution on rank 0 (empty elsewhere), in single precision.
    rhs: Vec<f32>,
    gather: ffi::VecScatter,
    whole: ffi::Vec,
    symmetric: bool,
    /// The matrix factored and its nonzero state then: a refactorization needs the same
    /// matrix with the same pattern (its entries in the same order).
    matrix: ffi::Mat,
    nonzero_state: ffi::PetscObjectState,
    /// MUMPS holds an instance (JOB = -1 succeeded): ended with JOB = -2 on drop.
    started: bool,
    report: FactorizationReport,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> SingleLu<'p> {
    /// Factorizes `a` in single precision: LU, or LDL^T with pivoting (MUMPS' SYM = 2) when
    /// `symmetric` (then only the upper triangle of `a` is handed over; `a` must be
    /// symmetric).
    ///
    /// # Collective
    pub fn factorize(petsc: &'p Petsc, a: &SparseMatrix, symmetric: bool) -> Result<Self> {
        let n = a.global_rows();
        let (mut rows, mut cols, mut values) = (Vec::new(), Vec::new(), Vec::new());
        a.for_each_local_row(|row, c, v| {
            for (&col, &value) in c.iter().zip(v) {
                if symmetric && (col as usize) < row {
                    continue;
                }
                rows.push((row + 1) as MumpsInt);
                cols.push((col + 1) as MumpsInt);
                values.push(value as f32);
            }
        })?;
        // SAFETY: SMUMPS_STRUC_C is plain data (integers, floats, pointers, char arrays);
        // all zero is the state MUMPS' documentation starts from before JOB = -1.
        let mut id: Box<ffi::SMUMPS_STRUC_C> = Box::new(unsafe { std::mem::zeroed() });
        id.comm_fortran = {
            // SAFETY: converts a valid communicator handle.
            unsafe { ffi::mpi_sys::RSMPI_Comm_c2f(petsc.comm()) as MumpsInt }
        };
        id.par = 1;
        id.sym = if symmetric { 2 } else { 0 };
        let mut solver = SingleLu {
            id,
            _rows: rows,
            _cols: cols,
            _values: values,
            rhs: Vec::new(),
            gather: std::ptr::null_mut(),
            whole: std::ptr::null_mut(),
            symmetric,
            matrix: a.raw,
            nonzero_state: nonzero_state(a)?,
            started: false,
            report: FactorizationReport::unknown(),
            _petsc: PhantomData,
        };
        solver.call(JOB_INIT, "initialization")?;
        solver.started = true;
        let id = &mut solver.id;
        // Quiet: no messages, statistics or warnings (ICNTL(1..4)).
        for k in 0..4 {
            id.icntl[k] = 0;
        }
        id.icntl[4] = 0; // ICNTL(5): assembled matrix
        id.icntl[17] = 3; // ICNTL(18): distributed entries
        id.icntl[19] = 0; // ICNTL(20): dense right-hand side on the host
        id.icntl[20] = 0; // ICNTL(21): centralized solution
        id.n = n as MumpsInt;
        id.nnz_loc = solver._rows.len() as MumpsInt8;
        id.nz_loc = solver._rows.len() as MumpsInt;
        id.irn_loc = solver._rows.as_mut_ptr();
        id.jcn_loc = solver._cols.as_mut_ptr();
        id.a_loc = solver._values.as_mut_ptr();
        solver.call(JOB_ANALYSE_FACTORIZE, "factorization")?;
        solver.report = solver.read_report()?;
        let layout = a.new_vector()?;
        call!(VecScatterCreateToZero(
            layout.raw,
            &mut solver.gather,
            &mut solver.whole
        ))?;
        if petsc.rank() == 0 {
            solver.rhs = vec![0.0; n];
        }
        Ok(solver)
    }

    fn read_report(&self) -> Result<FactorizationReport> {
        let infog = |i: usize| self.id.infog[i - 1];
        let entries = infog(29);
        let largest_rank_entries = max_over_ranks(self.matrix, mumps_count(self.id.info[26]))?;
        Ok(FactorizationReport {
            factor_entries: mumps_count(entries),
            factor_entries_largest_rank: largest_rank_entries,
            ordering: infog(7),
            memory_max_mb: infog(21),
            memory_mb: infog(22),
            flops: f64::from(self.id.rinfog[2]),
            negative_pivots: infog(12),
        })
    }

    pub fn report(&self) -> FactorizationReport {
        self.report
    }

    /// Whether `a` is the matrix this factor was computed from, with the same pattern (what
    /// [`Self::refactorize`] needs).
    pub fn factors(&self, a: &SparseMatrix) -> Result<bool> {
        Ok(a.raw == self.matrix && nonzero_state(a)? == self.nonzero_state)
    }

    /// Factorizes `a` again after its values changed in place: MUMPS' numerical phase on the
    /// first factorization's ordering and analysis (the analysis of a reduced model with
    /// dense modal rows is a large part of a factorization). `a` must be the matrix factored
    /// first, with its pattern unchanged ([`Self::factors`]).
    ///
    /// # Collective
    pub fn refactorize(&mut self, a: &SparseMatrix) -> Result<()> {
        if !self.factors(a)? {
            return Err(super::LaError::Invalid(
                "single-precision refactorization: not the matrix (or pattern) factored".into(),
            ));
        }
        let symmetric = self.symmetric;
        let mut k = 0;
        let values = &mut self._values;
        a.for_each_local_row(|row, c, v| {
            for (&col, &value) in c.iter().zip(v) {
                if symmetric && (col as usize) < row {
                    continue;
                }
                if let Some(slot) = values.get_mut(k) {
                    *slot = value as f32;
                }
                k += 1;
            }
        })?;
        if k != values.len() {
            return Err(super::LaError::Invalid(format!(
                "single-precision refactorization: {k} local entries, {} factored",
                values.len()
            )));
        }
        self.id.a_loc = self._values.as_mut_ptr();
        self.call(JOB_FACTORIZE, "factorization")?;
        self.report = self.read_report()?;
        Ok(())
    }

    pub fn is_symmetric(&self) -> bool {
        self.symmetric
    }

    /// Solves A x = b: b gathered to rank 0, rounded to single precision, solved, and the
    /// solution scattered back in double precision.
    ///
    /// # Collective
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> Result<()> {
        self.scatter(b.raw, self.whole, ffi::SCATTER_FORWARD)?;
        let n = self.rhs.len();
        if n > 0 {
            let mut data = std::ptr::null_mut();
            call!(VecGetArray(self.whole, &mut data))?;
            // SAFETY: the sequential vector on rank 0 holds the n entries.
            let whole = unsafe { std::slice::from_raw_parts_mut(data, n) };
            for (r, &v) in self.rhs.iter_mut().zip(whole.iter()) {
                *r = v as f32;
            }
            call!(VecRestoreArray(self.whole, &mut data))?;
        }
        self.id.rhs = self.rhs.as_mut_ptr();
        self.id.nrhs = 1;
        self.id.lrhs = n as MumpsInt;
        self.call(JOB_SOLVE, "solve")?;
        if n > 0 {
            let mut data = std::ptr::null_mut();
            call!(VecGetArray(self.whole, &mut data))?;
            // SAFETY: as above.
            let whole = unsafe { std::slice::from_raw_parts_mut(data, n) };
            for (w, &r) in whole.iter_mut().zip(&self.rhs) {
                *w = f64::from(r);
            }
            call!(VecRestoreArray(self.whole, &mut data))?;
        }
        self.scatter(self.whole, x.raw, ffi::SCATTER_REVERSE)
    }

    /// Moves `from` into `to` along the gather (forward: to rank 0; reverse: back).
    ///
    /// # Collective
    fn scatter(&self, from: ffi::Vec, to: ffi::Vec, mode: ffi::ScatterMode) -> Result<()> {
        let insert = ffi::INSERT_VALUES;
        call!(VecScatterBegin(self.gather, from, to, insert, mode))?;
        call!(VecScatterEnd(self.gather, from, to, insert, mode))
    }

    /// Runs a MUMPS job; a negative INFOG(1) is an error (on every rank: INFOG is global).
    fn call(&mut self, job: i32, phase: &'static str) -> Result<()> {
        self.id.job = job;
        // SAFETY: `id` was initialized by JOB = -1 (or is being), and every pointer it holds
        // points into buffers this structure owns for as long as MUMPS may read them.
        unsafe { ffi::smumps_c(&mut *self.id) };
        let (infog1, infog2) = (self.id.infog[0], self.id.infog[1]);
        if infog1 < 0 {
            return Err(LaError::Mumps {
                phase,
                infog1,
                infog2,
                prefix: "(single precision, no PETSc prefix) ".into(),
            });
        }
        Ok(())
    }
}

fn nonzero_state(a: &SparseMatrix) -> Result<ffi::PetscObjectState> {
    let mut state = 0;
    call!(MatGetNonzeroState(a.raw, &mut state))?;
    Ok(state)
}

impl Drop for SingleLu<'_> {
    fn drop(&mut self) {
        if !self.gather.is_null() {
            super::report_destroy(call!(VecScatterDestroy(&mut self.gather)));
            super::report_destroy(call!(VecDestroy(&mut self.whole)));
        }
        if self.started {
            self.id.job = JOB_END;
            // SAFETY: ends the instance JOB = -1 started (collective, as drops of a factor
            // are).
            unsafe { ffi::smumps_c(&mut *self.id) };
        }
    }
}
