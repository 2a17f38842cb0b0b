//! The safe PETSc/SLEPc layer: the only module of squeal with `unsafe`.
//!
//! Every object borrows the [`Petsc`] init guard, which itself borrows the rsmpi `Universe`, so
//! PETSc objects are destroyed before PETSc finalizes, and PETSc finalizes before MPI — by
//! construction, not by convention.

pub mod block_add;
pub mod column_block;
mod csr;
pub mod dense_quadratic;
pub mod eigen;
pub(crate) mod error;
pub mod gmres;
pub mod hessenberg;
pub mod lapack;
pub mod lapack_complex;
pub mod local_lu;
pub mod low_rank;
pub mod matrix;
pub mod observation;
pub mod one_column_gemm;
pub mod quadratic;
pub mod single_lu;

pub mod solver;
pub mod vector;

use std::ffi::CString;
use std::marker::PhantomData;
use std::os::raw::c_char;

use mpi::environment::Universe;
use mpi::topology::{Communicator, SimpleCommunicator};
use petsc_sys as ffi;

pub use block_add::BlockAddPlan;
pub use column_block::ColumnBlock;
pub use eigen::{EigenOptions, GeneralizedEigen, SymmetricEigenSolution};
use error::call;
pub use error::{DenseError, LaError, PetscError, Result};
pub use low_rank::{ColumnKey, Dominant, LowRankUpdate, TangentChange};
pub use matrix::{MatrixFormat, MatrixInfo, Operator, Preallocation, SparseMatrix};
pub use observation::ObservationMatrix;
pub use quadratic::{solve_quadratic, QuadraticEigenSolution, QuadraticOptions};
pub use solver::{DirectSolver, Factorization, FactorizationReport};
pub use vector::{Selection, Vector};

/// Bytes of one stored sparse entry in PETSc's AIJ format: its value and its column index (what
/// a product streams per entry).
pub const SPARSE_ENTRY_BYTES: f64 =
    (std::mem::size_of::<f64>() + std::mem::size_of::<ffi::PetscInt>()) as f64;

/// PETSc and SLEPc, initialized on top of an rsmpi `Universe`; finalized on drop.
pub struct Petsc<'u> {
    world: SimpleCommunicator,
    rank: i32,
    size: i32,
    /// Ranks sharing this rank's node (its memory).
    ranks_on_node: i32,
    /// The options the user gave (ours are set around them, never over them).
    user_options: Vec<String>,
    // PETSc keeps pointers into argv; they must outlive the session.
    _args: Vec<CString>,
    _argv: Vec<*mut c_char>,
    _universe: PhantomData<&'u Universe>,
}

/// Sends this process' standard output to `path` (appended): the root of a group of ranks
/// that is not the run's rank 0 keeps its console in a file instead of printing beside rank 0
/// (only rank 0 prints). Here because it needs `unsafe` (dup2).
pub fn redirect_stdout(path: &std::path::Path) -> std::io::Result<()> {
    use std::io::Write as _;
    use std::os::fd::AsRawFd;
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)?;
    std::io::stdout().flush()?;
    // SAFETY: both descriptors are open; descriptor 1 is replaced by a copy of the file's,
    // which stays open after `file` is dropped.
    let done = unsafe { libc::dup2(file.as_raw_fd(), 1) };
    if done < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

impl<'u> Petsc<'u> {
    /// Initializes PETSc and SLEPc on MPI_COMM_WORLD. `options` are PETSc command-line options
    /// (for example `-eps_ncv 300 -st_mat_mumps_icntl_7 4`), usually those after `--`.
    ///
    /// # Collective
    pub fn initialize(universe: &'u Universe, options: &[String]) -> Result<Self> {
        Self::initialize_in(universe, universe.world(), options)
    }

    /// Initializes PETSc and SLEPc on `world`, a part of MPI_COMM_WORLD (a group of ranks that
    /// works on its own: every PETSc object of this session lives on it).
    ///
    /// # Collective (on every rank of MPI_COMM_WORLD, each with its group)
    pub fn initialize_in(
        _universe: &'u Universe,
        world: SimpleCommunicator,
        options: &[String],
    ) -> Result<Self> {
        {
            use mpi::raw::AsRaw;
            // SAFETY: set before PetscInitialize, which reads it (PETSc's documented way to run
            // on a subcommunicator); the communicator outlives the session (kept in `world`).
            unsafe { ffi::PETSC_COMM_WORLD = world.as_raw() };
        }
        // PETSc's signal handlers would override Rust's (a broken pipe would end in MPI_Abort).
        let key = CString::new("-no_signal_handler").unwrap();
        call!(PetscOptionsSetValue(
            std::ptr::null_mut(),
            key.as_ptr(),
            std::ptr::null()
        ))?;
        let mut args: Vec<CString> = vec![CString::new("squeal").unwrap()];
        for o in options {
            args.push(CString::new(o.as_str()).map_err(|_| {
                LaError::Invalid(format!("PETSc option {o:?} contains a NUL byte"))
            })?);
        }
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        argv.push(std::ptr::null_mut());
        let mut argc = args.len() as i32;
        let mut argv_ptr = argv.as_mut_ptr();
        call!(SlepcInitialize(
            &mut argc,
            &mut argv_ptr,
            std::ptr::null(),
            std::ptr::null()
        ))?;
        call!(PetscPushErrorHandler(
            Some(error::record_error),
            std::ptr::null_mut()
        ))?;
        let ranks_on_node = world.split_shared(world.rank()).size();
        Ok(Petsc {
            rank: world.rank(),
            size: world.size(),
            ranks_on_node,
            user_options: options.to_vec(),
            world,
            _args: args,
            _argv: argv,
            _universe: PhantomData,
        })
    }

