//! Values moved between AIJ matrices whose nonzero patterns nest, through PETSc's own CSR
//! arrays of each rank's rows. PETSc's MatCopy and MatAXPY with SUBSET_NONZERO_PATTERN on a
//! distributed matrix go row by row through MatSetValues and then an assembly: at the 100k
//! brake's superelement (6.7 million stored entries) that copy of K0 into the static tangent
//! took a fifth of a noise-matrix point (perf, 2026-11-27). Here it is one merge of sorted
//! column lists per row.

use petsc_sys as ffi;
use std::ffi::CStr;

use super::error::{call, LaError, Result};
use super::matrix::SparseMatrix;

/// One sequential block of a rank's rows: the matrix itself on one rank, or the diagonal
/// and off-diagonal parts of an MPIAIJ matrix (the latter's columns numbered through
/// `colmap`, PETSc's garray, increasing).
pub(super) struct Block {
    pub(super) mat: ffi::Mat,
    pub(super) colmap: Option<*const ffi::PetscInt>,
    pub(super) rows: usize,
    ia: *const ffi::PetscInt,
    ja: *const ffi::PetscInt,
}

impl Block {
    pub(super) fn row(&self, r: usize) -> std::ops::Range<usize> {
        // SAFETY: ia has rows + 1 entries while the row structure is held (see `blocks`).
        unsafe { *self.ia.add(r) as usize..*self.ia.add(r + 1) as usize }
    }

    pub(super) fn column(&self, k: usize) -> ffi::PetscInt {
        // SAFETY: k < ia[rows] (a position of a row); colmap covers every local column index.
        unsafe {
            let j = *self.ja.add(k);
            match self.colmap {
                Some(g) => *g.add(j as usize),
                None => j,
            }
        }
    }

    pub(super) fn entries(&self) -> usize {
        // SAFETY: as in `row`.
        unsafe { *self.ia.add(self.rows) as usize }
    }
}

/// The sequential blocks of `m` with their row structure taken (give them back with
/// [`release`]), or None when `m` is not AIJ.
pub(super) fn blocks(m: ffi::Mat) -> Result<Option<Vec<Block>>> {
    let mut kind: ffi::MatType = std::ptr::null();
    call!(MatGetType(m, &mut kind))?;
    // SAFETY: PETSc returns its static type name.
    let kind = unsafe { CStr::from_ptr(kind) }.to_bytes();
    let parts = match kind {
        b"seqaij" => vec![(m, None)],
        b"mpiaij" => {
            let (mut ad, mut ao, mut colmap) =
                (std::ptr::null_mut(), std::ptr::null_mut(), std::ptr::null());
            call!(MatMPIAIJGetSeqAIJ(m, &mut ad, &mut ao, &mut colmap))?;
            vec![(ad, None), (ao, Some(colmap))]
        }
        _ => return Ok(None),
    };
    let mut out = Vec::with_capacity(parts.len());
    for (mat, colmap) in parts {
        let (mut n, mut ia, mut ja, mut done) =
            (0, std::ptr::null(), std::ptr::null(), ffi::PETSC_FALSE);
        call!(MatGetRowIJ(
            mat,
            0,
            ffi::PETSC_FALSE,
            ffi::PETSC_FALSE,
            &mut n,
            &mut ia,
            &mut ja,
            &mut done
        ))?;
        let block = Block {
            mat,
            colmap,
            rows: n as usize,
            ia,
            ja,
        };
        if done != ffi::PETSC_TRUE {
            release(&[block])?;
            release(&out)?;
            return Ok(None);
        }
        out.push(block);
    }
    Ok(Some(out))
}

pub(super) fn release(blocks: &[Block]) -> Result<()> {
    for b in blocks {
        let (mut n, mut ia, mut ja, mut done) =
            (b.rows as ffi::PetscInt, b.ia, b.ja, ffi::PETSC_FALSE);
        call!(MatRestoreRowIJ(
            b.mat,
            0,
            ffi::PETSC_FALSE,
            ffi::PETSC_FALSE,
            &mut n,
            &mut ia,
            &mut ja,
            &mut done
        ))?;
    }
    Ok(())
}

/// Calls `pair(destination position, source position)` for every stored entry of `source`
/// at its place in `destination` (same rows): false when one has no place there.
fn merge(destination: &Block, source: &Block, mut pair: impl FnMut(usize, usize)) -> bool {
    if destination.rows != source.rows {
        return false;
    }
    for r in 0..source.rows {
        let mut p = destination.row(r);
        for s in source.row(r) {
            let c = source.column(s);
            while p.start < p.end && destination.column(p.start) < c {
                p.start += 1;
            }
            if p.start == p.end || destination.column(p.start) != c {
                return false;
            }
            pair(p.start, s);
            p.start += 1;
        }
    }
    true
}

