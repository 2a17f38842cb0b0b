//! Analyses of a trajectory (DESIGN.md §2b): spectra, the limit cycle, modal energies, the
//! contact state over the cycle and dynamic stability along it; pseudo trajectories belong
//! here too. Writers of their
//! results live in `io::output`.

pub mod contact_cycle;
pub mod dynamic_stability;
pub mod limit_cycle;
pub mod modal_energy;
pub mod pseudo_contact;
pub mod pseudo_period;
pub mod pseudo_trajectory;
pub mod spectrum;
pub mod states;
