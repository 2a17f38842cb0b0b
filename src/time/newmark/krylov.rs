//! Newton-Krylov: GMRES on the consistent tangent at the iterate, right-preconditioned by the
//! step's factor updated by a low-rank (Woodbury) correction where the contact tangent changed.

use super::{Jacobian, Newmark, KRYLOV_MAX};
use crate::la::{LaError, Operator, TangentChange, Vector};

impl<'p> Newmark<'_, 'p> {
    /// Whether a Newton-Krylov correction of the last step attempt was inexact (GMRES ended
    /// at its iteration limit): only then can a full Newton do what it did not.
    pub fn krylov_exhausted(&self) -> bool {
        self.krylov_exhausted
    }

    /// dz = -(J - X) dq by products (a Krylov correction does not satisfy J dq = R).
    pub(super) fn linear_change_from_matrix(&mut self) -> Result<(), LaError> {
        let matrix =
            self.jacobian.matrix.as_ref().ok_or_else(|| {
                LaError::Invalid("Newton-Krylov needs the assembled Jacobian".into())
            })?;
        matrix.mult(&self.dq, &mut self.dz)?;
        if let Some(extra) = &self.jacobian.extra {
            self.tmp.set_all(0.0)?;
            extra.mult_add(&self.dq, &mut self.tmp)?;
            self.dz.axpy(-1.0, &self.tmp)?;
        }
        self.dz.scale(-1.0)
    }

    /// GMRES on J(state) dq = R, right-preconditioned by the step's factor, from dq = 0, to a
    /// relative residual of 1e-4 (an inexact Newton step: the outer iteration converges
    /// linearly at that rate), or to `floor` (a tenth of the step's residual target: a
    /// smaller linear residual cannot make the Newton step better than converged), or
    /// KRYLOV_MAX iterations (the best solution then: GMRES
    /// minimizes the residual, and the line search judges the step). Returns the iterations.
    ///
    /// # Collective
    pub(super) fn krylov_solve(
        &mut self,
        tangent: &dyn TangentChange<'p>,
        floor: f64,
    ) -> Result<usize, LaError> {
        let enough = |beta0: f64| (1e-4 * beta0).max(floor);
        let m = KRYLOV_MAX;
        let t = std::time::Instant::now();
        self.solves.solves += self
            .low_rank
            .prepare(&self.jacobian.factor, tangent, &self.q1)?;
        self.solves.seconds += t.elapsed().as_secs_f64();
        while self.basis.len() < m + 1 {
            self.basis.push(self.q1.duplicate()?);
        }
        let beta0 = self.r.norm2()?;
        self.dq.set_all(0.0)?;
        if beta0 == 0.0 {
            return Ok(0);
        }
        self.basis[0].copy_from(&self.r)?;
        self.basis[0].scale(1.0 / beta0)?;
        // Hessenberg columns, Givens rotations, and the rotated right-hand side.
        let mut h = vec![vec![0.0; m + 1]; m];
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta0;
        let mut k = 0;
        while k < m {
            // w = J(state) P^-1 v_k, into basis[k + 1].
            self.solves.precondition(
                &self.low_rank,
                &self.jacobian.factor,
                &self.basis[k],
                &mut self.dz,
            )?;
            let (head, tail) = self.basis.split_at_mut(k + 1);
            let w = &mut tail[0];
            apply_consistent(self.jacobian, tangent, &self.dz, w)?;
            // Classical Gram-Schmidt twice (CGS2: as orthogonal as modified Gram-Schmidt, in
            // two reductions over the ranks instead of k + 1).
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
            if g[k].abs() <= enough(beta0) || !g[k].is_finite() {
                break;
            }
        }
        // (A NaN counts as inexact.)
        let reached = g[k].abs() <= enough(beta0);
        self.krylov_exhausted |= !reached;
        // y from the triangular system, then dq = P^-1 (V y).
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let mut t = g[i];
            for j in i + 1..k {
                t -= h[j][i] * y[j];
            }
            y[i] = t / h[i][i];
        }
        self.tmp.set_all(0.0)?;
        for (i, yi) in y.iter().enumerate() {
            self.tmp.axpy(*yi, &self.basis[i])?;
        }
        self.solves.precondition(
            &self.low_rank,
            &self.jacobian.factor,
            &self.tmp,
            &mut self.dq,
        )?;
        Ok(k)
    }
}

/// y = J(state) x = J x + (X(state) - extra) x, with `change` = X(state) - extra (the
/// contact tangent's change since J was built, from [`Linearize`]).
///
/// # Collective
fn apply_consistent<'p>(
    jacobian: &Jacobian<'_, 'p>,
    change: &dyn Operator<'p>,
    x: &Vector<'p>,
    y: &mut Vector<'p>,
) -> Result<(), LaError> {
    let matrix = jacobian
        .matrix
        .as_ref()
        .ok_or_else(|| LaError::Invalid("Newton-Krylov needs the assembled Jacobian".into()))?;
    matrix.mult(x, y)?;
    change.mult_add(x, y)
}
