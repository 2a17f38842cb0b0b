//! The program as a chain of typed stages (DESIGN.md §3): each stage is a public function from
//! the previous stages' typed results to its own, callable from tests:
//!
//! Scene -> [`model::Model`] -> [`operators::Operators`] -> [`statics::Preloaded`] ->
//! [`modes::real_modes`] -> [`complex::ComplexModes`] | [`sweep::SweepOutput`] ->
//! [`reduce::Reduced`] -> [`transient::Trajectory`]
//!
//! The driver that runs what a scene asks is `crate::pipeline`; writers of each stage's
//! output live in `crate::io::output`; the run's summary is [`summary::RunSummary`].

pub mod complex;
pub mod model;
pub mod modes;
pub mod operators;
pub mod reduce;
pub mod statics;
pub mod summary;
pub mod sweep;
pub mod transient;

use std::path::PathBuf;
use std::time::Instant;

use crate::io::matrix_market::MatrixMarketError;
use crate::io::output::WriteError;
use crate::io::results::ResultsError;
use crate::la::fem_assembly::SystemError;
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
    #[error("results: {0}")]
    Results(#[from] ResultsError),
    #[error("mesh: {0}")]
    Inp(#[from] crate::mesh::abaqus_inp::InpError),
    #[error("mesh: {0}")]
    Msh(#[from] crate::mesh::gmsh_msh::MshError),
    #[error("{0}")]
    Quality(#[from] crate::mesh::quality::QualityError),
    #[error("brake model: {0}")]
    Brake(String),
    /// A scene asks for something its other tables do not provide.
    #[error("key '{key}': {message}")]
    Scene { key: &'static str, message: String },
    #[error("{0}")]
    Contact(#[from] crate::contact::ContactError),
    #[error("{0}")]
    Statics(#[from] crate::statics::StaticError),
    #[error("{0}")]
    Complex(#[from] complex::ComplexModesError),
    #[error("{0}")]
    Sweep(#[from] sweep::SweepError),
    #[error("{0}")]
    Reduction(#[from] reduce::ReductionError),
    #[error("{0}")]
    TransientSetup(#[from] transient::TransientSetupError),
    #[error("transient: {0}")]
    Time(#[from] crate::time::newmark::TimeError),
    #[error("output: {0}")]
    Output(#[from] WriteError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl RunError {
    pub(crate) fn scene(key: &'static str, message: impl Into<String>) -> Self {
        RunError::Scene {
            key,
            message: message.into(),
        }
    }
}

/// Wall-clock seconds per stage, in order.
#[derive(Debug, Clone, Default)]
pub struct Timings {
    pub stages: Vec<(String, f64)>,
}

impl Timings {
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.stages
            .push((name.to_string(), start.elapsed().as_secs_f64()));
        out
    }
}
