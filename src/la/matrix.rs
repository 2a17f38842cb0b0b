//! Distributed sparse matrices (PETSc `Mat`): AIJ, and BAIJ/SBAIJ assembled blockwise.

use std::marker::PhantomData;
use std::path::Path;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::local_lu::Csr;
use super::vector::Vector;
use super::{cconst, cstr, report_destroy, Petsc};

/// Storage format. SBAIJ stores the upper triangle only and is what MUMPS Cholesky accepts;
/// BAIJ is what MUMPS LU orders best (see TOOLCHAIN.md); AIJ takes anything.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatrixFormat {
    Aij,
    Baij,
    Sbaij,
}

impl MatrixFormat {
    fn petsc_type(self) -> *const std::os::raw::c_char {
        match self {
            MatrixFormat::Aij => cconst(ffi::MATMPIAIJ),
            MatrixFormat::Baij => cconst(ffi::MATMPIBAIJ),
            MatrixFormat::Sbaij => cconst(ffi::MATMPISBAIJ),
        }
    }
}

/// Storage figures of an assembled matrix (summed over ranks).
#[derive(Debug, Clone, Copy)]
pub struct MatrixInfo {
    pub nonzeros: f64,
    pub memory_bytes: f64,
}

/// A square distributed sparse matrix; each rank owns a contiguous range of rows.
pub struct SparseMatrix<'p> {
    pub(crate) raw: ffi::Mat,
    format: MatrixFormat,
    block_size: usize,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

/// Exact preallocation of a matrix: stored entries per local (block) row in the diagonal and
/// off-diagonal parts, and of their upper triangles (for symmetric storage).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Preallocation {
    pub diag: Vec<i32>,
    pub off: Vec<i32>,
    pub diag_upper: Vec<i32>,
    pub off_upper: Vec<i32>,
}

impl<'p> SparseMatrix<'p> {
    /// Creates a square matrix with `local_rows` rows on this rank (a multiple of
    /// `block_size`) and exact preallocation (per local block row).
    ///
    /// # Collective
    pub fn new(
        petsc: &'p Petsc,
        format: MatrixFormat,
        block_size: usize,
        local_rows: usize,
        prealloc: &Preallocation,
    ) -> Result<Self> {
        if !local_rows.is_multiple_of(block_size) {
            return Err(LaError::Invalid(format!(
                "{local_rows} local rows is not a multiple of block size {block_size}"
            )));
        }
        let nb = local_rows / block_size;
        for (name, v) in [
            ("diag", &prealloc.diag),
            ("off", &prealloc.off),
            ("diag_upper", &prealloc.diag_upper),
            ("off_upper", &prealloc.off_upper),
        ] {
            if v.len() != nb {
                return Err(LaError::Invalid(format!(
                    "preallocation '{name}' has {} entries for {nb} local block rows",
                    v.len()
                )));
            }
        }
        let mut raw = std::ptr::null_mut();
        call!(MatCreate(petsc.comm(), &mut raw))?;
        let m = SparseMatrix {
            raw,
            format,
            block_size,
            _petsc: PhantomData,
        };
        let n = local_rows as ffi::PetscInt;
        call!(MatSetSizes(
            m.raw,
            n,
            n,
            ffi::PETSC_DETERMINE as ffi::PetscInt,
            ffi::PETSC_DETERMINE as ffi::PetscInt
        ))?;
        call!(MatSetType(m.raw, format.petsc_type()))?;
        call!(MatSetBlockSize(m.raw, block_size as ffi::PetscInt))?;
        call!(MatXAIJSetPreallocation(
            m.raw,
            block_size as ffi::PetscInt,
            prealloc.diag.as_ptr(),
            prealloc.off.as_ptr(),
            prealloc.diag_upper.as_ptr(),
            prealloc.off_upper.as_ptr()
        ))?;
        if format == MatrixFormat::Sbaij {
            // Element matrices are added whole; SBAIJ keeps the upper triangle.
            call!(MatSetOption(
                m.raw,
                ffi::MAT_IGNORE_LOWER_TRIANGULAR,
                ffi::PETSC_TRUE
            ))?;
        }
        call!(MatSetOption(
            m.raw,
            ffi::MAT_NEW_NONZERO_ALLOCATION_ERR,
            ffi::PETSC_TRUE
        ))?;
        Ok(m)
    }

    pub fn format(&self) -> MatrixFormat {
        self.format
    }

