//! Tests of the MPI suite, grouped by the reference they reproduce.

pub mod common;
pub mod convergence;
pub mod parallel_and_solvers;
pub mod real_modes_verification;

use squeal::la::Petsc;

pub fn all() -> Vec<(&'static str, fn(&Petsc) -> Result<(), String>)> {
    let mut v: Vec<(&'static str, fn(&Petsc) -> Result<(), String>)> = Vec::new();
    v.extend(real_modes_verification::tests());
    v.extend(convergence::tests());
    v.extend(parallel_and_solvers::tests());
    v
}
