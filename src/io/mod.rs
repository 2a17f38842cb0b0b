//! Storage and drawing backends (DESIGN.md §3): parallel HDF5 (results.h5, and the transient's
//! series through `crate::time::store`), XDMF, Matrix Market and user matrices, figure
//! primitives and the model preview. Nothing here knows a stage: what a run writes, and how,
//! is decided in `crate::report`.

pub mod figure;
pub mod matrix_journal;
pub mod matrix_market;
pub mod preview;
pub mod results;
pub mod series;
pub mod user_matrices;
pub mod xdmf;

use std::path::PathBuf;

/// A failure to write results: the backend's error, or the file that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error(transparent)]
    Results(#[from] results::ResultsError),
    #[error(transparent)]
    La(#[from] crate::la::LaError),
    #[error(transparent)]
    MatrixMarket(#[from] matrix_market::MatrixMarketError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}
