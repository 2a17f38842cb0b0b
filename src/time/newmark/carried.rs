//! The carried linear force z = M a + C v + K q with a single-precision factor. The
//! corrections update z by -(R - X dq), which is the true change only when J dq = R holds to
//! round-off; a single-precision solve meets it to ~u |J| |dq| (u = 2^-24), so z drifts from
//! the model's by the solves' errors (measured on the small brake: 2.8e-3 N after 1,000
//! saturated steps against a residual target of 2.2e-4 N). The step recomputes z by products
//! whenever the drift could put the residual it would accept above its target, judged by a
//! bound: the drift grows with the residuals the solves were given, at a ratio measured at
//! every recomputation (z carried against z recomputed), times a safety factor; and at least
//! every RECALIBRATE_STEPS steps. Where the solves' errors are small against the target (the
//! growth of a vibration at a loose tolerance) that skips the products; where they are not
//! (the saturated regime), every step recomputes z.

use super::{Newmark, StepReport};
use crate::la::LaError;

/// The measured drift per unit of solved residual is multiplied by this in the bound.
const SAFETY: f64 = 4.0;
/// Steps at most between two recomputations (a recalibration of the ratio).
const RECALIBRATE_STEPS: usize = 64;

/// What is known about the carried z's drift.
#[derive(Debug, Clone, Copy)]
pub(super) struct Drift {
    /// Drift per unit of solved residual (infinite until measured).
    ratio: f64,
    /// The residual norms solved with the single-precision factor since z was last
    /// recomputed (0: z is exact; infinite: unknown, as for a new integrator).
    residuals: f64,
    /// Steps accepted since z was last recomputed.
    steps: usize,
}

impl Default for Drift {
    fn default() -> Self {
        Drift {
            ratio: f64::INFINITY,
            residuals: f64::INFINITY,
            steps: 0,
        }
    }
}

impl Drift {
    /// A bound on |z carried - z|.
    pub(super) fn bound(&self) -> f64 {
        if self.residuals == 0.0 {
            0.0
        } else if self.ratio.is_finite() && self.residuals.is_finite() {
            self.ratio * self.residuals
        } else {
            f64::INFINITY
        }
    }

    /// Whether z must be recomputed before a residual `r` (None: not evaluated) is accepted
    /// against `target`.
    pub(super) fn due(&self, r: Option<f64>, target: f64) -> bool {
        r.unwrap_or(0.0) + self.bound() > target || self.steps >= RECALIBRATE_STEPS
    }

    /// z is exact (recomputed from scratch at the predictor).
    pub(super) fn exact(&mut self) {
        self.residuals = 0.0;
    }

    pub(super) fn is_exact(&self) -> bool {
        self.residuals == 0.0
    }

    /// A correction solved a residual of norm `r` with the single-precision factor.
    pub(super) fn solved(&mut self, r: f64) {
        self.residuals += r;
    }

    /// The carried z became a combination of earlier ones with coefficients of absolute sum
    /// `sum` (Anderson's step): their errors add up to at most that multiple.
    pub(super) fn mixed(&mut self, sum: f64) {
        self.residuals *= sum.max(1.0);
    }

    /// A step was accepted (counted towards the next forced recomputation; a no-op in
    /// effect for a double-precision factor, which never asks `due`).
    pub(super) fn accepted(&mut self) {
        self.steps += 1;
    }

    /// z was recomputed; `difference` = |z carried - z|.
    fn measured(&mut self, difference: f64) {
        if self.residuals.is_finite() && self.residuals > 0.0 {
            let ratio = SAFETY * difference / self.residuals;
            self.ratio = if self.ratio.is_finite() {
                self.ratio.max(ratio)
            } else {
                ratio
            };
        }
        self.residuals = 0.0;
        self.steps = 0;
    }
}

impl<'p> Newmark<'_, 'p> {
    /// The residual judged with z recomputed (the carried z assumed J dq = R exactly):
    /// |R| and the reference force (`reference_force`), f being current at the iterate.
    ///
    /// # Collective
    pub(super) fn residual_with_exact_z(
        &mut self,
        pred_exact: bool,
        report: &mut StepReport,
    ) -> Result<(f64, f64), LaError> {
        self.exact_linear_force(pred_exact, report)?;
        self.r.copy_from(&self.z)?;
        self.r.axpy(-1.0, &self.f)?;
        let reference = self.reference_force()?;
        Ok((self.r.norm2()?, reference))
    }

    /// z = M a1 + C v1 + K q1 at the iterate by products: when z was exact at the predictor,
    /// z_pred + (J - X)(q1 - q_pred) by one product with J (z is affine in q1 within a step,
    /// with the derivative J - X); otherwise from scratch. Measures the drift it removes.
    ///
    /// # Collective
    pub(super) fn exact_linear_force(
        &mut self,
        pred_exact: bool,
        report: &mut StepReport,
    ) -> Result<(), LaError> {
        let clock = std::time::Instant::now();
        self.z_carried.copy_from(&self.z)?;
        match (&self.jacobian.matrix, pred_exact) {
            (Some(j), true) => {
                self.tmp.copy_from(&self.q1)?;
                self.tmp.axpy(-1.0, &self.q_pred)?;
                self.z.copy_from(&self.z_pred)?;
                j.mult_add(&self.tmp, &mut self.z)?;
                if let Some(extra) = &self.jacobian.extra {
                    self.dz.set_all(0.0)?;
                    extra.mult_add(&self.tmp, &mut self.dz)?;
                    self.z.axpy(-1.0, &self.dz)?;
                }
            }
            _ => self.linear_force()?,
        }
        self.z_carried.axpy(-1.0, &self.z)?;
        let difference = self.z_carried.norm2()?;
        self.drift.measured(difference);
        report.linear_force_seconds += clock.elapsed().as_secs_f64();
        report.linear_force_calls += 1;
        Ok(())
    }
}
