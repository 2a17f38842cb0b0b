//! Adaptive stepping around the Newmark integrator: how a stalled step is retried (the factor
//! updated at the contact points whose tangent changed most, a refreshed Jacobian,
//! Newton-Krylov, a full Newton where Newton-Krylov's linear solves were inexact, each with
//! line search) before it is cut, and the step control a checkpoint carries.

use super::newmark::{
    Correction, Damping, Eliminate, Factorize, Forces, Linearize, Newmark, NewmarkSettings, State,
    StepReport, TimeError,
};
use crate::la::{SparseMatrix, Vector};

/// What an adaptive run did besides stepping, and where its step control stands (so a
/// checkpoint can resume it exactly).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
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
    /// then by a full Newton, each with line search; and how the current step is corrected
    /// (FIXED, UPDATED, KRYLOV, FULL).
    pub krylov_retries: usize,
    pub full_newton_retries: usize,
    pub fallback: u8,
    /// Steps retried with the factor updated at the dominant contact points.
    pub updated_retries: usize,
    /// Iterations and solves with a factor of the attempts that failed (the accepted
    /// attempts' are in each step's report).
    pub failed_iterations: usize,
    pub failed_solves: usize,
    /// Wall time of the attempts that failed (s, this process's).
    pub failed_seconds: f64,
}

/// How a step is corrected (`StepControl::fallback`): the fixed factor, the factor updated at
/// the dominant contact points, Newton-Krylov, a full Newton.
pub const FIXED: u8 = 0;
pub const UPDATED: u8 = 1;
pub const KRYLOV: u8 = 2;
pub const FULL: u8 = 3;

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
    /// Where the fixed factor stalls, update it at the contact points whose tangent changed
    /// most (needs a linearization) before refactorizing.
    pub update: bool,
}

/// What a failed step attempt is followed by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Next {
    /// J rebuilt at the current state, the step retried with the same correction.
    Refresh,
    /// The step retried with another correction (no new factor).
    Retry(u8),
    /// The step halved (new factor).
    Cut,
}

/// What the run has to retry a step with.
#[derive(Clone, Copy)]
struct Options {
    adaptivity: Adaptivity,
    linearize: bool,
    matrix: bool,
    krylov_exhausted: bool,
}

/// The next attempt after a failed one, in order of cost: the factor updated where the
/// tangent changed (no factorization), J rebuilt at the current state, Newton-Krylov on the
/// consistent tangent (needs the assembled J), a full Newton only where a GMRES solve ended
/// inexact (otherwise its iterates are Newton-Krylov's own, each at a factorization's price),
/// a halved step; None: nothing is left.
fn next_attempt(control: &StepControl, o: Options) -> Option<Next> {
    let a = o.adaptivity;
    let update = a.update && o.linearize && !a.full_newton;
    let escalate = if control.fallback == FIXED && update {
        Some(Next::Retry(UPDATED))
    } else if control.fallback <= UPDATED {
        Some(Next::Retry(if o.linearize && o.matrix {
            KRYLOV
        } else {
            FULL
        }))
    } else if control.fallback == KRYLOV && o.krylov_exhausted {
        Some(Next::Retry(FULL))
    } else {
        None
    };
    if a.refresh && !control.fresh {
        // The update first where there is one: it may do without a factorization.
        return Some(match escalate {
            Some(Next::Retry(UPDATED)) => Next::Retry(UPDATED),
            _ => Next::Refresh,
        });
    }
    match escalate {
        Some(next) if a.refresh && !a.full_newton => Some(next),
        _ => ((control.level as usize) < a.max_cuts).then_some(Next::Cut),
    }
}

/// The correction of the attempt that just failed, for the log.
fn attempt_name(control: &StepControl, full_newton: bool, eliminating: bool) -> &'static str {
    match control.fallback {
        _ if full_newton => "the full Newton",
        FULL => "the full Newton",
        KRYLOV => "Newton-Krylov",
        UPDATED if eliminating => "the nonlinear elimination",
        UPDATED => "the updated factor",
        _ if control.fresh => "the refreshed Jacobian",
        _ => "the fixed Jacobian",
    }
}

