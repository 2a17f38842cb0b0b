//! The preload's load stepping and Newton iterations: each load step (a pressure and a
//! friction fraction) solved by a modified Newton iteration with line search, a step that
//! stalls retried from the last converged state with half the increment.

use std::collections::VecDeque;
use std::time::Instant;

use super::tangent::{Scale, TangentSolver};
use super::{
    backtrack, stalled, worst_interface, Evaluation, Factored, NewtonRecord, Start, StaticError,
    StaticSettings, StaticState,
};
use crate::contact::{ContactModel, ContactState};
use crate::la::{LaError, Petsc, SparseMatrix, Vector};

/// Halvings of one load step in a row at most.
const MAX_CUTS: usize = 6;

/// Where a load step's Newton iteration gave up: its iterations, residual and target.
struct Stall {
    iterations: usize,
    residual: f64,
    target: f64,
}

/// The preload's equations, the Newton iteration's vectors, its record and its budget.
struct Preload<'s, 'p> {
    petsc: &'p Petsc<'p>,
    k0: &'s SparseMatrix<'p>,
    contact: &'s ContactModel<'p>,
    settings: &'s StaticSettings,
    tangent: TangentSolver<'p>,
    /// The iterate, a trial along the correction, the correction, R, the load, f_c.
    q: Vector<'p>,
    trial: Vector<'p>,
    dq: Vector<'p>,
    residual: Vector<'p>,
    f: Vector<'p>,
    fc: Vector<'p>,
    log: Vec<NewtonRecord>,
    iterations_spent: usize,
    iteration_budget: usize,
}

/// R = K0 q - f_c(q) - f into `r`: (|R|, the reference force, the contact state).
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the operators, q, the friction fraction, the load, R
fn evaluate<'p>(
    k0: &SparseMatrix<'p>,
    contact: &ContactModel<'p>,
    fc: &mut Vector<'p>,
    q: &Vector<'p>,
    psi: f64,
    f: &Vector<'p>,
    r: &mut Vector<'p>,
) -> Result<Evaluation, LaError> {
    let state = contact.evaluate(q, None, psi)?;
    contact.force(&state, fc)?;
    k0.mult(q, r)?;
    r.axpy(-1.0, fc)?;
    r.axpy(-1.0, f)?;
    Ok((r.norm2()?, f.norm2()?.max(fc.norm2()?), state))
}

/// [`super::solve`] from `start_at`.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // as solve
pub fn solve_from<'p>(
    petsc: &'p Petsc,
    k0: &SparseMatrix<'p>,
    contact: &ContactModel<'p>,
    f_ext: &Vector<'p>,
    settings: &StaticSettings,
    start_at: Start<'_, 'p>,
    mut progress: impl FnMut(&NewtonRecord),
) -> Result<StaticState<'p>, StaticError> {
    let start = Instant::now();
    let (start_from, factor) = (start_at.displacement, start_at.factor);
    let cut_budget = start_at.cut_budget.unwrap_or(4 * MAX_CUTS);
    let budget = start_at.iteration_budget.unwrap_or(usize::MAX);
    let model = (k0, contact, settings);
    let mut p = Preload::new(petsc, model, start_from, budget, factor.take())?;
    let friction = contact
        .interfaces()
        .iter()
        .any(|i| i.friction.is_sliding() && i.friction.mu() > 0.0)
        && contact.disc_speed() != 0.0;
    // Warm start (a sweep's next point): one step at the full load, cut if it stalls.
    let mut targets: VecDeque<(f64, f64)> = match start_from {
        Some(_) => vec![(1.0, 1.0)].into(),
        None => settings.schedule(friction).into(),
    };
    let mut converged_at = (0.0, 0.0);
    let mut saved = p.q.duplicate()?;
    let (mut cuts, mut cut_steps, mut step) = (0, 0usize, 0);
    let mut last_state = None;
    while let Some(&(phi, psi)) = targets.front() {
        step += 1;
        p.f.copy_from(f_ext)?;
        p.f.scale(phi)?;
        match p.load_step(step, (phi, psi), &mut progress)? {
            Ok(state) => {
                targets.pop_front();
                converged_at = (phi, psi);
                saved.copy_from(&p.q)?;
                cuts = 0;
                last_state = Some(state);
            }
            Err(stall) => {
                // A warm start has no smaller load step to fall back to: the caller decides
                // (a sweep restarts cold).
                if cuts >= MAX_CUTS || cut_steps >= cut_budget || start_from.is_some() {
                    return Err(StaticError::NotConverged {
                        step,
                        pressure: 100.0 * phi,
                        friction: 100.0 * psi,
                        iterations: stall.iterations,
                        residual: stall.residual,
                        target: stall.target,
                        interface: worst_interface(petsc, contact, &p.residual)?,
                    });
                }
                cuts += 1;
                cut_steps += 1;
                p.tangent.mark_stale();
                p.q.copy_from(&saved)?;
                let half = (0.5 * (converged_at.0 + phi), 0.5 * (converged_at.1 + psi));
                targets.push_front(half);
                if petsc.rank() == 0 {
                    println!(
                        "  static step {step} stalled at residual {:.3e} N: cutting the increment, next target pressure {:.1} %, friction {:.1} %",
                        stall.residual,
                        100.0 * half.0,
                        100.0 * half.1
                    );
                }
            }
        }
    }
    let state = last_state.expect("at least one load step");
    p.finish(state, f_ext.norm2()?, cut_steps, start, factor)
}

