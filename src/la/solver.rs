//! Direct solves with MUMPS through PETSc's KSP: one factorization serves many solves.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::error::{call, LaError, Result};
use super::matrix::{MatrixFormat, SparseMatrix};
use super::vector::Vector;
use super::{cconst, cstr, report_destroy, Petsc};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factorization {
    /// LDL^T for symmetric matrices (SBAIJ, or AIJ marked symmetric).
    Cholesky,
    /// LU for anything.
    Lu,
}

/// What MUMPS reports about a factorization (summed over ranks).
#[derive(Debug, Clone, Copy)]
pub struct FactorizationReport {
    /// Entries in the factors (INFOG(29)).
    pub factor_entries: f64,
    /// Entries in the factors on the rank that holds most (MUMPS' INFO(27), largest over the
    /// ranks; the whole factor when every rank holds one): a solve streams at least these
    /// from one rank's memory.
    pub factor_entries_largest_rank: f64,
    /// Ordering used in the analysis (INFOG(7)): 0 AMD, 2 AMF, 3 SCOTCH, 4 PORD, 5 METIS, 6 QAMD.
    pub ordering: i32,
    /// Memory of the factorization: largest on one rank (INFOG(21)) and total (INFOG(22)), MB.
    pub memory_max_mb: i32,
    pub memory_mb: i32,
    /// Floating-point operations of the elimination (RINFOG(3)).
    pub flops: f64,
    /// Negative pivots (INFOG(12)), the inertia for a symmetric factorization.
    pub negative_pivots: i32,
}

impl FactorizationReport {
    /// Nothing known yet (or not reported by the solver): zero entries, ordering -1.
    pub fn unknown() -> Self {
        FactorizationReport {
            factor_entries: 0.0,
            factor_entries_largest_rank: 0.0,
            ordering: -1,
            memory_max_mb: 0,
            memory_mb: 0,
            flops: 0.0,
            negative_pivots: 0,
        }
    }

    pub fn ordering_name(&self) -> &'static str {
        match self.ordering {
            0 => "AMD",
            1 => "user",
            2 => "AMF",
            3 => "SCOTCH",
            4 => "PORD",
            5 => "METIS",
            6 => "QAMD",
            _ => "unknown",
        }
    }
}

/// Reads MUMPS' INFOG/RINFOG from a factored matrix and fails on a negative INFOG(1).
/// Caps MUMPS' working memory per rank (ICNTL(23), MB) at what this node can still give
/// divided among its ranks, unless the user set it: a factorization that cannot fit then
/// fails before it allocates, with INFOG(1) = -19 ([`mumps_memory_error`]), instead of being
/// killed by the kernel. Call before the options are read (KSPSetFromOptions).
pub(crate) fn cap_mumps_memory(petsc: &Petsc, prefix: &str) -> Result<()> {
    let key = format!("-{prefix}mat_mumps_icntl_23");
    if petsc.user_gave(&key) {
        return Ok(());
    }
    release_freed_memory();
    let Some(bytes) = crate::parallel::available_memory_bytes() else {
        return Ok(());
    };
    // The smallest share over ranks, so that every rank applies the same cap.
    let share = bytes / 1048576.0 / f64::from(petsc.ranks_on_node().max(1));
    let share = -crate::parallel::max(petsc.world(), -share);
    petsc.set_option(&key, Some(&format!("{}", share.floor().max(1.0) as i64)))
}

/// Hands the heap's free pages back to the system (glibc `malloc_trim`). Open MPI's memory
/// hooks keep freed memory in the process, so a factor just dropped (the previous Newton
/// iteration's, the statics' before the modes') did not show in MemAvailable and the cap
/// counted it as taken: at 600k DOF the static preload's second factorization was refused
/// (8.9 GB available with ~12 GB freed but held by the two ranks).
fn release_freed_memory() {
    extern "C" {
        fn malloc_trim(pad: usize) -> std::os::raw::c_int;
    }
    // SAFETY: malloc_trim only returns free heap pages to the system; no pointer is involved.
    unsafe {
        malloc_trim(0);
    }
}

