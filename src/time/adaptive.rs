//! Adaptive stepping around the Newmark integrator: how a stalled step is retried (refreshed
//! Jacobian, Newton-Krylov, full Newton where Newton-Krylov's linear solves were inexact, each
//! with line search) before it is cut, and the step control a checkpoint carries.

use super::newmark::{
    Correction, Damping, Factorize, Forces, Linearize, Newmark, NewmarkSettings, State, StepReport,
    TimeError,
};
use crate::la::SparseMatrix;

/// What an adaptive run did besides stepping, and where its step control stands (so a
/// checkpoint can resume it exactly).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepControl {
    pub steps: usize,
    /// Steps halved after a failed step (each with a new factor), and doublings back.
    pub cuts: usize,
    pub restores: usize,
    /// Jacobians rebuilt with the tangent of the current state after a failed step.
    pub refreshes: usize,
    pub factorizations: usize,
    /// The step is the nominal one / 2^level; good steps since the last change.
    pub level: u32,
    pub good: usize,
    /// J uses a state's tangent (after the first refresh), and J was built at the state it
    /// retries from (a failure there cuts the step).
    pub refreshed: bool,
    pub fresh: bool,
    /// Steps retried on the consistent tangent after the refreshed Jacobian stalled: by
    /// Newton-Krylov (the factor, updated by the dominant contact points, as preconditioner),
    /// then by a full Newton, each with line search; and where the current step stands (0
    /// fixed J, 1 Newton-Krylov, 2 full Newton).
    pub krylov_retries: usize,
    pub full_newton_retries: usize,
    pub fallback: u8,
}

/// How an adaptive run reacts to failed steps.
#[derive(Debug, Clone, Copy)]
pub struct Adaptivity {
    /// Step halvings at most, and good steps before the step is doubled back.
    pub max_cuts: usize,
    pub restore_after: usize,
    /// Rebuild J with the current state's tangent before cutting.
    pub refresh: bool,
    /// A full Newton (J at every iterate) instead of the fixed Jacobian.
    pub full_newton: bool,
}