    pub fn block_size(&self) -> usize {
        self.block_size
    }

    /// Declares the matrix symmetric (lets SLEPc and MUMPS use it).
    pub fn set_symmetric(&self, symmetric: bool) -> Result<()> {
        let flag = if symmetric {
            ffi::PETSC_TRUE
        } else {
            ffi::PETSC_FALSE
        };
        call!(MatSetOption(self.raw, ffi::MAT_SYMMETRIC, flag))?;
        call!(MatSetOption(self.raw, ffi::MAT_SYMMETRY_ETERNAL, flag))
    }

    /// Adds a dense row-major block of values at global scalar indices; negative indices
    /// (eliminated DOFs) are skipped by PETSc.
    pub fn add_values(&mut self, rows: &[i32], cols: &[i32], values: &[f64]) -> Result<()> {
        debug_assert_eq!(values.len(), rows.len() * cols.len());
        call!(MatSetValues(
            self.raw,
            rows.len() as ffi::PetscInt,
            rows.as_ptr(),
            cols.len() as ffi::PetscInt,
            cols.as_ptr(),
            values.as_ptr(),
            ffi::ADD_VALUES
        ))
    }

    /// Adds a dense row-major matrix of `block_size` blocks at global block indices; negative
    /// block indices are skipped.
    pub fn add_blocked(&mut self, rows: &[i32], cols: &[i32], values: &[f64]) -> Result<()> {
        debug_assert_eq!(
            values.len(),
            rows.len() * cols.len() * self.block_size * self.block_size
        );
        call!(MatSetValuesBlocked(
            self.raw,
            rows.len() as ffi::PetscInt,
            rows.as_ptr(),
            cols.len() as ffi::PetscInt,
            cols.as_ptr(),
            values.as_ptr(),
            ffi::ADD_VALUES
        ))
    }

    /// Finishes assembly (communicates entries added for rows of other ranks).
    ///
    /// # Collective
    pub fn assemble(&mut self) -> Result<()> {
        call!(MatAssemblyBegin(self.raw, ffi::MAT_FINAL_ASSEMBLY))?;
        call!(MatAssemblyEnd(self.raw, ffi::MAT_FINAL_ASSEMBLY))
    }

    pub fn global_rows(&self) -> usize {
        let (mut m, mut n) = (0, 0);
        call!(MatGetSize(self.raw, &mut m, &mut n)).expect("valid matrix");
        m as usize
    }

    /// The global row range this rank owns.
    pub fn ownership(&self) -> std::ops::Range<usize> {
        let (mut lo, mut hi) = (0, 0);
        call!(MatGetOwnershipRange(self.raw, &mut lo, &mut hi)).expect("valid matrix");
        lo as usize..hi as usize
    }