/// The memory (INFOG(1) = -19) or singularity (-10) error of a failed factorization whose
/// factor is `factor`, if that was why.
pub(crate) fn mumps_memory_error(factor: ffi::Mat, prefix: &str) -> Option<LaError> {
    let infog = |i: i32| -> Option<i32> {
        let mut v = 0;
        call!(MatMumpsGetInfog(factor, i, &mut v)).ok()?;
        Some(v)
    };
    let icntl23 = {
        let mut v = 0;
        call!(MatMumpsGetIcntl(factor, 23, &mut v)).ok()?;
        v
    };
    match infog(1)? {
        -19 => Some(LaError::MumpsMemory {
            phase: "factorization",
            needed_mb: infog(16).unwrap_or(-1),
            ooc_mb: infog(26).unwrap_or(-1),
            allowed_mb: icntl23,
            prefix: prefix.to_string(),
        }),
        -10 => Some(LaError::SingularMatrix {
            prefix: prefix.to_string(),
            eliminated: infog(2).unwrap_or(-1),
        }),
        code @ (-8 | -9) => Some(LaError::NearlySingular {
            prefix: prefix.to_string(),
            infog1: code,
            infog2: infog(2).unwrap_or(-1),
            percent: {
                let mut v = 0;
                call!(MatMumpsGetIcntl(factor, 14, &mut v)).ok()?;
                v
            },
        }),
        _ => None,
    }
}

/// A count MUMPS reports in an int: stored as -(count / 1e6) when it overflows.
pub(crate) fn mumps_count(value: i32) -> f64 {
    if value < 0 {
        -(value as f64) * 1e6
    } else {
        value as f64
    }
}

pub(crate) fn mumps_report(factor: ffi::Mat, prefix: &str) -> Result<FactorizationReport> {
    let infog = |i: i32| -> Result<i32> {
        let mut v = 0;
        call!(MatMumpsGetInfog(factor, i, &mut v))?;
        Ok(v)
    };
    let info1 = infog(1)?;
    if let Some(e) = mumps_memory_error(factor, prefix) {
        return Err(e);
    }
    if info1 < 0 {
        return Err(LaError::Mumps {
            phase: "factorization",
            infog1: info1,
            infog2: infog(2)?,
            prefix: prefix.to_string(),
        });
    }
    let mut flops = 0.0;
    call!(MatMumpsGetRinfog(factor, 3, &mut flops))?;
    let entries = infog(29)?;
    // INFOG(29) is an int; MUMPS stores -(entries/1e6) when it overflows.
    let factor_entries = mumps_count(entries);
    let mut local = 0;
    call!(MatMumpsGetInfo(factor, 27, &mut local))?;
    Ok(FactorizationReport {
        factor_entries,
        factor_entries_largest_rank: super::csr::max_over_ranks(factor, mumps_count(local))?,
        ordering: infog(7)?,
        memory_max_mb: infog(21)?,
        memory_mb: infog(22)?,
        flops,
        negative_pivots: infog(12)?,
    })
}

/// A factored matrix ready for repeated solves (KSPPREONLY + MUMPS).
pub struct DirectSolver<'p> {
    /// Null for the single-precision factor, which PETSc does not hold.
    raw: ffi::KSP,
    single: Option<std::cell::RefCell<super::single_lu::SingleLu<'p>>>,
    prefix: String,
    report: FactorizationReport,
    _petsc: PhantomData<&'p Petsc<'p>>,
}

