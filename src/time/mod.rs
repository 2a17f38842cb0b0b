//! Nonlinear time integration (Newmark with a fixed Jacobian) and the transient stage.

pub mod newmark;
pub mod transient;
