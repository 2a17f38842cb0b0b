//! Eigenvalues of a dense generalized problem A x = lambda B x by LAPACK's QZ algorithm
//! (dggev): no shift, no Krylov space, no projection, every eigenvalue at once. It is the
//! independent reference the complex modes of small models are checked against (on the
//! companion form of the quadratic problem), and what a user can run on exported matrices.

use std::os::raw::{c_char, c_int};

use super::lapack::dim;

extern "C" {
    fn dggev_(
        jobvl: *const c_char,
        jobvr: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        b: *mut f64,
        ldb: *const c_int,
        alphar: *mut f64,
        alphai: *mut f64,
        beta: *mut f64,
        vl: *mut f64,
        ldvl: *const c_int,
        vr: *mut f64,
        ldvr: *const c_int,
        work: *mut f64,
        lwork: *const c_int,
        info: *mut c_int,
    );
}

/// The eigenvalues `(re, im)` of the n x n column-major pencil (a, b) (both consumed); an
/// infinite eigenvalue (beta = 0, singular b) is left out. Conjugate pairs come consecutive.
pub fn generalized_eigenvalues(
    n: usize,
    mut a: Vec<f64>,
    mut b: Vec<f64>,
) -> Result<Vec<(f64, f64)>, String> {
    if a.len() != n * n || b.len() != n * n {
        return Err(format!(
            "QZ: {} and {} entries for order {n}",
            a.len(),
            b.len()
        ));
    }
    if a.iter().chain(&b).any(|x| !x.is_finite()) {
        return Err("QZ: the pencil has NaN or infinite entries".into());
    }
    if n == 0 {
        return Ok(Vec::new());
    }
    let ni = dim(n)?;
    let (mut ar, mut ai, mut beta) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut unused = [0.0f64; 1];
    let no = b'N' as c_char;
    let one: c_int = 1;
    let mut info: c_int = 0;
    let mut call = |work: &mut [f64], lwork: c_int, info: &mut c_int| {
        // SAFETY: a and b hold n x n entries, the outputs n each, work lwork (or 1 for the
        // workspace query, lwork = -1); no eigenvectors are asked for (ldv = 1).
        unsafe {
            dggev_(
                &no,
                &no,
                &ni,
                a.as_mut_ptr(),
                &ni,
                b.as_mut_ptr(),
                &ni,
                ar.as_mut_ptr(),
                ai.as_mut_ptr(),
                beta.as_mut_ptr(),
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
        return Err(format!("dggev workspace query failed (info {info})"));
    }
    let lwork = (query[0] as usize).max(8 * n);
    let mut work = vec![0.0; lwork];
    call(&mut work, dim(lwork)?, &mut info);
    if info != 0 {
        return Err(format!(
            "dggev failed (info {info}): the QZ iteration of order {n} did not converge"
        ));
    }
    Ok((0..n)
        .filter(|&j| beta[j] != 0.0)
        .map(|j| (ar[j] / beta[j], ai[j] / beta[j]))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diagonal_pencil_and_a_rotation_give_their_closed_forms() {
        // diag(2, 6) x = lambda diag(1, 3) x: lambda = 2, 2.
        let l =
            generalized_eigenvalues(2, vec![2.0, 0.0, 0.0, 6.0], vec![1.0, 0.0, 0.0, 3.0]).unwrap();
        assert!(
            l.iter()
                .all(|&(re, im)| (re - 2.0).abs() < 1e-14 && im == 0.0),
            "{l:?}"
        );
        // [[0, -w], [w, 0]] (column-major) with B = 2 I: lambda = +- i w / 2.
        let w = 3.0;
        let l =
            generalized_eigenvalues(2, vec![0.0, w, -w, 0.0], vec![2.0, 0.0, 0.0, 2.0]).unwrap();
        let mut im: Vec<f64> = l.iter().map(|z| z.1).collect();
        im.sort_by(f64::total_cmp);
        assert!(
            (im[0] + 1.5).abs() < 1e-14 && (im[1] - 1.5).abs() < 1e-14,
            "{l:?}"
        );
        // A singular B gives an infinite eigenvalue, left out.
        let l =
            generalized_eigenvalues(2, vec![1.0, 0.0, 0.0, 1.0], vec![1.0, 0.0, 0.0, 0.0]).unwrap();
        assert_eq!(l.len(), 1);
        assert!(generalized_eigenvalues(1, vec![f64::NAN], vec![1.0]).is_err());
    }
}