impl<'p> DirectSolver<'p> {
    /// Factorizes `a` with MUMPS. `prefix` names the solver's options (for example
    /// `"static_"` takes `-static_mat_mumps_icntl_7 4` from the command line).
    ///
    /// # Collective
    pub fn factorize(
        petsc: &'p Petsc,
        a: &SparseMatrix,
        kind: Factorization,
        prefix: &str,
    ) -> Result<Self> {
        let key = format!("-{prefix}mat_mumps_icntl_14");
        let mut result = Self::factorize_once(petsc, a, kind, prefix);
        if petsc.user_gave(&key) {
            return result;
        }
        // The numerical phase outgrew the work space the analysis estimated (delayed pivots:
        // the 600k brake's superelement at 35-39 bar ran out at MUMPS' default of 20 %, also
        // after a fresh analysis): again with 5x, then 20x the margin, for this solver only.
        for percent in ["400", "2000"] {
            if !matches!(result, Err(LaError::NearlySingular { .. })) {
                break;
            }
            drop(result);
            petsc.set_option(&key, Some(percent))?;
            result = Self::factorize_once(petsc, a, kind, prefix);
            petsc.clear_option(&key)?;
        }
        result
    }

    fn factorize_once(
        petsc: &'p Petsc,
        a: &SparseMatrix,
        kind: Factorization,
        prefix: &str,
    ) -> Result<Self> {
        let mut raw = std::ptr::null_mut();
        call!(KSPCreate(petsc.comm(), &mut raw))?;
        let mut solver = DirectSolver {
            raw,
            single: None,
            prefix: prefix.to_string(),
            report: FactorizationReport::unknown(),
            _petsc: PhantomData,
        };
        let p = cstr(prefix);
        call!(KSPSetOptionsPrefix(solver.raw, p.as_ptr()))?;
        call!(KSPSetOperators(solver.raw, a.raw, a.raw))?;
        call!(KSPSetType(solver.raw, cconst(ffi::KSPPREONLY)))?;
        call!(KSPSetErrorIfNotConverged(solver.raw, ffi::PETSC_TRUE))?;
        let mut pc = std::ptr::null_mut();
        call!(KSPGetPC(solver.raw, &mut pc))?;
        configure_mumps_pc(pc, a.format(), kind)?;
        cap_mumps_memory(petsc, prefix)?;
        call!(KSPSetFromOptions(solver.raw))?;
        if let Err(e) = call!(KSPSetUp(solver.raw)) {
            let mut factor = std::ptr::null_mut();
            if call!(PCFactorGetMatrix(pc, &mut factor)).is_ok() {
                return Err(mumps_memory_error(factor, prefix).unwrap_or(e));
            }
            return Err(e);
        }
        // The factor belongs to the matrix as it was now: later changes of `a` (a Newton
        // tangent updated in place) must not trigger a silent refactorization inside KSPSolve.
        call!(KSPSetReusePreconditioner(solver.raw, ffi::PETSC_TRUE))?;
        solver.report = match mumps_factor(pc)? {
            Some(factor) => mumps_report(factor, prefix)?,
            None => other_report(pc)?,
        };
        Ok(solver)
    }

