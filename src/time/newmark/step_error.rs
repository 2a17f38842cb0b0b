//! Accepting an iterate on the step's own error instead of the residual tolerance alone.
//!
//! The fixed Jacobian's iteration converges linearly: each move is about theta times the one
//! before, so the error left in q1 after a move of size d is about theta / (1 - theta) d (the
//! geometric tail; Hairer and Wanner, Solving ODEs II, IV.8, the stopping rule of implicit
//! Runge-Kutta codes). Newmark's step itself leaves a local truncation error in q1 of about
//! (beta - 1/6) h^2 |a1 - a0| (Zienkiewicz and Xie 1991, "A simple error estimator and
//! adaptive time stepping procedure for dynamic analysis": the difference between Newmark's
//! q1 and the one of a cubic displacement through the same accelerations). Iterating below a
//! small fraction kappa of that error buys nothing the step keeps: the iteration's error adds
//! at most kappa of the discretization's own to each step.
//!
//! theta is measured, not assumed: the ratio of the last two moves of the iterate (each the
//! elimination's and the correction's together), both taken in full (a line search's
//! shortened move says nothing about convergence), and it must be below one. The first move
//! of a step is special: from the predictor it removes the inertial part of the residual,
//! which J holds exactly, so the second move's ratio to it can overstate the rate the
//! contact's nonlinearity leaves for the moves after. The second move is therefore judged with
//! the larger of its own ratio and the last ratio measured between later moves (of this or an
//! earlier step); until one was measured, only later moves are judged. On the small brake's
//! saturated window this guard changed little (4.12 -> 4.00 iterations per step without the
//! elimination, the same steps with it): it keeps the estimate honest, it is not what sets the
//! accuracy (benches/transient-results.md).

use super::{Newmark, NewmarkSettings, State};
use crate::la::LaError;

/// The sizes of the current step's moves, for their contraction, and the rate measured
/// between moves after the first (kept from step to step).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Contraction {
    /// The last move's size, if it was a full one, and its number in the step (1: the first).
    last_full_move: Option<(f64, usize)>,
    moves: usize,
    later_rate: Option<f64>,
}

impl Contraction {
    /// A new step: its moves are counted from the predictor.
    pub(super) fn new_step(&mut self) {
        self.last_full_move = None;
        self.moves = 0;
    }
}

impl<'p> Newmark<'_, 'p> {
    /// Whether the iterate's remaining error is below `step_error_fraction` of the step's
    /// truncation error, after a move of the iterate from `q_before` by `alpha` of the
    /// correction. Records the move for the next call.
    ///
    /// # Collective
    pub(super) fn within_step_error(
        &mut self,
        state: &State<'p>,
        alpha: f64,
    ) -> Result<bool, LaError> {
        let NewmarkSettings {
            beta,
            step: h,
            step_error_fraction: kappa,
            ..
        } = self.settings;
        self.tmp.copy_from(&self.q1)?;
        self.tmp.axpy(-1.0, &self.q_before)?;
        let moved = self.tmp.norm2()?;
        let full = alpha == 1.0;
        let c = &mut self.contraction;
        c.moves += 1;
        let previous = c.last_full_move;
        c.last_full_move = full.then_some((moved, c.moves));
        let Some((previous, number)) = previous.filter(|_| full) else {
            return Ok(false);
        };
        let measured = moved / previous;
        let theta = if number == 1 {
            match c.later_rate {
                Some(later) => measured.max(later),
                None => return Ok(false),
            }
        } else {
            c.later_rate = Some(measured).filter(|r| r.is_finite());
            measured
        };
        if theta.is_nan() || theta >= 1.0 {
            return Ok(false);
        }
        let remaining = theta / (1.0 - theta) * moved;
        self.tmp.copy_from(&self.a1)?;
        self.tmp.axpy(-1.0, &state.a)?;
        let truncation = (beta - 1.0 / 6.0).abs() * h * h * self.tmp.norm2()?;
        Ok(remaining <= kappa * truncation)
    }
}
