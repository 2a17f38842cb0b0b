//! Eigenvalue analyses: real modes of the structure (and, later, complex modes).

pub mod real_modes;
