//! `squeal merge DIR... --output OUT`: the slices of one noise matrix (each a run's output
//! directory with its journal) combined into one journal, results.h5 (/matrix), the CSVs,
//! the figures and a report, as the unsliced run writes them. Slices of another scene, of
//! another slicing or overlapping ones are refused; missing slices are reported, and the
//! merged journal can be completed by `squeal run --restart --output OUT`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::io::matrix_journal::{self, Journal, JournalHeader, JournalWriter, JOURNAL};
use crate::io::results::ResultsFile;
use crate::matrix::point::PointResult;
use crate::matrix::sample::Slice;
use crate::report::matrix::MatrixReport;
use crate::stages::matrix::MatrixOutput;

/// Why slices cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("squeal merge: give at least one slice directory")]
    Nothing,
    #[error(transparent)]
    Journal(#[from] matrix_journal::JournalError),
    #[error("{}: {detail}", dir.display())]
    Refused { dir: PathBuf, detail: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] crate::io::WriteError),
    #[error(transparent)]
    Results(#[from] crate::io::results::ResultsError),
}

/// A directory's journal (or the journal file itself).
fn journal_of(dir: &Path) -> Result<Journal, MergeError> {
    let path = if dir.is_dir() {
        dir.join(JOURNAL)
    } else {
        dir.to_path_buf()
    };
    if !path.is_file() {
        let detail = format!(
            "no {JOURNAL} here: give the output directories of `squeal run --slice K/N` (or their journals)"
        );
        let dir = dir.to_path_buf();
        return Err(MergeError::Refused { dir, detail });
    }
    Ok(matrix_journal::read(&path)?)
}

/// The journals' points combined, after checking that they are slices of one matrix. Returns
/// the merged points (by index) and the first header.
pub fn combine(journals: &[Journal]) -> Result<(JournalHeader, Vec<PointResult>), MergeError> {
    let first = journals.first().ok_or(MergeError::Nothing)?;
    let h0 = &first.header;
    let refuse = |j: &Journal, detail: String| MergeError::Refused {
        dir: j.path.clone(),
        detail,
    };
    let mut points: BTreeMap<usize, PointResult> = BTreeMap::new();
    let mut slices: BTreeMap<usize, PathBuf> = BTreeMap::new();
    for j in journals {
        let h = &j.header;
        if h.fingerprint != h0.fingerprint || h.axes != h0.axes || h.total != h0.total {
            let detail = format!(
                "a slice of another scene (matrix fingerprint {}, {} points over {:?}) than {} (fingerprint {}, {} points over {:?}): merge only slices run from the same scene",
                h.fingerprint, h.total, h.axes, first.path.display(), h0.fingerprint, h0.total, h0.axes
            );
            return Err(refuse(j, detail));
        }
        let slice: Slice = h
            .slice
            .parse()
            .map_err(|e| refuse(j, format!("header: {e}")))?;
        let c0: Slice = h0
            .slice
            .parse()
            .map_err(|e| refuse(first, format!("header: {e}")))?;
        if slice.count != c0.count {
            let detail = format!(
                "slice {slice}, but {} is a slice of {}: merge slices of one --slice K/N split",
                first.path.display(),
                c0.count
            );
            return Err(refuse(j, detail));
        }
        if let Some(other) = slices.insert(slice.index, j.path.clone()) {
            let detail = format!(
                "slice {slice} is also in {}: give each slice once",
                other.display()
            );
            return Err(refuse(j, detail));
        }
        let range = slice.range(h.total);
        for p in &j.points {
            if !range.contains(&p.index) {
                let detail = format!(
                    "point {} lies outside its slice {slice} ({}..{})",
                    p.index + 1,
                    range.start + 1,
                    range.end
                );
                return Err(refuse(j, detail));
            }
            points.insert(p.index, p.clone());
        }
    }
    Ok((h0.clone(), points.into_values().collect()))
}

