//! Every eigenvalue of a dense quadratic eigenproblem (s^2 M + s C + K) x = 0 with M symmetric
//! positive definite, by LAPACK alone: no shift, no Krylov space, no projection. It is the
//! independent reference the complex modes of small models are checked against, on the
//! matrices `[output] export_matrices` writes.
//!
//! The companion form is scaled so that its blocks have norm ~1 (s = gamma mu with
//! gamma = sqrt(||K|| / ||M||), everything divided by ||K||; Fan, Lin & Van Dooren, SIMAX 26,
//! 2004) and turned into a standard problem with the Cholesky factor of M:
//! [[0, I], [-M~^-1 K~, -M~^-1 C~]], whose eigenvalues dgeev finds (balancing, Hessenberg QR).
//! QZ on the pencil (dggev) would not need M^-1 but is much slower at the orders the projected
//! routes reach (benches/decisions-results.md, "dense-quadratic").

use crate::la::DenseError;
use std::os::raw::{c_char, c_int};

use super::lapack::{dim, eigenvalues};
use crate::measure::nan_max;

extern "C" {
    fn dpotrf_(
        uplo: *const c_char,
        n: *const c_int,
        a: *mut f64,
        lda: *const c_int,
        info: *mut c_int,
    );
    fn dpotrs_(
        uplo: *const c_char,
        n: *const c_int,
        nrhs: *const c_int,
        a: *const f64,
        lda: *const c_int,
        b: *mut f64,
        ldb: *const c_int,
        info: *mut c_int,
    );
}

/// Solves M X = B in place for the symmetric positive definite n x n column-major `m`
/// (consumed; Cholesky, dpotrf + dpotrs) and the n x nrhs column-major `b`.
pub fn solve_spd(n: usize, mut m: Vec<f64>, b: &mut [f64]) -> Result<(), DenseError> {
    if m.len() != n * n || n == 0 || !b.len().is_multiple_of(n) {
        return Err(DenseError::Shape {
            what: "Cholesky solve (matrix, then right-hand sides of that order)",
            found: m.len().max(b.len()),
            order: n,
        });
    }
    let (ni, nrhs) = (dim(n)?, dim(b.len() / n)?);
    let lower = b'L' as c_char;
    let mut info: c_int = 0;
    // SAFETY: m holds n x n entries (leading dimension n).
    unsafe { dpotrf_(&lower, &ni, m.as_mut_ptr(), &ni, &mut info) };
    if info != 0 {
        return Err(super::lapack::lapack(
            "dpotrf",
            info,
            n,
            "the matrix is not positive definite",
        ));
    }
    // SAFETY: m is the factor (n x n), b holds n x nrhs entries (leading dimension n).
    unsafe {
        dpotrs_(
            &lower,
            &ni,
            &nrhs,
            m.as_ptr(),
            &ni,
            b.as_mut_ptr(),
            &ni,
            &mut info,
        )
    };
    if info != 0 {
        return Err(super::lapack::lapack("dpotrs", info, n, "bad argument"));
    }
    Ok(())
}

/// The eigenvalues `(re, im)` of (s^2 M + s C + K) x = 0 for dense n x n column-major K, C and
/// M (M symmetric positive definite), conjugate pairs included.
pub fn quadratic_eigenvalues(
    n: usize,
    k: &[f64],
    c: &[f64],
    m: &[f64],
) -> Result<Vec<(f64, f64)>, DenseError> {
    if let Some(&found) = [k.len(), c.len(), m.len()].iter().find(|&&l| l != n * n) {
        return Err(DenseError::Shape {
            what: "quadratic eigenproblem (K, C, M)",
            found,
            order: n,
        });
    }
    let inf_norm = |a: &[f64]| {
        (0..n)
            .map(|i| (0..n).map(|j| a[i + n * j].abs()).sum::<f64>())
            .fold(0.0, nan_max)
    };
    let (norm_k, norm_m) = (inf_norm(k), inf_norm(m));
    let gamma = (norm_k / norm_m).sqrt();
    // [K~ C~] = ([K C gamma] / ||K||), solved with M~ = M gamma^2 / ||K||: M~^-1 [K~ C~].
    let mut rhs: Vec<f64> = k
        .iter()
        .map(|x| x / norm_k)
        .chain(c.iter().map(|x| x * gamma / norm_k))
        .collect();
    let scaled_m: Vec<f64> = m.iter().map(|x| x * gamma * gamma / norm_k).collect();
    solve_spd(n, scaled_m, &mut rhs)?;
    let two = 2 * n;
    let mut a = vec![0.0; two * two];
    for i in 0..n {
        a[i + two * (n + i)] = 1.0;
        for j in 0..n {
            a[(n + i) + two * j] = -rhs[i + n * j];
            a[(n + i) + two * (n + j)] = -rhs[n * n + i + n * j];
        }
    }
    Ok(eigenvalues(two, a)?
        .into_iter()
        .map(|(re, im)| (re * gamma, im * gamma))
        .collect())
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn damped_oscillators_give_their_closed_form_roots() {
        // Two uncoupled oscillators m s^2 + c s + k = 0: s = (-c +- sqrt(c^2 - 4 m k)) / (2 m),
        // one underdamped, one overdamped, with stiffness and mass of brake-like scales.
        let (m, c, k) = ([2e-3, 1e-3], [0.4, 30.0], [8e7, 1e5]);
        let diag = |v: [f64; 2]| vec![v[0], 0.0, 0.0, v[1]];
        let mut s = quadratic_eigenvalues(2, &diag(k), &diag(c), &diag(m)).unwrap();
        s.sort_by(|a, b| (a.0, a.1).partial_cmp(&(b.0, b.1)).unwrap());
        let mut exact = Vec::new();
        for i in 0..2 {
            let disc = c[i] * c[i] - 4.0 * m[i] * k[i];
            let (re, im) = if disc < 0.0 {
                (-c[i] / (2.0 * m[i]), (-disc).sqrt() / (2.0 * m[i]))
            } else {
                (disc.sqrt() / (2.0 * m[i]), 0.0)
            };
            let centre = if disc < 0.0 { re } else { -c[i] / (2.0 * m[i]) };
            if disc < 0.0 {
                exact.extend([(centre, -im), (centre, im)]);
            } else {
                exact.extend([(centre - re, 0.0), (centre + re, 0.0)]);
            }
        }
        exact.sort_by(|a, b| (a.0, a.1).partial_cmp(&(b.0, b.1)).unwrap());
        for (got, want) in s.iter().zip(&exact) {
            let scale = want.0.hypot(want.1);
            assert!(
                (got.0 - want.0).hypot(got.1 - want.1) <= 1e-12 * scale,
                "{got:?} vs {want:?}"
            );
        }
        assert!(eigenvalues(1, vec![f64::NAN]).is_err());
        assert!(
            quadratic_eigenvalues(1, &[1.0], &[0.0], &[-1.0]).is_err(),
            "M not SPD"
        );
    }
}
