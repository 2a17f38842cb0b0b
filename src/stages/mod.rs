//! The program as a chain of typed stages (DESIGN.md §3): each stage is a public function from
//! the previous stages' typed results to its own, callable from tests:
//!
//! Scene -> [`model::Model`] -> [`operators::Operators`] -> [`statics::Preloaded`] ->
//! [`modes::real_modes`] -> [`complex::complex_modes`] | [`sweep::SweepOutput`] |
//! [`matrix::MatrixOutput`] ->
//! [`reduce::Reduced`] -> [`transient::Trajectory`]
//!
//! Stages compute and return; they never write. `crate::pipeline` is the driver of a whole
//! run (it runs what the scene asks, in chain order, and keeps the outputs in [`Analyses`]);
//! the writers of each stage's output, the run's summary and report.html are in
//! `crate::report`.

pub mod check;
pub mod complex;
pub mod link;
pub mod loudness;
pub mod matrix;
mod matrix_lining;
mod matrix_share;
pub mod model;
pub mod modes;
pub mod motion;
pub mod operators;
pub mod parameter_shapes;
pub mod post;
pub mod pseudo;
pub mod reduce;
pub mod statics;
pub mod sweep;
pub mod transient;

use std::path::PathBuf;
use std::time::Instant;

use crate::fem::petsc::SystemError;
use crate::io::matrix_market::MatrixMarketError;
use crate::io::results::ResultsError;
use crate::la::LaError;

