//! One Newmark step: the predictor, then corrections of the iterate until its residual (or
//! its move, or the step's own error) meets the tolerance, or the attempt stalls.

use super::correction::SolveCount;
use super::LINEAR_FORCE_REFRESH;
use super::{carried, Correction, Forces, Newmark, State, StepReport, TimeError};
use crate::measure::nan_max;

/// An attempt at a step in progress: what its start fixed and where its iterations stand.
struct Attempt {
    started: std::time::Instant,
    /// The step's end time and number.
    t1: f64,
    step: usize,
    /// Anderson's combination redirects the fixed factor's corrections after an
    /// elimination (alone, it did not pay: `anderson.rs`).
    accelerate: bool,
    /// The factor is single precision: the carried linear force drifts and is made exact
    /// where that is due.
    inexact: bool,
    /// The carried z's drift at the start (a failed attempt's solves do not count), and
    /// whether the predictor's z was exact.
    drift_at_start: carried::Drift,
    predictor_exact: bool,
    judge_step_error: bool,
    line_search: bool,
    /// The residual norm at the current iterate and its reference, and at every iterate.
    r: f64,
    reference: f64,
    history: Vec<f64>,
}

/// What an iteration ended in.
enum Iterated {
    Accepted,
    Continue,
}

impl<'p> Newmark<'_, 'p> {
    /// Advances `state` by one step.
    ///
    /// # Collective
    pub fn step(
        &mut self,
        state: &mut State<'p>,
        forces: &mut Forces<'_, 'p>,
    ) -> Result<StepReport, TimeError> {
        self.step_with(state, forces, Correction::Fixed, false)
    }

    /// [`Newmark::step`] with another correction (a full Newton: J rebuilt and factorized at
    /// every iterate, for the steps the fixed Jacobian cannot do; the updated factor;
    /// Newton-Krylov; an elimination), and with `line_search` each correction backtracked
    /// on |R| (Armijo): where a contact point crosses the friction law's regularization band
    /// or opens, a full Newton step can overshoot and cycle, and no step size removes that;
    /// a shorter step along the same direction does.
    ///
    /// # Collective
    pub fn step_with(
        &mut self,
        state: &mut State<'p>,
        forces: &mut Forces<'_, 'p>,
        mut correction: Correction<'_, '_, 'p>,
        line_search: bool,
    ) -> Result<StepReport, TimeError> {
        let (mut attempt, mut report) = self.predict(state, &correction, line_search)?;
        // R = z - f at the predictor; later iterates come evaluated from the correction.
        (attempt.r, attempt.reference) = self.residual(attempt.t1, forces, &mut report)?;
        if !(attempt.r.is_finite() && attempt.reference.is_finite()) {
            // The predictor is built from the last accepted state alone: no smaller step or
            // better Jacobian can help.
            return Err(TimeError::NotFinite {
                step: attempt.step,
                time: attempt.t1,
                what: "the residual at the predictor (from the last accepted state and the forces)",
            });
        }
        self.contraction.new_step();
        loop {
            let iterated =
                self.iteration(state, forces, &mut correction, &mut attempt, &mut report)?;
            if let Iterated::Accepted = iterated {
                return self.finish(state, attempt.t1, report);
            }
        }
    }

    /// The predictor (constant acceleration, q1 = q0 + h v0 + h^2/2 a0), its kinematics and
    /// linear force (carried from the last step, exact every [`LINEAR_FORCE_REFRESH`] steps),
    /// and the attempt's bookkeeping.
    ///
    /// # Collective
    fn predict(
        &mut self,
        state: &State<'p>,
        correction: &Correction<'_, '_, 'p>,
        line_search: bool,
    ) -> Result<(Attempt, StepReport), TimeError> {
        let started = std::time::Instant::now();
        let h = self.settings.step;
        self.krylov_exhausted = false;
        self.solves = SolveCount::default();
        self.anderson.clear();
        self.q1.copy_from(&state.q)?;
        self.q1.axpy(h, &state.v)?;
        self.q1.axpy(0.5 * h * h, &state.a)?;
        self.kinematics(state)?;
        let clock = std::time::Instant::now();
        match &state.linear {
            Some(z_n) if !state.step.is_multiple_of(LINEAR_FORCE_REFRESH) => {
                self.predicted_linear_force(state, z_n)?
            }
            _ => {
                self.linear_force()?;
                self.drift.exact();
            }
        }
        let inexact = self.jacobian.factor.is_single();
        if inexact {
            self.q_pred.copy_from(&self.q1)?;
            self.z_pred.copy_from(&self.z)?;
        }
        let report = StepReport {
            linear_force_seconds: clock.elapsed().as_secs_f64(),
            linear_force_calls: 1,
            forces_current: true,
            ..StepReport::default()
        };
        let attempt = Attempt {
            started,
            t1: state.time + h,
            step: state.step + 1,
            accelerate: self.anderson.depth() > 0
                && matches!(correction, Correction::Eliminated(_)),
            inexact,
            drift_at_start: self.drift,
            predictor_exact: self.drift.is_exact(),
            judge_step_error: self.settings.step_error_fraction > 0.0,
            line_search,
            r: 0.0,
            reference: 0.0,
            history: Vec::new(),
        };
        Ok((attempt, report))
    }

    /// One iteration: the iterate judged (accepted, failed or stalled), else corrected (an
    /// elimination first, where that is the correction), moved (by line search, or whole)
    /// and, unless its moves accept it, its residual evaluated.
    ///
    /// # Collective
    fn iteration(
        &mut self,
        state: &State<'p>,
        forces: &mut Forces<'_, 'p>,
        correction: &mut Correction<'_, '_, 'p>,
        a: &mut Attempt,
        report: &mut StepReport,
    ) -> Result<Iterated, TimeError> {
        let Some(target) = self.judge(a, report)? else {
            return Ok(Iterated::Accepted);
        };
        if a.judge_step_error {
            self.q_before.copy_from(&self.q1)?;
        }
        if let Correction::Eliminated(eliminate) = correction {
            if self.eliminate(&mut **eliminate, (a.t1, a.step), target)? {
                (a.r, a.reference) = self.residual(a.t1, forces, report)?;
                let mismatch = self.residual_where_moved()? / target;
                report.elimination_mismatch = nan_max(report.elimination_mismatch, mismatch);
                if a.r <= self.settings.tolerance * a.reference.max(f64::MIN_POSITIVE) {
                    // Accepted at the next judgement (where the carried z is judged).
                    return Ok(Iterated::Continue);
                }
            }
        }
        let t = std::time::Instant::now();
        if a.inexact && !matches!(correction, Correction::Krylov(_)) {
            // (Newton-Krylov updates z by products.)
            self.drift.solved(a.r);
        }
        self.correction(correction, (a.t1, a.step), target, report)?;
        report.solve_seconds += t.elapsed().as_secs_f64();
        report.iterations += 1;
        if a.accelerate {
            self.accelerate(a.inexact)?;
        }
        let alpha = if a.line_search {
            let (alpha, evaluated) = self.backtrack(a.t1, a.r, forces, report)?;
            (a.r, a.reference) = evaluated;
            alpha
        } else {
            self.correct(1.0)?;
            1.0
        };
        if let Some(on_step_error) = self.accepted_on_moves(state, alpha, a.judge_step_error)? {
            if a.inexact && self.drift.due(None, self.settings.tolerance * a.reference) {
                self.exact_linear_force(a.predictor_exact, report)?;
            }
            report.forces_current = a.line_search;
            report.on_step_error = on_step_error;
            return Ok(Iterated::Accepted);
        }
        if !a.line_search {
            (a.r, a.reference) = self.residual(a.t1, forces, report)?;
        }
        Ok(Iterated::Continue)
    }

    /// The iterate's residual against the tolerance (after an exact linear force where one
    /// is due): None, converged; the target, to go on; the error when the iterations ran
    /// out, stalled (less than a halving over the last four after eight: at that rate the
    /// tolerance is out of reach within the limit, and the caller has better corrections to
    /// try; a patient rule that let such attempts go on was neutral at 600k:
    /// benches/transient-results.md) or the residual is not finite.
    ///
    /// # Collective
    fn judge(
        &mut self,
        a: &mut Attempt,
        report: &mut StepReport,
    ) -> Result<Option<f64>, TimeError> {
        let tolerance = self.settings.tolerance;
        let mut target = tolerance * a.reference.max(f64::MIN_POSITIVE);
        if a.r <= target && a.inexact && self.drift.due(Some(a.r), target) {
            (a.r, a.reference) = self.residual_with_exact_z(a.predictor_exact, report)?;
            target = tolerance * a.reference.max(f64::MIN_POSITIVE);
        }
        report.residual = a.r;
        report.reference = a.reference;
        if a.r <= target {
            return Ok(None);
        }
        a.history.push(a.r);
        let k = a.history.len();
        let stalled = k > 8 && a.r > 0.5 * a.history[k - 5];
        if report.iterations >= self.settings.max_iterations || !a.r.is_finite() || stalled {
            let history = std::mem::take(&mut a.history);
            self.fail(report.iterations, a.started, history, a.drift_at_start);
            return Err(TimeError::NotConverged {
                step: a.step,
                time: a.t1,
                iterations: report.iterations,
                residual: a.r,
                target,
            });
        }
        Ok(Some(target))
    }
}
