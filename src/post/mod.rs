//! Post-processing of time signals.

pub mod spectrum;
