//! Matrix Market files (coordinate, real, general or symmetric): reading user matrices and
//! exporting assembled ones.

use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use mpi::traits::*;

use crate::la::{LaError, MatrixFormat, SparseMatrix};

#[derive(Debug, thiserror::Error)]
pub enum MatrixMarketError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error(transparent)]
    La(#[from] LaError),
    #[error("an operator needs at least one matrix term")]
    NoTerms,
}

/// A sparse matrix as coordinate triplets (0-based), lower triangle only when `symmetric`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Triplets {
    pub rows: usize,
    pub cols: usize,
    pub symmetric: bool,
    pub entries: Vec<(u32, u32, f64)>,
}

impl Triplets {
    /// All entries with the symmetric half expanded.
    pub fn expanded(&self) -> Vec<(u32, u32, f64)> {
        let mut out = self.entries.clone();
        if self.symmetric {
            out.extend(
                self.entries
                    .iter()
                    .filter(|(i, j, _)| i != j)
                    .map(|&(i, j, v)| (j, i, v)),
            );
        }
        out
    }
}

/// Reads a Matrix Market coordinate file (real or integer; general or symmetric), gzipped
/// when its name ends in `.gz`.
pub fn read(path: &Path) -> Result<Triplets, MatrixMarketError> {
    let io = |source| MatrixMarketError::Io {
        path: path.to_path_buf(),
        source,
    };
    let parse = |line: usize, message: String| MatrixMarketError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    // Matrices are often shipped compressed: read `.gz` transparently.
    let reader: Box<dyn std::io::Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(flate2::read::GzDecoder::new(file))
    } else {
        Box::new(file)
    };
    let mut lines = BufReader::new(reader).lines().enumerate();
    let (_, header) = lines.next().ok_or_else(|| parse(1, "empty file".into()))?;
    let header = header.map_err(io)?.to_lowercase();
    let words: Vec<&str> = header.split_whitespace().collect();
    if words.len() < 5 || words[0] != "%%matrixmarket" || words[1] != "matrix" {
        return Err(parse(
            1,
            "expected the header '%%MatrixMarket matrix coordinate real general|symmetric'".into(),
        ));
    }
    if words[2] != "coordinate" {
        return Err(parse(
            1,
            format!("format '{}' not supported: use 'coordinate'", words[2]),
        ));
    }
    if words[3] != "real" && words[3] != "integer" && words[3] != "double" {
        return Err(parse(
            1,
            format!("field '{}' not supported: use 'real'", words[3]),
        ));
    }
    let symmetric = match words[4] {
        "general" => false,
        "symmetric" => true,
        other => {
            return Err(parse(
                1,
                format!("symmetry '{other}' not supported: use 'general' or 'symmetric'"),
            ))
        }
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut t = Triplets {
        symmetric,
        ..Default::default()
    };
    for (i, line) in lines {
        let lineno = i + 1;
        let line = line.map_err(io)?;
        let s = line.trim();
        if s.is_empty() || s.starts_with('%') {
            continue;
        }
        let mut it = s.split_whitespace();
        match size {
            None => {
                let mut num = || -> Result<usize, MatrixMarketError> {
                    it.next()
                        .and_then(|w| w.parse().ok())
                        .ok_or_else(|| parse(lineno, "expected 'rows cols entries'".into()))
                };
                let (r, c, n) = (num()?, num()?, num()?);
                if r > u32::MAX as usize || c > u32::MAX as usize {
                    return Err(parse(
                        lineno,
                        format!("{r} x {c}: at most {} rows and columns", u32::MAX),
                    ));
                }
                t.rows = r;
                t.cols = c;
                // The announced count is checked at the end; a corrupt one must not allocate
                // gigabytes up front.
                t.entries.reserve(n.min(1 << 24));
                size = Some((r, c, n));
            }
            Some((r, c, _)) => {
                let bad = || {
                    parse(
                        lineno,
                        format!("expected 'row col value' with 1 <= row <= {r}, 1 <= col <= {c}"),
                    )
                };
                let i: usize = it.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?;
                let j: usize = it.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?;
                let v: f64 = it.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?;
                if i == 0 || j == 0 || i > r || j > c {
                    return Err(bad());
                }
                if !v.is_finite() {
                    return Err(parse(lineno, format!("value {v} is not finite")));
                }
                if symmetric && j > i {
                    return Err(parse(
                        lineno,
                        "a symmetric file stores the lower triangle only (row >= col)".into(),
                    ));
                }
                t.entries.push(((i - 1) as u32, (j - 1) as u32, v));
            }
        }
    }
    let (_, _, n) = size.ok_or_else(|| parse(1, "no size line".into()))?;
    if t.entries.len() != n {
        return Err(parse(
            0,
            format!(
                "the size line announces {n} entries, the file has {}",
                t.entries.len()
            ),
        ));
    }
    Ok(t)
}

