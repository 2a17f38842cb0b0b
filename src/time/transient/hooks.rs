//! What a stage lends the transient to watch it with: a monitor that may end the run (the
//! saturation stop), and a sampler of the stored states (the modal sensors). time/ defines
//! them; the stages supply them from post/.

use super::Transient;
use crate::la::LaError;

/// Asked after every accepted step whether the run has seen enough.
pub trait Monitor {
    /// True: the run ends at this step. `steps`: the steps accepted so far (a restart's
    /// included); `record`: the signals so far, alike on every rank. Every rank must answer
    /// alike.
    ///
    /// # Collective
    fn stop(&mut self, steps: usize, record: &Transient) -> bool;
}

/// The run goes to its last step.
pub struct ToTheEnd;

impl Monitor for ToTheEnd {
    fn stop(&mut self, _steps: usize, _record: &Transient) -> bool {
        false
    }
}

/// The modal coordinates and velocities of one state, and its kinetic energy v'Mv/2.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalSample {
    pub eta: Vec<f64>,
    pub eta_dot: Vec<f64>,
    pub kinetic: f64,
}

/// Takes a sample of every stored state, a block of states at a time (the recorder buffers
/// them), stored beside the states.
pub trait StateSampler<'p> {
    /// The coordinates per sample.
    fn count(&self) -> usize;

    /// The samples of `states` states given by this rank's rows: `displacements` and
    /// `velocities` hold one state's rows after the other.
    ///
    /// # Collective
    fn sample_block(
        &self,
        displacements: &[f64],
        velocities: &[f64],
        states: usize,
    ) -> Result<Vec<ModalSample>, LaError>;
}
