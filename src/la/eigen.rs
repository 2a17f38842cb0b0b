//! Generalized symmetric eigenproblems `K x = lambda M x` with SLEPc: Krylov-Schur,
//! shift-and-invert, MUMPS Cholesky inside the spectral transform.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::matrix::SparseMatrix;
use super::solver::{
    cap_mumps_memory, configure_mumps_pc, mumps_memory_error, mumps_report, Factorization,
    FactorizationReport,
};
use super::vector::Vector;
use super::{cconst, cstr, report_destroy, Petsc};

/// What to compute, and how.
#[derive(Debug, Clone)]
pub struct EigenOptions {
    /// Number of eigenvalues nearest `shift` (ignored when `max_eigenvalue` is set).
    pub count: usize,
    /// Every eigenvalue in (`shift`, `max_eigenvalue`] by spectrum slicing (Sylvester inertia
    /// from the MUMPS factorization), instead of a fixed count.
    pub max_eigenvalue: Option<f64>,
    /// Shift sigma of shift-and-invert; below the lowest eigenvalue, eigenvalues come out in
    /// ascending order. Negative for free-free bodies (K singular).
    pub shift: f64,
    /// Krylov subspace size; None picks max(count + 30, 1.2 count) (TOOLCHAIN.md: about
    /// 1.2 x nev was fastest for 250 modes; the orthogonalization is what a large ncv costs).
    pub ncv: Option<usize>,
    /// Relative tolerance of the eigensolver.
    pub tolerance: f64,
    /// Options prefix: `-{prefix}eps_...`, `-{prefix}st_mat_mumps_icntl_...`.
    pub prefix: String,
}

impl Default for EigenOptions {
    fn default() -> Self {
        EigenOptions {
            count: 10,
            max_eigenvalue: None,
            shift: 0.0,
            ncv: None,
            tolerance: 1e-10,
            prefix: String::new(),
        }
    }
}

/// Eigenpairs in ascending order of eigenvalue; vectors M-normalized by SLEPc (GHEP).
pub struct SymmetricEigenSolution<'p> {
    pub values: Vec<f64>,
    pub vectors: Vec<Vector<'p>>,
    pub iterations: usize,
    /// The shift-and-invert factorization (None with spectrum slicing, which factors several
    /// shifts).
    pub factorization: Option<FactorizationReport>,
}

