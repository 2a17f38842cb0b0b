//! Eigenvalue analyses: real modes of the structure, complex modes of a tangent state, the
//! stability of contact states on a fixed modal basis, and mode tracking by MAC.

pub mod complex_modes;
pub mod near_shift;
pub mod real_modes;
pub mod stability;
pub mod sweep;
pub mod tracking;
