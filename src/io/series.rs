//! Time series written as a run goes (`transient.h5`, parallel HDF5): resizable chunked
//! datasets that grow by appended rows, so an interrupted run keeps what it wrote and a
//! restart truncates them back to its checkpoint. Small signals are written by rank 0; state
//! rows by every rank (its own columns). Every dataset carries its units.

use std::ops::Range;
use std::path::Path;

use hdf5::types::VarLenUnicode;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use ndarray::{s, Array1, Array2};

use super::results::ResultsError;
use crate::time::store::{Series, Storage, StoreError, StoreResult};

pub struct SeriesFile {
    file: hdf5::File,
    path: String,
    rank: i32,
}

impl SeriesFile {
    /// Creates (truncates) the file.
    ///
    /// # Collective
    pub fn create(comm: &SimpleCommunicator, path: &Path) -> Result<Self, ResultsError> {
        Self::open_with(comm, path, true)
    }

    /// Opens an existing file for appending.
    ///
    /// # Collective
    pub fn open(comm: &SimpleCommunicator, path: &Path) -> Result<Self, ResultsError> {
        Self::open_with(comm, path, false)
    }

    fn open_with(
        comm: &SimpleCommunicator,
        path: &Path,
        create: bool,
    ) -> Result<Self, ResultsError> {
        let file = super::results::open_parallel(comm, path, create)?;
        Ok(SeriesFile {
            file,
            path: path.to_string_lossy().to_string(),
            rank: comm.rank(),
        })
    }

    fn err(&self) -> impl Fn(hdf5::Error) -> ResultsError + '_ {
        move |source| ResultsError::Hdf5 {
            path: self.path.clone(),
            source,
        }
    }

    fn group(&self, path: &str) -> Result<hdf5::Group, ResultsError> {
        super::results::group_at(&self.file, path).map_err(self.err())
    }

    /// Creates an empty series of rows of `columns` values (1: a 1D signal).
    ///
    /// # Collective
    pub fn create_series(
        &self,
        path: &str,
        columns: usize,
        units: &str,
    ) -> Result<(), ResultsError> {
        let (dir, name) = path.rsplit_once('/').unwrap_or(("", path));
        let g = self.group(dir)?;
        let builder = g.new_dataset::<f64>();
        let ds = if columns == 1 {
            builder
                .chunk(4096)
                .shape(hdf5::SimpleExtents::resizable([0]))
                .create(name)
        } else {
            let rows_per_chunk = (65536 / columns).clamp(1, 1024);
            builder
                .chunk((rows_per_chunk, columns))
                .shape(hdf5::SimpleExtents::new([
                    hdf5::Extent::resizable(0),
                    hdf5::Extent::fixed(columns),
                ]))
                .create(name)
        }
        .map_err(self.err())?;
        let v: VarLenUnicode = units.parse().unwrap();
        ds.new_attr::<VarLenUnicode>()
            .create("units")
            .map_err(self.err())?
            .write_scalar(&v)
            .map_err(self.err())
    }

    fn dataset(&self, path: &str) -> Result<hdf5::Dataset, ResultsError> {
        self.file.dataset(path).map_err(self.err())
    }

    /// Values per row of a series (1 for a signal).
    pub fn columns(&self, path: &str) -> Result<usize, ResultsError> {
        Ok(self.dataset(path)?.shape().get(1).copied().unwrap_or(1))
    }

    /// Rows in a series.
    pub fn rows(&self, path: &str) -> Result<usize, ResultsError> {
        Ok(self.dataset(path)?.shape().first().copied().unwrap_or(0))
    }

    /// Appends rows (row-major, `columns` values each; every rank passes the same values,
    /// rank 0 writes them).
    ///
    /// # Collective
    pub fn append(&self, path: &str, values: &[f64]) -> Result<(), ResultsError> {
        let ds = self.dataset(path)?;
        let shape = ds.shape();
        let columns = shape.get(1).copied().unwrap_or(1);
        let start = shape[0];
        let rows = values.len() / columns;
        if rows == 0 {
            return Ok(());
        }
        if shape.len() == 1 {
            ds.resize([start + rows]).map_err(self.err())?;
            if self.rank == 0 {
                ds.write_slice(&Array1::from(values.to_vec()), s![start..start + rows])
                    .map_err(self.err())?;
            }
        } else {
            ds.resize([start + rows, columns]).map_err(self.err())?;
            if self.rank == 0 {
                let a = Array2::from_shape_vec((rows, columns), values.to_vec())
                    .expect("rows x columns values");
                ds.write_slice(&a, s![start..start + rows, ..])
                    .map_err(self.err())?;
            }
        }
        Ok(())
    }

    /// Appends `rows` rows of a distributed vector: every rank writes `local` (row-major,
    /// `rows` x its columns) at `columns`.
    ///
    /// # Collective
    pub fn append_distributed(
        &self,
        path: &str,
        local: &[f64],
        rows: usize,
        columns: std::ops::Range<usize>,
    ) -> Result<(), ResultsError> {
        if rows == 0 {
            return Ok(());
        }
        let ds = self.dataset(path)?;
        let shape = ds.shape();
        let row = shape[0];
        ds.resize([row + rows, shape[1]]).map_err(self.err())?;
        if !columns.is_empty() {
            let a = Array2::from_shape_vec((rows, columns.len()), local.to_vec())
                .expect("rows x local columns values");
            ds.write_slice(&a, s![row..row + rows, columns.start..columns.end])
                .map_err(self.err())?;
        }
        Ok(())
    }

    /// Cuts a series back to its first `rows` rows.
    ///
    /// # Collective
    pub fn truncate(&self, path: &str, rows: usize) -> Result<(), ResultsError> {
        let ds = self.dataset(path)?;
        let mut shape = ds.shape();
        shape[0] = rows.min(shape[0]);
        ds.resize(shape).map_err(self.err())
    }

    /// A whole series (row-major), read on every rank.
    pub fn read(&self, path: &str) -> Result<Vec<f64>, ResultsError> {
        self.dataset(path)?.read_raw::<f64>().map_err(self.err())
    }

    /// This rank's `columns` of row `row` of a 2D series (one stored state's own part).
    pub fn read_row_part(
        &self,
        path: &str,
        row: usize,
        columns: std::ops::Range<usize>,
    ) -> Result<Vec<f64>, ResultsError> {
        let ds = self.dataset(path)?;
        let a: Array2<f64> = ds
            .read_slice_2d(s![row..row + 1, columns.start..columns.end])
            .map_err(self.err())?;
        Ok(a.iter().copied().collect())
    }

    /// Pushes what was written to the file, so a crash keeps it.
    ///
    /// # Collective
    pub fn flush(&self) -> Result<(), ResultsError> {
        self.file.flush().map_err(self.err())
    }
}

