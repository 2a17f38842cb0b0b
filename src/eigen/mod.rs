//! Eigenvalue analyses: real modes of the structure, complex modes of a tangent state.

pub mod complex_modes;
pub mod real_modes;
pub mod sweep;
