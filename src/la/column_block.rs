//! Chosen columns of a distributed sparse matrix, this rank's rows of them, stored by column:
//! the product with a vector that is zero outside a few of those columns costs their entries
//! alone, with no communication when every rank knows those few values. A nonlinear
//! elimination moves ~1,000 of the 600k brake's 35,000 reduced unknowns and needs the
//! linear force's change that move makes: a full product streams the whole operator (9.4e6
//! stored entries) for ~3 % of it.

use super::error::Result;
use super::matrix::{MatrixFormat, SparseMatrix};

/// The columns `columns` (ascending global indices, the same on every rank) of a matrix,
/// restricted to this rank's rows, in compressed-column form.
#[derive(Debug, Clone)]
pub struct ColumnBlock {
    /// This rank's rows of the matrix (global indices).
    own: std::ops::Range<usize>,
    /// Where each chosen column's entries start (one past the last column's end at the end).
    start: Vec<usize>,
    /// The entries' rows, relative to `own.start`, ascending within a column.
    rows: Vec<u32>,
    values: Vec<f64>,
}

impl ColumnBlock {
    /// Takes the columns `columns` of `a` on this rank's rows (a's AIJ form; other formats
    /// are converted first, which is collective).
    ///
    /// # Collective
    pub fn new(a: &SparseMatrix, columns: &[usize]) -> Result<Self> {
        let converted;
        let a = match a.format() {
            MatrixFormat::Aij => a,
            _ => {
                converted = a.convert(MatrixFormat::Aij)?;
                &converted
            }
        };
        let mut position = vec![u32::MAX; a.global_rows()];
        for (p, &c) in columns.iter().enumerate() {
            position[c] = p as u32;
        }
        let own = a.ownership();
        // Two passes over the rows (count, then fill): rows visited in ascending order leave
        // each column's rows ascending, with no sort.
        let mut start = vec![0usize; columns.len() + 1];
        a.for_each_local_row(|_, cols, _| {
            for &c in cols {
                let p = position[c as usize];
                if p != u32::MAX {
                    start[p as usize + 1] += 1;
                }
            }
        })?;
        for p in 0..columns.len() {
            start[p + 1] += start[p];
        }
        let mut next = start.clone();
        let mut rows = vec![0u32; start[columns.len()]];
        let mut values = vec![0.0; start[columns.len()]];
        a.for_each_local_row(|row, cols, vals| {
            for (&c, &v) in cols.iter().zip(vals) {
                let p = position[c as usize];
                if p != u32::MAX {
                    let k = &mut next[p as usize];
                    rows[*k] = (row - own.start) as u32;
                    values[*k] = v;
                    *k += 1;
                }
            }
        })?;
        Ok(ColumnBlock {
            own,
            start,
            rows,
            values,
        })
    }

    /// This rank's rows (global indices): the local part `mult_add` writes.
    pub fn ownership(&self) -> std::ops::Range<usize> {
        self.own.clone()
    }

    /// Stored entries on this rank.
    pub fn entries(&self) -> usize {
        self.values.len()
    }

    /// y += scale A x on this rank's rows, x given by its nonzero entries as (position in the
    /// chosen columns, value). `y`: the local part of a vector with the matrix's row layout.
    pub fn mult_add(&self, scale: f64, x: impl IntoIterator<Item = (usize, f64)>, y: &mut [f64]) {
        debug_assert_eq!(y.len(), self.own.len());
        for (p, xp) in x {
            let s = scale * xp;
            for k in self.start[p]..self.start[p + 1] {
                y[self.rows[k] as usize] += s * self.values[k];
            }
        }
    }
}