/// SLEPc EPS configured for a generalized symmetric-definite pencil.
pub struct GeneralizedEigen<'p> {
    raw: ffi::EPS,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> GeneralizedEigen<'p> {
    /// Solves `K x = lambda M x` for symmetric K and symmetric positive definite M.
    /// `mass_pattern_in_stiffness`: M's nonzero pattern is contained in K's (true for FE
    /// assembly), which makes forming K - sigma M cheap. Declared as SUBSET: with SBAIJ,
    /// SAME_NONZERO_PATTERN silently lost the shift here (rigid modes came out at sigma).
    ///
    /// # Collective
    pub fn solve(
        petsc: &'p Petsc,
        k: &SparseMatrix<'p>,
        m: &SparseMatrix,
        mass_pattern_in_stiffness: bool,
        opts: &EigenOptions,
        progress: Option<&mut dyn FnMut(usize, usize)>,
    ) -> Result<SymmetricEigenSolution<'p>> {
        let mut raw = std::ptr::null_mut();
        call!(EPSCreate(petsc.comm(), &mut raw))?;
        let eps = GeneralizedEigen {
            raw,
            _petsc: PhantomData,
        };
        let prefix = cstr(&opts.prefix);
        call!(EPSSetOptionsPrefix(eps.raw, prefix.as_ptr()))?;
        call!(EPSSetOperators(eps.raw, k.raw, m.raw))?;
        call!(EPSSetProblemType(eps.raw, ffi::EPS_GHEP))?;
        call!(EPSSetType(eps.raw, cconst(ffi::EPSKRYLOVSCHUR)))?;
        // M is positive definite once constrained DOFs are eliminated: purification would
        // cost one more solve per converged mode for nothing.
        call!(EPSSetPurify(eps.raw, ffi::PETSC_FALSE))?;
        call!(EPSSetTolerances(
            eps.raw,
            opts.tolerance,
            ffi::PETSC_DEFAULT as ffi::PetscInt
        ))?;
        let mut st = std::ptr::null_mut();
        call!(EPSGetST(eps.raw, &mut st))?;
        call!(STSetType(st, cconst(ffi::STSINVERT)))?;
        if mass_pattern_in_stiffness {
            call!(STSetMatStructure(st, ffi::SUBSET_NONZERO_PATTERN))?;
        }
        let mut ksp = std::ptr::null_mut();
        call!(STGetKSP(st, &mut ksp))?;
        call!(KSPSetType(ksp, cconst(ffi::KSPPREONLY)))?;
        call!(KSPSetErrorIfNotConverged(ksp, ffi::PETSC_TRUE))?;
        let mut pc = std::ptr::null_mut();
        call!(KSPGetPC(ksp, &mut pc))?;
        let format = k.format();
        configure_mumps_pc(pc, format, Factorization::Cholesky)?;
        let slicing = opts.max_eigenvalue.is_some();
        if let Some(upper) = opts.max_eigenvalue {
            if upper <= opts.shift {
                return Err(LaError::Invalid(format!(
                    "eigenvalue interval ({}, {upper}] is empty",
                    opts.shift
                )));
            }
            call!(EPSSetInterval(eps.raw, opts.shift, upper))?;
            // Slicing counts eigenvalues by Sylvester inertia; MUMPS must compute it for the
            // global matrix (ICNTL(13) = 1), which PETSc does not set for us in parallel.
            let key = format!("-{}st_mat_mumps_icntl_13", opts.prefix);
            if !petsc.has_option(&key) {
                petsc.set_option(&key, Some("1"))?;
            }
            call!(EPSSetWhichEigenpairs(eps.raw, ffi::EPS_ALL))?;
        } else {
            let nev = opts.count.max(1);
            let ncv = opts
                .ncv
                .unwrap_or_else(|| (nev + 30).max((1.2 * nev as f64).ceil() as usize));
            call!(EPSSetDimensions(
                eps.raw,
                nev as ffi::PetscInt,
                ncv.max(nev + 1) as ffi::PetscInt,
                ffi::PETSC_DEFAULT as ffi::PetscInt
            ))?;
            call!(EPSSetTarget(eps.raw, opts.shift))?;
            call!(EPSSetWhichEigenpairs(eps.raw, ffi::EPS_TARGET_MAGNITUDE))?;
        }
        let st_prefix = format!("{}st_", opts.prefix);
        cap_mumps_memory(petsc, &st_prefix)?;
        call!(EPSSetFromOptions(eps.raw))?;
        // The set-up factorizes K - sigma M (not with slicing, which factorizes per slice):
        // a factorization that cannot fit says so here.
        if let Err(e) = call!(EPSSetUp(eps.raw)) {
            let mut factor = std::ptr::null_mut();
            if !slicing && call!(PCFactorGetMatrix(pc, &mut factor)).is_ok() {
                return Err(mumps_memory_error(factor, &st_prefix).unwrap_or(e));
            }
            return Err(e);
        }
        // Progress: SLEPc calls the monitor after every restart with the converged count.
        let mut monitor_ctx: Option<Box<Monitor>> = progress.map(|f| Box::new(Monitor { f }));
        if let Some(ctx) = monitor_ctx.as_mut() {
            let ptr: *mut Monitor = &mut **ctx;
            call!(EPSMonitorSet(
                eps.raw,
                Some(monitor_trampoline),
                ptr as *mut std::os::raw::c_void,
                None
            ))?;
        }
        call!(EPSSolve(eps.raw))?;
        drop(monitor_ctx);

        let mut reason = 0;
        call!(EPSGetConvergedReason(eps.raw, &mut reason))?;
        let mut nconv = 0;
        call!(EPSGetConverged(eps.raw, &mut nconv))?;
        let mut its = 0;
        call!(EPSGetIterationNumber(eps.raw, &mut its))?;
        let wanted = if slicing {
            nconv as usize
        } else {
            opts.count.max(1)
        };
        if reason < 0 || (nconv as usize) < wanted {
            return Err(LaError::NotConverged {
                solver: "SLEPc EPS (real modes)",
                detail: format!(
                    "{nconv} of {wanted} eigenpairs converged in {its} iterations (reason {reason}); \
                     raise -{p}eps_max_it, enlarge -{p}eps_ncv, or loosen -{p}eps_tol",
                    p = opts.prefix
                ),
            });
        }
        let factorization = if slicing {
            None
        } else {
            let mut factor = std::ptr::null_mut();
            call!(PCFactorGetMatrix(pc, &mut factor))?;
            Some(mumps_report(factor, &format!("{}st_", opts.prefix))?)
        };

        let mut pairs = Vec::with_capacity(wanted);
        for i in 0..wanted {
            let x = k.new_vector()?;
            let (mut kr, mut ki) = (0.0, 0.0);
            call!(EPSGetEigenpair(
                eps.raw,
                i as ffi::PetscInt,
                &mut kr,
                &mut ki,
                x.raw,
                std::ptr::null_mut()
            ))?;
            pairs.push((kr, x));
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (values, vectors) = pairs.into_iter().unzip();
        let solution = SymmetricEigenSolution {
            values,
            vectors,
            iterations: its as usize,
            factorization,
        };
        Ok(solution)
    }
}

/// Context of the EPS monitor: a callback (converged count, outer iteration).
struct Monitor<'a> {
    f: &'a mut dyn FnMut(usize, usize),
}

unsafe extern "C" fn monitor_trampoline(
    _eps: ffi::EPS,
    its: ffi::PetscInt,
    nconv: ffi::PetscInt,
    _eigr: *mut ffi::PetscScalar,
    _eigi: *mut ffi::PetscScalar,
    _errest: *mut ffi::PetscReal,
    _nest: ffi::PetscInt,
    ctx: *mut std::os::raw::c_void,
) -> ffi::PetscErrorCode {
    // SAFETY: ctx is the Monitor registered above, alive for the whole EPSSolve.
    let monitor = unsafe { &mut *(ctx as *mut Monitor) };
    (monitor.f)(nconv as usize, its as usize);
    0
}

impl Drop for GeneralizedEigen<'_> {
    fn drop(&mut self) {
        report_destroy(call!(EPSDestroy(&mut self.raw)));
    }
}
