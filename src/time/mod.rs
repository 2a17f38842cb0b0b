//! Nonlinear time integration (Newmark with a fixed Jacobian) and the transient stage.

pub mod adaptive;
pub mod newmark;
pub mod store;
pub mod transient;
