//! Analyses of a trajectory (DESIGN.md §2b): spectra today; modal energies, the limit cycle,
//! dynamic stability along the cycle and pseudo trajectories belong here too. Writers of their
//! results live in `io::output`.

pub mod limit_cycle;
pub mod spectrum;
