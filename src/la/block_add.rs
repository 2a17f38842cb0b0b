//! Dense blocks added again and again at the same places of an AIJ matrix (the contact
//! tangent's point blocks in a Newton iteration), straight into PETSc's CSR value arrays.
//!
//! Why: MatSetValues puts every entry of a row another rank owns into PETSc's stash, which
//! the assembly sorts row by row before sending. On the 100k brake's superelement the points
//! of one rank add mostly into rows of the other, and that sort took 14 % of that rank's time
//! in the noise matrix (perf, 2026-11-27) while the other rank waited for it. A plan computes
//! once where every entry lands: a position in this rank's arrays, or a slot of the buffer
//! sent to the rank that owns the row, which knows the position of each slot it receives.

use petsc_sys as ffi;

use super::csr::{all_ranks, blocks, release, Block};
use super::error::{call, LaError, Result};
use super::matrix::SparseMatrix;

/// An entry whose row or column is negative (not an unknown): skipped, as MatSetValues does.
const SKIP: u32 = u32::MAX;

/// Where each entry of a fixed list of square dense blocks lands in one matrix.
pub struct BlockAddPlan {
    /// The matrix and its nonzero state when planned (positions hold for that pattern only).
    matrix: ffi::Mat,
    comm: ffi::mpi_sys::MPI_Comm,
    nonzero_state: ffi::PetscObjectState,
    /// Every block's indices, concatenated (checked at each addition: same blocks).
    indices: Vec<i32>,
    /// Start of each block in `indices` (blocks + 1 entries).
    starts: Vec<usize>,
    /// Start of each block's entries in `targets` (blocks + 1 entries).
    entry_starts: Vec<usize>,
    /// Per entry (blocks in order, each row-major): a position in the diagonal block's
    /// values (< diagonal), in the off-diagonal block's (diagonal + position), a slot of
    /// the send buffer (diagonal + off_diagonal + slot), or SKIP.
    targets: Vec<u32>,
    diagonal: usize,
    off_diagonal: usize,
    send_counts: Vec<i32>,
    send_starts: Vec<i32>,
    receive_counts: Vec<i32>,
    receive_starts: Vec<i32>,
    /// Where each received value lands here (encoded as in `targets`, never a slot).
    received_targets: Vec<u32>,
    send: Vec<f64>,
    received: Vec<f64>,
    dense: Vec<f64>,
}

/// The rows and columns this rank's blocks of a matrix hold.
struct Layout {
    rows: std::ops::Range<usize>,
    columns: std::ops::Range<usize>,
    /// Row ranges of all ranks (size + 1 starts).
    row_starts: Vec<usize>,
    diagonal: usize,
}

impl Layout {
    fn owner(&self, row: usize) -> usize {
        self.row_starts.partition_point(|&s| s <= row) - 1
    }

    /// The encoded position of (row, column), a row of this rank, or None when the pattern
    /// has no such entry.
    fn locate(&self, parts: &[Block], row: usize, column: usize) -> Option<u32> {
        let r = row - self.rows.start;
        let found = if self.columns.contains(&column) {
            position(&parts[0], r, (column - self.columns.start) as ffi::PetscInt)
        } else {
            let off = parts.get(1)?;
            position(off, r, column as ffi::PetscInt).map(|p| self.diagonal + p)
        };
        found.and_then(|p| u32::try_from(p).ok().filter(|&p| p != SKIP))
    }
}

/// The position of `column` in row `r` of a block (its columns increase along a row).
fn position(block: &Block, r: usize, column: ffi::PetscInt) -> Option<usize> {
    let range = block.row(r);
    let (mut lo, mut hi) = (range.start, range.end);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if block.column(mid) < column {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    (lo < range.end && block.column(lo) == column).then_some(lo)
}

pub(super) fn communicator(m: ffi::Mat) -> Result<ffi::mpi_sys::MPI_Comm> {
    let mut comm = ffi::mpi_sys::MPI_Comm(std::ptr::null_mut());
    call!(PetscObjectGetComm(m as ffi::PetscObject, &mut comm))?;
    Ok(comm)
}

fn mpi(code: i32, what: &str) -> Result<()> {
    match code {
        0 => Ok(()),
        _ => Err(LaError::Invalid(format!(
            "block addition: {what} failed (MPI error {code})"
        ))),
    }
}

/// Exclusive prefix sums of counts.
fn starts_of(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0, |at, &c| {
            let s = *at;
            *at += c;
            Some(s)
        })
        .collect()
}

