//! The residual at the iterate, the move along a correction, and the backtracking line search
//! on |R| (Armijo) for the steps where a full correction overshoots.

use super::{Forces, Newmark, NewmarkSettings, StepReport};
use crate::la::LaError;

/// The least share of the whole force a vibration's reference counts for. At rest on the
/// equilibrium (no kick) the departure is zero and so would be the target; the residual's
/// round-off there is a few eps of the whole force (z and f each sum to it), so the target
/// stays ~1e4 eps above it at a tolerance of 1e-6 (the correction criterion, which needs
/// no reference, ends such steps first).
pub(crate) const VIBRATION_FLOOR: f64 = 1e-6;

impl<'p> Newmark<'_, 'p> {
    /// R = z - f at the current iterate (into `r`); returns |R| and the reference force
    /// (`reference_force`).
    ///
    /// # Collective
    pub(super) fn residual(
        &mut self,
        t1: f64,
        forces: &mut Forces<'_, 'p>,
        report: &mut StepReport,
    ) -> Result<(f64, f64), LaError> {
        let clock = std::time::Instant::now();
        forces(t1, &self.q1, &self.v1, &mut self.f)?;
        report.force_seconds += clock.elapsed().as_secs_f64();
        report.force_calls += 1;
        self.r.copy_from(&self.z)?;
        self.r.axpy(-1.0, &self.f)?;
        let reference = self.reference_force()?;
        Ok((self.r.norm2()?, reference))
    }

    /// The force the residual is judged against, f and z being current at the iterate: the
    /// whole force max(|f|, |z|), or with an equilibrium force f_s their departure from it,
    /// max(|f - f_s|, |z - f_s|), counted at least [`VIBRATION_FLOOR`] of the whole force.
    ///
    /// # Collective
    pub(super) fn reference_force(&mut self) -> Result<f64, LaError> {
        let total = self.f.norm2()?.max(self.z.norm2()?);
        let Some((equilibrium, departure)) = &mut self.equilibrium else {
            return Ok(total);
        };
        departure.copy_from(&self.f)?;
        departure.axpy(-1.0, equilibrium)?;
        let of_f = departure.norm2()?;
        departure.copy_from(&self.z)?;
        departure.axpy(-1.0, equilibrium)?;
        let of_z = departure.norm2()?;
        // NaN propagates (max would drop it): a NaN force must fail the step.
        if of_f.is_nan() || of_z.is_nan() {
            return Ok(f64::NAN);
        }
        Ok(of_f.max(of_z).max(VIBRATION_FLOOR * total))
    }

    /// Moves the iterate by `-alpha dq` (q1, a1, v1 by the Newmark relations, z linearly).
    pub(super) fn correct(&mut self, alpha: f64) -> Result<(), LaError> {
        let NewmarkSettings {
            beta,
            gamma,
            step: h,
            ..
        } = self.settings;
        self.q1.axpy(-alpha, &self.dq)?;
        self.a1.axpy(-alpha / (beta * h * h), &self.dq)?;
        self.v1.axpy(-alpha * gamma / (beta * h), &self.dq)?;
        self.z.axpy(alpha, &self.dz)
    }

    /// Backtracking on |R| along the correction: the first alpha in 1, 1/2, ... 1/1024 with
    /// |R(alpha)| <= (1 - 1e-4 alpha) |R(0)|, else the best alpha tried if it lowers |R| at all,
    /// else the full step (the caller's iteration limit then decides). The iterate is left at
    /// the chosen alpha with its residual evaluated.
    ///
    /// # Collective
    pub(super) fn backtrack(
        &mut self,
        t1: f64,
        r0: f64,
        forces: &mut Forces<'_, 'p>,
        report: &mut StepReport,
    ) -> Result<(f64, (f64, f64)), LaError> {
        let (mut alpha, mut at) = (1.0, 0.0);
        let mut best: Option<(f64, f64)> = None;
        loop {
            self.correct(alpha - at)?;
            at = alpha;
            let evaluated = self.residual(t1, forces, report)?;
            let r = evaluated.0;
            if r.is_finite() && r <= (1.0 - 1e-4 * alpha) * r0 {
                return Ok((alpha, evaluated));
            }
            if r.is_finite() && best.is_none_or(|b| r < b.1) {
                best = Some((alpha, r));
            }
            if alpha < 1.0 / 1024.0 {
                let chosen = best.filter(|b| b.1 < r0).map_or(1.0, |b| b.0);
                self.correct(chosen - at)?;
                return Ok((chosen, self.residual(t1, forces, report)?));
            }
            alpha *= 0.5;
        }
    }
}
