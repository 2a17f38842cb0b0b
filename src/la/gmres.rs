//! GMRES (right-preconditioned, no restart) over PETSc vectors, for a system given by its
//! products: the static Newton's correction with a stale LU factor as preconditioner, and
//! the transient's Newton-Krylov on the consistent tangent (the step's factor with its
//! low-rank update as preconditioner).
//!
//! No `unsafe` here; it lives in `la/` beside the vectors it works on.

use super::{LaError, Vector};

/// A right-preconditioned system A M^-1 y = b, x = M^-1 y.
pub trait Preconditioned<'p> {
    /// w = A M^-1 v.
    fn apply(&mut self, v: &Vector<'p>, w: &mut Vector<'p>) -> Result<(), LaError>;
    /// x = M^-1 v.
    fn precondition(&mut self, v: &Vector<'p>, x: &mut Vector<'p>) -> Result<(), LaError>;
}

/// How a GMRES solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresOutcome {
    /// Arnoldi steps taken (one product with A M^-1 each; one more M^-1 forms x).
    pub iterations: usize,
    /// |b - A x| as GMRES' recurrence gives it.
    pub residual: f64,
    /// The residual reached `enough` (false also when it is NaN).
    pub converged: bool,
}

/// Solves A x = b from x = 0 until |b - A x| <= `enough` or `max_iterations` steps, with the
/// Krylov basis in `basis` (grown as needed, kept for the next call). x holds the minimal-
/// residual solution either way; the caller decides what an unconverged one is worth.
///
/// # Collective
pub fn gmres<'p>(
    system: &mut impl Preconditioned<'p>,
    b: &Vector<'p>,
    x: &mut Vector<'p>,
    basis: &mut Vec<Vector<'p>>,
    enough: f64,
    max_iterations: usize,
) -> Result<GmresOutcome, LaError> {
    let m = max_iterations.max(1);
    while basis.len() < m + 1 {
        basis.push(b.duplicate()?);
    }
    let beta0 = b.norm2()?;
    x.set_all(0.0)?;
    if beta0 <= enough {
        return Ok(GmresOutcome {
            iterations: 0,
            residual: beta0,
            converged: beta0.is_finite(),
        });
    }
    basis[0].copy_from(b)?;
    basis[0].scale(1.0 / beta0)?;
    // Hessenberg columns (Givens-rotated to triangular), the rotations, the rotated b.
    let mut h = vec![vec![0.0; m + 1]; m];
    let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
    let mut g = vec![0.0; m + 1];
    g[0] = beta0;
    let mut k = 0;
    while k < m {
        let (head, tail) = basis.split_at_mut(k + 1);
        let w = &mut tail[0];
        system.apply(&head[k], w)?;
        // Classical Gram-Schmidt twice: as orthogonal as modified Gram-Schmidt, in two
        // reductions over the ranks instead of k + 1.
        let previous: Vec<&Vector<'p>> = head.iter().collect();
        for _ in 0..2 {
            let coefficients = w.mdot(&previous)?;
            let negated: Vec<f64> = coefficients.iter().map(|c| -c).collect();
            w.maxpy(&negated, &previous)?;
            for (hi, c) in h[k].iter_mut().zip(&coefficients) {
                *hi += c;
            }
        }
        h[k][k + 1] = w.norm2()?;
        if h[k][k + 1] > 0.0 {
            w.scale(1.0 / h[k][k + 1])?;
        }
        for i in 0..k {
            let t = cs[i] * h[k][i] + sn[i] * h[k][i + 1];
            h[k][i + 1] = -sn[i] * h[k][i] + cs[i] * h[k][i + 1];
            h[k][i] = t;
        }
        let d = h[k][k].hypot(h[k][k + 1]);
        (cs[k], sn[k]) = if d > 0.0 {
            (h[k][k] / d, h[k][k + 1] / d)
        } else {
            (1.0, 0.0)
        };
        h[k][k] = d;
        h[k][k + 1] = 0.0;
        g[k + 1] = -sn[k] * g[k];
        g[k] *= cs[k];
        k += 1;
        // A breakdown (h = 0) is the exact solution: |g[k]| is then 0 too.
        if g[k].abs() <= enough || !g[k].is_finite() {
            break;
        }
    }
    // y from the triangular system, then x = M^-1 (V y).
    let mut y = vec![0.0; k];
    for i in (0..k).rev() {
        let mut t = g[i];
        for j in i + 1..k {
            t -= h[j][i] * y[j];
        }
        y[i] = t / h[i][i];
    }
    let used: Vec<&Vector<'p>> = basis[..k].iter().collect();
    let mut combined = b.duplicate()?;
    combined.maxpy(&y, &used)?;
    system.precondition(&combined, x)?;
    let residual = g[k].abs();
    Ok(GmresOutcome {
        iterations: k,
        residual,
        converged: residual <= enough,
    })
}