/// Integrates from `state` to `end_time` with the nominal step of `settings`. When a step's
/// fixed-Jacobian iterations fail, J is first rebuilt with the tangent of the current state
/// (when `refresh` is set) and the step retried; if that fails, the step is retried on the
/// consistent tangent with line search: by Newton-Krylov (when `linearize` is given and J is
/// kept), then by a full Newton only if a GMRES solve ended inexact (otherwise the full
/// Newton's iterates are Newton-Krylov's own, each at the price of a factorization); if that
/// fails too, the step is halved (J refactorized) and retried from the same state, at most
/// `max_cuts` levels deep; after `restore_after` good steps the step is doubled back towards the nominal one. Once refreshed,
/// every later factorization uses the current state's tangent. Every change goes to `log`.
/// Only when the smallest step fails too is the error returned. `control` starts at its
/// default, or where a checkpoint left it.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // operators, factor builder, state, forces, controls, sinks
pub fn integrate_adaptive<'p>(
    settings: NewmarkSettings,
    m: &SparseMatrix<'p>,
    c: Damping<'_, 'p>,
    k: &SparseMatrix<'p>,
    factorize: &mut Factorize<'_, 'p>,
    mut linearize: Option<&mut Linearize<'_, 'p>>,
    state: &mut State<'p>,
    forces: &mut Forces<'_, 'p>,
    end_time: f64,
    adaptivity: Adaptivity,
    control: &mut StepControl,
    on_step: &mut dyn FnMut(&State<'p>, &StepReport, &StepControl) -> Result<(), TimeError>,
    log: &mut dyn FnMut(&str),
) -> Result<(), TimeError> {
    let Adaptivity {
        max_cuts,
        restore_after,
        refresh,
        full_newton,
    } = adaptivity;
    let nominal = settings.step;
    let step_of = |level: u32| nominal / f64::from(1u32 << level);
    while state.time < end_time - 0.25 * step_of(control.level) {
        let step_settings = NewmarkSettings {
            step: step_of(control.level),
            ..settings
        };
        let factor = factorize(&step_settings, control.refreshed.then_some(&*state))?;
        control.factorizations += 1;
        let mut integrator = Newmark::new(step_settings, m, c, k, &factor)?;
        loop {
            if state.time >= end_time - 0.25 * step_settings.step {
                break;
            }
            let step = match (full_newton, control.fallback, &mut linearize) {
                (true, _, _) | (_, 2, _) => {
                    integrator.step_with(state, forces, Correction::Full(&mut *factorize), true)
                }
                (_, 1, Some(l)) if factor.matrix.is_some() => {
                    integrator.step_with(state, forces, Correction::Krylov(&mut **l), true)
                }
                _ => integrator.step(state, forces),
            };
            match step {
                Ok(report) => {
                    // Newton-Krylov stays on for the steps that follow (a point that crossed
                    // the friction band crosses back within the cycle); the fixed J is tried
                    // again after `restore_after` good steps.
                    // (after a full-Newton rescue, back to Newton-Krylov where there is one).
                    if control.good + 1 >= restore_after {
                        control.fallback = 0;
                    } else if control.fallback == 2 {
                        control.fallback = u8::from(linearize.is_some());
                    }
                    control.steps += 1;
                    control.fresh = false;
                    control.good += 1;
                    let restore = control.level > 0 && control.good >= restore_after;
                    if restore {
                        control.level -= 1;
                        control.restores += 1;
                        control.good = 0;
                        log(&format!(
                            "t = {:.6e} s: {restore_after} steps converged, step back to {:.3e} s",
                            state.time,
                            step_of(control.level)
                        ));
                    }
                    on_step(state, &report, control)?;
                    if restore {
                        break;
                    }
                }
                Err(TimeError::NotConverged {
                    residual, target, ..
                }) if refresh && !control.fresh => {
                    control.refreshed = true;
                    control.fresh = true;
                    control.good = 0;
                    control.refreshes += 1;
                    log(&format!(
                        "t = {:.6e} s: fixed-Jacobian iterations stalled (residual {residual:.3e} vs {target:.3e}); Jacobian rebuilt with the current contact tangent",
                        state.time
                    ));
                    break;
                }
                // A Newton-Krylov whose linear solves converged took the full Newton's own
                // iterates (the same consistent tangent, the same line search): only a
                // smaller step can help then.
                Err(TimeError::NotConverged {
                    residual, target, ..
                }) if refresh
                    && !full_newton
                    && (control.fallback == 0
                        || (control.fallback == 1 && integrator.krylov_exhausted())) =>
                {
                    // Newton-Krylov needs the assembled J and a linearization; without them
                    // straight to the full Newton.
                    let krylov =
                        control.fallback == 0 && linearize.is_some() && factor.matrix.is_some();
                    control.fallback = if krylov { 1 } else { 2 };
                    let how = if krylov {
                        control.krylov_retries += 1;
                        "Newton-Krylov (GMRES on the consistent tangent, preconditioned by the factor updated at the points that changed most)"
                    } else {
                        control.full_newton_retries += 1;
                        "a full Newton (the consistent tangent factorized at every iterate)"
                    };
                    log(&format!(
                        "t = {:.6e} s: stalled with {} (residual {residual:.3e} vs {target:.3e}); retrying the step with {how} and line search",
                        state.time,
                        ["the refreshed Jacobian", "Newton-Krylov"][control.fallback as usize - 1]
                    ));
                }
                Err(TimeError::NotConverged {
                    residual, target, ..
                }) if (control.level as usize) < max_cuts => {
                    // What failed last, for the log.
                    let failed = if full_newton || control.fallback == 2 {
                        "the full Newton"
                    } else if control.fallback == 1 {
                        "Newton-Krylov"
                    } else if control.fresh {
                        "the refreshed Jacobian"
                    } else {
                        "the fixed Jacobian"
                    };
                    control.fallback = 0;
                    control.level += 1;
                    control.cuts += 1;
                    control.good = 0;
                    control.fresh = control.refreshed;
                    log(&format!(
                        "t = {:.6e} s: stalled with {failed} (residual {residual:.3e} vs {target:.3e}); step cut to {:.3e} s, Jacobian refactorized",
                        state.time,
                        step_of(control.level)
                    ));
                    break;
                }
                Err(e) => return Err(e),
            }
        }
    }
    Ok(())
}
