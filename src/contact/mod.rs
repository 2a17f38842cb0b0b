//! Contact and friction (DESIGN.md §2): pairing once, observation matrices C_NOR, C_TAN,
//! C_CONV as distributed sparse matrices, laws, and the contact force and tangent matrices
//! at a state. The disc mesh does not rotate (Eulerian frame): the rigid sliding speed
//! Omega r and the convection term Omega C_CONV q enter the sliding speed instead.

pub mod kernel;
pub mod law;
pub mod linearize;
mod model;
pub mod pairing;
mod settings;
mod state;
mod summary;
pub mod surface;

pub use model::{point_rows, ContactModel};
pub use settings::{ContactSettings, InterfaceLaws, ResolvedInterface};
pub use state::ContactState;
pub use summary::InterfaceSummary;

use crate::la::LaError;

#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    #[error("contact: {0}")]
    Setup(String),
    /// A sweep's laws would turn a sliding interface into a sticking one or back.
    #[error("contact: interface '{interface}': a sweep may change a law's parameters, not whether the interface slides")]
    SlidingChanged { interface: String },
    #[error(transparent)]
    La(#[from] LaError),
}