    /// Factorizes `a` on every rank: the whole matrix gathered to each rank (PCREDUNDANT) and
    /// LU-factorized there by PETSc's own sequential LU (nested-dissection ordering); a solve
    /// then gathers the right-hand side, solves locally and keeps the rank's rows. For small
    /// systems solved very often (a reduced model's time-stepping Jacobian, ~2k unknowns): one
    /// solve streams the factor at one core's bandwidth, while MUMPS' distributed solve adds
    /// fixed costs that dominate at this size (benches/decisions-results.md,
    /// "per-rank-factor"). The factorization itself is not
    /// parallel and its memory is on every rank: for large systems use [`Self::factorize`].
    /// No pivoting beyond the diagonal (PETSc's LU): for matrices with a dominant diagonal,
    /// such as M / (beta h^2) + ... + K; a zero pivot is an error, not a silent result.
    /// Options under `<prefix>redundant_` reach the local solver.
    ///
    /// # Collective
    pub fn factorize_per_rank(petsc: &'p Petsc, a: &SparseMatrix, prefix: &str) -> Result<Self> {
        let mut raw = std::ptr::null_mut();
        call!(KSPCreate(petsc.comm(), &mut raw))?;
        let mut solver = DirectSolver {
            raw,
            single: None,
            prefix: prefix.to_string(),
            report: FactorizationReport::unknown(),
            _petsc: PhantomData,
        };
        let p = cstr(prefix);
        call!(KSPSetOptionsPrefix(solver.raw, p.as_ptr()))?;
        call!(KSPSetType(solver.raw, cconst(ffi::KSPPREONLY)))?;
        call!(KSPSetErrorIfNotConverged(solver.raw, ffi::PETSC_TRUE))?;
        let mut pc = std::ptr::null_mut();
        call!(KSPGetPC(solver.raw, &mut pc))?;
        if petsc.size() == 1 {
            // One rank: PCREDUNDANT would hand the MPI-type matrix to the sequential LU,
            // which refuses it; the diagonal block is the whole matrix, sequential (owned by
            // `a`, referenced by the KSP).
            let mut local = std::ptr::null_mut();
            call!(MatGetDiagonalBlock(a.raw, &mut local))?;
            call!(KSPSetOperators(solver.raw, local, local))?;
            call!(PCSetType(pc, cconst(ffi::PCLU)))?;
            call!(PCFactorSetMatSolverType(pc, cconst(ffi::MATSOLVERPETSC)))?;
            call!(PCFactorSetMatOrderingType(pc, cconst(ffi::MATORDERINGND)))?;
            call!(KSPSetFromOptions(solver.raw))?;
            call!(KSPSetUp(solver.raw))?;
            call!(KSPSetReusePreconditioner(solver.raw, ffi::PETSC_TRUE))?;
            solver.report = other_report(pc)?;
            return Ok(solver);
        }
        call!(KSPSetOperators(solver.raw, a.raw, a.raw))?;
        call!(PCSetType(pc, cconst(ffi::PCREDUNDANT)))?;
        // One copy per rank (PETSc's default splits the ranks into subgroups of one).
        call!(PCRedundantSetNumber(pc, petsc.size() as ffi::PetscInt))?;
        let mut inner_ksp = std::ptr::null_mut();
        call!(PCRedundantGetKSP(pc, &mut inner_ksp))?;
        let mut inner = std::ptr::null_mut();
        call!(KSPGetPC(inner_ksp, &mut inner))?;
        call!(PCSetType(inner, cconst(ffi::PCLU)))?;
        call!(PCFactorSetMatSolverType(inner, cconst(ffi::MATSOLVERPETSC)))?;
        call!(PCFactorSetMatOrderingType(
            inner,
            cconst(ffi::MATORDERINGND)
        ))?;
        call!(KSPSetFromOptions(solver.raw))?;
        call!(KSPSetUp(solver.raw))?;
        // The local factorization now, not at the first solve.
        call!(KSPSetUp(inner_ksp))?;
        call!(KSPSetReusePreconditioner(solver.raw, ffi::PETSC_TRUE))?;
        solver.report = match mumps_factor(inner)? {
            Some(factor) => mumps_report(factor, prefix)?,
            None => other_report(inner)?,
        };
        Ok(solver)
    }

    /// Factorizes `a` with MUMPS in single precision over all ranks (libsmumps directly:
    /// [`super::single_lu`]), LU or LDL^T as `kind` says. `prefix` only names the solver in
    /// messages: PETSc's options do not reach this factor.
    ///
    /// # Collective
    pub fn factorize_single(
        petsc: &'p Petsc,
        a: &SparseMatrix,
        kind: Factorization,
        prefix: &str,
    ) -> Result<Self> {
        let factor =
            super::single_lu::SingleLu::factorize(petsc, a, kind == Factorization::Cholesky)?;
        Ok(DirectSolver {
            raw: std::ptr::null_mut(),
            report: factor.report(),
            single: Some(std::cell::RefCell::new(factor)),
            prefix: prefix.to_string(),
            _petsc: PhantomData,
        })
    }

    pub fn report(&self) -> FactorizationReport {
        self.report
    }

    /// A single-precision factor ([`DirectSolver::factorize_single`]).
    pub fn is_single(&self) -> bool {
        self.single.is_some()
    }

