//! The states a transient stored (transient.h5 `/states`: time, displacement, velocity every
//! `transient.state_interval`), read back one at a time in the integrated unknowns' layout:
//! what the analyses of a trajectory work on. Reading them back rather than keeping them in
//! memory lets the analyses run again on a finished run (`--restart` after the last step).
//! The analyses read through [`StateSource`], which `crate::io::series` implements for HDF5.

use std::ops::Range;

use crate::contact::{ContactModel, ContactState};
use crate::la::{LaError, Petsc, Vector};
use crate::reduce::Reduction;

/// A failure of the source, with the backend's error (which names the file) as its source.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct SourceError(pub Box<dyn std::error::Error + Send + Sync>);

/// Where the stored states are read from: series of rows by name (`states/time`,
/// `states/displacement`, ...).
pub trait StateSource {
    /// A whole series, row-major.
    fn read(&self, path: &str) -> Result<Vec<f64>, SourceError>;
    /// Values per row of a series.
    fn columns(&self, path: &str) -> Result<usize, SourceError>;
    /// `columns` of row `row` (collective for a parallel file).
    fn read_row_part(
        &self,
        path: &str,
        row: usize,
        columns: Range<usize>,
    ) -> Result<Vec<f64>, SourceError>;
}

/// Why the stored states cannot be analysed.
#[derive(Debug, thiserror::Error)]
pub enum StatesError {
    #[error("{0}")]
    Source(#[from] SourceError),
    #[error("{0}")]
    La(#[from] LaError),
    #[error(
        "{path}: {found} states stored; the analyses of [post] need at least {needed} (lower 'transient.state_interval' or run longer)"
    )]
    TooFew {
        path: String,
        found: usize,
        needed: usize,
    },
    #[error(
        "{path}: the stored states have {stored} unknowns, the model has {model} (the file is from another scene)"
    )]
    Layout {
        path: String,
        stored: usize,
        model: usize,
    },
}

pub struct StoredStates<'s> {
    file: Box<dyn StateSource + 's>,
    path: String,
    pub times: Vec<f64>,
}

impl<'s> StoredStates<'s> {
    /// The states of `file` (named `name` in messages: transient.h5's path), with at least
    /// `needed` of them.
    ///
    /// # Collective
    pub fn new(
        file: Box<dyn StateSource + 's>,
        name: String,
        needed: usize,
    ) -> Result<Self, StatesError> {
        let times = file.read("states/time")?;
        if times.len() < needed {
            return Err(StatesError::TooFew {
                path: name,
                found: times.len(),
                needed,
            });
        }
        Ok(StoredStates {
            file,
            path: name,
            times,
        })
    }

    pub fn len(&self) -> usize {
        self.times.len()
    }

    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// The stored state nearest to time `t` (0 when there is none).
    pub fn nearest(&self, t: f64) -> usize {
        nearest(&self.times, t)
    }

    /// The end of the analysed window: the last cycle start at or before the last stored
    /// state, else the last stored state.
    pub fn window_end(&self, cycle_starts: &[f64]) -> f64 {
        let last = self.times.last().copied().unwrap_or(0.0);
        cycle_starts
            .iter()
            .rev()
            .copied()
            .find(|&t| t <= last)
            .unwrap_or(last)
    }

    /// The stored states at times in [from, to].
    pub fn between(&self, from: f64, to: f64) -> Vec<usize> {
        (0..self.len())
            .filter(|&i| self.times[i] >= from && self.times[i] <= to)
            .collect()
    }

    /// The modal samples the transient took with the states (`modes` real modes).
    pub fn modal_samples(
        &self,
        modes: usize,
    ) -> Result<Vec<crate::post::modal_energy::ModalSample>, StatesError> {
        let eta = self.file.read("states/modal_coordinate")?;
        let eta_dot = self.file.read("states/modal_velocity")?;
        let kinetic = self.file.read("states/kinetic_energy")?;
        let rows = kinetic.len().min(self.len());
        if eta.len() < rows * modes || eta_dot.len() < rows * modes {
            return Err(StatesError::Layout {
                path: self.path.clone(),
                stored: eta.len() / rows.max(1),
                model: modes,
            });
        }
        Ok((0..rows)
            .map(|i| crate::post::modal_energy::ModalSample {
                eta: eta[i * modes..(i + 1) * modes].to_vec(),
                eta_dot: eta_dot[i * modes..(i + 1) * modes].to_vec(),
                kinetic: kinetic[i],
            })
            .collect())
    }

    /// State `k` into `q` and `v` (each rank reads its own part).
    ///
    /// # Collective
    pub fn read<'p>(
        &self,
        k: usize,
        q: &mut Vector<'p>,
        v: &mut Vector<'p>,
    ) -> Result<(), StatesError> {
        let columns = q.ownership();
        let stored = self.file.columns("states/displacement")?;
        if stored != q.global_len() {
            return Err(StatesError::Layout {
                path: self.path.clone(),
                stored,
                model: q.global_len(),
            });
        }
        for (path, x) in [("states/displacement", q), ("states/velocity", v)] {
            let part = self.file.read_row_part(path, k, columns.clone())?;
            x.local_mut()?.copy_from_slice(&part);
        }
        Ok(())
    }
}

/// How the stored states map to the full model's unknowns (where the contact is observed).
pub enum Lift<'a> {
    Full,
    Reduced(&'a Reduction),
}

/// The full model's contact evaluated at stored states.
pub struct ContactAt<'a, 'p> {
    pub petsc: &'p Petsc<'p>,
    pub contact: &'a ContactModel<'p>,
    pub lift: Lift<'a>,
    /// A full-model vector (its layout) and one of the stored states' layout.
    pub full_template: &'a Vector<'p>,
    pub state_template: &'a Vector<'p>,
}

impl ContactAt<'_, '_> {
    /// The contact state (gaps, slips, sliding speeds and the laws' response) at state `k`.
    ///
    /// # Collective
    pub fn state(&self, states: &StoredStates, k: usize) -> Result<ContactState, StatesError> {
        let mut x = self.state_template.duplicate()?;
        let mut xv = self.state_template.duplicate()?;
        states.read(k, &mut x, &mut xv)?;
        Ok(match self.lift {
            Lift::Full => self.contact.evaluate(&x, Some(&xv), 1.0)?,
            Lift::Reduced(r) => {
                let mut q = self.full_template.duplicate()?;
                let mut v = self.full_template.duplicate()?;
                r.recover(self.petsc, &x, &mut q)?;
                r.recover(self.petsc, &xv, &mut v)?;
                self.contact.evaluate(&q, Some(&v), 1.0)?
            }
        })
    }
}

/// Index of the time nearest to `t` (0 for an empty list).
pub fn nearest(times: &[f64], t: f64) -> usize {
    (0..times.len())
        .min_by(|&a, &b| (times[a] - t).abs().total_cmp(&(times[b] - t).abs()))
        .unwrap_or(0)
}
