//! Raw FFI bindings to PETSc and SLEPc (real scalars, double precision), generated at build time.
//!
//! MPI handle types are rsmpi's (`mpi-sys`), so a communicator from `mpi` passes straight
//! through. Everything here is `unsafe`; squeal wraps it in `squeal::la`.
#![allow(
    non_upper_case_globals,
    non_camel_case_types,
    non_snake_case,
    dead_code,
    improper_ctypes,
    clippy::all
)]

include!(concat!(env!("OUT_DIR"), "/bindings.rs"));

pub use mpi_sys;
