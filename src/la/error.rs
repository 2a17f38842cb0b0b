//! Errors from PETSc/SLEPc calls: the raw code, PETSc's own message, the C function and the
//! Rust call site.

use std::cell::RefCell;
use std::ffi::CStr;
use std::fmt;
use std::os::raw::{c_char, c_int, c_void};
use std::panic::Location;

use petsc_sys as ffi;

/// A failed PETSc or SLEPc call.
#[derive(Debug, Clone)]
pub struct PetscError {
    /// PETSc's error code, kept raw (never transmuted into an enum).
    pub code: i32,
    /// The C function squeal called.
    pub function: &'static str,
    /// PETSc's message (the innermost one, with the PETSc routine that raised it).
    pub message: String,
    /// Where in squeal the call was made.
    pub location: &'static Location<'static>,
}

impl fmt::Display for PetscError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} failed (PETSc error {}): {} [called from {}:{}]",
            self.function,
            self.code,
            self.message,
            self.location.file(),
            self.location.line()
        )
    }
}

impl std::error::Error for PetscError {}

/// Errors of the linear-algebra layer.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LaError {
    #[error(transparent)]
    Petsc(#[from] PetscError),
    /// An eigensolver's solution that is not finite: the operators hold NaN or Inf.
    #[error("{what} {index} has eigenvalue {value} and backward error {backward_error}: not finite; the operators hold NaN or Inf (check the materials, matrix files and contact state)")]
    NotFinite {
        what: &'static str,
        index: usize,
        value: f64,
        backward_error: f64,
    },
    /// MUMPS reported a failure in INFOG(1) (PETSc does not always raise it).
    #[error(
        "MUMPS {phase} failed with INFOG(1) = {infog1}, INFOG(2) = {infog2} (solver prefix \
         '{prefix}'); see the MUMPS users' guide, section 'Error diagnostics'. A negative \
         INFOG(1) of -9 or -8 means the work array was too small: raise ICNTL(14) with \
         -{prefix}mat_mumps_icntl_14 50"
    )]
    Mumps {
        phase: &'static str,
        infog1: i32,
        infog2: i32,
        prefix: String,
    },
    /// MUMPS' analysis needs more memory per rank than the node can give (INFOG(1) = -19
    /// against the cap squeal sets in ICNTL(23), or the user's).
    #[error(
        "MUMPS {phase} (solver prefix '{prefix}') needs about {needed_mb} MB per rank in core \
         ({ooc_mb} MB out of core) and may use {allowed_mb} MB per rank here; it was not \
         started. Run on more ranks or nodes, or out of core with \
         -{prefix}mat_mumps_icntl_22 1, or (complex modes) use the projected route"
    )]
    MumpsMemory {
        phase: &'static str,
        needed_mb: i32,
        ooc_mb: i32,
        allowed_mb: i32,
        prefix: String,
    },
    /// MUMPS found the matrix numerically singular (INFOG(1) = -10).
    #[error(
        "the matrix of solver '{prefix}' is numerically singular (MUMPS INFOG(1) = -10 after {eliminated} eliminated pivots)"
    )]
    SingularMatrix { prefix: String, eliminated: i32 },
    /// MUMPS' numerical phase outgrew its work space (INFOG(1) = -8 or -9) even with
    /// ICNTL(14) raised to `percent`: pivots delayed by the threshold pivoting, which is what a
    /// nearly singular matrix causes.
    #[error(
        "the matrix of solver '{prefix}' is nearly singular: MUMPS' numerical factorization outgrew its work space (INFOG(1) = {infog1}, INFOG(2) = {infog2}) even with {percent} % over the analysis' estimate (ICNTL(14)); its threshold pivoting delayed that many pivots. A larger -{prefix}mat_mumps_icntl_14 may still factor it"
    )]
    NearlySingular {
        prefix: String,
        infog1: i32,
        infog2: i32,
        percent: i32,
    },
    /// An iterative solver stopped before converging.
    #[error("{solver} did not converge: {detail}")]
    NotConverged {
        solver: &'static str,
        detail: String,
    },
    /// A caller passed inconsistent arguments.
    #[error("{0}")]
    Invalid(String),
    #[error(transparent)]
    Dense(#[from] DenseError),
}

/// A dense (LAPACK) computation that cannot be done or did not succeed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DenseError {
    /// The arrays do not have the sizes the order implies.
    #[error("{what}: {found} entries for order {order}")]
    Shape {
        what: &'static str,
        found: usize,
        order: usize,
    },
    #[error("{what}: the matrix has NaN or infinite entries")]
    NotFinite { what: &'static str },
    #[error("dense order {0} is too large for LAPACK")]
    TooLarge(usize),
    /// LAPACK returned a non-zero info: the routine, its info, the order and what it means.
    #[error("LAPACK {routine} failed (info {info}) at order {order}: {meaning}")]
    Lapack {
        routine: &'static str,
        info: i32,
        order: usize,
        meaning: &'static str,
    },
    #[error("eigenvector {index} of an order-{order} problem")]
    NoEigenvector { index: usize, order: usize },
}

pub type Result<T, E = LaError> = std::result::Result<T, E>;

thread_local! {
    static LAST_MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// PETSc error handler that records the innermost message instead of printing it, so the
/// Rust error carries it. PETSc calls it once per level of its traceback.
pub(crate) unsafe extern "C" fn record_error(
    _comm: ffi::mpi_sys::MPI_Comm,
    line: c_int,
    func: *const c_char,
    file: *const c_char,
    code: ffi::PetscErrorCode,
    kind: ffi::PetscErrorType,
    message: *const c_char,
    _ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    let text = |p: *const c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: PETSc passes NUL-terminated strings or NULL.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    if kind == ffi::PETSC_ERROR_INITIAL {
        let msg = format!(
            "{} (in {} at {}:{})",
            text(message).trim(),
            text(func),
            text(file),
            line
        );
        LAST_MESSAGE.with(|m| *m.borrow_mut() = Some(msg));
    }
    code
}

/// Turns a PETSc return code into a `Result`.
#[track_caller]
pub(crate) fn check(code: ffi::PetscErrorCode, function: &'static str) -> Result<()> {
    if code == 0 {
        return Ok(());
    }
    let recorded = LAST_MESSAGE.with(|m| m.borrow_mut().take());
    let message = recorded.unwrap_or_else(|| {
        let mut text: *const c_char = std::ptr::null();
        // SAFETY: PetscErrorMessage writes a pointer to a static string.
        unsafe { ffi::PetscErrorMessage(code, &mut text, std::ptr::null_mut()) };
        if text.is_null() {
            "unknown error".into()
        } else {
            // SAFETY: static NUL-terminated string owned by PETSc.
            unsafe { CStr::from_ptr(text) }
                .to_string_lossy()
                .into_owned()
        }
    });
    Err(PetscError {
        code,
        function,
        message,
        location: Location::caller(),
    }
    .into())
}

/// Calls a PETSc function and checks its return code, naming the function in the error.
macro_rules! call {
    ($f:ident ( $($arg:expr),* $(,)? )) => {
        $crate::la::error::check(
            // SAFETY: arguments are valid PETSc handles/pointers owned by the calling wrapper.
            unsafe { petsc_sys::$f($($arg),*) },
            stringify!($f),
        )
    };
}
pub(crate) use call;
