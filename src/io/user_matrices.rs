//! The `matrices` model source: a model given as assembled matrices (from another code), each
//! operator a sum of Matrix Market files with coefficients, e.g.
//! K(Omega) = K1 + KR + Omega^2 KGEO.

use crate::measure::nan_max;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::matrix_market::{read, MatrixMarketError};
use crate::la::Preallocation;
use crate::la::{MatrixFormat, Petsc, SparseMatrix};

/// One term `coefficient x file` of an operator.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MatrixTerm {
    pub file: PathBuf,
    #[serde(default = "one")]
    pub coefficient: f64,
    /// The coefficient is multiplied by disc_speed^speed_power.
    #[serde(default)]
    pub speed_power: i32,
}

impl MatrixTerm {
    /// The term with disc_speed^speed_power folded into its coefficient.
    pub fn at_speed(&self, disc_speed: Option<f64>) -> MatrixTerm {
        let factor = match (self.speed_power, disc_speed) {
            (0, _) | (_, None) => 1.0,
            (p, Some(w)) => w.powi(p),
        };
        MatrixTerm {
            file: self.file.clone(),
            coefficient: self.coefficient * factor,
            speed_power: 0,
        }
    }
}

fn one() -> f64 {
    1.0
}

/// A distributed sum of user matrices, with what was learned reading it.
pub struct UserMatrix<'p> {
    pub matrix: SparseMatrix<'p>,
    /// max |a_ij - a_ji| / max |a_ij| of the sum.
    pub asymmetry: f64,
    pub rows: usize,
}

/// Rows [ranges[r], ranges[r+1]) on rank r: an even contiguous split.
pub fn row_ranges(n: usize, ranks: usize) -> Vec<usize> {
    (0..=ranks).map(|r| r * n / ranks).collect()
}

/// Reads the terms (relative paths from `base`) and assembles their weighted sum as a
/// distributed AIJ matrix, marked symmetric when it is (to 1e-12 relative).
///
/// # Collective
pub fn load_sum<'p>(
    petsc: &'p Petsc,
    terms: &[MatrixTerm],
    base: &Path,
) -> Result<UserMatrix<'p>, MatrixMarketError> {
    if terms.is_empty() {
        return Err(MatrixMarketError::NoTerms);
    }
    let mut sum: HashMap<(u32, u32), f64> = HashMap::new();
    let mut n = None;
    for term in terms {
        let path = base.join(&term.file);
        let t = read(&path)?;
        if t.rows != t.cols {
            return Err(MatrixMarketError::Parse {
                path,
                line: 0,
                message: format!("matrix is {} x {}, expected square", t.rows, t.cols),
            });
        }
        if let Some(n0) = n {
            if n0 != t.rows {
                return Err(MatrixMarketError::Parse {
                    path,
                    line: 0,
                    message: format!("matrix has {} rows, the other terms {n0}", t.rows),
                });
            }
        }
        n = Some(t.rows);
        for (i, j, v) in t.expanded() {
            *sum.entry((i, j)).or_insert(0.0) += term.coefficient * v;
        }
    }
    let n = n.unwrap();
    let max = sum.values().fold(0.0f64, |a, v| nan_max(a, v.abs()));
    let asym = sum
        .iter()
        .map(|(&(i, j), v)| (v - sum.get(&(j, i)).copied().unwrap_or(0.0)).abs())
        .fold(0.0f64, nan_max);
    let asymmetry = if max > 0.0 { asym / max } else { 0.0 };

    let ranges = row_ranges(n, petsc.size() as usize);
    let rank = petsc.rank() as usize;
    let (lo, hi) = (ranges[rank], ranges[rank + 1]);
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); hi - lo];
    for (&(i, j), &v) in &sum {
        let i = i as usize;
        if (lo..hi).contains(&i) {
            rows[i - lo].push((j, v));
        }
    }
    let mut p = Preallocation::default();
    for (r, row) in rows.iter_mut().enumerate() {
        row.sort_unstable_by_key(|e| e.0);
        let diag = row
            .iter()
            .filter(|(j, _)| (lo..hi).contains(&(*j as usize)))
            .count() as i32;
        let upper_diag = row
            .iter()
            .filter(|(j, _)| (lo..hi).contains(&(*j as usize)) && *j as usize >= lo + r)
            .count() as i32;
        let upper = row.iter().filter(|(j, _)| *j as usize >= lo + r).count() as i32;
        p.diag.push(diag);
        p.off.push(row.len() as i32 - diag);
        p.diag_upper.push(upper_diag);
        p.off_upper.push(upper - upper_diag);
    }
    let mut matrix = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, hi - lo, &p)?;
    for (r, row) in rows.iter().enumerate() {
        let cols: Vec<i32> = row.iter().map(|e| e.0 as i32).collect();
        let vals: Vec<f64> = row.iter().map(|e| e.1).collect();
        matrix.add_values(&[(lo + r) as i32], &cols, &vals)?;
    }
    matrix.assemble()?;
    matrix.set_symmetric(asymmetry <= 1e-12)?;
    Ok(UserMatrix {
        matrix,
        asymmetry,
        rows: n,
    })
}
