//! Dense LAPACK/BLAS (the library PETSc links, OpenBLAS here) for the small dense problems of
//! the projected complex modes and the reduction: the general eigenproblem of the companion
//! matrix (dgeev, with its balancing; also without eigenvectors), the symmetric one of a Gram
//! matrix (dsyev), matrix products (dgemm, and dsyrk for symmetric ones) and the LU of a small
//! real system (dgetrf, dgetrs: the transient's low-rank update). Column-major storage
//! throughout.

use crate::la::one_column_gemm::dgemm_;
use crate::la::DenseError;
use std::os::raw::{c_char, c_int};

extern "C" {
    fn dgeev_(
        jobvl: *const c_char,
        jobvr: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        wr: *mut f64,
        wi: *mut f64,
        vl: *mut f64,
        ldvl: *const c_int,
        vr: *mut f64,
        ldvr: *const c_int,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn dsyev_(
        jobz: *const c_char,
        uplo: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        w: *mut f64,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn dgetrf_(
        m: *const c_int,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        ipiv: *mut c_int,
        info: *mut c_int,
    );
    fn dgetrs_(
        trans: *const c_char,
        n: *const c_int,
        nrhs: *const c_int,
        a: *const f64,
        lda: *const c_int,
        ipiv: *const c_int,
        b: *mut f64,
        ldb: *const c_int,
        info: *mut c_int,
    );
    fn dsyrk_(
        uplo: *const c_char,
        trans: *const c_char,
        n: *const c_int,
        k: *const c_int,
        alpha: *const f64,
        a: *const f64,
        lda: *const c_int,
        beta: *const f64,
        c: *mut f64,
        ldc: *const c_int,
    );
}

/// Eigenvalues `(re, im)` and right eigenvectors (`(re, im)` per entry) of a general real
/// matrix. Conjugate pairs come as in LAPACK: consecutive, positive imaginary part first.
pub struct DenseEigen {
    pub values: Vec<(f64, f64)>,
    /// Column j is the eigenvector of `values[j]`, Euclidean norm 1.
    pub vectors: Vec<Vec<(f64, f64)>>,
}

/// A LAPACK failure: `routine` returned `info` on an order-`order` problem.
pub(crate) fn lapack(
    routine: &'static str,
    info: c_int,
    order: usize,
    meaning: &'static str,
) -> DenseError {
    DenseError::Lapack {
        routine,
        info,
        order,
        meaning,
    }
}

/// The LU factors (dgetrf) of a real n x n matrix, for solves (dgetrs).
#[derive(Debug, Clone)]
pub struct RealLu {
    n: usize,
    factors: Vec<f64>,
    pivots: Vec<c_int>,
}

impl RealLu {
    /// Factors the column-major n x n matrix `a` (consumed). Errs on a singular matrix (a zero
    /// pivot) or non-finite entries.
    pub fn new(n: usize, mut a: Vec<f64>) -> Result<Self, DenseError> {
        if a.len() != n * n {
            return Err(DenseError::Shape {
                what: "real LU",
                found: a.len(),
                order: n,
            });
        }
        if a.iter().any(|x| !x.is_finite()) {
            return Err(DenseError::NotFinite { what: "real LU" });
        }
        let ni = dim(n.max(1))?;
        let mut pivots: Vec<c_int> = vec![0; n];
        let mut info: c_int = 0;
        if n > 0 {
            // SAFETY: a is n x n with leading dimension n, pivots has n entries.
            unsafe {
                dgetrf_(
                    &ni,
                    &ni,
                    a.as_mut_ptr(),
                    &ni,
                    pivots.as_mut_ptr(),
                    &mut info,
                )
            };
        }
        if info != 0 {
            let meaning = if info > 0 { "singular" } else { "bad argument" };
            return Err(lapack("dgetrf", info, n, meaning));
        }
        Ok(RealLu {
            n,
            factors: a,
            pivots,
        })
    }

    /// Solves A x = b in place (b of length n).
    pub fn solve(&self, b: &mut [f64]) -> Result<(), DenseError> {
        let n = self.n;
        if n == 0 {
            return Ok(());
        }
        if b.len() != n {
            return Err(DenseError::Shape {
                what: "real LU solve",
                found: b.len(),
                order: n,
            });
        }
        let (ni, one) = (dim(n)?, 1 as c_int);
        let trans = b'N' as c_char;
        let mut info: c_int = 0;
        // SAFETY: the factors and pivots come from dgetrf of order n; b has n entries.
        unsafe {
            dgetrs_(
                &trans,
                &ni,
                &one,
                self.factors.as_ptr(),
                &ni,
                self.pivots.as_ptr(),
                b.as_mut_ptr(),
                &ni,
                &mut info,
            );
        }
        if info != 0 {
            return Err(lapack("dgetrs", info, n, "bad argument"));
        }
        Ok(())
    }
}

/// A dimension as LAPACK's integer.
pub(crate) fn dim(n: usize) -> Result<c_int, DenseError> {
    c_int::try_from(n).map_err(|_| DenseError::TooLarge(n))
}

/// Eigen-decomposition of the n x n column-major matrix `a` (consumed).
pub fn eigen_general(n: usize, mut a: Vec<f64>) -> Result<DenseEigen, DenseError> {
    if a.len() != n * n {
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
    if n == 0 {
        return Ok(DenseEigen {
            values: Vec::new(),
            vectors: Vec::new(),
        });
    }
    let ni = dim(n)?;
    let (mut wr, mut wi) = (vec![0.0; n], vec![0.0; n]);
    let mut vr = vec![0.0; n * n];
    let mut vl = [0.0f64; 1];
    let (no, yes) = (b'N' as c_char, b'V' as c_char);
    let one: c_int = 1;
    let mut info: c_int = 0;
    // Workspace query, then the decomposition.
    let mut query = 0.0f64;
    let minus_one: c_int = -1;
    // SAFETY: every pointer is valid for the sizes LAPACK reads (n x n, n, workspace length).
    unsafe {
        dgeev_(
            &no,
            &yes,
            &ni,
            a.as_mut_ptr(),
            &ni,
            wr.as_mut_ptr(),
            wi.as_mut_ptr(),
            vl.as_mut_ptr(),
            &one,
            vr.as_mut_ptr(),
            &ni,
            &mut query,
            &minus_one,
            &mut info,
        );
    }
    if info != 0 {
        return Err(lapack("dgeev", info, n, "workspace query"));
    }
    let lwork = (query as usize).max(4 * n);
    let mut work = vec![0.0; lwork];
    let lw = dim(lwork)?;
    // SAFETY: as above, with a workspace of lwork entries.
    unsafe {
        dgeev_(
            &no,
            &yes,
            &ni,
            a.as_mut_ptr(),
            &ni,
            wr.as_mut_ptr(),
            wi.as_mut_ptr(),
            vl.as_mut_ptr(),
            &one,
            vr.as_mut_ptr(),
            &ni,
            work.as_mut_ptr(),
            &lw,
            &mut info,
        );
    }
    if info != 0 {
        return Err(lapack("dgeev", info, n, "did not converge"));
    }
    let col = |j: usize| &vr[j * n..(j + 1) * n];
    let mut vectors = Vec::with_capacity(n);
    let mut j = 0;
    while j < n {
        if wi[j] != 0.0 && j + 1 < n {
            let (re, im) = (col(j), col(j + 1));
            let v: Vec<(f64, f64)> = re.iter().zip(im).map(|(&r, &i)| (r, i)).collect();
            let conj: Vec<(f64, f64)> = v.iter().map(|&(r, i)| (r, -i)).collect();
            vectors.push(v);
            vectors.push(conj);
            j += 2;
        } else {
            vectors.push(col(j).iter().map(|&r| (r, 0.0)).collect());
            j += 1;
        }
    }
    Ok(DenseEigen {
        values: wr.into_iter().zip(wi).collect(),
        vectors,
    })
}

/// The eigenvalues `(re, im)` of the n x n column-major matrix `a` (consumed) by LAPACK's
/// dgeev (balancing, Hessenberg QR), without eigenvectors.
pub fn eigenvalues(n: usize, mut a: Vec<f64>) -> Result<Vec<(f64, f64)>, DenseError> {
    if a.len() != n * n {
        return Err(DenseError::Shape {
            what: "dgeev",
            found: a.len(),
            order: n,
        });
    }
    if a.iter().any(|x| !x.is_finite()) {
        return Err(DenseError::NotFinite { what: "dgeev" });
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let ni = dim(n)?;
    let (mut wr, mut wi) = (vec![0.0; n], vec![0.0; n]);
    let mut unused = [0.0f64; 1];
    let no = b'N' as c_char;
    let one: c_int = 1;
    let mut info: c_int = 0;
    let mut call = |work: &mut [f64], lwork: c_int, info: &mut c_int| {
        // SAFETY: a holds n x n entries, wr and wi n each, work lwork (1 for the workspace
        // query, lwork = -1); no eigenvectors are asked for (ldv = 1).
        unsafe {
            dgeev_(
                &no,
                &no,
                &ni,
                a.as_mut_ptr(),
                &ni,
                wr.as_mut_ptr(),
                wi.as_mut_ptr(),
                unused.as_mut_ptr(),
                &one,
                unused.as_mut_ptr(),
                &one,
                work.as_mut_ptr(),
                &lwork,
                info,
            );
        }
    };
    let mut query = [0.0f64];
    call(&mut query, -1, &mut info);
    if info != 0 {
        return Err(lapack("dgeev", info, n, "workspace query"));
    }
    let lwork = (query[0] as usize).max(3 * n);
    let mut work = vec![0.0; lwork];
    call(&mut work, dim(lwork)?, &mut info);
    if info != 0 {
        return Err(lapack("dgeev", info, n, "did not converge"));
    }
    Ok(wr.into_iter().zip(wi).collect())
}

/// Eigenvalues (ascending) and orthonormal eigenvectors (column-major, n x n) of the
/// symmetric n x n column-major matrix `a` (its lower triangle is read; consumed).
pub fn eigen_symmetric(n: usize, mut a: Vec<f64>) -> Result<(Vec<f64>, Vec<f64>), DenseError> {
    if a.len() != n * n {
        return Err(DenseError::Shape {
            what: "dense symmetric eigenproblem",
            found: a.len(),
            order: n,
        });
    }
    if n == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let ni = dim(n)?;
    let (jobz, uplo) = (b'V' as c_char, b'L' as c_char);
    let mut w = vec![0.0; n];
    let mut info: c_int = 0;
    let mut query = 0.0f64;
    let minus_one: c_int = -1;
    // SAFETY: workspace query (lwork = -1): LAPACK writes the optimal size into `query`; a is
    // n x n (lda n), w has n entries.
    unsafe {
        dsyev_(
            &jobz,
            &uplo,
            &ni,
            a.as_mut_ptr(),
            &ni,
            w.as_mut_ptr(),
            &mut query,
            &minus_one,
            &mut info,
        );
    }
    if info != 0 {
        return Err(lapack("dsyev", info, n, "workspace query"));
    }
    let lwork = (query as usize).max(3 * n);
    let mut work = vec![0.0; lwork];
    let lw = dim(lwork)?;
    // SAFETY: as above with a workspace of lwork entries.
    unsafe {
        dsyev_(
            &jobz,
            &uplo,
            &ni,
            a.as_mut_ptr(),
            &ni,
            w.as_mut_ptr(),
            work.as_mut_ptr(),
            &lw,
            &mut info,
        );
    }
    if info != 0 {
        return Err(lapack("dsyev", info, n, "did not converge"));
    }
    Ok((w, a))
}

/// C = op(A) op(B) (op = transpose when the flag is set) for column-major operands; C is
/// m x n, the inner dimension k. A is k x m when transposed, else m x k; B is n x k when
/// transposed, else k x n.
fn gemm(ta: bool, tb: bool, m: usize, k: usize, n: usize, a: &[f64], b: &[f64]) -> Vec<f64> {
    assert!(a.len() >= k * m && b.len() >= k * n, "gemm: operand sizes");
    let mut c = vec![0.0; m * n];
    if k == 0 || m == 0 || n == 0 {
        return c;
    }
    let (ki, mi, ni) = (
        dim(k).expect("gemm order"),
        dim(m).expect("gemm order"),
        dim(n).expect("gemm order"),
    );
    let flag = |t: bool| if t { b'T' as c_char } else { b'N' as c_char };
    let (lda, ldb) = (if ta { ki } else { mi }, if tb { ni } else { ki });
    let (alpha, beta) = (1.0f64, 0.0f64);
    // SAFETY: A is stored with leading dimension lda and k x m or m x k entries, B likewise
    // with ldb, C is m x n (ldc m); the sizes are asserted above.
    unsafe {
        dgemm_(
            &flag(ta),
            &flag(tb),
            &mi,
            &ni,
            &ki,
            &alpha,
            a.as_ptr(),
            &lda,
            b.as_ptr(),
            &ldb,
            &beta,
            c.as_mut_ptr(),
            &mi,
            1,
            1,
        );
    }
    c
}

/// C = A^T B for column-major A (k x m) and B (k x n); returns m x n column-major.
pub fn gemm_tn(k: usize, m: usize, n: usize, a: &[f64], b: &[f64]) -> Vec<f64> {
    gemm(true, false, m, k, n, a, b)
}

/// C = A B for column-major A (m x k) and B (k x n); returns m x n column-major.
pub fn gemm_nn(m: usize, k: usize, n: usize, a: &[f64], b: &[f64]) -> Vec<f64> {
    gemm(false, false, m, k, n, a, b)
}

/// out += sign A^T A for column-major A (k x m), out m x m column-major: half the flops of
/// [`gemm_tn`] for a symmetric product (dsyrk fills one triangle; it is mirrored here).
pub fn add_gram(k: usize, m: usize, sign: f64, a: &[f64], out: &mut [f64]) {
    assert!(
        a.len() >= k * m && out.len() == m * m,
        "syrk: operand sizes"
    );
    if k == 0 || m == 0 {
        return;
    }
    let (ki, mi) = (dim(k).expect("syrk order"), dim(m).expect("syrk order"));
    let mut c = vec![0.0; m * m];
    let (uplo, trans, beta) = (b'U' as c_char, b'T' as c_char, 0.0f64);
    // SAFETY: A is k x m with leading dimension k (asserted), C is m x m with ldc m.
    unsafe {
        dsyrk_(
            &uplo,
            &trans,
            &mi,
            &ki,
            &sign,
            a.as_ptr(),
            &ki,
            &beta,
            c.as_mut_ptr(),
            &mi,
        );
    }
    for j in 0..m {
        for i in 0..=j {
            let v = c[j * m + i];
            out[j * m + i] += v;
            if i != j {
                out[i * m + j] += v;
            }
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn symmetric_eigenvectors_are_orthonormal_and_diagonalize() {
        // [[2, 1, 0], [1, 2, 1], [0, 1, 2]]: 2 - sqrt 2, 2, 2 + sqrt 2.
        let a = vec![2.0, 1.0, 0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0];
        let (w, v) = eigen_symmetric(3, a.clone()).unwrap();
        let s = 2f64.sqrt();
        for (got, want) in w.iter().zip([2.0 - s, 2.0, 2.0 + s]) {
            assert!((got - want).abs() < 1e-14, "{got} vs {want}");
        }
        let av = gemm_nn(3, 3, 3, &a, &v);
        let vtav = gemm_tn(3, 3, 3, &v, &av);
        let vtv = gemm_tn(3, 3, 3, &v, &v);
        for i in 0..3 {
            for j in 0..3 {
                let d = if i == j { 1.0 } else { 0.0 };
                assert!((vtv[i + 3 * j] - d).abs() < 1e-14);
                assert!((vtav[i + 3 * j] - d * w[i]).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn rotation_scaling_has_conjugate_pair_and_vectors_satisfy_av_equals_lambda_v() {
        // [[1, -2], [2, 1]] : 1 +- 2i; plus a real eigenvalue 3 in a 3x3 block diagonal.
        let a = vec![1.0, 2.0, 0.0, -2.0, 1.0, 0.0, 0.0, 0.0, 3.0];
        let e = eigen_general(3, a.clone()).unwrap();
        for (j, &(re, im)) in e.values.iter().enumerate() {
            let v = &e.vectors[j];
            for i in 0..3 {
                let (mut sr, mut si) = (0.0, 0.0);
                for k in 0..3 {
                    sr += a[k * 3 + i] * v[k].0;
                    si += a[k * 3 + i] * v[k].1;
                }
                let (lr, li) = (re * v[i].0 - im * v[i].1, re * v[i].1 + im * v[i].0);
                assert!((sr - lr).abs() < 1e-14 && (si - li).abs() < 1e-14);
            }
        }
        let mut found: Vec<(f64, f64)> = e.values.clone();
        found.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(found.len(), 3);
        assert!((found[0].0 - 1.0).abs() < 1e-14 && (found[0].1 + 2.0).abs() < 1e-14);
        assert!((found[2].0 - 3.0).abs() < 1e-14);
    }

    #[test]
    fn gemm_tn_matches_loops() {
        let (k, m, n) = (5, 3, 4);
        let a: Vec<f64> = (0..k * m).map(|i| (i as f64).sin()).collect();
        let b: Vec<f64> = (0..k * n).map(|i| (i as f64 * 0.7).cos()).collect();
        let c = gemm_tn(k, m, n, &a, &b);
        for i in 0..m {
            for j in 0..n {
                let s: f64 = (0..k).map(|l| a[i * k + l] * b[j * k + l]).sum();
                assert!((c[j * m + i] - s).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn add_gram_matches_the_general_product_in_both_triangles() {
        let (k, m) = (7, 4);
        let a: Vec<f64> = (0..k * m).map(|i| (i as f64 * 1.3).sin()).collect();
        let full = gemm_tn(k, m, m, &a, &a);
        let mut out: Vec<f64> = (0..m * m).map(|i| i as f64).collect();
        add_gram(k, m, -2.0, &a, &mut out);
        for (i, (o, f)) in out.iter().zip(&full).enumerate() {
            let expected = i as f64 - 2.0 * f;
            assert!((o - expected).abs() < 1e-13, "entry {i}: {o} vs {expected}");
        }
    }

    #[test]
    fn non_finite_input_is_an_error() {
        assert!(eigen_general(1, vec![f64::NAN]).is_err());
    }
}
