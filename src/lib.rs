//! squeal: MPI-parallel finite elements for friction-induced instabilities (brake squeal).
//!
//! Pure-Rust kernels (`fem`, `mesh`) write into sinks; everything that talks to PETSc/SLEPc goes
//! through `la`, the only module with `unsafe`.
#![deny(unsafe_op_in_unsafe_fn)]
// Index loops over components and nodes mirror the formulas they implement.
#![allow(clippy::needless_range_loop)]
// clippy.toml bars f64::max/min from the tests' checks; the library's uses are reviewed by
// the grep of scripts/test and by measure.rs's helpers where an error measure is folded.
#![allow(clippy::disallowed_methods)]

pub mod contact;
pub mod dense;
pub mod eigen;
pub mod fault;
pub mod fem;
pub mod invalid;
pub mod io;
pub mod la;
pub mod matrix;
pub mod measure;
pub mod mesh;
pub mod parallel;
pub mod pipeline;
pub mod post;
pub mod progress;
pub mod range;
pub mod reduce;
pub mod report;
pub mod scene;
pub mod stages;
pub mod statics;
pub mod time;
