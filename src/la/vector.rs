//! Distributed vectors (PETSc `Vec`, type mpi).

use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};

use petsc_sys as ffi;

use super::error::{call, Result};
use super::{report_destroy, Petsc};

/// A distributed vector; each rank owns a contiguous range of entries.
pub struct Vector<'p> {
    pub(crate) raw: ffi::Vec,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> Vector<'p> {
    pub(crate) fn from_raw(raw: ffi::Vec) -> Self {
        Vector {
            raw,
            _petsc: PhantomData,
        }
    }

    /// A zero vector with `local` entries on this rank.
    ///
    /// # Collective
    pub fn new(petsc: &'p Petsc, local: usize) -> Result<Self> {
        let mut raw = std::ptr::null_mut();
        call!(VecCreateMPI(
            petsc.comm(),
            local as ffi::PetscInt,
            ffi::PETSC_DETERMINE as ffi::PetscInt,
            &mut raw
        ))?;
        let mut v = Vector::from_raw(raw);
        v.set_all(0.0)?;
        Ok(v)
    }

    /// A vector holding `values` as this rank's entries.
    ///
    /// # Collective
    pub fn from_local(petsc: &'p Petsc, values: &[f64]) -> Result<Self> {
        let mut v = Vector::new(petsc, values.len())?;
        v.local_mut()?.copy_from_slice(values);
        Ok(v)
    }

    /// Same layout, entries zero.
    ///
    /// # Collective
    pub fn duplicate(&self) -> Result<Vector<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(VecDuplicate(self.raw, &mut raw))?;
        let mut v = Vector::from_raw(raw);
        v.set_all(0.0)?;
        Ok(v)
    }

    /// Same layout and values.
    ///
    /// # Collective
    pub fn try_clone(&self) -> Result<Vector<'p>> {
        let v = self.duplicate()?;
        call!(VecCopy(self.raw, v.raw))?;
        Ok(v)
    }

    pub fn global_len(&self) -> usize {
        let mut n = 0;
        call!(VecGetSize(self.raw, &mut n)).expect("VecGetSize on a valid vector");
        n as usize
    }

    /// The global index range this rank owns.
    pub fn ownership(&self) -> std::ops::Range<usize> {
        let (mut lo, mut hi) = (0, 0);
        call!(VecGetOwnershipRange(self.raw, &mut lo, &mut hi)).expect("valid vector");
        lo as usize..hi as usize
    }

    pub fn set_all(&mut self, value: f64) -> Result<()> {
        call!(VecSet(self.raw, value))
    }

    /// `self += alpha * x`
    pub fn axpy(&mut self, alpha: f64, x: &Vector) -> Result<()> {
        call!(VecAXPY(self.raw, alpha, x.raw))
    }

    pub fn scale(&mut self, alpha: f64) -> Result<()> {
        call!(VecScale(self.raw, alpha))
    }

    pub fn copy_from(&mut self, x: &Vector) -> Result<()> {
        call!(VecCopy(x.raw, self.raw))
    }

    /// Whether every entry equals `x`'s exactly (same layout).
    ///
    /// # Collective
    pub fn equals(&self, x: &Vector) -> Result<bool> {
        let mut flag = ffi::PETSC_FALSE;
        call!(VecEqual(self.raw, x.raw, &mut flag))?;
        Ok(flag == ffi::PETSC_TRUE)
    }

    /// # Collective
    pub fn dot(&self, x: &Vector) -> Result<f64> {
        let mut d = 0.0;
        call!(VecDot(self.raw, x.raw, &mut d))?;
        Ok(d)
    }

    /// The dot products with every vector of `xs`, in one reduction.
    ///
    /// # Collective
    pub fn mdot(&self, xs: &[&Vector]) -> Result<Vec<f64>> {
        let raws: Vec<ffi::Vec> = xs.iter().map(|x| x.raw).collect();
        let mut out = vec![0.0; xs.len()];
        if !xs.is_empty() {
            call!(VecMDot(
                self.raw,
                xs.len() as ffi::PetscInt,
                raws.as_ptr(),
                out.as_mut_ptr()
            ))?;
        }
        Ok(out)
    }

    /// `self += sum_i alphas[i] xs[i]`
    pub fn maxpy(&mut self, alphas: &[f64], xs: &[&Vector]) -> Result<()> {
        debug_assert_eq!(alphas.len(), xs.len());
        let mut raws: Vec<ffi::Vec> = xs.iter().map(|x| x.raw).collect();
        if xs.is_empty() {
            return Ok(());
        }
        call!(VecMAXPY(
            self.raw,
            xs.len() as ffi::PetscInt,
            alphas.as_ptr(),
            raws.as_mut_ptr()
        ))
    }

    /// # Collective
    pub fn norm2(&self) -> Result<f64> {
        let mut n = 0.0;
        call!(VecNorm(self.raw, ffi::NORM_2, &mut n))?;
        Ok(n)
    }

    /// # Collective
    pub fn norm_inf(&self) -> Result<f64> {
        let mut n = 0.0;
        call!(VecNorm(self.raw, ffi::NORM_INFINITY, &mut n))?;
        Ok(n)
    }

    /// Read access to this rank's entries; the array is restored when the guard drops.
    pub fn local(&self) -> Result<LocalRead<'_, 'p>> {
        let mut ptr = std::ptr::null();
        call!(VecGetArrayRead(self.raw, &mut ptr))?;
        let mut n = 0;
        call!(VecGetLocalSize(self.raw, &mut n))?;
        Ok(LocalRead {
            vec: self,
            ptr,
            len: n as usize,
        })
    }

    /// Write access to this rank's entries; the array is restored when the guard drops.
    pub fn local_mut(&mut self) -> Result<LocalWrite<'_, 'p>> {
        let mut ptr = std::ptr::null_mut();
        call!(VecGetArray(self.raw, &mut ptr))?;
        let mut n = 0;
        call!(VecGetLocalSize(self.raw, &mut n))?;
        Ok(LocalWrite {
            vec: self,
            ptr,
            len: n as usize,
        })
    }

    /// Adds values at global indices (any rank's); call [`Vector::assemble`] before use.
    pub fn add_values(&mut self, indices: &[i32], values: &[f64]) -> Result<()> {
        debug_assert_eq!(indices.len(), values.len());
        call!(VecSetValues(
            self.raw,
            indices.len() as ffi::PetscInt,
            indices.as_ptr(),
            values.as_ptr(),
            ffi::ADD_VALUES
        ))
    }

    /// Sends values added for other ranks' entries to their owners.
    ///
    /// # Collective
    pub fn assemble(&mut self) -> Result<()> {
        call!(VecAssemblyBegin(self.raw))?;
        call!(VecAssemblyEnd(self.raw))
    }

    /// `self = x .* y`
    pub fn pointwise_mult(&mut self, x: &Vector, y: &Vector) -> Result<()> {
        call!(VecPointwiseMult(self.raw, x.raw, y.raw))
    }

    /// All entries on every rank (for small vectors and tests).
    ///
    /// # Collective
    pub fn gather_all(&self) -> Result<Vec<f64>> {
        let mut scatter = std::ptr::null_mut();
        let mut seq = std::ptr::null_mut();
        call!(VecScatterCreateToAll(self.raw, &mut scatter, &mut seq))?;
        scatter_forward(scatter, self.raw, seq)?;
        let seqv = Vector::from_raw(seq);
        let out = seqv.local()?.to_vec();
        drop(seqv);
        call!(VecScatterDestroy(&mut scatter))?;
        Ok(out)
    }
}