/// Writes an assembled matrix (rank 0 writes; every rank sends its rows). SBAIJ matrices are
/// written as 'symmetric' (lower triangle), others as 'general'.
///
/// # Collective
pub fn write(
    comm: &mpi::topology::SimpleCommunicator,
    matrix: &SparseMatrix,
    path: &Path,
) -> Result<(), MatrixMarketError> {
    let symmetric = matrix.format() == MatrixFormat::Sbaij;
    let mut text = String::new();
    let mut count = 0u64;
    matrix.for_each_local_row(|row, cols, vals| {
        for (&c, &v) in cols.iter().zip(vals) {
            // SBAIJ stores its diagonal blocks whole, so MatGetRow also returns a few entries
            // left of the diagonal: keep the upper triangle, written transposed as the lower
            // triangle that Matrix Market expects.
            if symmetric && (c as usize) < row {
                continue;
            }
            let (i, j) = if symmetric {
                (c as usize, row)
            } else {
                (row, c as usize)
            };
            let _ = writeln!(text, "{} {} {:.17e}", i + 1, j + 1, v);
            count += 1;
        }
    })?;
    let root = comm.process_at_rank(0);
    let mut total = 0u64;
    comm.all_reduce_into(&count, &mut total, mpi::collective::SystemOperation::sum());
    let bytes = text.into_bytes();
    let len = bytes.len() as i32;
    if comm.rank() == 0 {
        let mut lens = vec![0i32; comm.size() as usize];
        root.gather_into_root(&len, &mut lens[..]);
        let displs: Vec<i32> = lens
            .iter()
            .scan(0, |acc, &l| {
                let d = *acc;
                *acc += l;
                Some(d)
            })
            .collect();
        let mut all = vec![0u8; lens.iter().map(|&l| l as usize).sum()];
        {
            let mut partition =
                mpi::datatype::PartitionMut::new(&mut all[..], &lens[..], &displs[..]);
            root.gather_varcount_into_root(&bytes[..], &mut partition);
        }
        let io = |source| MatrixMarketError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        let n = matrix.global_rows();
        writeln!(
            f,
            "%%MatrixMarket matrix coordinate real {}\n% written by squeal\n{n} {n} {total}",
            if symmetric { "symmetric" } else { "general" }
        )
        .map_err(io)?;
        f.write_all(&all).map_err(io)?;
        f.flush().map_err(io)?;
    } else {
        root.gather_into(&len);
        root.gather_varcount_into(&bytes[..]);
    }
    Ok(())
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn write_tmp(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("squeal-mm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn reads_symmetric_and_expands() {
        let p = write_tmp(
            "a.mtx",
            "%%MatrixMarket matrix coordinate real symmetric\n% c\n3 3 4\n1 1 2\n2 1 -1\n2 2 2\n3 3 1e-3\n",
        );
        let t = read(&p).unwrap();
        assert!(t.symmetric);
        assert_eq!(t.expanded().len(), 5);
    }

    #[test]
    fn errors_name_file_and_line() {
        let p = write_tmp(
            "b.mtx",
            "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n3 1 2.0\n",
        );
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("b.mtx:4"), "{e}");
        let p = write_tmp("c.mtx", "%%MatrixMarket matrix array real general\n2 2\n");
        assert!(read(&p).unwrap_err().to_string().contains("coordinate"));
        let p = write_tmp(
            "d.mtx",
            "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 nan\n",
        );
        assert!(read(&p).unwrap_err().to_string().contains("d.mtx:3"));
        let p = write_tmp(
            "e.mtx",
            "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 1\n",
        );
        assert!(read(&p).unwrap_err().to_string().contains("announces 3"));
    }
}
