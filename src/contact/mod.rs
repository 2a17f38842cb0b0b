//! Contact and friction (DESIGN.md §2): pairing once, observation matrices C_NOR, C_TAN,
//! C_CONV as distributed sparse matrices, laws, and the contact force and tangent matrices
//! at a state. The disc mesh does not rotate (Eulerian frame): the rigid sliding speed
//! Omega r and the convection term Omega C_CONV q enter the sliding speed instead.

pub mod kernel;
pub mod law;
pub mod linearize;
mod local;
mod model;
pub mod pairing;
mod settings;
mod state;
mod summary;
pub mod surface;
pub mod tie;
pub mod vary;

pub use model::{point_rows, ContactModel};
pub use settings::{ContactSettings, InterfaceLaws, ResolvedInterface};
pub use state::ContactState;
pub use summary::InterfaceSummary;

use crate::la::LaError;

#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    #[error("contact: interface '{interface}': {side}: {source}")]
    Surface {
        interface: String,
        side: &'static str,
        source: crate::mesh::MeshError,
    },
    #[error("contact: interface '{interface}': surface '{surface}' is empty")]
    EmptySurface { interface: String, surface: String },
    #[error(
        "contact: interface '{interface}': none of the {candidates} points of surface '{master}' lies within contact.search_distance = {distance} m of surface '{slave}'; check the surfaces or raise the distance"
    )]
    NoPoints {
        interface: String,
        candidates: usize,
        master: String,
        slave: String,
        distance: f64,
    },
    #[error(
        "contact: interface '{interface}': a contact point couples DOF {dof}, which the reduction does not keep; keep every contact interface's elements"
    )]
    NotKept { interface: String, dof: i32 },
    /// A sweep's laws would turn a sliding interface into a sticking one or back.
    #[error("contact: interface '{interface}': a sweep may change a law's parameters, not whether the interface slides")]
    SlidingChanged { interface: String },
    #[error(transparent)]
    La(#[from] LaError),
}