/// `to` = the entries of `from` that `scatter` selects.
fn scatter_forward(scatter: ffi::VecScatter, from: ffi::Vec, to: ffi::Vec) -> Result<()> {
    call!(VecScatterBegin(
        scatter,
        from,
        to,
        ffi::INSERT_VALUES,
        ffi::SCATTER_FORWARD
    ))?;
    call!(VecScatterEnd(
        scatter,
        from,
        to,
        ffi::INSERT_VALUES,
        ffi::SCATTER_FORWARD
    ))
}

/// A fixed selection of a distributed vector's entries, gathered whole on every rank: the
/// scatter is built once ([`Vector::gather_all`] builds one per call, and gathers every entry).
pub struct Selection<'p> {
    scatter: ffi::VecScatter,
    seq: ffi::Vec,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> Selection<'p> {
    /// The entries `indices` (global, the same on every rank) of vectors laid out as
    /// `template`.
    ///
    /// # Collective
    pub fn new(template: &Vector<'p>, indices: &[usize]) -> Result<Self> {
        let idx: Vec<ffi::PetscInt> = indices.iter().map(|&i| i as ffi::PetscInt).collect();
        // SAFETY: MPI_COMM_SELF is a valid communicator for the whole run.
        let comm_self = unsafe { ffi::mpi_sys::RSMPI_COMM_SELF };
        let mut out = Selection {
            scatter: std::ptr::null_mut(),
            seq: std::ptr::null_mut(),
            _petsc: PhantomData,
        };
        call!(VecCreateSeq(
            comm_self,
            idx.len() as ffi::PetscInt,
            &mut out.seq
        ))?;
        let mut is = std::ptr::null_mut();
        call!(ISCreateGeneral(
            comm_self,
            idx.len() as ffi::PetscInt,
            idx.as_ptr(),
            ffi::PETSC_COPY_VALUES,
            &mut is
        ))?;
        let made = call!(VecScatterCreate(
            template.raw,
            is,
            out.seq,
            std::ptr::null_mut(),
            &mut out.scatter
        ));
        report_destroy(call!(ISDestroy(&mut is)));
        made?;
        Ok(out)
    }

    /// The selected entries of `x`, in the order of the indices given to [`Selection::new`].
    ///
    /// # Collective
    pub fn gather(&self, x: &Vector<'p>) -> Result<Vec<f64>> {
        scatter_forward(self.scatter, x.raw, self.seq)?;
        let mut n: ffi::PetscInt = 0;
        call!(VecGetLocalSize(self.seq, &mut n))?;
        let mut ptr: *const f64 = std::ptr::null();
        call!(VecGetArrayRead(self.seq, &mut ptr))?;
        // SAFETY: PETSc lends the sequential vector's n entries until VecRestoreArrayRead.
        let out = unsafe { std::slice::from_raw_parts(ptr, n as usize) }.to_vec();
        call!(VecRestoreArrayRead(self.seq, &mut ptr))?;
        Ok(out)
    }
}

