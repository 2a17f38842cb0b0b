//! The noise matrix' journal, `matrix-points.jsonl`: a header line (the scene's matrix
//! fingerprint, the axes, the slice) and one JSON line per finished point, appended and
//! flushed as each finishes. A killed run resumes from it (`squeal run --restart`), and
//! `squeal merge` combines the journals of slices. A last line cut by a kill is ignored.

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::matrix::point::PointResult;
use crate::matrix::{Axis, Sampling};

/// The journal's name in an output directory.
pub const JOURNAL: &str = "matrix-points.jsonl";

/// Format version of the header (a journal of another version is refused).
pub const FORMAT: u32 = 1;

/// The journal's first line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JournalHeader {
    pub squeal_matrix: u32,
    /// `Scene::matrix_fingerprint` of the scene that computed the points.
    pub fingerprint: String,
    pub axes: Vec<Axis>,
    pub sampling: Sampling,
    /// Points of the whole matrix.
    pub total: usize,
    /// "K/N".
    pub slice: String,
    /// The scene's value of each axis (NaN as null).
    pub nominal: Vec<Option<f64>>,
    /// Damping ratio below -margin counts as unstable.
    pub margin: f64,
    /// The scene's text, for the merged report.
    pub scene: String,
}

/// Why a journal cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}, line {line}: {detail}", path.display())]
    Malformed {
        path: PathBuf,
        line: usize,
        detail: String,
    },
}

/// A journal read back: its header and its complete point lines.
#[derive(Debug, Clone)]
pub struct Journal {
    pub path: PathBuf,
    pub header: JournalHeader,
    pub points: Vec<PointResult>,
    /// A last line cut short (a run killed while writing it), left out.
    pub truncated: bool,
}

/// Reads a journal. A malformed line other than the last is an error naming it.
pub fn read(path: &Path) -> Result<Journal, JournalError> {
    let io = |source| JournalError::Io {
        path: path.to_path_buf(),
        source,
    };
    let malformed = |line: usize, detail: String| JournalError::Malformed {
        path: path.to_path_buf(),
        line,
        detail,
    };
    let lines: Vec<String> = BufReader::new(File::open(path).map_err(io)?)
        .lines()
        .collect::<Result<_, _>>()
        .map_err(io)?;
    let first = lines
        .first()
        .ok_or_else(|| malformed(1, "empty: no header line".into()))?;
    let header: JournalHeader = serde_json::from_str(first)
        .map_err(|e| malformed(1, format!("not a squeal matrix journal header ({e})")))?;
    if header.squeal_matrix != FORMAT {
        let detail = format!(
            "journal format {}, this squeal writes {FORMAT}",
            header.squeal_matrix
        );
        return Err(malformed(1, detail));
    }
    let mut points = Vec::with_capacity(lines.len() - 1);
    let mut truncated = false;
    for (k, line) in lines.iter().enumerate().skip(1) {
        match serde_json::from_str::<PointResult>(line) {
            Ok(p) if p.index < header.total && p.values.len() == header.axes.len() => {
                points.push(p)
            }
            Ok(p) => {
                let detail = format!(
                    "point {} with {} values does not belong to a matrix of {} points over {} axes",
                    p.index,
                    p.values.len(),
                    header.total,
                    header.axes.len()
                );
                return Err(malformed(k + 1, detail));
            }
            Err(_) if k + 1 == lines.len() => truncated = true,
            Err(e) => return Err(malformed(k + 1, format!("not a point ({e})"))),
        }
    }
    Ok(Journal {
        path: path.to_path_buf(),
        header,
        points,
        truncated,
    })
}

/// Appends points to a journal, one flushed line each.
pub struct JournalWriter {
    path: PathBuf,
    file: File,
}

impl JournalWriter {
    /// A new journal (replacing any) with its header.
    pub fn create(path: &Path, header: &JournalHeader) -> Result<Self, JournalError> {
        let file = File::create(path).map_err(|source| JournalError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut w = JournalWriter {
            path: path.to_path_buf(),
            file,
        };
        w.line(&serde_json::to_string(header).expect("a header serializes"))?;
        Ok(w)
    }

    /// An existing journal, rewritten with its complete lines (a cut last line dropped), to
    /// append to.
    pub fn resume(journal: &Journal) -> Result<Self, JournalError> {
        let mut w = JournalWriter::create(&journal.path, &journal.header)?;
        for p in &journal.points {
            w.append(p)?;
        }
        Ok(w)
    }

    pub fn append(&mut self, point: &PointResult) -> Result<(), JournalError> {
        self.line(&serde_json::to_string(point).expect("a point serializes"))
    }

    fn line(&mut self, text: &str) -> Result<(), JournalError> {
        let written = writeln!(self.file, "{text}").and_then(|()| self.file.flush());
        written.map_err(|source| JournalError::Io {
            path: self.path.clone(),
            source,
        })
    }
}

/// Opens `path` for appending only if it exists (for tests of a cut line).
pub fn append_raw(path: &Path, text: &str) -> std::io::Result<()> {
    OpenOptions::new()
        .append(true)
        .open(path)?
        .write_all(text.as_bytes())
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::matrix::point::{Outcome, PointMode, SolvedPoint};

    fn header() -> JournalHeader {
        JournalHeader {
            squeal_matrix: FORMAT,
            fingerprint: "0123".into(),
            axes: vec![Axis::PressureBar, Axis::Mu],
            sampling: Sampling::Sobol,
            total: 8,
            slice: "1/2".into(),
            nominal: vec![Some(20.0), None],
            margin: 1e-4,
            scene: "[model]\n".into(),
        }
    }

    /// Written, killed in the middle of a line, read back: the complete points exactly (f64
    /// through JSON round-trips), the cut line left out; a malformed line elsewhere is named.
    #[test]
    fn journal_survives_a_cut_last_line_and_names_a_bad_one() {
        let dir = std::env::temp_dir().join(format!("squeal-journal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(JOURNAL);
        let points = vec![
            PointResult {
                index: 3,
                values: vec![11.413238048553469, 0.1 + 0.2],
                outcome: Outcome::Solved(SolvedPoint {
                    modes: vec![PointMode {
                        label: Some(35),
                        re: 348.123456789,
                        im: 18296.5,
                        mac: 0.987654321,
                    }],
                    braking_torque: 471.5,
                    normal_force: 9000.25,
                    newton_iterations: 3,
                    factorizations: 1,
                    cold_restart: false,
                    seconds_statics: 0.25,
                    seconds_factorizing: 0.125,
                    full_check: None,
                    saturation: Vec::new(),
                    factor_solves: 0,
                    seconds_solving: 0.0,
                    seconds_modes: 0.01,
                }),
            },
            PointResult {
                index: 0,
                values: vec![5.0, 0.6],
                outcome: Outcome::Failed {
                    reason: "static state: did not converge".into(),
                    seconds: 1.5,
                },
            },
        ];
        let mut w = JournalWriter::create(&path, &header()).unwrap();
        for p in &points {
            w.append(p).unwrap();
        }
        drop(w);
        append_raw(&path, "{\"index\": 5, \"val").unwrap();
        let j = read(&path).unwrap();
        assert_eq!(j.header, header());
        assert_eq!(j.points, points);
        assert!(j.truncated);
        JournalWriter::resume(&j).unwrap();
        let again = read(&path).unwrap();
        assert_eq!((again.points.len(), again.truncated), (2, false));
        append_raw(&path, "garbage\n{\"index\": 1}\n").unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(err.contains("line 4") && err.contains(JOURNAL), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