    pub fn rank(&self) -> i32 {
        self.rank
    }

    pub fn size(&self) -> i32 {
        self.size
    }

    /// The rsmpi communicator PETSc works on.
    pub fn world(&self) -> &SimpleCommunicator {
        &self.world
    }

    pub(crate) fn comm(&self) -> ffi::mpi_sys::MPI_Comm {
        use mpi::raw::AsRaw;
        self.world.as_raw()
    }

    /// Sets a PETSc option in the global database (as if given on the command line).
    pub fn set_option(&self, key: &str, value: Option<&str>) -> Result<()> {
        let k = CString::new(key).map_err(|_| LaError::Invalid(format!("bad option {key:?}")))?;
        let v = value.map(|v| CString::new(v).unwrap());
        call!(PetscOptionsSetValue(
            std::ptr::null_mut(),
            k.as_ptr(),
            v.as_ref().map_or(std::ptr::null(), |v| v.as_ptr())
        ))
    }

    /// Removes an option from the global database (one squeal set for a single solver).
    pub fn clear_option(&self, key: &str) -> Result<()> {
        let k = CString::new(key).map_err(|_| LaError::Invalid(format!("bad option {key:?}")))?;
        call!(PetscOptionsClearValue(std::ptr::null_mut(), k.as_ptr()))
    }

    /// Ranks sharing this rank's node.
    pub fn ranks_on_node(&self) -> i32 {
        self.ranks_on_node
    }

    /// Whether the user gave this option (not one squeal set).
    pub fn user_gave(&self, key: &str) -> bool {
        self.user_options.iter().any(|o| o == key)
    }

    /// Whether an option was given (e.g. to let command-line options override scene values).
    pub fn has_option(&self, key: &str) -> bool {
        let k = CString::new(key).unwrap();
        let mut set: ffi::PetscBool = ffi::PETSC_FALSE;
        let _ = call!(PetscOptionsHasName(
            std::ptr::null_mut(),
            std::ptr::null(),
            k.as_ptr(),
            &mut set
        ));
        set == ffi::PETSC_TRUE
    }

    /// Peak resident memory of this process so far, in bytes (the kernel's high-water mark,
    /// else PETSc's current usage).
    pub fn peak_memory(&self) -> f64 {
        if let Some(bytes) = crate::parallel::peak_rss_bytes() {
            return bytes;
        }
        let mut mem = 0.0;
        let _ = call!(PetscMemoryGetCurrentUsage(&mut mem));
        mem
    }
}

impl Drop for Petsc<'_> {
    fn drop(&mut self) {
        if let Err(e) = call!(SlepcFinalize()) {
            eprintln!("[rank {}] SlepcFinalize failed: {e}", self.rank);
        }
    }
}

/// Reports a failed XDestroy from a `Drop` (which cannot return an error).
pub(crate) fn report_destroy(result: Result<()>) {
    if let Err(e) = result {
        let rank = mpi::topology::SimpleCommunicator::world().rank();
        eprintln!("[rank {rank}] {e}");
    }
}

/// Installs a panic hook that prints the rank and the message, then calls MPI_Abort, so a
/// panic on one rank never leaves the others waiting in a collective call.
pub fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let world = SimpleCommunicator::world();
        crate::fault::say(&format!("squeal: rank {} panicked: {info}", world.rank()));
        default(info);
        world.abort(70);
    }));
}

/// Converts a Rust string into a C string for PETSc; panics only on interior NUL (a bug).
pub(crate) fn cstr(s: &str) -> CString {
    CString::new(s).expect("string passed to PETSc contains a NUL byte")
}

/// PETSc's string constants (`MATMPISBAIJ`, ...) are NUL-terminated byte arrays.
pub(crate) fn cconst(bytes: &'static [u8]) -> *const c_char {
    debug_assert_eq!(bytes.last(), Some(&0));
    bytes.as_ptr() as *const c_char
}