/// Sends each owner the (row, column) pairs asked of it (`requests`, `counts[r]` pairs for
/// rank r, in rank order): how many pairs each rank asked of this one, and the pairs.
///
/// # Collective
fn ask_owners(
    comm: ffi::mpi_sys::MPI_Comm,
    counts: &[i32],
    requests: &[i64],
) -> Result<(Vec<i32>, Vec<i64>)> {
    let mut receive_counts = vec![0i32; counts.len()];
    // SAFETY: one i32 to and from every rank of the communicator.
    mpi(
        unsafe {
            ffi::mpi_sys::MPI_Alltoall(
                counts.as_ptr().cast(),
                1,
                ffi::mpi_sys::RSMPI_INT32_T,
                receive_counts.as_mut_ptr().cast(),
                1,
                ffi::mpi_sys::RSMPI_INT32_T,
                comm,
            )
        },
        "MPI_Alltoall",
    )?;
    let pairs = |v: &[i32]| v.iter().map(|&c| 2 * c).collect::<Vec<i32>>();
    let received: usize = receive_counts.iter().map(|&c| c as usize).sum();
    let mut asked = vec![0i64; 2 * received];
    // SAFETY: counts and starts (in i64s: two per pair) match both buffers' lengths.
    mpi(
        unsafe {
            ffi::mpi_sys::MPI_Alltoallv(
                requests.as_ptr().cast(),
                pairs(counts).as_ptr(),
                pairs(&starts_of(counts)).as_ptr(),
                ffi::mpi_sys::RSMPI_INT64_T,
                asked.as_mut_ptr().cast(),
                pairs(&receive_counts).as_ptr(),
                pairs(&starts_of(&receive_counts)).as_ptr(),
                ffi::mpi_sys::RSMPI_INT64_T,
                comm,
            )
        },
        "MPI_Alltoallv",
    )?;
    Ok((receive_counts, asked))
}

impl BlockAddPlan {
    /// Plans adding square dense blocks, block k at rows and columns `blocks[k]`, into
    /// `matrix`. None, on every rank alike, when the matrix is not AIJ or its pattern lacks
    /// an entry of a block (then add with MatSetValues).
    ///
    /// # Collective
    pub fn new(matrix: &SparseMatrix, blocks_indices: &[&[i32]]) -> Result<Option<Self>> {
        let m = matrix.raw;
        let parts = blocks(m)?;
        let planned = match &parts {
            Some(parts) => Self::plan(m, parts, blocks_indices),
            // Matches `plan`'s first agreement, where the other ranks then stop too.
            None => all_ranks(m, false).map(|_| None),
        };
        if let Some(parts) = &parts {
            release(parts)?;
        }
        planned
    }