/// Merges the slices in `dirs` into `output`, as the points of `slice` of the matrix (the
/// whole matrix for `squeal merge`; a run's slice for the groups of that run).
///
/// # Collective (results.h5 is written by every rank of `comm`; run it on one)
pub fn merge(
    comm: &SimpleCommunicator,
    dirs: &[PathBuf],
    output: &Path,
    slice: Slice,
) -> Result<MatrixReport, MergeError> {
    use mpi::traits::Communicator;
    let journals = dirs
        .iter()
        .map(|d| journal_of(d))
        .collect::<Result<Vec<_>, _>>()?;
    let (header, points) = combine(&journals)?;
    std::fs::create_dir_all(output).map_err(|source| MergeError::Io {
        path: output.to_path_buf(),
        source,
    })?;
    let merged = JournalHeader {
        slice: slice.to_string(),
        ..header.clone()
    };
    let journal_path = output.join(JOURNAL);
    if journals.iter().any(|j| j.path == journal_path) {
        let detail = "the output directory is one of the slices: give another --output".to_string();
        return Err(MergeError::Refused {
            dir: output.to_path_buf(),
            detail,
        });
    }
    if comm.rank() == 0 {
        let mut w = JournalWriter::create(&journal_path, &merged)?;
        for p in &points {
            w.append(p)?;
        }
    }
    let run = MatrixOutput {
        axes: header.axes.clone(),
        sampling: header.sampling,
        slice,
        total: header.total,
        resumed: points.len(),
        points,
        nominal: header
            .nominal
            .iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect(),
        margin: header.margin,
    };
    let report = MatrixReport::of(run);
    let file = ResultsFile::create(comm, &output.join("results.h5"))?;
    file.set_text("/", "scene", &header.scene)?;
    crate::report::matrix::write_matrix(comm.rank(), &file, &report, output)?;
    drop(file);
    if comm.rank() == 0 {
        crate::report::matrix::write_standalone_report(&report, &header.scene, output).map_err(
            |source| MergeError::Io {
                path: output.join("report.html"),
                source,
            },
        )?;
    }
    Ok(report)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::matrix::point::Outcome;
    use crate::matrix::{Axis, Sampling};

    fn journal(slice: &str, fingerprint: &str, indices: &[usize]) -> Journal {
        Journal {
            path: PathBuf::from(format!("slice-{}", slice.replace('/', "-of-"))),
            header: JournalHeader {
                squeal_matrix: matrix_journal::FORMAT,
                fingerprint: fingerprint.into(),
                axes: vec![Axis::Mu],
                sampling: Sampling::Sobol,
                total: 10,
                slice: slice.into(),
                nominal: vec![Some(0.4)],
                margin: 1e-4,
                scene: String::new(),
            },
            points: indices
                .iter()
                .map(|&i| PointResult {
                    index: i,
                    values: vec![0.3 + 0.01 * i as f64],
                    outcome: Outcome::Failed {
                        reason: "test".into(),
                        seconds: 0.0,
                    },
                })
                .collect(),
            truncated: false,
        }
    }

    #[test]
    fn slices_combine_and_foreign_or_repeated_slices_are_refused() {
        let (a, b) = (
            journal("1/2", "f", &[0, 1, 2, 3, 4]),
            journal("2/2", "f", &[5, 7, 9]),
        );
        let (_, points) = combine(&[b.clone(), a.clone()]).unwrap();
        let idx: Vec<usize> = points.iter().map(|p| p.index).collect();
        assert_eq!(idx, vec![0, 1, 2, 3, 4, 5, 7, 9]);
        let foreign = journal("2/2", "g", &[5]);
        let err = combine(&[a.clone(), foreign]).unwrap_err().to_string();
        assert!(
            err.contains("another scene") && err.contains("slice-2-of-2"),
            "{err}"
        );
        let err = combine(&[a.clone(), a.clone()]).unwrap_err().to_string();
        assert!(err.contains("give each slice once"), "{err}");
        let err = combine(&[a.clone(), journal("2/3", "f", &[4])])
            .unwrap_err()
            .to_string();
        assert!(err.contains("--slice K/N"), "{err}");
        let err = combine(&[journal("2/2", "f", &[1])])
            .unwrap_err()
            .to_string();
        assert!(err.contains("outside its slice"), "{err}");
    }
}