    /// Whether this is a factor of the matrix `a` itself (MUMPS or another PETSc factor; the
    /// single-precision factor also needs `a`'s pattern unchanged), which
    /// [`Self::refactorize`] can renew.
    pub fn factors(&self, a: &SparseMatrix) -> Result<bool> {
        if let Some(single) = &self.single {
            return single.borrow().factors(a);
        }
        let (mut amat, mut pmat) = (std::ptr::null_mut(), std::ptr::null_mut());
        call!(KSPGetOperators(self.raw, &mut amat, &mut pmat))?;
        Ok(pmat == a.raw)
    }

    /// Factorizes `a` again after its values changed in place (same matrix, same nonzero
    /// pattern): the numerical factorization only, on the ordering and symbolic analysis of
    /// the first (MUMPS' analysis is a large part of a factorization: a Newton iteration that
    /// refreshes its tangent pays it once). PETSc redoes the analysis itself if the pattern
    /// grew. `a` must be the matrix this solver factored ([`Self::factors`]).
    ///
    /// # Collective
    pub fn refactorize(&mut self, a: &SparseMatrix) -> Result<()> {
        if let Some(single) = &self.single {
            let mut single = single.borrow_mut();
            single.refactorize(a)?;
            self.report = single.report();
            return Ok(());
        }
        if !self.factors(a)? {
            return Err(LaError::Invalid(
                "refactorize: not a PETSc factor of this matrix".into(),
            ));
        }
        call!(KSPSetReusePreconditioner(self.raw, ffi::PETSC_FALSE))?;
        call!(KSPSetOperators(self.raw, a.raw, a.raw))?;
        let mut pc = std::ptr::null_mut();
        call!(KSPGetPC(self.raw, &mut pc))?;
        if let Err(e) = call!(KSPSetUp(self.raw)) {
            let mut factor = std::ptr::null_mut();
            if call!(PCFactorGetMatrix(pc, &mut factor)).is_ok() {
                return Err(mumps_memory_error(factor, &self.prefix).unwrap_or(e));
            }
            return Err(e);
        }
        call!(KSPSetReusePreconditioner(self.raw, ffi::PETSC_TRUE))?;
        self.report = match mumps_factor(pc)? {
            Some(factor) => mumps_report(factor, &self.prefix)?,
            None => other_report(pc)?,
        };
        Ok(())
    }

    /// This factor renewed for `a`'s new values ([`Self::refactorize`]) or, where the
    /// numerical phase on the old analysis fails (short of MUMPS running out of memory, which
    /// is returned), a new factor from `fresh`, this one freed first (peak memory). The
    /// numerical phase can outgrow MUMPS' workspace where pivoting fills the factor more than
    /// the old analysis foresaw (INFOG(1) = -8 on the 100k superelement at 35-39 bar): a
    /// fresh analysis of these values (MUMPS' scaling and pivot order depend on them).
    ///
    /// # Collective
    pub fn renewed_or(
        mut self,
        a: &SparseMatrix,
        fresh: impl FnOnce() -> Result<Self>,
    ) -> Result<Self> {
        match self.refactorize(a) {
            Ok(()) => Ok(self),
            Err(e @ LaError::MumpsMemory { .. }) => Err(e),
            Err(_) => {
                drop(self);
                fresh()
            }
        }
    }

    /// Solves `A x = b` with the stored factors.
    ///
    /// # Collective
    pub fn solve(&self, b: &Vector, x: &mut Vector) -> Result<()> {
        match &self.single {
            Some(f) => f.borrow_mut().solve(b, x),
            None => call!(KSPSolve(self.raw, b.raw, x.raw)),
        }
    }

    pub fn prefix(&self) -> &str {
        &self.prefix
    }
}

/// The MUMPS factor behind `pc`, or None when options chose another solver or preconditioner.
fn mumps_factor(pc: ffi::PC) -> Result<Option<ffi::Mat>> {
    if !is_factor_pc(pc)? {
        return Ok(None);
    }
    let mut solver_type: ffi::MatSolverType = std::ptr::null();
    call!(PCFactorGetMatSolverType(pc, &mut solver_type))?;
    if solver_type.is_null() || type_name(solver_type) != "mumps" {
        return Ok(None);
    }
    let mut factor = std::ptr::null_mut();
    call!(PCFactorGetMatrix(pc, &mut factor))?;
    Ok(Some(factor))
}

