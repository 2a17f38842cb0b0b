//! How a step's iterate is corrected: modified Newton with the step's fixed factor, the same
//! factor updated at the contact points whose tangent changed most, a full Newton with J
//! rebuilt at every iterate, or Newton-Krylov (`krylov.rs`); and what a correction changes in
//! the carried linear force.

use super::{Jacobian, Newmark, NewmarkSettings, RetiredJacobian, State, StepReport};
use crate::la::{DirectSolver, LaError, LowRankUpdate, TangentChange, Vector};

/// Builds and factorizes J for a step size; `None`: the initial tangent (the static state's),
/// `Some(state)`: the tangent of that state. The third argument hands back the matrix and
/// factor of the Jacobian this one replaces, which a builder may renew in place (numerical
/// refactorization on the same pattern) instead of building anew.
pub type Factorize<'f, 'p> = dyn FnMut(
        &NewmarkSettings,
        Option<&State<'p>>,
        Option<RetiredJacobian<'p>>,
    ) -> Result<Jacobian<'f, 'p>, LaError>
    + 'f;

/// The change of the nonlinear forces' tangent between the Jacobian's factor and an iterate,
/// X(iterate) - extra (X = K_c + K_stick + K_f + gamma/(beta h) C_f for contact: the
/// consistent Jacobian beyond the linear operators; `extra`: the part J was built with), as an
/// operator: J + that change is the consistent Jacobian at the iterate.
pub type Linearize<'f, 'p> = dyn FnMut(&NewmarkSettings, &State<'p>) -> Result<Box<dyn TangentChange<'p> + 'f>, LaError>
    + 'f;

/// A nonlinear elimination at an iterate (the iterate, its residual R, the residual target):
/// the increment of the unknowns coupled to the contact points whose tangent changed most
/// that zeroes R's rows there with the other unknowns held (None: no such point).
pub type Eliminate<'f, 'p> = dyn FnMut(
        &NewmarkSettings,
        &State<'p>,
        &Vector<'p>,
        f64,
    ) -> Result<Option<Elimination<'p>>, LaError>
    + 'f;

/// What a nonlinear elimination moves: the increment delta of the unknowns (zero off the
/// eliminated ones), and the change of the linear force M a + C v + K q it makes,
/// L delta with L = M / (beta h^2) + gamma / (beta h) C + K (J without its contact part:
/// computed from L's columns on the moved unknowns, not by a product with the whole J).
pub struct Elimination<'p> {
    pub delta: Vector<'p>,
    pub linear_change: Vector<'p>,
}