impl Drop for Selection<'_> {
    fn drop(&mut self) {
        report_destroy(call!(VecScatterDestroy(&mut self.scatter)));
        report_destroy(call!(VecDestroy(&mut self.seq)));
    }
}

impl Drop for Vector<'_> {
    fn drop(&mut self) {
        report_destroy(call!(VecDestroy(&mut self.raw)));
    }
}

pub struct LocalRead<'a, 'p> {
    vec: &'a Vector<'p>,
    ptr: *const f64,
    len: usize,
}

impl Deref for LocalRead<'_, '_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: PETSc guarantees `len` valid entries until VecRestoreArrayRead.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl Drop for LocalRead<'_, '_> {
    fn drop(&mut self) {
        report_destroy(call!(VecRestoreArrayRead(self.vec.raw, &mut self.ptr)));
    }
}

pub struct LocalWrite<'a, 'p> {
    vec: &'a Vector<'p>,
    ptr: *mut f64,
    len: usize,
}

impl Deref for LocalWrite<'_, '_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: as for LocalRead; exclusive access is tied to the guard.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl DerefMut for LocalWrite<'_, '_> {
    fn deref_mut(&mut self) -> &mut [f64] {
        if self.len == 0 {
            return &mut [];
        }
        // SAFETY: as above.
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
    }
}

impl Drop for LocalWrite<'_, '_> {
    fn drop(&mut self) {
        report_destroy(call!(VecRestoreArray(self.vec.raw, &mut self.ptr)));
    }
}