    /// A vector with this matrix's row layout.
    ///
    /// # Collective
    pub fn new_vector(&self) -> Result<Vector<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(MatCreateVecs(self.raw, &mut raw, std::ptr::null_mut()))?;
        let mut v = Vector::from_raw(raw);
        v.set_all(0.0)?;
        Ok(v)
    }

    /// `y = A x`
    ///
    /// # Collective
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMult(self.raw, x.raw, y.raw))
    }

    /// The diagonal into `d`.
    ///
    /// # Collective
    pub fn diagonal(&self, d: &mut Vector) -> Result<()> {
        call!(MatGetDiagonal(self.raw, d.raw))
    }

    /// `y = A^T x`
    ///
    /// # Collective
    pub fn mult_transpose(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMultTranspose(self.raw, x.raw, y.raw))
    }

    /// `y = y + A x`
    ///
    /// # Collective
    pub fn mult_add(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMultAdd(self.raw, x.raw, y.raw, y.raw))
    }

    /// # Collective
    pub fn norm_frobenius(&self) -> Result<f64> {
        let mut n = 0.0;
        call!(MatNorm(self.raw, ffi::NORM_FROBENIUS, &mut n))?;
        Ok(n)
    }

    /// # Collective
    pub fn norm_infinity(&self) -> Result<f64> {
        let mut n = 0.0;
        call!(MatNorm(self.raw, ffi::NORM_INFINITY, &mut n))?;
        Ok(n)
    }

    /// Stored nonzeros and memory, summed over ranks.
    ///
    /// # Collective
    pub fn info(&self) -> Result<MatrixInfo> {
        // SAFETY: MatInfo is plain old data.
        let mut info: ffi::MatInfo = unsafe { std::mem::zeroed() };
        call!(MatGetInfo(self.raw, ffi::MAT_GLOBAL_SUM, &mut info))?;
        Ok(MatrixInfo {
            nonzeros: info.nz_used,
            memory_bytes: info.memory,
        })
    }

    /// Writes the matrix in PETSc's binary format (readable by `MatLoad`, SLEPc's examples
    /// and PETSc's Python/MATLAB readers).
    ///
    /// # Collective
    pub fn save_binary(&self, petsc: &Petsc, path: &Path) -> Result<()> {
        let name = cstr(&path.to_string_lossy());
        let mut viewer = std::ptr::null_mut();
        call!(PetscViewerBinaryOpen(
            petsc.comm(),
            name.as_ptr(),
            ffi::FILE_MODE_WRITE,
            &mut viewer
        ))?;
        let result = call!(MatView(self.raw, viewer));
        call!(PetscViewerDestroy(&mut viewer))?;
        result
    }

    /// Visits this rank's rows as (global row, columns, values). For SBAIJ only the stored upper
    /// triangle is visited.
    pub fn for_each_local_row(&self, mut f: impl FnMut(usize, &[i32], &[f64])) -> Result<()> {
        let upper = self.format == MatrixFormat::Sbaij;
        if upper {
            call!(MatGetRowUpperTriangular(self.raw))?;
        }
        let mut result = Ok(());
        for row in self.ownership() {
            let mut ncols = 0;
            let mut cols = std::ptr::null();
            let mut vals = std::ptr::null();
            let r = row as ffi::PetscInt;
            if let Err(e) = call!(MatGetRow(self.raw, r, &mut ncols, &mut cols, &mut vals)) {
                result = Err(e);
                break;
            }
            let n = ncols as usize;
            let (c, v) = if n == 0 {
                (&[][..], &[][..])
            } else {
                // SAFETY: PETSc returns `ncols` valid entries until MatRestoreRow.
                unsafe {
                    (
                        std::slice::from_raw_parts(cols, n),
                        std::slice::from_raw_parts(vals, n),
                    )
                }
            };
            f(row, c, v);
            if let Err(e) = call!(MatRestoreRow(self.raw, r, &mut ncols, &mut cols, &mut vals)) {
                result = Err(e);
                break;
            }
        }
        if upper {
            call!(MatRestoreRowUpperTriangular(self.raw))?;
        }
        result
    }

    /// A new matrix of another format with the same values.
    ///
    /// # Collective
    pub fn convert(&self, format: MatrixFormat) -> Result<SparseMatrix<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(MatConvert(
            self.raw,
            format.petsc_type(),
            ffi::MAT_INITIAL_MATRIX,
            &mut raw
        ))?;
        Ok(SparseMatrix {
            raw,
            format,
            block_size: self.block_size,
            _petsc: PhantomData,
        })
    }

    /// `self += alpha * x` (x may have a different nonzero pattern).
    ///
    /// # Collective
    pub fn axpy(&mut self, alpha: f64, x: &SparseMatrix) -> Result<()> {
        call!(MatAXPY(
            self.raw,
            alpha,
            x.raw,
            ffi::DIFFERENT_NONZERO_PATTERN
        ))
    }

    /// `self += alpha * x` where x's nonzero pattern is a subset of this matrix's (kept).
    ///
    /// # Collective
    pub fn axpy_subset(&mut self, alpha: f64, x: &SparseMatrix) -> Result<()> {
        if super::csr::add_nested(self, alpha, x, false)? {
            return Ok(());
        }
        call!(MatAXPY(self.raw, alpha, x.raw, ffi::SUBSET_NONZERO_PATTERN))
    }

    /// Overwrites the values with those of `source`, whose nonzero pattern must be a subset of
    /// this matrix's (entries outside it become zero).
    ///
    /// # Collective
    pub fn copy_values_from(&mut self, source: &SparseMatrix) -> Result<()> {
        if super::csr::add_nested(self, 1.0, source, true)? {
            return Ok(());
        }
        call!(MatCopy(source.raw, self.raw, ffi::SUBSET_NONZERO_PATTERN))
    }

    /// Declares that every later assembly sends a subset of the entries for other ranks' rows
    /// that the next one sends (a tangent re-added on a fixed pattern): PETSc then keeps that
    /// assembly's communication pattern instead of agreeing on a new one every time.
    pub fn fix_off_rank_pattern(&self) -> Result<()> {
        call!(MatSetOption(
            self.raw,
            ffi::MAT_SUBSET_OFF_PROC_ENTRIES,
            ffi::PETSC_TRUE
        ))
    }

    /// `self *= alpha`
    ///
    /// # Collective
    pub fn scale(&mut self, alpha: f64) -> Result<()> {
        call!(MatScale(self.raw, alpha))
    }

    /// # Collective
    pub fn zero_entries(&mut self) -> Result<()> {
        call!(MatZeroEntries(self.raw))
    }

    /// The same matrix (same global numbering, pattern and values) with this rank owning the
    /// rows and columns `rows` instead: a new contiguous row distribution.
    ///
    /// # Collective
    pub fn redistributed(
        &self,
        petsc: &'p Petsc,
        rows: std::ops::Range<usize>,
    ) -> Result<SparseMatrix<'p>> {
        let mut is = std::ptr::null_mut();
        call!(ISCreateStride(
            petsc.comm(),
            rows.len() as ffi::PetscInt,
            rows.start as ffi::PetscInt,
            1,
            &mut is
        ))?;
        let mut raw = std::ptr::null_mut();
        let made = call!(MatCreateSubMatrix(
            self.raw,
            is,
            is,
            ffi::MAT_INITIAL_MATRIX,
            &mut raw
        ));
        report_destroy(call!(ISDestroy(&mut is)));
        made?;
        Ok(SparseMatrix {
            raw,
            format: self.format,
            block_size: self.block_size,
            _petsc: PhantomData,
        })
    }

    /// The block of rows and columns `indices` (ascending global indices, the same on every
    /// rank) as a sparse |indices| x |indices| matrix on every rank: a small subproblem's
    /// operator. AIJ only (a blocked format would need block-aligned indices).
    ///
    /// # Collective
    pub fn block(&self, indices: &[usize]) -> Result<Csr> {
        if self.format != MatrixFormat::Aij {
            return Err(LaError::Invalid("block: the matrix must be AIJ".into()));
        }
        let n = indices.len();
        let idx: Vec<ffi::PetscInt> = indices.iter().map(|&i| i as ffi::PetscInt).collect();
        let mut is = std::ptr::null_mut();
        // SAFETY: MPI_COMM_SELF is a valid communicator for the whole run.
        let comm_self = unsafe { ffi::mpi_sys::RSMPI_COMM_SELF };
        call!(ISCreateGeneral(
            comm_self,
            n as ffi::PetscInt,
            idx.as_ptr(),
            ffi::PETSC_COPY_VALUES,
            &mut is
        ))?;
        let mut subs: *mut ffi::Mat = std::ptr::null_mut();
        let made = call!(MatCreateSubMatrices(
            self.raw,
            1,
            &is,
            &is,
            ffi::MAT_INITIAL_MATRIX,
            &mut subs
        ));
        report_destroy(call!(ISDestroy(&mut is)));
        made?;
        // SAFETY: MatCreateSubMatrices returned an array of one matrix.
        let sub = unsafe { *subs };
        let mut block = Csr {
            n,
            row_start: vec![0; n + 1],
            columns: Vec::new(),
            values: Vec::new(),
        };
        let mut result = Ok(());
        for row in 0..n {
            let mut ncols = 0;
            let mut cols = std::ptr::null();
            let mut vals = std::ptr::null();
            let r = row as ffi::PetscInt;
            if let Err(e) = call!(MatGetRow(sub, r, &mut ncols, &mut cols, &mut vals)) {
                result = Err(e);
                break;
            }
            if ncols > 0 {
                // SAFETY: PETSc returns `ncols` valid entries until MatRestoreRow.
                let (c, v) = unsafe {
                    (
                        std::slice::from_raw_parts(cols, ncols as usize),
                        std::slice::from_raw_parts(vals, ncols as usize),
                    )
                };
                // (MatGetRow gives a row's columns ascending.)
                block.columns.extend(c.iter().map(|&col| col as usize));
                block.values.extend_from_slice(v);
            }
            block.row_start[row + 1] = block.columns.len();
            if let Err(e) = call!(MatRestoreRow(sub, r, &mut ncols, &mut cols, &mut vals)) {
                result = Err(e);
                break;
            }
        }
        report_destroy(call!(MatDestroySubMatrices(1, &mut subs)));
        result.map(|_| block)
    }

    /// An identity of this matrix while it lives (two live matrices never share one): to
    /// recognize a matrix handed back as the one built earlier.
    pub fn identity(&self) -> usize {
        self.raw as usize
    }

    /// For `count` vectors given by this rank's rows (`columns`: column-major, `count` columns
    /// of `ownership().len()` rows), this rank's share of each x_j^T A x_j: the sum over this
    /// rank's rows of x_j (A x_j); the caller sums over the ranks. One sparse-dense product,
    /// which streams A once per four columns instead of once per vector.
    ///
    /// # Collective
    pub fn local_quadratic_forms(&self, columns: &[f64], count: usize) -> Result<Vec<f64>> {
        let rows = self.ownership().len();
        assert_eq!(columns.len(), rows * count, "local_quadratic_forms: layout");
        if count == 0 {
            return Ok(Vec::new());
        }
        let comm = super::block_add::communicator(self.raw)?;
        // PETSc reads B's array in place; it is copied so that no pointer to `columns` is
        // handed out as mutable.
        let mut data = columns.to_vec();
        let (m, n) = (rows as ffi::PetscInt, count as ffi::PetscInt);
        let mut b = DenseGuard(std::ptr::null_mut());
        call!(MatCreateDense(
            comm,
            m,
            ffi::PETSC_DECIDE,
            ffi::PETSC_DETERMINE,
            n,
            data.as_mut_ptr(),
            &mut b.0
        ))?;
        let mut c = DenseGuard(std::ptr::null_mut());
        call!(MatMatMult(
            self.raw,
            b.0,
            ffi::MAT_INITIAL_MATRIX,
            ffi::PETSC_DEFAULT as ffi::PetscReal,
            &mut c.0
        ))?;
        let mut lda: ffi::PetscInt = 0;
        call!(MatDenseGetLDA(c.0, &mut lda))?;
        let mut ptr = std::ptr::null();
        call!(MatDenseGetArrayRead(c.0, &mut ptr))?;
        let lda = lda as usize;
        // A rank without rows has no share (and PETSc's array may then be empty or null).
        let forms = if rows == 0 {
            vec![0.0; count]
        } else {
            // SAFETY: C holds this rank's `rows` rows of `count` columns with leading
            // dimension lda >= rows; the array stays valid until it is restored below.
            let ax = unsafe { std::slice::from_raw_parts(ptr, lda * (count - 1) + rows) };
            (0..count)
                .map(|j| {
                    let x = &columns[j * rows..(j + 1) * rows];
                    x.iter()
                        .zip(&ax[j * lda..j * lda + rows])
                        .map(|(a, b)| a * b)
                        .sum()
                })
                .collect()
        };
        call!(MatDenseRestoreArrayRead(c.0, &mut ptr))?;
        drop(c);
        drop(b);
        drop(data);
        Ok(forms)
    }

    /// Same layout, pattern and values.
    ///
    /// # Collective
    pub fn try_clone(&self) -> Result<SparseMatrix<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(MatDuplicate(self.raw, ffi::MAT_COPY_VALUES, &mut raw))?;
        Ok(SparseMatrix {
            raw,
            format: self.format,
            block_size: self.block_size,
            _petsc: PhantomData,
        })
    }
}

impl Drop for SparseMatrix<'_> {
    fn drop(&mut self) {
        report_destroy(call!(MatDestroy(&mut self.raw)));
    }
}

/// A linear operator applied without being assembled, or a matrix: `y = y + A x`.
pub trait Operator<'p> {
    /// # Collective
    fn mult_add(&self, x: &Vector<'p>, y: &mut Vector<'p>) -> Result<()>;
}

impl<'p> Operator<'p> for SparseMatrix<'p> {
    fn mult_add(&self, x: &Vector<'p>, y: &mut Vector<'p>) -> Result<()> {
        SparseMatrix::mult_add(self, x, y)
    }
}

impl<'p, T: Operator<'p> + ?Sized> Operator<'p> for &T {
    fn mult_add(&self, x: &Vector<'p>, y: &mut Vector<'p>) -> Result<()> {
        (**self).mult_add(x, y)
    }
}

/// A dense matrix made for one product, destroyed when it goes out of scope.
struct DenseGuard(ffi::Mat);

impl Drop for DenseGuard {
    fn drop(&mut self) {
        if !self.0.is_null() {
            report_destroy(call!(MatDestroy(&mut self.0)));
        }
    }
}
