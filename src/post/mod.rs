//! Analyses of a trajectory (DESIGN.md §2b): spectra, the limit cycle, modal energies and
//! dynamic stability along the cycle; pseudo trajectories belong here too. Writers of their
//! results live in `io::output`.

pub mod dynamic_stability;
pub mod limit_cycle;
pub mod modal_energy;
pub mod spectrum;
pub mod states;
