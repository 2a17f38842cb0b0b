//! Nonlinear time integration (Newmark with a fixed Jacobian) and the transient stage.

pub mod adaptive;
pub mod newmark;
pub mod transient;
