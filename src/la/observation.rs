//! Rectangular distributed sparse matrices (PETSc AIJ): the contact observation matrices
//! C_NOR, C_TAN, C_CONV map DOF vectors to values at contact points. Each rank owns a contiguous
//! range of points (rows) and the usual range of DOFs (columns).

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::vector::Vector;
use super::{report_destroy, Petsc};

/// A distributed `points x dofs` matrix with rows given as sparse (column, value) lists.
pub struct ObservationMatrix<'p> {
    raw: ffi::Mat,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> ObservationMatrix<'p> {
    /// Builds the matrix from this rank's rows (global row numbers start at `first_row`, the
    /// sum of the row counts of lower ranks). `columns` is this rank's DOF range; every rank
    /// passes its own. Entries with a negative column (eliminated DOFs) are skipped.
    ///
    /// # Collective
    pub fn from_rows(
        petsc: &'p Petsc,
        first_row: usize,
        rows: &[Vec<(i32, f64)>],
        columns: std::ops::Range<usize>,
    ) -> Result<Self> {
        let mut diag = Vec::with_capacity(rows.len());
        let mut off = Vec::with_capacity(rows.len());
        for row in rows {
            let mut cols: Vec<i32> = row.iter().filter(|e| e.0 >= 0).map(|e| e.0).collect();
            cols.sort_unstable();
            cols.dedup();
            let d = cols
                .iter()
                .filter(|&&c| columns.contains(&(c as usize)))
                .count();
            diag.push(d as ffi::PetscInt);
            off.push((cols.len() - d) as ffi::PetscInt);
        }
        let mut raw = std::ptr::null_mut();
        call!(MatCreate(petsc.comm(), &mut raw))?;
        let m = ObservationMatrix {
            raw,
            _petsc: PhantomData,
        };
        call!(MatSetSizes(
            m.raw,
            rows.len() as ffi::PetscInt,
            columns.len() as ffi::PetscInt,
            ffi::PETSC_DETERMINE as ffi::PetscInt,
            ffi::PETSC_DETERMINE as ffi::PetscInt
        ))?;
        call!(MatSetType(m.raw, super::cconst(ffi::MATAIJ)))?;
        call!(MatSeqAIJSetPreallocation(m.raw, 0, diag.as_ptr()))?;
        call!(MatMPIAIJSetPreallocation(
            m.raw,
            0,
            diag.as_ptr(),
            0,
            off.as_ptr()
        ))?;
        call!(MatSetOption(
            m.raw,
            ffi::MAT_NEW_NONZERO_ALLOCATION_ERR,
            ffi::PETSC_TRUE
        ))?;
        let (mut lo, mut hi) = (0, 0);
        call!(MatGetOwnershipRangeColumn(m.raw, &mut lo, &mut hi))?;
        if lo as usize != columns.start || hi as usize != columns.end {
            return Err(LaError::Invalid(format!(
                "observation matrix columns {lo}..{hi} differ from the DOF range {columns:?}"
            )));
        }
        for (i, row) in rows.iter().enumerate() {
            let r = [(first_row + i) as ffi::PetscInt];
            let (cols, vals): (Vec<i32>, Vec<f64>) =
                row.iter().filter(|e| e.0 >= 0).copied().unzip();
            if cols.is_empty() {
                continue;
            }
            call!(MatSetValues(
                m.raw,
                1,
                r.as_ptr(),
                cols.len() as ffi::PetscInt,
                cols.as_ptr(),
                vals.as_ptr(),
                ffi::ADD_VALUES
            ))?;
        }
        call!(MatAssemblyBegin(m.raw, ffi::MAT_FINAL_ASSEMBLY))?;
        call!(MatAssemblyEnd(m.raw, ffi::MAT_FINAL_ASSEMBLY))?;
        Ok(m)
    }

    /// (global rows, global columns)
    pub fn size(&self) -> (usize, usize) {
        let (mut m, mut n) = (0, 0);
        call!(MatGetSize(self.raw, &mut m, &mut n)).expect("valid matrix");
        (m as usize, n as usize)
    }

    /// Stored entries, summed over the ranks (what one product streams, with their column
    /// indices).
    ///
    /// # Collective
    pub fn stored_entries(&self) -> Result<f64> {
        // SAFETY: MatInfo is plain old data.
        let mut info: ffi::MatInfo = unsafe { std::mem::zeroed() };
        call!(MatGetInfo(self.raw, ffi::MAT_GLOBAL_SUM, &mut info))?;
        Ok(info.nz_used)
    }

    /// A vector with the row (point) layout.
    ///
    /// # Collective
    pub fn new_point_vector(&self) -> Result<Vector<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(MatCreateVecs(self.raw, std::ptr::null_mut(), &mut raw))?;
        let mut v = Vector::from_raw(raw);
        v.set_all(0.0)?;
        Ok(v)
    }

    /// `y = C x` (x: DOF vector, y: point vector)
    ///
    /// # Collective
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMult(self.raw, x.raw, y.raw))
    }

    /// `y = C^T x` (x: point vector, y: DOF vector)
    ///
    /// # Collective
    pub fn mult_transpose(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMultTranspose(self.raw, x.raw, y.raw))
    }

    /// `y += C^T x`
    ///
    /// # Collective
    pub fn mult_transpose_add(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        call!(MatMultTransposeAdd(self.raw, x.raw, y.raw, y.raw))
    }
}

impl Drop for ObservationMatrix<'_> {
    fn drop(&mut self) {
        report_destroy(call!(MatDestroy(&mut self.raw)));
    }
}