impl SeriesFile {
    /// A distributed vector as one 1D dataset: every rank writes its `columns`.
    ///
    /// # Collective
    pub fn write_vector(
        &self,
        path: &str,
        local: &[f64],
        columns: std::ops::Range<usize>,
        global: usize,
    ) -> Result<(), ResultsError> {
        let (dir, name) = path.rsplit_once('/').unwrap_or(("", path));
        let ds = self
            .group(dir)?
            .new_dataset::<f64>()
            .shape([global])
            .create(name)
            .map_err(self.err())?;
        if !columns.is_empty() {
            ds.write_slice(
                &Array1::from(local.to_vec()),
                s![columns.start..columns.end],
            )
            .map_err(self.err())?;
        }
        Ok(())
    }

    /// This rank's `columns` of a 1D dataset.
    pub fn read_vector(
        &self,
        path: &str,
        columns: std::ops::Range<usize>,
    ) -> Result<Vec<f64>, ResultsError> {
        let ds = self.dataset(path)?;
        let a: Array1<f64> = ds
            .read_slice_1d(s![columns.start..columns.end])
            .map_err(self.err())?;
        Ok(a.to_vec())
    }

    /// A numeric attribute of the root group.
    ///
    /// # Collective
    pub fn set_number(&self, name: &str, value: f64) -> Result<(), ResultsError> {
        let g = self.group("")?;
        let attr = g.new_attr::<f64>().create(name).map_err(self.err())?;
        attr.write_scalar(&value).map_err(self.err())
    }