/// How a step's corrections are computed.
pub enum Correction<'r, 'f, 'p> {
    /// With the factor of the step's fixed J (modified Newton).
    Fixed,
    /// With the fixed factor updated at every iterate by the consistent tangent's change at
    /// its dominant contact points (Woodbury, `la::LowRankUpdate`): a Newton step on the
    /// tangent's dominant part for one solve with the factor (plus one per new point column,
    /// cached for the factor's life), converging nearly as a full Newton where the change sits
    /// on a few points, which the saturated regime's does.
    Updated(&'r mut Linearize<'f, 'p>),
    /// Newton-Krylov: GMRES on the consistent tangent at every iterate, right-preconditioned
    /// by the fixed factor (a few solves where J differs in a few contact points).
    Krylov(&'r mut Linearize<'f, 'p>),
    /// A full Newton: J rebuilt and factorized at every iterate.
    Full(&'r mut Factorize<'f, 'p>),
    /// The fixed factor's correction after a nonlinear elimination of the contact points
    /// whose tangent changed most (`Eliminate`; needs J's matrix).
    Eliminated(&'r mut Eliminate<'f, 'p>),
}

/// Counts and times solves with a factor.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SolveCount {
    pub(super) solves: usize,
    pub(super) seconds: f64,
}

impl SolveCount {
    pub(super) fn solve<'p>(
        &mut self,
        factor: &DirectSolver<'p>,
        b: &Vector<'p>,
        x: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        let t = std::time::Instant::now();
        factor.solve(b, x)?;
        self.solves += 1;
        self.seconds += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// x = P^-1 b with the factor updated by `low_rank` (one solve with the factor).
    pub(super) fn precondition<'p>(
        &mut self,
        low_rank: &LowRankUpdate<'p>,
        factor: &DirectSolver<'p>,
        b: &Vector<'p>,
        x: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        let t = std::time::Instant::now();
        low_rank.apply(factor, b, x)?;
        self.solves += 1;
        self.seconds += t.elapsed().as_secs_f64();
        Ok(())
    }
}

impl<'p> Newmark<'_, 'p> {
    /// dq for the current iterate by `correction`, and the linear force's change dz with it;
    /// `at`: the iterate's time and step number (a Jacobian or tangent built there).
    ///
    /// # Collective
    pub(super) fn correction(
        &mut self,
        correction: &mut Correction<'_, '_, 'p>,
        at: (f64, usize),
        target: f64,
        report: &mut StepReport,
    ) -> Result<(), LaError> {
        let iterate = |s: &Self| s.iterate(at);
        match correction {
            Correction::Fixed | Correction::Eliminated(_) => {
                self.solves
                    .solve(&self.jacobian.factor, &self.r, &mut self.dq)?;
                self.linear_change(self.jacobian, report)
            }
            Correction::Updated(linearize) => {
                let tangent = linearize(&self.settings, &iterate(self)?)?;
                self.updated_correction(tangent.as_ref(), report)
            }
            Correction::Full(build) => {
                let retired = self.full_newton_spare.take();
                let fresh = build(&self.settings, Some(&iterate(self)?), retired)?;
                self.solves.solve(&fresh.factor, &self.r, &mut self.dq)?;
                self.linear_change(&fresh, report)?;
                self.full_newton_spare = fresh.retire();
                Ok(())
            }
            Correction::Krylov(linearize) => {
                let tangent = linearize(&self.settings, &iterate(self)?)?;
                report.krylov_iterations += self.krylov_solve(tangent.as_ref(), 0.1 * target)?;
                self.linear_change_from_matrix()
            }
        }
    }

    /// dq = P^-1 R with P the factor updated by `tangent`'s dominant part (U D U^T), and
    /// dz = -(J - X) dq = -(P dq - U D U^T dq - X dq) = -R + U D U^T dq + X dq.
    ///
    /// # Collective
    pub(super) fn updated_correction(
        &mut self,
        tangent: &dyn TangentChange<'p>,
        report: &mut StepReport,
    ) -> Result<(), LaError> {
        let t = std::time::Instant::now();
        self.solves.solves += self
            .low_rank
            .prepare(&self.jacobian.factor, tangent, &self.q1)?;
        self.solves.seconds += t.elapsed().as_secs_f64();
        self.solves
            .precondition(&self.low_rank, &self.jacobian.factor, &self.r, &mut self.dq)?;
        self.linear_change(self.jacobian, report)?;
        self.low_rank.mult_add_update(&self.dq, &mut self.dz)
    }

    /// The current iterate as a state at `at` (time, step number), for a builder or a tangent.
    fn iterate(&self, at: (f64, usize)) -> Result<State<'p>, LaError> {
        Ok(State {
            time: at.0,
            step: at.1,
            q: self.q1.try_clone()?,
            v: self.v1.try_clone()?,
            a: self.a1.try_clone()?,
            linear: None,
        })
    }

    /// Moves the iterate by the nonlinear elimination's increment (if it found points):
    /// dq = -delta, z by the linear force's change the elimination computed (exact, no
    /// solve).
    ///
    /// # Collective
    pub(super) fn eliminate(
        &mut self,
        eliminate: &mut Eliminate<'_, 'p>,
        at: (f64, usize),
        target: f64,
    ) -> Result<bool, LaError> {
        let iterate = self.iterate(at)?;
        let Some(moved) = eliminate(&self.settings, &iterate, &self.r, target)? else {
            return Ok(false);
        };
        self.dq.copy_from(&moved.delta)?;
        self.dq.scale(-1.0)?;
        self.dz.copy_from(&moved.linear_change)?;
        self.correct(1.0)?;
        Ok(true)
    }

    /// dz = -(J - X) dq for the correction just solved with `jacobian` (whose J dq = R holds to
    /// the factor's accuracy): -R + X dq.
    pub(super) fn linear_change(
        &mut self,
        jacobian: &Jacobian<'_, 'p>,
        report: &mut StepReport,
    ) -> Result<(), LaError> {
        self.dz.copy_from(&self.r)?;
        self.dz.scale(-1.0)?;
        if let Some(extra) = &jacobian.extra {
            let clock = std::time::Instant::now();
            extra.mult_add(&self.dq, &mut self.dz)?;
            report.product_seconds += clock.elapsed().as_secs_f64();
            report.product_calls += 1;
        }
        Ok(())
    }
}
