//! Adaptive stepping around the Newmark integrator: how a stalled step is retried (the factor
//! updated at the contact points whose tangent changed most, a refreshed Jacobian,
//! Newton-Krylov, a full Newton where Newton-Krylov's linear solves were inexact, each with
//! line search) before it is cut, and the step control a checkpoint carries.

use std::cell::RefCell;

use super::newmark::{
    Correction, Damping, Eliminate, Elimination, Factorize, Forces, Jacobian, Linearize, Newmark,
    NewmarkSettings, RetiredJacobian, State, StepReport, TimeError,
};
use crate::la::{LaError, SparseMatrix, TangentChange, Vector};

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

impl StepControl {
    /// The step size at the current level, the nominal one / 2^level: the one place the
    /// step of an attempt is worked out (the integrator's settings and every hook take it
    /// from here).
    pub fn step_size(&self, nominal: f64) -> f64 {
        nominal / f64::from(1u32 << self.level)
    }
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

/// What the caller wants after an accepted step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// End the integration here, before `end_time` (a transient that has seen enough).
    Stop,
}

/// What [`AdaptiveNewmark`] steps: the forces and J's factorization, and where the problem
/// has them, the change of the tangent at an iterate (for the updated-factor and
/// Newton-Krylov retries) and a nonlinear elimination.
pub trait StepProblem<'a, 'p> {
    /// f = the external and nonlinear forces at (t, q, v) ([`Forces`]).
    ///
    /// # Collective
    fn forces(
        &mut self,
        t: f64,
        q: &Vector<'p>,
        v: &Vector<'p>,
        f: &mut Vector<'p>,
    ) -> Result<(), LaError>;

    /// J for a step size, at the initial tangent or at a state's ([`Factorize`]).
    ///
    /// # Collective
    fn factorize(
        &mut self,
        ns: &NewmarkSettings,
        at: Option<&State<'p>>,
        retired: Option<RetiredJacobian<'p>>,
    ) -> Result<Jacobian<'a, 'p>, LaError>;

    /// Whether [`StepProblem::linearize`] is there.
    fn can_linearize(&self) -> bool {
        false
    }

    /// The tangent's change from J's at an iterate ([`Linearize`]); called only where
    /// [`StepProblem::can_linearize`].
    ///
    /// # Collective
    fn linearize(
        &mut self,
        _ns: &NewmarkSettings,
        _at: &State<'p>,
    ) -> Result<Box<dyn TangentChange<'p> + 'a>, LaError> {
        unreachable!("linearize is called only where can_linearize")
    }

    /// Whether [`StepProblem::eliminate`] is there.
    fn can_eliminate(&self) -> bool {
        false
    }

    /// A nonlinear elimination at an iterate ([`Eliminate`]); called only where
    /// [`StepProblem::can_eliminate`].
    ///
    /// # Collective
    fn eliminate(
        &mut self,
        _ns: &NewmarkSettings,
        _at: &State<'p>,
        _residual: &Vector<'p>,
        _target: f64,
    ) -> Result<Option<Elimination<'p>>, LaError> {
        unreachable!("eliminate is called only where can_eliminate")
    }
}

/// What the caller watches the run with.
pub trait StepHooks<'p> {
    /// After an accepted step of size `h` (the state, the step's report, the control after
    /// it): go on or stop.
    ///
    /// # Collective
    fn on_step(
        &mut self,
        state: &State<'p>,
        report: &StepReport,
        control: &StepControl,
        h: f64,
    ) -> Result<Flow, TimeError>;

    /// One line on a change of the step control (a stalled attempt and what follows it, a
    /// step doubled back).
    ///
    /// # Collective
    fn log(&mut self, line: &str);
}

/// A step problem and its hooks given as closures (for callers with no state to share
/// between them).
pub struct Closures<'r, 'f, 'p> {
    pub forces: &'r mut Forces<'f, 'p>,
    pub factorize: &'r mut Factorize<'f, 'p>,
    pub linearize: Option<&'r mut Linearize<'f, 'p>>,
    pub on_step: &'r mut OnStep<'f, 'p>,
    pub log: &'r mut dyn FnMut(&str),
}

