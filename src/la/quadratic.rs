//! Quadratic (and nonsymmetric) eigenproblems `(lambda^2 M + lambda C + K) x = 0` with SLEPc's
//! PEP (TOAR) in real arithmetic: complex eigenvalues come as conjugate pairs.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::matrix::SparseMatrix;
use super::solver::{cap_mumps_memory, configure_mumps_pc, mumps_memory_error, Factorization};
use super::vector::Vector;
use super::{cconst, cstr, report_destroy, Petsc};

#[derive(Debug, Clone)]
pub struct QuadraticOptions {
    /// Number of eigenvalues nearest `target` (a conjugate pair counts as two).
    pub count: usize,
    /// Real shift of shift-and-invert.
    pub target: f64,
    pub tolerance: f64,
    /// Scalar scaling of lambda (brake matrices: |M| ~ 1e-3, |K| ~ 1e11, see TOOLCHAIN.md).
    pub scale: bool,
    pub prefix: String,
}

impl Default for QuadraticOptions {
    fn default() -> Self {
        QuadraticOptions {
            count: 10,
            target: 0.0,
            tolerance: 1e-10,
            scale: true,
            prefix: String::new(),
        }
    }
}

/// Eigenvalue `re + i im` with eigenvector `xr + i xi`; conjugate pairs both listed.
pub struct QuadraticEigenSolution<'p> {
    pub values: Vec<(f64, f64)>,
    pub vectors: Vec<(Vector<'p>, Vector<'p>)>,
    /// PEP's backward error of every pair.
    pub backward_errors: Vec<f64>,
    pub iterations: usize,
}

struct Pep<'p> {
    raw: ffi::PEP,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl Drop for Pep<'_> {
    fn drop(&mut self) {
        report_destroy(call!(PEPDestroy(&mut self.raw)));
    }
}

/// Solves the quadratic problem with coefficient matrices `k`, `c`, `m` (any of them may be
/// unsymmetric; LU with MUMPS inside the spectral transform).
///
/// # Collective
pub fn solve_quadratic<'p>(
    petsc: &'p Petsc,
    k: &SparseMatrix<'p>,
    c: &SparseMatrix,
    m: &SparseMatrix,
    opts: &QuadraticOptions,
) -> Result<QuadraticEigenSolution<'p>> {
    let mut raw = std::ptr::null_mut();
    call!(PEPCreate(petsc.comm(), &mut raw))?;
    let pep = Pep {
        raw,
        _petsc: PhantomData,
    };
    let prefix = cstr(&opts.prefix);
    call!(PEPSetOptionsPrefix(pep.raw, prefix.as_ptr()))?;
    let mut mats = [k.raw, c.raw, m.raw];
    call!(PEPSetOperators(pep.raw, 3, mats.as_mut_ptr()))?;
    call!(PEPSetType(pep.raw, cconst(ffi::PEPTOAR)))?;
    call!(PEPSetProblemType(pep.raw, ffi::PEP_GENERAL))?;
    if opts.scale {
        call!(PEPSetScale(
            pep.raw,
            ffi::PEP_SCALE_SCALAR,
            ffi::PETSC_DEFAULT as f64,
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            ffi::PETSC_DEFAULT as ffi::PetscInt,
            ffi::PETSC_DEFAULT as f64
        ))?;
    }
    let nev = opts.count.max(1);
    call!(PEPSetDimensions(
        pep.raw,
        nev as ffi::PetscInt,
        ffi::PETSC_DEFAULT as ffi::PetscInt,
        ffi::PETSC_DEFAULT as ffi::PetscInt
    ))?;
    call!(PEPSetTolerances(
        pep.raw,
        opts.tolerance,
        ffi::PETSC_DEFAULT as ffi::PetscInt
    ))?;
    call!(PEPSetTarget(pep.raw, opts.target))?;
    call!(PEPSetWhichEigenpairs(pep.raw, ffi::PEP_TARGET_MAGNITUDE))?;
    let mut st = std::ptr::null_mut();
    call!(PEPGetST(pep.raw, &mut st))?;
    call!(STSetType(st, cconst(ffi::STSINVERT)))?;
    let mut ksp = std::ptr::null_mut();
    call!(STGetKSP(st, &mut ksp))?;
    call!(KSPSetType(ksp, cconst(ffi::KSPPREONLY)))?;
    call!(KSPSetErrorIfNotConverged(ksp, ffi::PETSC_TRUE))?;
    let mut pc = std::ptr::null_mut();
    call!(KSPGetPC(ksp, &mut pc))?;
    configure_mumps_pc(pc, k.format(), Factorization::Lu)?;
    let st_prefix = format!("{}st_", opts.prefix);
    cap_mumps_memory(petsc, &st_prefix)?;
    call!(PEPSetFromOptions(pep.raw))?;
    // The set-up factorizes the shifted operator: a factorization that cannot fit says so.
    if let Err(e) = call!(PEPSetUp(pep.raw)) {
        let mut factor = std::ptr::null_mut();
        if call!(PCFactorGetMatrix(pc, &mut factor)).is_ok() {
            return Err(mumps_memory_error(factor, &st_prefix).unwrap_or(e));
        }
        return Err(e);
    }
    call!(PEPSolve(pep.raw))?;

    let mut reason = 0;
    call!(PEPGetConvergedReason(pep.raw, &mut reason))?;
    let mut nconv = 0;
    call!(PEPGetConverged(pep.raw, &mut nconv))?;
    let mut its = 0;
    call!(PEPGetIterationNumber(pep.raw, &mut its))?;
    if reason < 0 || (nconv as usize) < nev {
        return Err(LaError::NotConverged {
            solver: "SLEPc PEP (quadratic eigenproblem)",
            detail: format!(
                "{nconv} of {nev} eigenpairs converged in {its} iterations (reason {reason}); \
                 raise -{p}pep_max_it or -{p}pep_ncv",
                p = opts.prefix
            ),
        });
    }
    let mut solution = QuadraticEigenSolution {
        values: Vec::new(),
        vectors: Vec::new(),
        backward_errors: Vec::new(),
        iterations: its as usize,
    };
    for i in 0..nconv as usize {
        let xr = k.new_vector()?;
        let xi = k.new_vector()?;
        let (mut re, mut im) = (0.0, 0.0);
        call!(PEPGetEigenpair(
            pep.raw,
            i as ffi::PetscInt,
            &mut re,
            &mut im,
            xr.raw,
            xi.raw
        ))?;
        let mut err = 0.0;
        call!(PEPComputeError(
            pep.raw,
            i as ffi::PetscInt,
            ffi::PEP_ERROR_BACKWARD,
            &mut err
        ))?;
        solution.values.push((re, im));
        solution.vectors.push((xr, xi));
        solution.backward_errors.push(err);
    }
    if solution.values.is_empty() {
        return Err(LaError::NotConverged {
            solver: "SLEPc PEP",
            detail: "no eigenpair converged".into(),
        });
    }
    Ok(solution)
}
