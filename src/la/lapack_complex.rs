//! Dense complex LAPACK (OpenBLAS here) for the eigenpairs near a shift of the projected
//! quadratic problem: the LU of a complex matrix (zgetrf / zgetrs), orthonormal columns by
//! Householder QR (zgeqrf / zungqr) and the eigenpairs of a small complex matrix (zgeev). Column-major storage; `Complex64` has the layout of Fortran's
//! double complex.

use crate::la::DenseError;
use std::os::raw::{c_char, c_int};

use num_complex::Complex64;

use super::lapack::dim;

extern "C" {
    fn zgetrf_(
        m: *const c_int,
        n: *const c_int,
        a: *mut Complex64,
        lda: *const c_int,
        ipiv: *mut c_int,
        info: *mut c_int,
    );
    fn zgetrs_(
        trans: *const c_char,
        n: *const c_int,
        nrhs: *const c_int,
        a: *const Complex64,
        lda: *const c_int,
        ipiv: *const c_int,
        b: *mut Complex64,
        ldb: *const c_int,
        info: *mut c_int,
    );
    fn zgemm_(
        transa: *const c_char,
        transb: *const c_char,
        m: *const c_int,
        n: *const c_int,
        k: *const c_int,
        alpha: *const Complex64,
        a: *const Complex64,
        lda: *const c_int,
        b: *const Complex64,
        ldb: *const c_int,
        beta: *const Complex64,
        c: *mut Complex64,
        ldc: *const c_int,
    );
    fn zgeqrf_(
        m: *const c_int,
        n: *const c_int,
        a: *mut Complex64,
        lda: *const c_int,
        tau: *mut Complex64,
        work: *mut Complex64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn zungqr_(
        m: *const c_int,
        n: *const c_int,
        k: *const c_int,
        a: *mut Complex64,
        lda: *const c_int,
        tau: *const Complex64,
        work: *mut Complex64,
        lwork: *const c_int,
        info: *mut c_int,
    );
    fn zgeev_(
        jobvl: *const c_char,
        jobvr: *const c_char,
        n: *const c_int,
        a: *mut Complex64,
        lda: *const c_int,
        w: *mut Complex64,
        vl: *mut Complex64,
        ldvl: *const c_int,
        vr: *mut Complex64,
        ldvr: *const c_int,
        work: *mut Complex64,
        lwork: *const c_int,
        rwork: *mut f64,
        info: *mut c_int,
    );
}

/// How [`gemm`] reads an operand.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Op {
    /// As stored.
    Plain,
    /// Conjugate transpose.
    Adjoint,
}

/// C = op(A) B for column-major operands: C is m x n, the inner dimension k; A is m x k when
/// plain, k x m when adjoint; B is k x n.
pub fn gemm(
    op: Op,
    m: usize,
    k: usize,
    n: usize,
    a: &[Complex64],
    b: &[Complex64],
) -> Vec<Complex64> {
    assert!(a.len() >= m * k && b.len() >= k * n, "zgemm: operand sizes");
    let mut c = vec![Complex64::default(); m * n];
    if m == 0 || n == 0 || k == 0 {
        return c;
    }
    let (mi, ki, ni) = (
        dim(m).expect("zgemm order"),
        dim(k).expect("zgemm order"),
        dim(n).expect("zgemm order"),
    );
    let (ta, lda) = match op {
        Op::Plain => (b'N' as c_char, mi),
        Op::Adjoint => (b'C' as c_char, ki),
    };
    let tb = b'N' as c_char;
    let (one, zero) = (Complex64::new(1.0, 0.0), Complex64::default());
    // SAFETY: A is m x k (lda m) or k x m (lda k), B is k x n (ldb k), C is m x n (ldc m); the
    // sizes are asserted above.
    unsafe {
        zgemm_(
            &ta,
            &tb,
            &mi,
            &ni,
            &ki,
            &one,
            a.as_ptr(),
            &lda,
            b.as_ptr(),
            &ki,
            &zero,
            c.as_mut_ptr(),
            &mi,
        );
    }
    c
}

/// The LU factors (with row pivots) of an n x n complex matrix.
pub struct ComplexLu {
    n: usize,
    factors: Vec<Complex64>,
    pivots: Vec<c_int>,
}

