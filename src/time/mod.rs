//! Nonlinear time integration (Newmark with a fixed Jacobian).

pub mod newmark;