impl<'s, 'p> Preload<'s, 'p> {
    /// # Collective
    fn new(
        petsc: &'p Petsc<'p>,
        (k0, contact, settings): (
            &'s SparseMatrix<'p>,
            &'s ContactModel<'p>,
            &'s StaticSettings,
        ),
        start_from: Option<&Vector<'p>>,
        iteration_budget: usize,
        factor: Option<Factored<'p>>,
    ) -> Result<Self, StaticError> {
        let (krylov, kind) = (settings.krylov, settings.factor);
        let tangent = match factor {
            Some(f) => {
                let solver = Some(f.solver);
                TangentSolver::new(petsc, f.jac, f.plan, solver, f.seconds, krylov, kind)
            }
            None => {
                let joined = contact.joined_matrix(petsc, k0)?;
                TangentSolver::new(petsc, joined, None, None, 0.0, krylov, kind)
            }
        };
        let mut q = k0.new_vector()?;
        if let Some(start) = start_from {
            q.copy_from(start)?;
        }
        Ok(Preload {
            petsc,
            k0,
            contact,
            settings,
            tangent,
            trial: q.duplicate()?,
            dq: q.duplicate()?,
            residual: q.duplicate()?,
            f: q.duplicate()?,
            fc: q.duplicate()?,
            q,
            log: Vec::new(),
            iterations_spent: 0,
            iteration_budget,
        })
    }

    /// R at the iterate.
    ///
    /// # Collective
    fn evaluate_at_iterate(&mut self, psi: f64) -> Result<Evaluation, LaError> {
        let (k0, contact) = (self.k0, self.contact);
        evaluate(
            k0,
            contact,
            &mut self.fc,
            &self.q,
            psi,
            &self.f,
            &mut self.residual,
        )
    }