    pub fn number(&self, name: &str) -> Result<f64, ResultsError> {
        self.group("")?
            .attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(self.err())
    }

    pub fn has(&self, path: &str) -> bool {
        self.file.link_exists(path)
    }
}

/// A [`SeriesFile`] failure as the integrator's storage error (the message names the file).
fn store(e: ResultsError) -> StoreError {
    StoreError(Box::new(e))
}

impl Series for SeriesFile {
    fn create_series(&self, path: &str, columns: usize, units: &str) -> StoreResult<()> {
        SeriesFile::create_series(self, path, columns, units).map_err(store)
    }
    fn columns(&self, path: &str) -> StoreResult<usize> {
        SeriesFile::columns(self, path).map_err(store)
    }
    fn rows(&self, path: &str) -> StoreResult<usize> {
        SeriesFile::rows(self, path).map_err(store)
    }
    fn append(&self, path: &str, values: &[f64]) -> StoreResult<()> {
        SeriesFile::append(self, path, values).map_err(store)
    }
    fn append_distributed(
        &self,
        path: &str,
        local: &[f64],
        rows: usize,
        columns: Range<usize>,
    ) -> StoreResult<()> {
        SeriesFile::append_distributed(self, path, local, rows, columns).map_err(store)
    }
    fn truncate(&self, path: &str, rows: usize) -> StoreResult<()> {
        SeriesFile::truncate(self, path, rows).map_err(store)
    }
    fn read(&self, path: &str) -> StoreResult<Vec<f64>> {
        SeriesFile::read(self, path).map_err(store)
    }
    fn read_row_part(
        &self,
        path: &str,
        row: usize,
        columns: Range<usize>,
    ) -> StoreResult<Vec<f64>> {
        SeriesFile::read_row_part(self, path, row, columns).map_err(store)
    }
    fn write_vector(
        &self,
        path: &str,
        local: &[f64],
        columns: Range<usize>,
        global: usize,
    ) -> StoreResult<()> {
        SeriesFile::write_vector(self, path, local, columns, global).map_err(store)
    }
    fn read_vector(&self, path: &str, columns: Range<usize>) -> StoreResult<Vec<f64>> {
        SeriesFile::read_vector(self, path, columns).map_err(store)
    }
    fn set_number(&self, name: &str, value: f64) -> StoreResult<()> {
        SeriesFile::set_number(self, name, value).map_err(store)
    }
    fn number(&self, name: &str) -> StoreResult<f64> {
        SeriesFile::number(self, name).map_err(store)
    }
    fn has(&self, path: &str) -> bool {
        SeriesFile::has(self, path)
    }
    fn flush(&self) -> StoreResult<()> {
        SeriesFile::flush(self).map_err(store)
    }
}

/// Parallel HDF5 files of series on a communicator: the integrator's [`Storage`].
pub struct Hdf5Storage<'c> {
    pub comm: &'c SimpleCommunicator,
}

impl Storage for Hdf5Storage<'_> {
    fn create(&self, path: &Path) -> StoreResult<Box<dyn Series>> {
        Ok(Box::new(
            SeriesFile::create(self.comm, path).map_err(store)?,
        ))
    }
    fn open(&self, path: &Path) -> StoreResult<Box<dyn Series>> {
        Ok(Box::new(SeriesFile::open(self.comm, path).map_err(store)?))
    }
}

impl crate::post::states::StateSource for SeriesFile {
    fn read(&self, path: &str) -> Result<Vec<f64>, crate::post::states::SourceError> {
        SeriesFile::read(self, path).map_err(|e| crate::post::states::SourceError(Box::new(e)))
    }
    fn columns(&self, path: &str) -> Result<usize, crate::post::states::SourceError> {
        SeriesFile::columns(self, path).map_err(|e| crate::post::states::SourceError(Box::new(e)))
    }
    fn read_row_part(
        &self,
        path: &str,
        row: usize,
        columns: Range<usize>,
    ) -> Result<Vec<f64>, crate::post::states::SourceError> {
        SeriesFile::read_row_part(self, path, row, columns)
            .map_err(|e| crate::post::states::SourceError(Box::new(e)))
    }
}
