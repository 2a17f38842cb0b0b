//! Anderson acceleration of the fixed-Jacobian iteration (Walker & Ni, SIAM J. Numer. Anal.
//! 49 (2011) 1715, "Anderson acceleration for fixed-point iterations"; the form used here is
//! their type II with the residual R as the quantity minimized).
//!
//! Why: after a nonlinear elimination of the contact points whose tangent changed most
//! (`time::transient`'s eliminate.rs), the fixed-Jacobian iteration q <- q - J^-1 R(q) on the
//! remaining unknowns is smooth (the contact switches are solved locally) but can still be
//! slow: on the small brake's first saturated steps its residual fell 1.7 % per iteration,
//! with every contact DOF eliminated, along a few directions where the consistent tangent is
//! far softer than the factored J (benches/transient-results.md). A slow
//! linear rate along a few directions is what a secant method over the last iterates removes.
//! Anderson's step takes the affine combination of the last plain-update targets
//! g_i = q_i - J^-1 R_i whose residuals combine to the smallest norm: for a linear problem it
//! is GMRES on J(q) preconditioned by J^-1, without the tangent ever being formed. It costs
//! no solve: dot products over `depth` stored vectors. Without the elimination it does not
//! pay: iterates whose contact points switch state make the secant model
//! point the wrong way.
//!
//! The linear force z = M a + C v + K q is affine in q within a step, so the same combination
//! of the targets' z (each carried as z_i + dz_i) is z at the combined iterate: no product
//! with the model's operators is needed.

use crate::la::lapack::RealLu;
use crate::la::{LaError, Vector};

/// Largest |coefficient| sum accepted: beyond it the least-squares problem is too ill-
/// conditioned for its combination to be trusted (and a single-precision z's drift would be
/// multiplied by it); the oldest iterate is dropped and the fit tried again.
const MAX_COEFFICIENT_SUM: f64 = 1e3;

/// The last iterates' residuals, plain-update targets and their linear forces.
pub(super) struct Anderson<'p> {
    depth: usize,
    /// Ring of stored iterates, oldest first: (R_i, g_i, z(g_i)).
    stored: Vec<[Vector<'p>; 3]>,
    /// Storage of iterates dropped, reused.
    spare: Vec<[Vector<'p>; 3]>,
    /// Differences R_k - R_i of the current fit.
    differences: Vec<Vector<'p>>,
}

/// What the combination did: the coefficients' absolute sum (1 for a plain update).
pub(super) struct Mixed {
    pub(super) coefficient_sum: f64,
}

impl<'p> Anderson<'p> {
    /// Keeps at most `depth` earlier iterates besides the current one (0: plain iteration).
    pub(super) fn new(depth: usize) -> Self {
        Anderson {
            depth,
            stored: Vec::new(),
            spare: Vec::new(),
            differences: Vec::new(),
        }
    }

    pub(super) fn depth(&self) -> usize {
        self.depth
    }

    /// Forgets every stored iterate (a new step, or a correction of another kind).
    pub(super) fn clear(&mut self) {
        self.spare.append(&mut self.stored);
    }

    /// Stores the current iterate's residual `r`, its plain-update target q - dq (in `q`) and
    /// that target's linear force z + dz (in `z`), and overwrites `q`, `z` with the
    /// accelerated iterate: sum_i alpha_i g_i and sum_i alpha_i z(g_i) with sum alpha_i = 1
    /// and |sum_i alpha_i R_i| least. With one iterate stored that is the plain update.
    ///
    /// # Collective
    pub(super) fn mix(
        &mut self,
        r: &Vector<'p>,
        q: &mut Vector<'p>,
        z: &mut Vector<'p>,
    ) -> Result<Mixed, LaError> {
        if self.stored.len() > self.depth {
            let oldest = self.stored.remove(0);
            self.spare.push(oldest);
        }
        let mut slot = match self.spare.pop() {
            Some(slot) => slot,
            None => [r.duplicate()?, r.duplicate()?, r.duplicate()?],
        };
        slot[0].copy_from(r)?;
        slot[1].copy_from(q)?;
        slot[2].copy_from(z)?;
        self.stored.push(slot);
        let Some(gamma) = self.fit()? else {
            return Ok(Mixed {
                coefficient_sum: 1.0,
            });
        };
        // sum_i alpha_i x_i = x_k - sum_i gamma_i (x_k - x_i) over the earlier iterates i.
        let first = self.stored.len() - 1 - gamma.len();
        let earlier = &self.stored[first..self.stored.len() - 1];
        let total: f64 = gamma.iter().sum();
        let gs: Vec<&Vector<'p>> = earlier.iter().map(|s| &s[1]).collect();
        let zs: Vec<&Vector<'p>> = earlier.iter().map(|s| &s[2]).collect();
        q.scale(1.0 - total)?;
        q.maxpy(&gamma, &gs)?;
        z.scale(1.0 - total)?;
        z.maxpy(&gamma, &zs)?;
        Ok(Mixed {
            coefficient_sum: (1.0 - total).abs() + gamma.iter().map(|g| g.abs()).sum::<f64>(),
        })
    }

    /// gamma minimizing |R_k - sum_i gamma_i (R_k - R_i)| over the most recent earlier
    /// iterates (as many as give a well-conditioned fit); None: the plain update.
    ///
    /// # Collective
    fn fit(&mut self) -> Result<Option<Vec<f64>>, LaError> {
        let k = self.stored.len() - 1;
        while self.differences.len() < k {
            self.differences.push(self.stored[k][0].duplicate()?);
        }
        for i in 0..k {
            self.differences[i].copy_from(&self.stored[k][0])?;
            self.differences[i].axpy(-1.0, &self.stored[i][0])?;
        }
        // Normal equations of the column-scaled problem (a handful of columns: their Gram
        // matrix is cheap and, scaled, well enough conditioned; what is not is dropped).
        let mut gram = vec![0.0; k * k];
        let mut rhs = vec![0.0; k];
        {
            let columns: Vec<&Vector<'p>> = self.differences[..k].iter().collect();
            for i in 0..k {
                let row = self.differences[i].mdot(&columns)?;
                gram[i * k..(i + 1) * k].copy_from_slice(&row);
                rhs[i] = self.differences[i].dot(&self.stored[k][0])?;
            }
        }
        // Fit over the last `m` earlier iterates, m from all down to 1.
        for m in (1..=k).rev() {
            let first = k - m;
            let scale: Vec<f64> = (first..k)
                .map(|i| 1.0 / gram[i * k + i].sqrt().max(f64::MIN_POSITIVE))
                .collect();
            let mut a = vec![0.0; m * m];
            for c in 0..m {
                for r in 0..m {
                    let g = gram[(first + r) * k + first + c] * scale[r] * scale[c];
                    a[c * m + r] = g + if r == c { 1e-12 } else { 0.0 };
                }
            }
            let mut b: Vec<f64> = (0..m).map(|r| rhs[first + r] * scale[r]).collect();
            let Ok(lu) = RealLu::new(m, a) else { continue };
            if lu.solve(&mut b).is_err() {
                continue;
            }
            let gamma: Vec<f64> = b.iter().zip(&scale).map(|(x, s)| x * s).collect();
            let sum = (1.0 - gamma.iter().sum::<f64>()).abs()
                + gamma.iter().map(|g| g.abs()).sum::<f64>();
            if gamma.iter().all(|g| g.is_finite()) && sum <= MAX_COEFFICIENT_SUM {
                return Ok(Some(gamma));
            }
        }
        Ok(None)
    }
}
