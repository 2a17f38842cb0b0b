//! What a transient streams through: its signals, stored states and checkpoints go to a
//! [`Series`] (rows appended as the run goes, truncated back on a restart) that a
//! [`Storage`] creates or opens by path. The integrator owns these traits, as fem/ owns its
//! assembly sink; `crate::io::series` implements them with parallel HDF5. Every method is
//! collective unless it only reads.

use std::ops::Range;
use std::path::Path;

/// A storage failure, with the backend's error (which names the file) as its source.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct StoreError(#[from] pub Box<dyn std::error::Error + Send + Sync>);

pub type StoreResult<T> = Result<T, StoreError>;

/// One file of growing series (datasets of rows), vectors and numbers.
pub trait Series {
    /// Creates an empty series of rows of `columns` values (1: a 1D signal), with its units.
    fn create_series(&self, path: &str, columns: usize, units: &str) -> StoreResult<()>;
    /// Values per row of a series.
    fn columns(&self, path: &str) -> StoreResult<usize>;
    /// Rows of a series.
    fn rows(&self, path: &str) -> StoreResult<usize>;
    /// Appends whole rows (rank 0's values; the others pass theirs too and write nothing).
    fn append(&self, path: &str, values: &[f64]) -> StoreResult<()>;
    /// Appends `rows` rows of which every rank holds `columns` (`local` row-major).
    fn append_distributed(
        &self,
        path: &str,
        local: &[f64],
        rows: usize,
        columns: Range<usize>,
    ) -> StoreResult<()>;
    /// Cuts a series back to `rows` rows.
    fn truncate(&self, path: &str, rows: usize) -> StoreResult<()>;
    /// A whole series, row-major.
    fn read(&self, path: &str) -> StoreResult<Vec<f64>>;
    /// `columns` of row `row`.
    fn read_row_part(&self, path: &str, row: usize, columns: Range<usize>)
        -> StoreResult<Vec<f64>>;
    /// A distributed vector of `global` values; every rank writes its `columns`.
    fn write_vector(
        &self,
        path: &str,
        local: &[f64],
        columns: Range<usize>,
        global: usize,
    ) -> StoreResult<()>;
    /// This rank's `columns` of a stored vector.
    fn read_vector(&self, path: &str, columns: Range<usize>) -> StoreResult<Vec<f64>>;
    /// A number attached to the file.
    fn set_number(&self, name: &str, value: f64) -> StoreResult<()>;
    fn number(&self, name: &str) -> StoreResult<f64>;
    fn has(&self, path: &str) -> bool;
    /// Makes what was written durable (a killed run keeps it).
    fn flush(&self) -> StoreResult<()>;
}

/// Creates and opens [`Series`] files.
pub trait Storage {
    /// Creates (truncates) the file at `path`.
    fn create(&self, path: &Path) -> StoreResult<Box<dyn Series>>;
    /// Opens an existing file for reading and appending.
    fn open(&self, path: &Path) -> StoreResult<Box<dyn Series>>;
}