    /// One load step's Newton iteration at load fraction `phi` (in `f`) and friction fraction
    /// `psi`: the converged contact state, or where it stalled; an error that no smaller
    /// increment can mend (not finite, a singular tangent, the budget spent).
    ///
    /// # Collective
    fn load_step(
        &mut self,
        step: usize,
        (phi, psi): (f64, f64),
        progress: &mut impl FnMut(&NewtonRecord),
    ) -> Result<Result<ContactState, Stall>, StaticError> {
        let (mut r, mut reference, mut state) = self.evaluate_at_iterate(psi)?;
        if !(r.is_finite() && reference.is_finite()) {
            // At the last converged state: no smaller load increment can help.
            return Err(StaticError::NotFinite { step });
        }
        // (residual, step length taken from it) of each iteration.
        let mut history: Vec<(f64, f64)> = Vec::new();
        let mut iteration = 0;
        loop {
            let target = self.settings.tolerance * reference;
            let record = |step_length| NewtonRecord {
                load_step: step,
                pressure_fraction: phi,
                friction_fraction: psi,
                iteration,
                residual: r,
                reference,
                step_length,
            };
            if r <= target {
                let rec = record(0.0);
                progress(&rec);
                self.log.push(rec);
                return Ok(Ok(state));
            }
            if self.iterations_spent >= self.iteration_budget {
                return Err(StaticError::BudgetSpent {
                    iterations: self.iterations_spent,
                    step,
                    pressure: 100.0 * phi,
                    friction: 100.0 * psi,
                    residual: r,
                    target,
                });
            }
            let settings = self.settings;
            if iteration >= settings.max_iterations || !r.is_finite() || stalled(&history, r) {
                return Ok(Err(Stall {
                    iterations: iteration,
                    residual: r,
                    target,
                }));
            }
            self.iterations_spent += 1;
            let newton = self.correct(&state, target, (step, phi, psi, iteration, r))?;
            let (k0, contact) = (self.k0, self.contact);
            let (fc, f, residual) = (&mut self.fc, &self.f, &mut self.residual);
            let chosen = backtrack(&self.q, &self.dq, r, &mut self.trial, |t| {
                evaluate(k0, contact, fc, t, psi, f, residual)
            })?;
            let Some((alpha, evaluated)) = chosen else {
                // Leave the residual of the current iterate for the error report (and for a
                // retry with a Newton correction when this one was the old factor's).
                self.evaluate_at_iterate(psi)?;
                if !newton {
                    self.tangent.mark_stale();
                    continue;
                }
                return Ok(Err(Stall {
                    iterations: iteration,
                    residual: r,
                    target,
                }));
            };
            let rec = record(alpha);
            progress(&rec);
            self.log.push(rec);
            history.push((r, alpha));
            self.q.axpy(alpha, &self.dq)?;
            let previous = r;
            (r, reference, state) = match evaluated {
                Some(e) => e,
                None => self.evaluate_at_iterate(psi)?,
            };
            if alpha < 1.0 || r > settings.reuse_contraction * previous {
                self.tangent.mark_stale();
            }
            iteration += 1;
        }
    }

    /// The correction dq of -R at the iterate (`at`: the load step, its fractions, the
    /// iteration and |R| for the error of a singular tangent); true: a Newton correction
    /// (with the iterate's tangent), false: the old factor's.
    ///
    /// # Collective
    fn correct(
        &mut self,
        state: &ContactState,
        target: f64,
        (step, phi, psi, iteration, r): (usize, f64, f64, usize, f64),
    ) -> Result<bool, StaticError> {
        self.residual.scale(-1.0)?;
        let scale = Scale {
            floor: 0.1 * target,
            reach: self.q.norm2()?,
        };
        let (k0, contact) = (self.k0, self.contact);
        let corrected =
            self.tangent
                .correct(k0, contact, state, &self.residual, &mut self.dq, scale);
        match corrected {
            Ok(kind) => Ok(kind.is_newton()),
            Err(e @ (LaError::SingularMatrix { .. } | LaError::NearlySingular { .. })) => {
                let how = match e {
                    LaError::NearlySingular { infog1, percent, .. } => format!("nearly singular (MUMPS' pivoting outgrew its work space, INFOG(1) = {infog1}, at {percent} % over its estimate)"),
                    _ => "singular (MUMPS INFOG(1) = -10)".to_string(),
                };
                Err(StaticError::SingularTangent {
                    how,
                    step,
                    pressure: 100.0 * phi,
                    friction: 100.0 * psi,
                    iteration,
                    residual: r,
                })
            }
            Err(e) => Err(e.into()),
        }
    }

    /// The solved state; the tangent and factor in use go back to `factor` for the next
    /// solve.
    fn finish(
        self,
        state: ContactState,
        load_norm: f64,
        cut_steps: usize,
        start: Instant,
        factor: &mut Option<Factored<'p>>,
    ) -> Result<StaticState<'p>, StaticError> {
        let tangent = self.tangent;
        let solved = StaticState {
            displacement: self.q,
            summaries: self.contact.summarize(self.petsc, &state),
            contact: state,
            log: self.log,
            factorizations: tangent.factorizations,
            factor_precision: tangent.factor_precision(),
            solves: tangent.solves,
            krylov_corrections: tangent.krylov_corrections,
            krylov_iterations: tangent.krylov_iterations,
            cut_steps,
            factor_entries: tangent.factor_entries(),
            seconds_factorizing: tangent.seconds_factorizing,
            seconds_solving: tangent.seconds_solving,
            factor_flops: tangent.factor_flops(),
            seconds: start.elapsed().as_secs_f64(),
            load_norm,
        };
        let (jac, plan, solver, seconds) = tangent.into_parts();
        *factor = solver.map(|solver| Factored {
            jac,
            plan,
            solver,
            seconds,
        });
        Ok(solved)
    }
}