    fn plan(m: ffi::Mat, parts: &[Block], blocks_indices: &[&[i32]]) -> Result<Option<Self>> {
        let comm = communicator(m)?;
        let mut size = 0;
        // SAFETY: an out-parameter on the matrix' communicator.
        mpi(
            unsafe { ffi::mpi_sys::MPI_Comm_size(comm, &mut size) },
            "MPI_Comm_size",
        )?;
        let size = size as usize;
        let mut starts_ptr: *const ffi::PetscInt = std::ptr::null();
        call!(MatGetOwnershipRanges(m, &mut starts_ptr))?;
        // SAFETY: PETSc's ownership ranges hold size + 1 entries.
        let row_starts: Vec<usize> = unsafe { std::slice::from_raw_parts(starts_ptr, size + 1) }
            .iter()
            .map(|&s| s as usize)
            .collect();
        let (mut lo, mut hi) = (0, 0);
        call!(MatGetOwnershipRangeColumn(m, &mut lo, &mut hi))?;
        let (mut rlo, mut rhi) = (0, 0);
        call!(MatGetOwnershipRange(m, &mut rlo, &mut rhi))?;
        let layout = Layout {
            rows: rlo as usize..rhi as usize,
            columns: lo as usize..hi as usize,
            row_starts,
            diagonal: parts[0].entries(),
        };
        let off_diagonal = parts.get(1).map_or(0, |b| b.entries());
        let mut nonzero_state = 0;
        call!(MatGetNonzeroState(m, &mut nonzero_state))?;

        // Local entries located; remote ones listed per owner as (row, column, entry).
        let mut indices = Vec::new();
        let mut starts = vec![0];
        let mut entry_starts = vec![0];
        let mut targets = Vec::new();
        let mut remote: Vec<Vec<(i64, i64, usize)>> = vec![Vec::new(); size];
        let mut ok = true;
        for block in blocks_indices {
            indices.extend_from_slice(block);
            starts.push(indices.len());
            for &r in block.iter() {
                for &c in block.iter() {
                    let entry = targets.len();
                    if r < 0 || c < 0 {
                        targets.push(SKIP);
                    } else if layout.rows.contains(&(r as usize)) {
                        let found = layout.locate(parts, r as usize, c as usize);
                        ok &= found.is_some();
                        targets.push(found.unwrap_or(SKIP));
                    } else {
                        remote[layout.owner(r as usize)].push((r as i64, c as i64, entry));
                        targets.push(SKIP);
                    }
                }
            }
            entry_starts.push(targets.len());
        }
        let first_slot = layout.diagonal + off_diagonal;
        let slots: usize = remote.iter().map(Vec::len).sum();
        ok &= first_slot + slots < SKIP as usize;
        if !all_ranks(m, ok)? {
            return Ok(None);
        }
        let mut slot = first_slot;
        let mut requests = Vec::with_capacity(2 * slots);
        for owner in &remote {
            for &(r, c, entry) in owner {
                targets[entry] = slot as u32;
                slot += 1;
                requests.extend([r, c]);
            }
        }
        let send_counts: Vec<i32> = remote.iter().map(|o| o.len() as i32).collect();
        let (receive_counts, asked) = ask_owners(comm, &send_counts, &requests)?;
        let (send_starts, receive_starts) = (starts_of(&send_counts), starts_of(&receive_counts));
        let received_total = asked.len() / 2;
        let mut ok = true;
        let received_targets: Vec<u32> = asked
            .chunks_exact(2)
            .map(|rc| {
                let (r, c) = (rc[0] as usize, rc[1] as usize);
                let found = layout
                    .rows
                    .contains(&r)
                    .then(|| layout.locate(parts, r, c))
                    .flatten();
                ok &= found.is_some();
                found.unwrap_or(SKIP)
            })
            .collect();
        if !all_ranks(m, ok)? {
            return Ok(None);
        }
        Ok(Some(BlockAddPlan {
            matrix: m,
            comm,
            nonzero_state,
            indices,
            starts,
            entry_starts,
            targets,
            diagonal: layout.diagonal,
            off_diagonal,
            send: vec![0.0; slots],
            received: vec![0.0; received_total],
            send_counts,
            send_starts,
            receive_counts,
            receive_starts,
            received_targets,
            dense: Vec::new(),
        }))
    }

    /// Whether this plan is for `matrix` with its pattern unchanged and for these blocks.
    pub fn fits(&self, matrix: &SparseMatrix, blocks_indices: &[&[i32]]) -> Result<bool> {
        let mut state = 0;
        call!(MatGetNonzeroState(matrix.raw, &mut state))?;
        Ok(matrix.raw == self.matrix
            && state == self.nonzero_state
            && blocks_indices.len() + 1 == self.starts.len()
            && blocks_indices
                .iter()
                .enumerate()
                .all(|(k, b)| *b == &self.indices[self.starts[k]..self.starts[k + 1]]))
    }

    /// [`fits`](Self::fits) on every rank.
    ///
    /// # Collective
    pub fn fits_everywhere(
        &self,
        matrix: &SparseMatrix,
        blocks_indices: &[&[i32]],
    ) -> Result<bool> {
        let fits = self.fits(matrix, blocks_indices)?;
        all_ranks(matrix.raw, fits)
    }