fn type_name(p: *const std::os::raw::c_char) -> String {
    // SAFETY: PETSc type names are static NUL-terminated strings.
    unsafe { std::ffi::CStr::from_ptr(p) }
        .to_string_lossy()
        .into_owned()
}

/// `pc`'s type name ("" when none is set).
fn pc_type(pc: ffi::PC) -> Result<String> {
    let mut pc_type: ffi::PCType = std::ptr::null();
    call!(PCGetType(pc, &mut pc_type))?;
    Ok(if pc_type.is_null() {
        String::new()
    } else {
        type_name(pc_type)
    })
}

/// The PC inside a redundant one (PCREDUNDANT: each rank's whole copy), or `pc` itself.
fn redundant_inner(pc: ffi::PC) -> Result<ffi::PC> {
    if pc_type(pc)? != "redundant" {
        return Ok(pc);
    }
    let mut inner_ksp = std::ptr::null_mut();
    call!(PCRedundantGetKSP(pc, &mut inner_ksp))?;
    let mut inner = std::ptr::null_mut();
    call!(KSPGetPC(inner_ksp, &mut inner))?;
    Ok(inner)
}

/// Whether `pc` is a factorization (LU or Cholesky), not a redundant or other wrapper.
fn is_factor_pc(pc: ffi::PC) -> Result<bool> {
    Ok(matches!(pc_type(pc)?.as_str(), "lu" | "cholesky"))
}

/// A factorization by another solver (PETSc's own LU, or one chosen by options): the
/// factor's stored entries where PETSc knows them (MatGetInfo, summed over the ranks that
/// share the factor), the rest unknown. A redundant PC's factor is its inner (per-rank)
/// PC's: those entries are one rank's copy.
fn other_report(pc: ffi::PC) -> Result<FactorizationReport> {
    let pc = redundant_inner(pc)?;
    let mut entries = 0.0;
    let mut factor = std::ptr::null_mut();
    if is_factor_pc(pc)? && call!(PCFactorGetMatrix(pc, &mut factor)).is_ok() {
        // SAFETY: MatInfo is plain numbers (PetscLogDouble); all zeros is a valid value.
        let mut info: ffi::MatInfo = unsafe { std::mem::zeroed() };
        if call!(MatGetInfo(factor, ffi::MAT_GLOBAL_SUM, &mut info)).is_ok() {
            entries = info.nz_used;
        }
    }
    Ok(FactorizationReport {
        factor_entries: entries,
        factor_entries_largest_rank: entries,
        ..FactorizationReport::unknown()
    })
}

/// Sets a PC to a MUMPS factorization of the right kind, with an ordering that avoids the
/// PETSc 3.18 trap of handing its own nested-dissection permutation to MUMPS (TOOLCHAIN.md).
pub(crate) fn configure_mumps_pc(
    pc: ffi::PC,
    format: MatrixFormat,
    kind: Factorization,
) -> Result<()> {
    let pctype = match kind {
        Factorization::Cholesky => cconst(ffi::PCCHOLESKY),
        Factorization::Lu => cconst(ffi::PCLU),
    };
    if kind == Factorization::Lu && format == MatrixFormat::Sbaij {
        return Err(LaError::Invalid(
            "LU of an SBAIJ matrix: SBAIJ stores only the upper triangle; use Cholesky".into(),
        ));
    }
    call!(PCSetType(pc, pctype))?;
    call!(PCFactorSetMatSolverType(pc, cconst(ffi::MATSOLVERMUMPS)))?;
    call!(PCFactorSetMatOrderingType(
        pc,
        cconst(ffi::MATORDERINGEXTERNAL)
    ))
}

impl Drop for DirectSolver<'_> {
    fn drop(&mut self) {
        if self.raw.is_null() {
            return;
        }
        report_destroy(call!(KSPDestroy(&mut self.raw)));
    }
}