/// [`StepHooks::on_step`] as a closure.
pub type OnStep<'f, 'p> =
    dyn FnMut(&State<'p>, &StepReport, &StepControl, f64) -> Result<Flow, TimeError> + 'f;

impl<'f, 'p> StepProblem<'f, 'p> for Closures<'_, 'f, 'p> {
    fn forces(
        &mut self,
        t: f64,
        q: &Vector<'p>,
        v: &Vector<'p>,
        f: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        (self.forces)(t, q, v, f)
    }

    fn factorize(
        &mut self,
        ns: &NewmarkSettings,
        at: Option<&State<'p>>,
        retired: Option<RetiredJacobian<'p>>,
    ) -> Result<Jacobian<'f, 'p>, LaError> {
        (self.factorize)(ns, at, retired)
    }

    fn can_linearize(&self) -> bool {
        self.linearize.is_some()
    }

    fn linearize(
        &mut self,
        ns: &NewmarkSettings,
        at: &State<'p>,
    ) -> Result<Box<dyn TangentChange<'p> + 'f>, LaError> {
        let linearize = self.linearize.as_mut().expect("checked by can_linearize");
        linearize(ns, at)
    }
}

impl<'p> StepHooks<'p> for Closures<'_, '_, 'p> {
    fn on_step(
        &mut self,
        state: &State<'p>,
        report: &StepReport,
        control: &StepControl,
        h: f64,
    ) -> Result<Flow, TimeError> {
        (self.on_step)(state, report, control, h)
    }

    fn log(&mut self, line: &str) {
        (self.log)(line)
    }
}

/// The problem and its hooks as the integrator takes them, each through the one `RefCell`
/// that holds the problem (the corrections call back into it within a step).
struct Parts<'r, 'f, 'p> {
    forces: &'r mut Forces<'f, 'p>,
    factorize: &'r mut Factorize<'f, 'p>,
    linearize: Option<&'r mut Linearize<'f, 'p>>,
    eliminate: Option<&'r mut Eliminate<'f, 'p>>,
    on_step: &'r mut OnStep<'f, 'p>,
    log: &'r mut dyn FnMut(&str),
}

/// How the steps on one factor ended.
enum OnFactor {
    /// A new factor is needed (a refresh, a cut, a step doubled back, or the end reached).
    Refactor,
    /// The hooks asked to stop.
    Stopped,
}

/// Newmark with adaptive step control over a [`StepProblem`]: the operators, the nominal
/// settings, the static equilibrium's force (with it, the residual is judged against the
/// forces' departure from it: [`Newmark::judge_against_equilibrium`]) and how failed steps
/// are retried.
pub struct AdaptiveNewmark<'o, 'p> {
    pub settings: NewmarkSettings,
    pub m: &'o SparseMatrix<'p>,
    pub c: Damping<'o, 'p>,
    pub k: &'o SparseMatrix<'p>,
    pub equilibrium: Option<&'o Vector<'p>>,
    pub adaptivity: Adaptivity,
}

