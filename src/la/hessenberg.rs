//! Eigenvalues of a general real matrix first, vectors only where asked: balancing (dgebal),
//! Hessenberg reduction (dgehrd) and the QR algorithm without Schur vectors (dhseqr, job 'E'),
//! then the right eigenvectors of selected eigenvalues by inverse iteration on the Hessenberg
//! form (dhsein), carried back by the reduction's reflectors (dormhr) and the balancing
//! (dgebak). For a caller that needs all eigenvalues but only a few vectors this costs about
//! two thirds of dgeev with vectors (benches/decisions-results.md, "hessenberg"): the Schur
//! vectors and all eigenvectors are what it skips; each vector then costs O(n^2).

use crate::la::DenseError;
use std::os::raw::{c_char, c_int};

use super::lapack::{dim, lapack};

extern "C" {
    fn dgebal_(
        job: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        ilo: *mut c_int,
        ihi: *mut c_int,
        scale: *mut f64,
        info: *mut c_int,
    );
    fn dgehrd_(
        n: *const c_int,
        ilo: *const c_int,
        ihi: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        tau: *mut f64,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn dhseqr_(
        job: *const c_char,
        compz: *const c_char,
        n: *const c_int,
        ilo: *const c_int,
        ihi: *const c_int,
        h: *mut f64,
        ldh: *const c_int,
        wr: *mut f64,
        wi: *mut f64,
        z: *mut f64,
        ldz: *const c_int,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn dhsein_(
        side: *const c_char,
        eigsrc: *const c_char,
        initv: *const c_char,
        select: *mut c_int,
        n: *const c_int,
        h: *const f64,
        ldh: *const c_int,
        wr: *mut f64,
        wi: *const f64,
        vl: *mut f64,
        ldvl: *const c_int,
        vr: *mut f64,
        ldvr: *const c_int,
        mm: *const c_int,
        m: *mut c_int,
        work: *mut f64,
        ifaill: *mut c_int,
        ifailr: *mut c_int,
        info: *mut c_int,
    );
    fn dormhr_(
        side: *const c_char,
        trans: *const c_char,
        m: *const c_int,
        n: *const c_int,
        ilo: *const c_int,
        ihi: *const c_int,
        a: *const f64,
        lda: *const c_int,
        tau: *const f64,
        c: *mut f64,
        ldc: *const c_int,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn dgebak_(
        job: *const c_char,
        side: *const c_char,
        n: *const c_int,
        ilo: *const c_int,
        ihi: *const c_int,
        scale: *const f64,
        m: *const c_int,
        v: *mut f64,
        ldv: *const c_int,
        info: *mut c_int,
    );
}

fn check(routine: &'static str, info: c_int, order: usize) -> Result<(), DenseError> {
    match info {
        0 => Ok(()),
        i if i < 0 => Err(lapack(routine, i, order, "bad argument")),
        i => Err(lapack(routine, i, order, "did not converge")),
    }
}

/// A real matrix's eigenvalues, with what it takes to compute selected eigenvectors.
pub struct EigenvaluesFirst {
    n: usize,
    /// dgehrd's output: the Hessenberg form on and above the subdiagonal, the reflectors
    /// below it.
    reduced: Vec<f64>,
    /// The Hessenberg form alone (zero below the subdiagonal).
    hessenberg: Vec<f64>,
    tau: Vec<f64>,
    ilo: c_int,
    ihi: c_int,
    scale: Vec<f64>,
    /// Eigenvalues `(re, im)`; conjugate pairs consecutive, positive imaginary part first.
    pub values: Vec<(f64, f64)>,
}

impl EigenvaluesFirst {
    /// The eigenvalues of the n x n column-major matrix `a` (consumed).
    pub fn new(n: usize, mut a: Vec<f64>) -> Result<Self, DenseError> {
        if a.len() != n * n || n == 0 {
            return Err(DenseError::Shape {
                what: "dense eigenproblem",
                found: a.len(),
                order: n,
            });
        }
        if a.iter().any(|x| !x.is_finite()) {
            return Err(DenseError::NotFinite {
                what: "dense eigenproblem",
            });
        }
        let ni = dim(n)?;
        let (mut ilo, mut ihi, mut info): (c_int, c_int, c_int) = (0, 0, 0);
        let mut scale = vec![0.0; n];
        let both = b'B' as c_char;
        // SAFETY: a is n x n (lda n), scale has n entries.
        unsafe {
            dgebal_(
                &both,
                &ni,
                a.as_mut_ptr(),
                &ni,
                &mut ilo,
                &mut ihi,
                scale.as_mut_ptr(),
                &mut info,
            )
        };
        check("dgebal", info, n)?;
        let lwork = 64 * n;
        let lw = dim(lwork)?;
        let mut work = vec![0.0; lwork];
        let mut tau = vec![0.0; n.saturating_sub(1).max(1)];
        // SAFETY: a is n x n, tau has n - 1 entries, work lwork >= n.
        unsafe {
            dgehrd_(
                &ni,
                &ilo,
                &ihi,
                a.as_mut_ptr(),
                &ni,
                tau.as_mut_ptr(),
                work.as_mut_ptr(),
                &lw,
                &mut info,
            )
        };
        check("dgehrd", info, n)?;
        let mut hessenberg = a.clone();
        for j in 0..n {
            for x in hessenberg[j * n..(j + 1) * n].iter_mut().skip(j + 2) {
                *x = 0.0;
            }
        }
        let mut h = hessenberg.clone();
        let (mut wr, mut wi) = (vec![0.0; n], vec![0.0; n]);
        let (job, compz, one) = (b'E' as c_char, b'N' as c_char, 1 as c_int);
        let mut z = [0.0f64; 1];
        // SAFETY: h is n x n (ldh n), wr and wi n entries, z is not referenced (compz 'N',
        // ldz 1), work lwork >= n.
        unsafe {
            dhseqr_(
                &job,
                &compz,
                &ni,
                &ilo,
                &ihi,
                h.as_mut_ptr(),
                &ni,
                wr.as_mut_ptr(),
                wi.as_mut_ptr(),
                z.as_mut_ptr(),
                &one,
                work.as_mut_ptr(),
                &lw,
                &mut info,
            )
        };
        check("dhseqr", info, n)?;
        Ok(EigenvaluesFirst {
            n,
            reduced: a,
            hessenberg,
            tau,
            ilo,
            ihi,
            scale,
            values: wr.into_iter().zip(wi).collect(),
        })
    }

    /// The right eigenvectors (Euclidean norm 1, `(re, im)` per entry) of the eigenvalues at
    /// `indices` (for a complex one, either member of its pair: the vector of the member
    /// asked for).
    pub fn vectors(&self, indices: &[usize]) -> Result<Vec<Vec<(f64, f64)>>, DenseError> {
        let n = self.n;
        let ni = dim(n)?;
        // The first member of each pair (positive imaginary part) selects it in dhsein.
        let first = |j: usize| {
            if j > 0 && self.values[j].1 < 0.0 && self.values[j - 1].1 > 0.0 {
                j - 1
            } else {
                j
            }
        };
        let mut select: Vec<c_int> = vec![0; n];
        for &j in indices {
            if j >= n {
                return Err(DenseError::NoEigenvector { index: j, order: n });
            }
            select[first(j)] = 1;
        }
        // Columns: one per selected real eigenvalue, two (re, im) per complex pair.
        let mut column = vec![usize::MAX; n];
        let mut columns = 0;
        for j in 0..n {
            if select[j] != 0 {
                column[j] = columns;
                columns += if self.values[j].1 != 0.0 { 2 } else { 1 };
            }
        }
        if columns == 0 {
            return Ok(Vec::new());
        }
        let mm = dim(columns)?;
        let mut vr = vec![0.0; n * columns];
        let mut vl = [0.0f64; 1];
        let (mut wr, wi): (Vec<f64>, Vec<f64>) = self.values.iter().copied().unzip();
        let mut work = vec![0.0; (n + 2) * n];
        let (mut ifaill, mut ifailr) = (vec![0 as c_int; columns], vec![0 as c_int; columns]);
        let (mut found, mut info, one): (c_int, c_int, c_int) = (0, 0, 1);
        let (right, source, init) = (b'R' as c_char, b'N' as c_char, b'N' as c_char);
        // SAFETY: the Hessenberg form is n x n (ldh n); select, wr, wi have n entries; vr is n
        // x mm with mm the columns the selection needs; vl is not referenced (side 'R', ldvl
        // 1); work has (n + 2) n entries; ifaill, ifailr mm.
        unsafe {
            dhsein_(
                &right,
                &source,
                &init,
                select.as_mut_ptr(),
                &ni,
                self.hessenberg.as_ptr(),
                &ni,
                wr.as_mut_ptr(),
                wi.as_ptr(),
                vl.as_mut_ptr(),
                &one,
                vr.as_mut_ptr(),
                &ni,
                &mm,
                &mut found,
                work.as_mut_ptr(),
                ifaill.as_mut_ptr(),
                ifailr.as_mut_ptr(),
                &mut info,
            )
        };
        if info > 0 {
            return Err(lapack(
                "dhsein",
                info,
                n,
                "eigenvectors failed to converge by inverse iteration",
            ));
        }
        check("dhsein", info, n)?;
        let (left, plain, lwork) = (b'L' as c_char, b'N' as c_char, 64 * columns.max(n));
        let lw = dim(lwork)?;
        let mut work = vec![0.0; lwork];
        // SAFETY: the reflectors are dgehrd's (n x n, lda n; tau n - 1) for the same ilo, ihi;
        // vr is n x mm (ldc n); work lwork >= mm.
        unsafe {
            dormhr_(
                &left,
                &plain,
                &ni,
                &mm,
                &self.ilo,
                &self.ihi,
                self.reduced.as_ptr(),
                &ni,
                self.tau.as_ptr(),
                vr.as_mut_ptr(),
                &ni,
                work.as_mut_ptr(),
                &lw,
                &mut info,
            )
        };
        check("dormhr", info, n)?;
        let both = b'B' as c_char;
        // SAFETY: scale, ilo, ihi from dgebal of order n; vr is n x mm (ldv n).
        unsafe {
            dgebak_(
                &both,
                &right,
                &ni,
                &self.ilo,
                &self.ihi,
                self.scale.as_ptr(),
                &mm,
                vr.as_mut_ptr(),
                &ni,
                &mut info,
            )
        };
        check("dgebak", info, n)?;
        let col = |k: usize| &vr[k * n..(k + 1) * n];
        Ok(indices
            .iter()
            .map(|&j| {
                let c = column[first(j)];
                let v: Vec<(f64, f64)> = if self.values[j].1 == 0.0 {
                    col(c).iter().map(|&r| (r, 0.0)).collect()
                } else {
                    // The pair's first member: re + i im; its conjugate: re - i im.
                    let sign = if first(j) == j { 1.0 } else { -1.0 };
                    col(c)
                        .iter()
                        .zip(col(c + 1))
                        .map(|(&r, &i)| (r, sign * i))
                        .collect()
                };
                let norm = v.iter().map(|z| z.0 * z.0 + z.1 * z.1).sum::<f64>().sqrt();
                v.into_iter()
                    .map(|z| (z.0 / norm.max(1e-300), z.1 / norm.max(1e-300)))
                    .collect()
            })
            .collect())
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::la::lapack::eigen_general;
    use crate::measure::nan_min;

    /// The eigenvalues are dgeev's, and each selected vector satisfies A v = lambda v to
    /// round-off (a scaled, unsymmetric matrix with real and complex eigenvalues, balanced).
    #[test]
    fn eigenvalues_first_match_dgeev_and_selected_vectors_are_eigenvectors() {
        let n = 12;
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                let x = ((k * 7919) % 101) as f64 / 101.0 - 0.5;
                x * 10f64.powi((i as i32 - j as i32) / 3)
            })
            .collect();
        let e = EigenvaluesFirst::new(n, a.clone()).unwrap();
        let full = eigen_general(n, a.clone()).unwrap();
        let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
        for &(re, im) in &full.values {
            let nearest = e
                .values
                .iter()
                .map(|&(r, i)| (r - re).hypot(i - im))
                .fold(f64::INFINITY, nan_min);
            assert!(nearest <= 1e-12 * norm, "{re} {im}: {nearest}");
        }
        let complex = e.values.iter().position(|v| v.1 != 0.0).expect("a pair");
        let real = e
            .values
            .iter()
            .position(|v| v.1 == 0.0)
            .expect("a real one");
        let chosen = [complex + 1, real, complex];
        let vectors = e.vectors(&chosen).unwrap();
        for (&j, v) in chosen.iter().zip(&vectors) {
            let (lr, li) = e.values[j];
            for i in 0..n {
                let (mut ar, mut ai) = (0.0, 0.0);
                for k in 0..n {
                    ar += a[k * n + i] * v[k].0;
                    ai += a[k * n + i] * v[k].1;
                }
                let (er, ei) = (lr * v[i].0 - li * v[i].1, lr * v[i].1 + li * v[i].0);
                assert!(
                    (ar - er).hypot(ai - ei) <= 1e-12 * norm,
                    "row {i} of vector {j}"
                );
            }
        }
        assert!(EigenvaluesFirst::new(2, vec![f64::NAN, 0.0, 0.0, 1.0]).is_err());
    }
}
