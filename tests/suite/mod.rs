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

use std::time::Duration;

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

/// How long a test may run before the suite's watchdog aborts it: about 5x its time measured on
/// 2 cores (1 and 2 ranks, the slower), at least 60 s; 3x that on more ranks than the 2 cores
/// (oversubscribed, every rank then gets part of a core).
pub fn time_limit(name: &str, ranks: i32) -> Duration {
    let seconds = LONG_TESTS
        .iter()
        .find(|(long, _)| *long == name)
        .map_or(60, |&(_, s)| s);
    Duration::from_secs(if ranks > 2 { 3 * seconds } else { seconds })
}

/// The tests that take longer than 12 s on 1 or 2 ranks, with their limit in seconds.
const LONG_TESTS: &[(&str, u64)] = &[];