impl<'p> AdaptiveNewmark<'_, 'p> {
    /// Integrates from `state` to `end_time`. When a step's iterations fail, it is retried as
    /// [`next_attempt`] says: with the factor updated at the dominant contact points (when
    /// `update` is set and the problem linearizes), with J rebuilt at the current state (when
    /// `refresh` is set), by Newton-Krylov, by a full Newton, each with line search; last the
    /// step is halved (J refactorized) and retried from the same state, at most `max_cuts`
    /// levels deep; after `restore_after` good steps the step is doubled back towards the
    /// nominal one and the fixed factor tried again. Once refreshed, every later
    /// factorization uses the current state's tangent. Every change goes to the hooks' log.
    /// Only when the smallest step fails too is the error returned. `control` starts at its
    /// default, or where a checkpoint left it.
    ///
    /// # Collective
    pub fn integrate<'a, P>(
        &self,
        run: &mut P,
        state: &mut State<'p>,
        end_time: f64,
        control: &mut StepControl,
    ) -> Result<(), TimeError>
    where
        P: StepProblem<'a, 'p> + StepHooks<'p>,
    {
        let (linearizes, eliminates) = (run.can_linearize(), run.can_eliminate());
        let cell = RefCell::new(run);
        let mut forces = |t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &mut Vector<'p>| {
            cell.borrow_mut().forces(t, q, v, f)
        };
        let mut factorize = |ns: &NewmarkSettings, at: Option<&State<'p>>, retired| {
            cell.borrow_mut().factorize(ns, at, retired)
        };
        let mut linearize = |ns: &NewmarkSettings, at: &State<'p>| {
            let change = cell.borrow_mut().linearize(ns, at)?;
            Ok(change as Box<dyn TangentChange<'p> + '_>)
        };
        let mut eliminate = |ns: &NewmarkSettings, at: &State<'p>, r: &Vector<'p>, target| {
            cell.borrow_mut().eliminate(ns, at, r, target)
        };
        let mut on_step = |s: &State<'p>, report: &StepReport, c: &StepControl, h: f64| {
            cell.borrow_mut().on_step(s, report, c, h)
        };
        let mut log = |line: &str| cell.borrow_mut().log(line);
        let mut parts = Parts {
            forces: &mut forces,
            factorize: &mut factorize,
            linearize: linearizes.then_some(&mut linearize as &mut Linearize<'_, 'p>),
            eliminate: eliminates.then_some(&mut eliminate as &mut Eliminate<'_, 'p>),
            on_step: &mut on_step,
            log: &mut log,
        };
        self.integrate_parts(&mut parts, state, end_time, control)
    }

    /// [`AdaptiveNewmark::integrate`]'s loop over factors.
    ///
    /// # Collective
    fn integrate_parts(
        &self,
        parts: &mut Parts<'_, '_, 'p>,
        state: &mut State<'p>,
        end_time: f64,
        control: &mut StepControl,
    ) -> Result<(), TimeError> {
        let nominal = self.settings.step;
        // The Jacobian a refresh replaces, handed back to be renewed in place.
        let mut retired = None;
        while state.time < end_time - 0.25 * control.step_size(nominal) {
            let settings = NewmarkSettings {
                step: control.step_size(nominal),
                ..self.settings
            };
            let at = control.refreshed.then_some(&*state);
            let factor = (parts.factorize)(&settings, at, retired.take())?;
            control.factorizations += 1;
            let mut integrator = Newmark::new(settings, self.m, self.c, self.k, &factor)?;
            if let Some(force) = self.equilibrium {
                integrator.judge_against_equilibrium(force)?;
            }
            let matrix = factor.matrix.is_some();
            let ended =
                self.steps_on_factor(&mut integrator, matrix, parts, state, end_time, control)?;
            drop(integrator);
            if let OnFactor::Stopped = ended {
                return Ok(());
            }
            retired = factor.retire();
        }
        Ok(())
    }

    /// Steps with one factor until a new one is needed or the hooks stop the run.
    ///
    /// # Collective
    fn steps_on_factor(
        &self,
        integrator: &mut Newmark<'_, 'p>,
        matrix: bool,
        parts: &mut Parts<'_, '_, 'p>,
        state: &mut State<'p>,
        end_time: f64,
        control: &mut StepControl,
    ) -> Result<OnFactor, TimeError> {
        let h = integrator.step_size();
        while state.time < end_time - 0.25 * h {
            match self.attempt(integrator, matrix, parts, state, control) {
                Ok(report) => {
                    let restored = self.accept(control, parts, state.time);
                    if (parts.on_step)(state, &report, control, h)? == Flow::Stop {
                        return Ok(OnFactor::Stopped);
                    }
                    if restored {
                        return Ok(OnFactor::Refactor);
                    }
                }
                Err(TimeError::NotConverged {
                    residual, target, ..
                }) => {
                    let failure = Failure {
                        residual,
                        target,
                        h,
                    };
                    let next =
                        self.after_failure(integrator, matrix, parts, state, control, failure)?;
                    if !matches!(next, Next::Retry(_)) {
                        return Ok(OnFactor::Refactor);
                    }
                }
                Err(e) => return Err(e),
            }
        }
        Ok(OnFactor::Refactor)
    }

    /// One attempt at the next step with the correction the control stands at.
    ///
    /// # Collective
    fn attempt(
        &self,
        integrator: &mut Newmark<'_, 'p>,
        matrix: bool,
        parts: &mut Parts<'_, '_, 'p>,
        state: &mut State<'p>,
        control: &StepControl,
    ) -> Result<StepReport, TimeError> {
        let forces = &mut *parts.forces;
        let correction = match (
            self.adaptivity.full_newton,
            control.fallback,
            &mut parts.linearize,
        ) {
            (true, _, _) | (_, FULL, _) => Correction::Full(&mut *parts.factorize),
            (_, KRYLOV, Some(l)) if matrix => Correction::Krylov(&mut **l),
            (_, UPDATED, Some(_)) if matrix && parts.eliminate.is_some() => {
                Correction::Eliminated(&mut **parts.eliminate.as_mut().expect("checked"))
            }
            (_, UPDATED, Some(l)) => Correction::Updated(&mut **l),
            _ => return integrator.step(state, forces),
        };
        integrator.step_with(state, forces, correction, true)
    }

    /// The control after an accepted step: the updated factor stays on for the steps that
    /// follow (a point that crossed the friction band crosses back within the cycle),
    /// Newton-Krylov and the full Newton are rescues of one step, and the fixed J is tried
    /// again after `restore_after` good steps, when a halved step is also doubled back
    /// (true: a new factor is needed).
    fn accept(&self, control: &mut StepControl, parts: &mut Parts<'_, '_, 'p>, time: f64) -> bool {
        let Adaptivity {
            restore_after,
            update,
            ..
        } = self.adaptivity;
        let linearizes = parts.linearize.is_some();
        let updated = if update && linearizes {
            UPDATED
        } else if linearizes && control.fallback >= KRYLOV {
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
            (parts.log)(&format!(
                "t = {time:.6e} s: {restore_after} steps converged, step back to {:.3e} s",
                control.step_size(self.settings.step)
            ));
        }
        restore
    }

    /// The control after a failed attempt, as [`next_attempt`] decides, with its log line;
    /// the error when nothing is left.
    fn after_failure(
        &self,
        integrator: &Newmark<'_, 'p>,
        matrix: bool,
        parts: &mut Parts<'_, '_, 'p>,
        state: &State<'p>,
        control: &mut StepControl,
        failure: Failure,
    ) -> Result<Next, TimeError> {
        let (iterations, solves) = integrator.failed_attempt();
        let (residuals, seconds) = integrator.failed_attempt_residuals();
        control.failed_iterations += iterations;
        control.failed_solves += solves;
        control.failed_seconds += seconds;
        let eliminating = parts.eliminate.is_some();
        let failed = attempt_name(control, self.adaptivity.full_newton, eliminating);
        let options = Options {
            adaptivity: self.adaptivity,
            linearize: parts.linearize.is_some(),
            matrix,
            krylov_exhausted: integrator.krylov_exhausted(),
        };
        let Failure {
            residual,
            target,
            h,
        } = failure;
        let Some(next) = next_attempt(control, options) else {
            return Err(TimeError::NotConverged {
                step: state.step + 1,
                time: state.time + h,
                iterations,
                residual,
                target,
            });
        };
        let action = match next {
            Next::Refresh => {
                control.refreshed = true;
                control.fresh = true;
                control.good = 0;
                control.refreshes += 1;
                "Jacobian rebuilt with the current contact tangent".to_string()
            }
            Next::Retry(fallback) => {
                let how = retry_with(control, fallback, eliminating);
                format!("retrying the step with {how} and line search")
            }
            Next::Cut => {
                control.fallback = FIXED;
                control.level += 1;
                control.cuts += 1;
                control.good = 0;
                control.fresh = control.refreshed;
                let cut = control.step_size(self.settings.step);
                format!("step cut to {cut:.3e} s, Jacobian refactorized")
            }
        };
        let history = attempt_history(residuals, seconds);
        (parts.log)(&format!(
            "t = {:.6e} s: stalled with {failed} (residual {residual:.3e} vs {target:.3e}; {history}); {action}",
            state.time
        ));
        Ok(next)
    }
}

/// A failed attempt's residual, its target and the step it tried.
#[derive(Clone, Copy)]
struct Failure {
    residual: f64,
    target: f64,
    h: f64,
}

/// The control set to retry a step with `fallback` (which then stays for `restore_after`
/// steps), and what that retry is, for the log.
fn retry_with(control: &mut StepControl, fallback: u8, eliminating: bool) -> &'static str {
    control.fallback = fallback;
    control.good = 0;
    match fallback {
        UPDATED if eliminating => {
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
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
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