/// A failed attempt's course for the log: its iterations, the residual at the predictor and
/// the least one, and its wall time.
fn attempt_history(residuals: &[f64], seconds: f64) -> String {
    let least = residuals
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.is_nan())
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or(String::new(), |(k, r)| format!(", least {r:.3e} after {k}"));
    let first = residuals
        .first()
        .map_or(String::new(), |r| format!(", {r:.3e} at the predictor"));
    format!(
        "{} iterations{first}{least}, {seconds:.3} s",
        residuals.len().saturating_sub(1)
    )
}

/// What the caller of [`integrate_adaptive`] wants after an accepted step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// End the integration here, before `end_time` (a transient that has seen enough).
    Stop,
}

/// Integrates from `state` to `end_time` with the nominal step of `settings`. When a step's
/// iterations fail, it is retried as [`next_attempt`] says: with the factor updated at the
/// dominant contact points (when `update` is set and `linearize` given), with J rebuilt at the
/// current state (when `refresh` is set), by Newton-Krylov, by a full Newton, each with line
/// search; last the step is halved (J refactorized) and retried from the same state, at most
/// `max_cuts` levels deep; after `restore_after` good steps the step is doubled back towards
/// the nominal one and the fixed factor tried again. Once refreshed, every later factorization
/// uses the current state's tangent. Every change goes to `log`. Only when the smallest step
/// fails too is the error returned. `control` starts at its default, or where a checkpoint
/// left it. With `equilibrium` (the static equilibrium's force) the residual is judged
/// against the forces' departure from it ([`Newmark::judge_against_equilibrium`]).
///
/// About 190 lines, on purpose: the factor's loop and the step's loop share the integrator
/// (which borrows the factor) and the control; what to do after a failure is decided in
/// [`next_attempt`], what stays here is each outcome's bookkeeping and its log line.
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
    mut eliminate: Option<&mut Eliminate<'_, 'p>>,
    state: &mut State<'p>,
    forces: &mut Forces<'_, 'p>,
    equilibrium: Option<&Vector<'p>>,
    end_time: f64,
    adaptivity: Adaptivity,
    control: &mut StepControl,
    on_step: &mut dyn FnMut(&State<'p>, &StepReport, &StepControl) -> Result<Flow, TimeError>,
    log: &mut dyn FnMut(&str),
) -> Result<(), TimeError> {
    let Adaptivity {
        restore_after,
        full_newton,
        update,
        ..
    } = adaptivity;
    let nominal = settings.step;
    let step_of = |level: u32| nominal / f64::from(1u32 << level);
    // The Jacobian a refresh replaces, handed back to be renewed in place.
    let mut retired = None;
    while state.time < end_time - 0.25 * step_of(control.level) {
        let step_settings = NewmarkSettings {
            step: step_of(control.level),
            ..settings
        };
        let factor = factorize(
            &step_settings,
            control.refreshed.then_some(&*state),
            retired.take(),
        )?;
        control.factorizations += 1;
        let mut integrator = Newmark::new(step_settings, m, c, k, &factor)?;
        if let Some(force) = equilibrium {
            integrator.judge_against_equilibrium(force)?;
        }
        loop {
            if state.time >= end_time - 0.25 * step_settings.step {
                break;
            }
            let step = match (full_newton, control.fallback, &mut linearize) {
                (true, _, _) | (_, FULL, _) => {
                    integrator.step_with(state, forces, Correction::Full(&mut *factorize), true)
                }
                (_, KRYLOV, Some(l)) if factor.matrix.is_some() => {
                    integrator.step_with(state, forces, Correction::Krylov(&mut **l), true)
                }
                (_, UPDATED, Some(_)) if eliminate.is_some() && factor.matrix.is_some() => {
                    let e = eliminate.as_mut().expect("checked");
                    integrator.step_with(state, forces, Correction::Eliminated(&mut **e), true)
                }
                (_, UPDATED, Some(l)) => {
                    integrator.step_with(state, forces, Correction::Updated(&mut **l), true)
                }
                _ => integrator.step(state, forces),
            };
            match step {
                Ok(report) => {
                    // The updated factor stays on for the steps that follow (a point that
                    // crossed the friction band crosses back within the cycle), Newton-Krylov
                    // and the full Newton are rescues of one step; the fixed J is tried again
                    // after `restore_after` good steps.
                    let updated = if update && linearize.is_some() {
                        UPDATED
                    } else if linearize.is_some() && control.fallback >= KRYLOV {
                        KRYLOV
                    } else {
                        FIXED
                    };
                    if control.good + 1 >= restore_after {
                        control.fallback = FIXED;
                    } else if control.fallback > UPDATED {
                        control.fallback = control.fallback.min(updated);
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
                    if on_step(state, &report, control)? == Flow::Stop {
                        return Ok(());
                    }
                    if restore {
                        break;
                    }
                }
                Err(TimeError::NotConverged {
                    residual, target, ..
                }) => {
                    let (iterations, solves) = integrator.failed_attempt();
                    let (residuals, seconds) = integrator.failed_attempt_residuals();
                    control.failed_iterations += iterations;
                    control.failed_solves += solves;
                    control.failed_seconds += seconds;
                    let failed = attempt_name(control, full_newton, eliminate.is_some());
                    let next = next_attempt(
                        control,
                        Options {
                            adaptivity,
                            linearize: linearize.is_some(),
                            matrix: factor.matrix.is_some(),
                            krylov_exhausted: integrator.krylov_exhausted(),
                        },
                    );
                    let Some(next) = next else {
                        return Err(TimeError::NotConverged {
                            step: state.step + 1,
                            time: state.time + step_settings.step,
                            iterations,
                            residual,
                            target,
                        });
                    };
                    let t = state.time;
                    let tail = format!(
                        "(residual {residual:.3e} vs {target:.3e}; {})",
                        attempt_history(residuals, seconds)
                    );
                    match next {
                        Next::Refresh => {
                            control.refreshed = true;
                            control.fresh = true;
                            control.good = 0;
                            control.refreshes += 1;
                            log(&format!(
                                "t = {t:.6e} s: stalled with {failed} {tail}; Jacobian rebuilt with the current contact tangent"
                            ));
                            break;
                        }
                        Next::Retry(fallback) => {
                            // The retry's correction then stays for `restore_after` steps.
                            control.fallback = fallback;
                            control.good = 0;
                            let how = match fallback {
                                UPDATED if eliminate.is_some() => {
                                    control.updated_retries += 1;
                                    "a nonlinear elimination of the contact points whose tangent changed most before each fixed-factor correction"
                                }
                                UPDATED => {
                                    control.updated_retries += 1;
                                    "the factor updated at the contact points whose tangent changed most"
                                }
                                KRYLOV => {
                                    control.krylov_retries += 1;
                                    "Newton-Krylov (GMRES on the consistent tangent, preconditioned by the factor updated at the points that changed most)"
                                }
                                _ => {
                                    control.full_newton_retries += 1;
                                    "a full Newton (the consistent tangent factorized at every iterate)"
                                }
                            };
                            log(&format!(
                                "t = {t:.6e} s: stalled with {failed} {tail}; retrying the step with {how} and line search"
                            ));
                        }
                        Next::Cut => {
                            control.fallback = FIXED;
                            control.level += 1;
                            control.cuts += 1;
                            control.good = 0;
                            control.fresh = control.refreshed;
                            log(&format!(
                                "t = {t:.6e} s: stalled with {failed} {tail}; step cut to {:.3e} s, Jacobian refactorized",
                                step_of(control.level)
                            ));
                            break;
                        }
                    }
                }
                Err(e) => return Err(e),
            }
        }
        drop(integrator);
        retired = factor.retire();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::attempt_history;

    #[test]
    fn a_stall_line_gives_the_attempts_course() {
        let line = attempt_history(&[1.0e4, 30.0, 6.9, 7.5], 0.147);
        assert_eq!(
            line,
            "3 iterations, 1.000e4 at the predictor, least 6.900e0 after 2, 0.147 s"
        );
        // A NaN residual is not the least one.
        let line = attempt_history(&[2.0, -f64::NAN], 0.01);
        assert!(line.contains("least 2.000e0 after 0"), "{line}");
    }
}