/// Why a run stopped; every variant names the stage (and the key or file where one applies).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("model: {0}")]
    System(#[from] SystemError),
    #[error("matrices: {0}")]
    Matrices(#[from] MatrixMarketError),
    #[error("{0}")]
    La(#[from] LaError),
    #[error("real modes need symmetric K and M; the stiffness sum has relative asymmetry {stiffness:.2e} and the mass {mass:.2e} (unsymmetric terms go under model.circulatory)")]
    Unsymmetric { stiffness: f64, mass: f64 },
    #[error("complex modes ({route} route): {mode} has eigenvalue {eigenvalue:?}: not finite; the operators hold NaN or Inf (check the materials, damping, matrix files and contact state)")]
    ComplexNotFinite {
        route: String,
        mode: String,
        eigenvalue: (f64, f64),
    },
    #[error("results: {0}")]
    Results(#[from] ResultsError),
    #[error("mesh: {0}")]
    Inp(#[from] crate::mesh::abaqus_inp::InpError),
    #[error("mesh: {0}")]
    Msh(#[from] crate::mesh::gmsh_msh::MshError),
    #[error("{0}")]
    Quality(#[from] crate::fem::quality::QualityError),
    /// An imported mesh with an inverted or degenerate element: the file to fix comes first.
    #[error("{}: {source} (elements counted from 0 in the order of the file)", file.display())]
    ImportedQuality {
        file: std::path::PathBuf,
        source: crate::fem::quality::QualityError,
    },
    #[error("brake model: {0}")]
    Brake(crate::invalid::InvalidSetting),
    /// A key out of range, found where the model is known (e.g. an interface the model lacks).
    #[error("{0}")]
    Setting(#[from] crate::invalid::InvalidSetting),
    /// A scene asks for something its other tables do not provide.
    #[error("key '{key}': {message}")]
    Scene { key: &'static str, message: String },
    #[error("{0}")]
    Contact(#[from] crate::contact::ContactError),
    #[error("{0}")]
    Statics(#[from] crate::statics::StaticError),
    #[error("model: {0}")]
    Load(#[from] crate::statics::LoadError),
    #[error("{0}")]
    Complex(#[from] complex::ComplexModesError),
    #[error("{0}")]
    Sweep(#[from] sweep::SweepError),
    #[error("{0}")]
    Reduction(#[from] reduce::ReductionError),
    #[error("{0}")]
    TransientSetup(#[from] transient::TransientSetupError),
    #[error("post: {0}")]
    States(#[from] crate::post::states::StatesError),
    #[error("transient: {0}")]
    Time(#[from] crate::time::newmark::TimeError),
    #[error("output: {0}")]
    Output(#[from] crate::io::WriteError),
    #[error("{0}")]
    Injected(#[from] crate::fault::InjectedFault),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl From<crate::post::radiator::RadiatorError> for RunError {
    fn from(e: crate::post::radiator::RadiatorError) -> Self {
        match e {
            crate::post::radiator::RadiatorError::Invalid(s) => RunError::Setting(s),
            crate::post::radiator::RadiatorError::La(e) => RunError::La(e),
        }
    }
}

impl RunError {
    pub(crate) fn scene(key: &'static str, message: impl Into<String>) -> Self {
        RunError::Scene {
            key,
            message: message.into(),
        }
    }
}

/// The model (None for user matrices), its mesh quality per block, and its operators.
pub type ModelAndOperators<'p> = (
    Option<model::Model>,
    Vec<crate::fem::quality::BlockQuality>,
    operators::Operators<'p>,
);

/// What the stages before the transient produced (each None / empty when not asked for).
pub struct Analyses<'p> {
    pub model: Option<model::Model>,
    pub quality: Vec<crate::fem::quality::BlockQuality>,
    pub ops: operators::Operators<'p>,
    pub preload: Option<statics::Preloaded<'p>>,
    pub modes: Option<crate::eigen::real_modes::RealModes<'p>>,
    pub complex: Vec<crate::eigen::complex_modes::ComplexModes<'p>>,
    pub sweep: Option<sweep::SweepOutput>,
    pub reduced: Option<reduce::Reduced<'p>>,
    /// The lining blocks' part of K0, when a noise matrix scales the lining's stiffness.
    pub lining: Option<crate::la::SparseMatrix<'p>>,
}

impl Analyses<'_> {
    /// The contact interfaces' names, in the contact model's order (empty without statics).
    pub fn interface_names(&self) -> Vec<String> {
        self.preload.as_ref().map_or(Vec::new(), |p| {
            p.contact
                .interfaces()
                .iter()
                .map(|i| i.name.clone())
                .collect()
        })
    }
}

/// Wall-clock seconds per stage, in order.
#[derive(Debug, Clone, Default)]
pub struct Timings {
    pub stages: Vec<(String, f64)>,
}

impl Timings {
    /// Runs and times a stage that can fail. A failure is agreed on by all ranks before
    /// anything is dropped ([`crate::fault::agree`]); a developer can provoke one
    /// ([`crate::fault::inject`]).
    pub fn stage<T, E: Into<RunError>>(
        &mut self,
        name: &str,
        f: impl FnOnce() -> Result<T, E>,
    ) -> Result<T, RunError> {
        let result = crate::fault::inject(name)
            .map_err(RunError::from)
            .and_then(|()| self.time(name, f).map_err(Into::into));
        crate::fault::checked(result)
    }

    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        let seconds = start.elapsed().as_secs_f64();
        // A stage run more than once (an export per format) is one entry: its total time.
        match self.stages.iter_mut().find(|(n, _)| n == name) {
            Some((_, total)) => *total += seconds,
            None => self.stages.push((name.to_string(), seconds)),
        }
        out
    }

    /// Each stage's time as the slowest rank's: the stage's wall time, and one value on every
    /// rank, so that results.h5 (written by all) and the report (by rank 0) state the same.
    ///
    /// # Collective
    pub fn slowest_rank(&mut self, comm: &mpi::topology::SimpleCommunicator) {
        use mpi::collective::{CommunicatorCollectives, SystemOperation};
        // Every stage is collective, so every rank has the same list; should one ever differ,
        // each rank keeps its own times rather than pairing unlike stages.
        let count = self.stages.len() as f64;
        if crate::parallel::max(comm, count) != -crate::parallel::max(comm, -count) {
            return;
        }
        let local: Vec<f64> = self.stages.iter().map(|(_, s)| *s).collect();
        let mut slowest = vec![0.0; local.len()];
        comm.all_reduce_into(&local[..], &mut slowest[..], SystemOperation::max());
        for ((_, seconds), s) in self.stages.iter_mut().zip(slowest) {
            *seconds = s;
        }
    }
}
