//! Analyses of a trajectory (DESIGN.md §2b, §2c): spectra, the limit cycle, modal energies,
//! the contact state over the cycle, dynamic stability along it, pseudo trajectories, and
//! loudness. Arrays in, arrays out: no file access (the stored states are read through
//! `states::StateSource`); their writers live in `crate::report`.

pub mod contact_cycle;
pub mod dynamic_stability;
pub mod limit_cycle;
pub mod loudness;
pub mod modal_energy;
pub mod pseudo_contact;
pub mod pseudo_period;
pub mod pseudo_trajectory;
pub mod radiator;
pub mod spectrum;
pub mod states;
