//! Tests of the MPI suite, grouped by the reference they reproduce.

pub mod common;
pub mod complex_modes;
pub mod contact_statics;
pub mod convergence;
pub mod growth;
pub mod link;
pub mod mode_coupling;
pub mod parallel_and_solvers;
pub mod pseudo_trajectory;
pub mod real_modes_verification;
pub mod reduction;
pub mod stages;
pub mod static_solve;
pub mod stick_slip;
pub mod time_integration;

use squeal::la::Petsc;

/// A test: its name and a function that returns Ok or what went wrong.
pub type NamedTest = (&'static str, fn(&Petsc) -> Result<(), String>);

pub fn all() -> Vec<NamedTest> {
    let mut v: Vec<NamedTest> = Vec::new();
    v.extend(real_modes_verification::tests());
    v.extend(convergence::tests());
    v.extend(parallel_and_solvers::tests());
    v.extend(static_solve::tests());
    v.extend(contact_statics::tests());
    v.extend(complex_modes::tests());
    v.extend(time_integration::tests());
    v.extend(reduction::tests());
    v.extend(stages::tests());
    v.extend(stick_slip::tests());
    v.extend(mode_coupling::tests());
    v.extend(growth::tests());
    v.extend(link::tests());
    v.extend(pseudo_trajectory::tests());
    v
}