/// `destination = alpha source` (`overwrite`: other entries zeroed) or `destination += alpha
/// source`, where source's pattern is within destination's on every rank: Ok(false), with
/// nothing changed, when it is not (or either is not AIJ); the caller then takes PETSc's
/// general route. Ends with an assembly (the matrix' state advances, so a factorization of it
/// sees the change).
///
/// # Collective
pub(crate) fn add_nested(
    destination: &SparseMatrix,
    alpha: f64,
    source: &SparseMatrix,
    overwrite: bool,
) -> Result<bool> {
    let d = blocks(destination.raw)?;
    let s = match &d {
        Some(_) => blocks(source.raw)?,
        None => None,
    };
    let nested = match (&d, &s) {
        (Some(d), Some(s)) if d.len() == s.len() => {
            d.iter().zip(s).all(|(d, s)| merge(d, s, |_, _| {}))
        }
        _ => false,
    };
    // Every rank takes the same route (the assembly below and PETSc's route are collective).
    let nested = all_ranks(destination.raw, nested)?;
    let mut moved = Ok(());
    if let (true, Some(d), Some(s)) = (nested, &d, &s) {
        for (d, s) in d.iter().zip(s) {
            moved = move_values(d, s, alpha, overwrite);
            if moved.is_err() {
                break;
            }
        }
    }
    for b in [&d, &s].into_iter().flatten() {
        release(b)?;
    }
    moved?;
    if nested {
        call!(MatAssemblyBegin(destination.raw, ffi::MAT_FINAL_ASSEMBLY))?;
        call!(MatAssemblyEnd(destination.raw, ffi::MAT_FINAL_ASSEMBLY))?;
    }
    Ok(nested)
}

fn move_values(d: &Block, s: &Block, alpha: f64, overwrite: bool) -> Result<()> {
    let (mut dv, mut sv) = (std::ptr::null_mut(), std::ptr::null());
    call!(MatSeqAIJGetArray(d.mat, &mut dv))?;
    if let Err(e) = call!(MatSeqAIJGetArrayRead(s.mat, &mut sv)) {
        call!(MatSeqAIJRestoreArray(d.mat, &mut dv))?;
        return Err(e);
    }
    {
        // SAFETY: PETSc's value arrays hold ia[rows] entries each until restored; the two
        // matrices are distinct objects (a matrix is never nested in itself here).
        let dst = unsafe { std::slice::from_raw_parts_mut(dv, d.entries()) };
        let src = unsafe { std::slice::from_raw_parts(sv, s.entries()) };
        if overwrite {
            dst.fill(0.0);
        }
        merge(d, s, |p, k| dst[p] += alpha * src[k]);
    }
    call!(MatSeqAIJRestoreArrayRead(s.mat, &mut sv))?;
    call!(MatSeqAIJRestoreArray(d.mat, &mut dv))
}

/// One value of `T` reduced by `op` over the ranks of `m`'s communicator.
fn reduce_over_ranks<T: Copy>(
    m: ffi::Mat,
    x: T,
    start: T,
    datatype: ffi::mpi_sys::MPI_Datatype,
    op: ffi::mpi_sys::MPI_Op,
) -> Result<T> {
    let mut comm = ffi::mpi_sys::MPI_Comm(std::ptr::null_mut());
    call!(PetscObjectGetComm(m as ffi::PetscObject, &mut comm))?;
    let mut reduced = start;
    // SAFETY: one value each way, of the datatype the callers pair with T, on the matrix'
    // communicator, which every rank calls with.
    let code = unsafe {
        ffi::mpi_sys::MPI_Allreduce(
            (&x as *const T).cast(),
            (&mut reduced as *mut T).cast(),
            1,
            datatype,
            op,
            comm,
        )
    };
    if code != 0 {
        return Err(LaError::Invalid(format!(
            "MPI_Allreduce over the ranks of a matrix failed with code {code}"
        )));
    }
    Ok(reduced)
}

/// The largest `x` over the ranks of `m`'s communicator.
pub(super) fn max_over_ranks(m: ffi::Mat, x: f64) -> Result<f64> {
    // SAFETY (of the pairing): RSMPI_DOUBLE is f64.
    let (datatype, op) = unsafe { (ffi::mpi_sys::RSMPI_DOUBLE, ffi::mpi_sys::RSMPI_MAX) };
    reduce_over_ranks(m, x, f64::NAN, datatype, op)
}

/// Whether `ok` holds on every rank of `m`'s communicator.
pub(super) fn all_ranks(m: ffi::Mat, ok: bool) -> Result<bool> {
    // SAFETY (of the pairing): RSMPI_INT32_T is i32.
    let (datatype, op) = unsafe { (ffi::mpi_sys::RSMPI_INT32_T, ffi::mpi_sys::RSMPI_MIN) };
    Ok(reduce_over_ranks(m, i32::from(ok), 0, datatype, op)? == 1)
}