    /// Adds block k, as `fill(k, values)` writes it (row-major, `values` zeroed before), for
    /// every block, then assembles the matrix (its state advances, so a factorization of it
    /// sees the change). Errors when the plan does not [`fit`](Self::fits) the matrix and
    /// blocks (every rank checks its own: call with the same matrix everywhere).
    ///
    /// # Collective
    pub fn add(
        &mut self,
        matrix: &mut SparseMatrix,
        blocks_indices: &[&[i32]],
        mut fill: impl FnMut(usize, &mut [f64]),
    ) -> Result<()> {
        if !self.fits_everywhere(matrix, blocks_indices)? {
            return Err(LaError::Invalid(
                "block addition: the plan is of another matrix, pattern or list of blocks".into(),
            ));
        }
        let parts = blocks(matrix.raw)?
            .ok_or_else(|| LaError::Invalid("block addition: the matrix is not AIJ".into()))?;
        let added = self.add_local(&parts, &mut fill);
        release(&parts)?;
        added?;
        call!(MatAssemblyBegin(matrix.raw, ffi::MAT_FINAL_ASSEMBLY))?;
        call!(MatAssemblyEnd(matrix.raw, ffi::MAT_FINAL_ASSEMBLY))
    }

    fn add_local(
        &mut self,
        parts: &[Block],
        fill: &mut impl FnMut(usize, &mut [f64]),
    ) -> Result<()> {
        let mut arrays = Vec::with_capacity(parts.len());
        for b in parts {
            let mut values = std::ptr::null_mut();
            if let Err(e) = call!(MatSeqAIJGetArray(b.mat, &mut values)) {
                for (b, mut v) in parts.iter().zip(arrays) {
                    call!(MatSeqAIJRestoreArray(b.mat, &mut v))?;
                }
                return Err(e);
            }
            arrays.push(values);
        }
        // SAFETY: each block's value array holds its ia[rows] entries until restored below;
        // the diagonal and off-diagonal blocks are distinct matrices.
        let diagonal = unsafe { std::slice::from_raw_parts_mut(arrays[0], self.diagonal) };
        let off: &mut [f64] = match arrays.get(1) {
            Some(&p) => unsafe { std::slice::from_raw_parts_mut(p, self.off_diagonal) },
            None => &mut [],
        };
        let mut values = Values {
            diagonal,
            off,
            slot_start: self.diagonal + self.off_diagonal,
        };
        self.send.fill(0.0);
        let mut dense = std::mem::take(&mut self.dense);
        for k in 0..self.starts.len() - 1 {
            let n = self.starts[k + 1] - self.starts[k];
            dense.clear();
            dense.resize(n * n, 0.0);
            fill(k, &mut dense);
            let targets = &self.targets[self.entry_starts[k]..self.entry_starts[k + 1]];
            for (&t, &v) in targets.iter().zip(&dense) {
                values.put(t, v, &mut self.send);
            }
        }
        self.dense = dense;
        let exchanged = self.exchange();
        if exchanged.is_ok() {
            for (&t, &v) in self.received_targets.iter().zip(&self.received) {
                values.put(t, v, &mut []);
            }
        }
        for (b, mut v) in parts.iter().zip(arrays) {
            call!(MatSeqAIJRestoreArray(b.mat, &mut v))?;
        }
        exchanged
    }

    /// Sends every slot to the rank owning its row; receives this rank's.
    ///
    /// # Collective
    fn exchange(&mut self) -> Result<()> {
        // SAFETY: counts and starts match the buffers' lengths (fixed when planned).
        mpi(
            unsafe {
                ffi::mpi_sys::MPI_Alltoallv(
                    self.send.as_ptr().cast(),
                    self.send_counts.as_ptr(),
                    self.send_starts.as_ptr(),
                    ffi::mpi_sys::RSMPI_DOUBLE,
                    self.received.as_mut_ptr().cast(),
                    self.receive_counts.as_ptr(),
                    self.receive_starts.as_ptr(),
                    ffi::mpi_sys::RSMPI_DOUBLE,
                    self.comm,
                )
            },
            "MPI_Alltoallv",
        )
    }
}

/// This rank's value arrays, addressed by an encoded target.
struct Values<'a> {
    diagonal: &'a mut [f64],
    off: &'a mut [f64],
    slot_start: usize,
}

impl Values<'_> {
    fn put(&mut self, target: u32, value: f64, send: &mut [f64]) {
        let t = target as usize;
        let diagonal = self.diagonal.len();
        if t < diagonal {
            self.diagonal[t] += value;
        } else if t < self.slot_start {
            self.off[t - diagonal] += value;
        } else if target != SKIP {
            send[t - self.slot_start] += value;
        }
    }
}
