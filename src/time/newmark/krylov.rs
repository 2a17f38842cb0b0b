//! Newton-Krylov: GMRES on the consistent tangent at the iterate, right-preconditioned by the
//! step's factor updated by a low-rank (Woodbury) correction where the contact tangent changed.

use super::correction::SolveCount;
use super::{Jacobian, Newmark, KRYLOV_MAX};
use crate::la::gmres::{gmres, Preconditioned};
use crate::la::{LaError, LowRankUpdate, Operator, TangentChange, Vector};

/// Newton-Krylov is chosen only where the factor keeps its matrix
/// (`AdaptiveNewmark::attempt`, `next_attempt`).
const NEEDS_MATRIX: &str = "Newton-Krylov runs only with the assembled Jacobian";

impl<'p> Newmark<'_, 'p> {
    /// Whether a Newton-Krylov correction of the last step attempt was inexact (GMRES ended
    /// at its iteration limit): only then can a full Newton do what it did not.
    pub fn krylov_exhausted(&self) -> bool {
        self.krylov_exhausted
    }

    /// dz = -(J - X) dq by products (a Krylov correction does not satisfy J dq = R).
    pub(super) fn linear_change_from_matrix(&mut self) -> Result<(), LaError> {
        let matrix = self.jacobian.matrix.as_ref().expect(NEEDS_MATRIX);
        matrix.mult(&self.dq, &mut self.dz)?;
        if let Some(extra) = &self.jacobian.extra {
            self.tmp.set_all(0.0)?;
            extra.mult_add(&self.dq, &mut self.tmp)?;
            self.dz.axpy(-1.0, &self.tmp)?;
        }
        self.dz.scale(-1.0)
    }

    /// GMRES (`la::gmres`) on J(state) dq = R, right-preconditioned by the step's factor
    /// with its low-rank update, from dq = 0, to a
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
        let t = std::time::Instant::now();
        self.solves.solves += self
            .low_rank
            .prepare(&self.jacobian.factor, tangent, &self.q1)?;
        self.solves.seconds += t.elapsed().as_secs_f64();
        let beta0 = self.r.norm2()?;
        let enough = (1e-4 * beta0).max(floor);
        let mut system = ConsistentTangent {
            jacobian: self.jacobian,
            low_rank: &self.low_rank,
            tangent,
            solves: &mut self.solves,
            preconditioned: &mut self.dz,
        };
        let outcome = gmres(
            &mut system,
            &self.r,
            &mut self.dq,
            &mut self.basis,
            enough,
            KRYLOV_MAX,
        )?;
        // (A NaN counts as inexact.)
        self.krylov_exhausted |= !outcome.converged;
        Ok(outcome.iterations)
    }
}

/// J(state) right-preconditioned by the step's factor with its low-rank update, the
/// preconditioner's solves counted.
struct ConsistentTangent<'s, 'p> {
    jacobian: &'s Jacobian<'s, 'p>,
    low_rank: &'s LowRankUpdate<'p>,
    tangent: &'s dyn TangentChange<'p>,
    solves: &'s mut SolveCount,
    /// P^-1 v of the last product.
    preconditioned: &'s mut Vector<'p>,
}

impl<'p> Preconditioned<'p> for ConsistentTangent<'_, 'p> {
    fn apply(&mut self, v: &Vector<'p>, w: &mut Vector<'p>) -> Result<(), LaError> {
        let factor = &self.jacobian.factor;
        self.solves
            .precondition(self.low_rank, factor, v, self.preconditioned)?;
        apply_consistent(self.jacobian, self.tangent, self.preconditioned, w)
    }

    fn precondition(&mut self, v: &Vector<'p>, x: &mut Vector<'p>) -> Result<(), LaError> {
        let factor = &self.jacobian.factor;
        self.solves.precondition(self.low_rank, factor, v, x)
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
    let matrix = jacobian.matrix.as_ref().expect(NEEDS_MATRIX);
    matrix.mult(x, y)?;
    change.mult_add(x, y)
}
