//! The contact response of a model's points at one state.

use super::kernel::{Observed, PointResponse};

/// The contact response of this rank's points at one state.
#[derive(Debug, Clone)]
pub struct ContactState {
    pub observed: Vec<Observed>,
    pub response: Vec<PointResponse>,
    pub friction_scale: f64,
}