impl ComplexLu {
    /// Factors the column-major n x n matrix `a` (consumed). Errs on a singular matrix (a zero
    /// pivot) or non-finite entries.
    pub fn new(n: usize, mut a: Vec<Complex64>) -> Result<Self, DenseError> {
        if a.len() != n * n {
            return Err(DenseError::Shape {
                what: "complex LU",
                found: a.len(),
                order: n,
            });
        }
        if a.iter().any(|z| !z.is_finite()) {
            return Err(DenseError::NotFinite { what: "complex LU" });
        }
        let ni = dim(n.max(1))?;
        let mut pivots: Vec<c_int> = vec![0; n];
        let mut info: c_int = 0;
        if n > 0 {
            // SAFETY: a is n x n with leading dimension n, pivots has n entries.
            unsafe {
                zgetrf_(
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
            return Err(super::lapack::lapack("zgetrf", info, n, meaning));
        }
        Ok(ComplexLu {
            n,
            factors: a,
            pivots,
        })
    }

    /// Solves A X = B in place for the column-major n x nrhs right-hand sides `b`.
    pub fn solve(&self, b: &mut [Complex64]) -> Result<(), DenseError> {
        let n = self.n;
        if n == 0 || b.is_empty() {
            return Ok(());
        }
        if !b.len().is_multiple_of(n) {
            return Err(DenseError::Shape {
                what: "complex LU solve",
                found: b.len(),
                order: n,
            });
        }
        let (ni, nrhs) = (dim(n)?, dim(b.len() / n)?);
        let trans = b'N' as c_char;
        let mut info: c_int = 0;
        // SAFETY: the factors and pivots come from zgetrf of order n; b is n x nrhs (ldb n).
        unsafe {
            zgetrs_(
                &trans,
                &ni,
                &nrhs,
                self.factors.as_ptr(),
                &ni,
                self.pivots.as_ptr(),
                b.as_mut_ptr(),
                &ni,
                &mut info,
            );
        }
        if info != 0 {
            return Err(super::lapack::lapack("zgetrs", info, n, "bad argument"));
        }
        Ok(())
    }
}

/// Replaces the columns of the column-major rows x cols block `q` (rows >= cols) by an
/// orthonormal basis of their span, by Householder QR (zgeqrf, zungqr): orthonormal to
/// round-off whatever their conditioning; where columns are dependent, the reflectors supply
/// orthonormal directions beyond their span.
pub fn orthonormalize(rows: usize, q: &mut [Complex64]) -> Result<(), DenseError> {
    if rows == 0 || q.is_empty() {
        return Ok(());
    }
    let cols = q.len() / rows;
    if q.len() != rows * cols || cols > rows {
        return Err(DenseError::Shape {
            what: "orthonormalize (columns of that many rows)",
            found: q.len(),
            order: rows,
        });
    }
    let (mi, ni) = (dim(rows)?, dim(cols)?);
    let lwork = 64 * cols;
    let lw = dim(lwork)?;
    let mut tau = vec![Complex64::default(); cols];
    let mut work = vec![Complex64::default(); lwork];
    let mut info: c_int = 0;
    // SAFETY: q is rows x cols (lda rows, rows >= cols, checked above), tau has cols entries,
    // work has lwork >= cols entries.
    unsafe {
        zgeqrf_(
            &mi,
            &ni,
            q.as_mut_ptr(),
            &mi,
            tau.as_mut_ptr(),
            work.as_mut_ptr(),
            &lw,
            &mut info,
        );
    }
    if info != 0 {
        return Err(super::lapack::lapack("zgeqrf", info, rows, "bad argument"));
    }
    // SAFETY: as above; zungqr forms the cols x cols reflectors' Q in place.
    unsafe {
        zungqr_(
            &mi,
            &ni,
            &ni,
            q.as_mut_ptr(),
            &mi,
            tau.as_ptr(),
            work.as_mut_ptr(),
            &lw,
            &mut info,
        );
    }
    if info != 0 {
        return Err(super::lapack::lapack("zungqr", info, rows, "bad argument"));
    }
    Ok(())
}

/// Eigenvalues and right eigenvectors (column j of the returned n x n column-major matrix,
/// Euclidean norm 1) of the general complex n x n column-major matrix `a` (consumed).
pub fn eigen_complex(
    n: usize,
    mut a: Vec<Complex64>,
) -> Result<(Vec<Complex64>, Vec<Complex64>), DenseError> {
    if a.len() != n * n {
        return Err(DenseError::Shape {
            what: "complex eigenproblem",
            found: a.len(),
            order: n,
        });
    }
    if a.iter().any(|z| !z.is_finite()) {
        return Err(DenseError::NotFinite {
            what: "complex eigenproblem",
        });
    }
    if n == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    let ni = dim(n)?;
    let (no, yes) = (b'N' as c_char, b'V' as c_char);
    let one: c_int = 1;
    let mut w = vec![Complex64::default(); n];
    let mut vr = vec![Complex64::default(); n * n];
    let mut vl = [Complex64::default(); 1];
    let mut rwork = vec![0.0f64; 2 * n];
    let lwork = 4 * n;
    let lw = dim(lwork)?;
    let mut work = vec![Complex64::default(); lwork];
    let mut info: c_int = 0;
    // SAFETY: a is n x n (lda n), w has n entries, vr is n x n (ldvr n), vl is not referenced
    // (jobvl 'N', ldvl 1), work has lwork >= 2n entries, rwork 2n.
    unsafe {
        zgeev_(
            &no,
            &yes,
            &ni,
            a.as_mut_ptr(),
            &ni,
            w.as_mut_ptr(),
            vl.as_mut_ptr(),
            &one,
            vr.as_mut_ptr(),
            &ni,
            work.as_mut_ptr(),
            &lw,
            rwork.as_mut_ptr(),
            &mut info,
        );
    }
    if info != 0 {
        return Err(super::lapack::lapack("zgeev", info, n, "did not converge"));
    }
    Ok((w, vr))
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn complex_lu_solves_and_eigenpairs_satisfy_av_equals_lambda_v() {
        // A = [[2, i], [1, 3 - i]] (column-major).
        let a = vec![c(2.0, 0.0), c(1.0, 0.0), c(0.0, 1.0), c(3.0, -1.0)];
        let x = [c(1.0, -2.0), c(0.5, 0.25)];
        let mut b = vec![a[0] * x[0] + a[2] * x[1], a[1] * x[0] + a[3] * x[1]];
        ComplexLu::new(2, a.clone()).unwrap().solve(&mut b).unwrap();
        for (got, want) in b.iter().zip(x) {
            assert!((got - want).norm() < 1e-15, "{got} vs {want}");
        }
        let (w, v) = eigen_complex(2, a.clone()).unwrap();
        for j in 0..2 {
            let col = &v[2 * j..2 * j + 2];
            for i in 0..2 {
                let av = a[i] * col[0] + a[2 + i] * col[1];
                assert!((av - w[j] * col[i]).norm() < 1e-14);
            }
        }
        assert!(
            ComplexLu::new(2, vec![c(1.0, 0.0), c(2.0, 0.0), c(2.0, 0.0), c(4.0, 0.0)]).is_err()
        );
        assert!(ComplexLu::new(1, vec![c(f64::NAN, 0.0)]).is_err());
    }

    /// Orthonormal columns spanning the block's span, also where two columns are parallel.
    #[test]
    fn orthonormalized_columns_are_orthonormal_and_span_the_block() {
        let rows = 5;
        let a: Vec<Complex64> = (0..rows * 3)
            .map(|k| c((k as f64 * 0.7).sin(), (k as f64 * 1.3).cos()))
            .collect();
        let mut q = a.clone();
        // The third column parallel to the first.
        for i in 0..rows {
            q[2 * rows + i] = q[i] * c(0.0, 2.0);
        }
        let parallel = q.clone();
        orthonormalize(rows, &mut q).unwrap();
        let gram = gemm(Op::Adjoint, 3, rows, 3, &q, &q);
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((gram[j * 3 + i] - c(want, 0.0)).norm() < 1e-14);
            }
        }
        // The first two input columns lie in the span: Q Q^H a = a.
        for col in parallel.chunks(rows).take(2) {
            let coef = gemm(Op::Adjoint, 3, rows, 1, &q, col);
            let back = gemm(Op::Plain, rows, 3, 1, &q, &coef);
            for (b, x) in back.iter().zip(col) {
                assert!((b - x).norm() < 1e-14);
            }
        }
    }
}
