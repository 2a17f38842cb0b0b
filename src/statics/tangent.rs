//! The static Newton's corrections: a modified Newton whose LU factor is kept while it
//! contracts; once it stops contracting, GMRES on the tangent at the iterate, preconditioned by
//! that factor, before a new factorization.
//!
//! Why GMRES first: the tangent changes between iterates only at the contact points, so the old
//! factor is a good preconditioner, and a factorization costs as much as tens of solves (100k
//! DOF: ~2.5 s against ~0.07 s; 600k: ~50 s against ~1 s). The choice is a ski rental: GMRES
//! iterations are spent with the old factor until, since that factor, they have cost as much
//! as one factorization (by MUMPS' counts of both); then the tangent is factorized. Never
//! worse than twice the better of the two choices in hindsight, whatever the contact does.

use std::time::Instant;

use super::StaticFactor;
use crate::contact::kernel::Part;
use crate::contact::{ContactModel, ContactState};
use crate::la::gmres::{gmres, Preconditioned};
use crate::la::{BlockAddPlan, DirectSolver, Factorization, LaError, Petsc, SparseMatrix, Vector};

/// GMRES' relative residual: an inexact Newton correction whose linear error (1e-3 of the
/// residual) is far below what a load step's first iterations gain, and costs one or two
/// outer iterations near convergence.
const KRYLOV_RELATIVE: f64 = 1e-3;
/// The elimination's flop rate over the solve's, measured on this machine kind (the 100k
/// brake's static tangent, 2 ranks): 8.52e10 flops in 2.47 s (34.5 GFlop/s) against
/// 2 x 9.42e7 in 0.072 s (2.6 GFlop/s), a ratio of 13. A machine where it differs by 2x
/// pays at most 2x more in one of the two (the rental's bound holds for the true price).
const ELIMINATION_OVER_SOLVE_RATE: f64 = 13.0;
/// Bounds of one GMRES' iterations (its basis is kept: at 600k, 50 vectors are 120 MB per
/// rank); with fewer left of the budget, the factorization is due.
const KRYLOV_MIN: usize = 3;
const KRYLOV_MAX: usize = 50;

/// What a correction is measured against.
#[derive(Debug, Clone, Copy)]
pub struct Scale {
    /// A linear residual below which no Newton correction can be better (N; a fraction of
    /// the Newton tolerance).
    pub floor: f64,
    /// |q| at the iterate (m).
    pub reach: f64,
}

/// Which correction the last call computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Correction {
    /// With a factor of an earlier iterate's tangent (modified Newton).
    Stale,
    /// GMRES on this iterate's tangent, preconditioned by an earlier factor.
    Krylov,
    /// With a factor of this iterate's tangent.
    Fresh,
}

impl Correction {
    /// A Newton correction of this iterate's tangent: a line search that fails along it will
    /// not do better with a new factor.
    pub fn is_newton(self) -> bool {
        self != Correction::Stale
    }
}

/// The tangent matrix, its factor and the counts of what they cost.
pub struct TangentSolver<'p> {
    petsc: &'p Petsc<'p>,
    /// K0's pattern joined with the contacts; holds the tangent at the iterate of the last
    /// Krylov or fresh correction (the factor may be of an older one: PETSc keeps a factor
    /// until `refactorize`).
    jac: SparseMatrix<'p>,
    /// Where the contact tangent's entries land in `jac` (None: not planned yet, or the
    /// pattern lacks them and MatSetValues adds them); kept with `jac` from solve to solve.
    plan: Option<BlockAddPlan>,
    solver: Option<DirectSolver<'p>>,
    /// The factor is of an earlier iterate's tangent and stopped contracting.
    stale: bool,
    krylov: bool,
    /// The precision of a new factor.
    precision: StaticFactor,
    basis: Vec<Vector<'p>>,
    preconditioned: Option<Vector<'p>>,
    /// What the last factorization took (handed on with the factor, for its report).
    last_factor_seconds: f64,
    /// The longest correction taken so far (m).
    longest_correction: f64,
    /// GMRES corrections refused for their length.
    pub krylov_refused: usize,
    /// GMRES iterations since the last factorization (the rent paid).
    krylov_since_factor: usize,
    pub factorizations: usize,
    pub solves: usize,
    pub seconds_factorizing: f64,
    pub seconds_solving: f64,
    pub krylov_corrections: usize,
    pub krylov_iterations: usize,
    /// GMRES solves that did not reach their tolerance within the budget (a factorization
    /// followed).
    pub krylov_failures: usize,
}

impl<'p> TangentSolver<'p> {
    /// From a matrix of the joined pattern, possibly its plan of contact entries and its
    /// factor of a nearby state (`factor_seconds`: what that factorization took, 0 if
    /// unknown).
    pub fn new(
        petsc: &'p Petsc<'p>,
        jac: SparseMatrix<'p>,
        plan: Option<BlockAddPlan>,
        solver: Option<DirectSolver<'p>>,
        factor_seconds: f64,
        krylov: bool,
        precision: StaticFactor,
    ) -> Self {
        TangentSolver {
            petsc,
            jac,
            plan,
            solver,
            stale: false,
            krylov,
            precision,
            basis: Vec::new(),
            preconditioned: None,
            last_factor_seconds: factor_seconds,
            krylov_since_factor: 0,
            longest_correction: 0.0,
            krylov_refused: 0,
            factorizations: 0,
            solves: 0,
            seconds_factorizing: 0.0,
            seconds_solving: 0.0,
            krylov_corrections: 0,
            krylov_iterations: 0,
            krylov_failures: 0,
        }
    }

    /// The factor no longer contracts well enough (or a line search along its correction
    /// failed): the next correction is a Newton one.
    pub fn mark_stale(&mut self) {
        self.stale = true;
    }

    pub fn factor_entries(&self) -> f64 {
        self.solver
            .as_ref()
            .map_or(0.0, |s| s.report().factor_entries)
    }

    /// The precision of the factor held (that of the settings for a new one).
    pub fn factor_precision(&self) -> StaticFactor {
        match &self.solver {
            Some(s) if s.is_single() => StaticFactor::Single,
            Some(_) => StaticFactor::Double,
            None => self.precision,
        }
    }

    pub fn factor_flops(&self) -> f64 {
        self.solver.as_ref().map_or(0.0, |s| s.report().flops)
    }

    /// The matrix, its plan, its factor and what the factorization took, for the next solve.
    pub fn into_parts(
        self,
    ) -> (
        SparseMatrix<'p>,
        Option<BlockAddPlan>,
        Option<DirectSolver<'p>>,
        f64,
    ) {
        (self.jac, self.plan, self.solver, self.last_factor_seconds)
    }

    /// dq with J dq = -R at the iterate q whose contact state is `state` (`minus_residual` =
    /// -R), with `scale` the iterate's [`Scale`].
    ///
    /// A GMRES correction longer than both |q| and every correction before it is refused (a
    /// new factor is computed instead): it follows a direction that the stale factor nearly
    /// cannot resist and that the residual norm GMRES minimizes does not see. Measured: the
    /// frictionless small brake, whose pads are held tangentially by nothing but open
    /// abutment contacts, converged to |R| within tolerance with its pads 5.8 m away.
    ///
    /// # Collective
    pub fn correct(
        &mut self,
        k0: &SparseMatrix<'p>,
        contact: &ContactModel<'p>,
        state: &ContactState,
        minus_residual: &Vector<'p>,
        dq: &mut Vector<'p>,
        scale: Scale,
    ) -> Result<Correction, LaError> {
        let Scale { floor, reach } = scale;
        let kind = match (&self.solver, self.stale) {
            (Some(_), false) => Correction::Stale,
            (Some(_), true) if self.krylov => {
                self.assemble(k0, contact, state)?;
                if self.krylov_solve(minus_residual, dq, floor)? {
                    let length = dq.norm2()?;
                    if length <= reach.max(self.longest_correction) {
                        self.longest_correction = self.longest_correction.max(length);
                        return Ok(Correction::Krylov);
                    }
                    self.krylov_refused += 1;
                }
                self.factorize()?;
                Correction::Fresh
            }
            _ => {
                self.assemble(k0, contact, state)?;
                self.factorize()?;
                Correction::Fresh
            }
        };
        self.solve(minus_residual, dq)?;
        self.longest_correction = self.longest_correction.max(dq.norm2()?);
        Ok(kind)
    }

    /// J = K0 + the contact tangent at `state` (normal, stick, friction, stick coupling).
    fn assemble(
        &mut self,
        k0: &SparseMatrix<'p>,
        contact: &ContactModel<'p>,
        state: &ContactState,
    ) -> Result<(), LaError> {
        self.jac.copy_values_from(k0)?;
        let parts = [
            Part::Normal,
            Part::Stick,
            Part::Friction,
            Part::StickCoupling,
        ];
        // A plan from an earlier solve may be of another contact model's points: planned
        // anew then (it costs about one assembly through MatSetValues).
        let fits = match &self.plan {
            Some(plan) => contact.tangent_plan_fits(plan, &self.jac)?,
            None => false,
        };
        if !fits {
            self.plan = None;
            self.plan = contact.tangent_plan(&self.jac)?;
        }
        match &mut self.plan {
            Some(plan) => contact.add_tangent_planned(state, &parts, &mut self.jac, plan),
            None => {
                contact.add_tangent(state, &parts, &mut self.jac)?;
                self.jac.assemble()
            }
        }
    }

    /// LU of `jac`: by the old factor's numerical phase when it factors `jac`, else anew (the
    /// old one freed first: peak memory).
    fn factorize(&mut self) -> Result<(), LaError> {
        let t = Instant::now();
        let (petsc, jac, precision) = (self.petsc, &self.jac, self.precision);
        let anew = || match precision {
            StaticFactor::Double => {
                DirectSolver::factorize(petsc, jac, Factorization::Lu, "static_")
            }
            StaticFactor::Single => {
                DirectSolver::factorize_single(petsc, jac, Factorization::Lu, "static_")
            }
        };
        self.solver = Some(match self.solver.take() {
            Some(solver) if solver.factors(jac)? => solver.renewed_or(jac, anew)?,
            other => {
                drop(other);
                anew()?
            }
        });
        self.last_factor_seconds = t.elapsed().as_secs_f64();
        self.seconds_factorizing += self.last_factor_seconds;
        self.factorizations += 1;
        self.krylov_since_factor = 0;
        self.stale = false;
        Ok(())
    }

    fn solve(&mut self, b: &Vector<'p>, x: &mut Vector<'p>) -> Result<(), LaError> {
        let t = Instant::now();
        self.solver
            .as_ref()
            .expect("the tangent is factorized before it solves")
            .solve(b, x)?;
        self.seconds_solving += t.elapsed().as_secs_f64();
        self.solves += 1;
        Ok(())
    }

    /// What a factorization costs in solves, from MUMPS' own counts: its elimination flops
    /// against a solve's (two per factor entry), at the rates measured for each (the solve
    /// streams the factor from memory, the elimination runs in dense blocks). Counts, not
    /// timings: the decision is the same on every rank and in every run (a restart recomputes
    /// the preload and must find the same state).
    fn factorization_price(&self) -> usize {
        let report = self.solver.as_ref().map(|s| s.report());
        match report {
            Some(r) if r.flops > 0.0 && r.factor_entries > 0.0 => {
                (r.flops / (2.0 * r.factor_entries) / ELIMINATION_OVER_SOLVE_RATE) as usize
            }
            _ => KRYLOV_MAX,
        }
    }

    /// GMRES on jac dq = b preconditioned by the factor, within what is left of one
    /// factorization's price in solves since the factor. Whether it converged (dq is then the
    /// correction).
    fn krylov_solve(
        &mut self,
        b: &Vector<'p>,
        dq: &mut Vector<'p>,
        floor: f64,
    ) -> Result<bool, LaError> {
        let price = self.factorization_price();
        let budget = price
            .saturating_sub(self.krylov_since_factor)
            .min(KRYLOV_MAX);
        if budget < KRYLOV_MIN {
            return Ok(false);
        }
        let enough = (KRYLOV_RELATIVE * b.norm2()?).max(floor);
        let mut basis = std::mem::take(&mut self.basis);
        let z = match self.preconditioned.take() {
            Some(z) => z,
            None => b.duplicate()?,
        };
        let mut system = StaleFactor { tangent: self, z };
        let outcome = gmres(&mut system, b, dq, &mut basis, enough, budget);
        let StaleFactor { z, .. } = system;
        self.preconditioned = Some(z);
        self.basis = basis;
        let outcome = outcome?;
        self.krylov_iterations += outcome.iterations;
        self.krylov_since_factor += outcome.iterations + 1;
        if outcome.converged {
            self.krylov_corrections += 1;
        } else {
            self.krylov_failures += 1;
        }
        Ok(outcome.converged)
    }
}

/// jac (M^-1 v) with M the factor: GMRES' operator.
struct StaleFactor<'s, 'p> {
    tangent: &'s mut TangentSolver<'p>,
    z: Vector<'p>,
}

impl<'p> Preconditioned<'p> for StaleFactor<'_, 'p> {
    fn apply(&mut self, v: &Vector<'p>, w: &mut Vector<'p>) -> Result<(), LaError> {
        self.tangent.solve(v, &mut self.z)?;
        self.tangent.jac.mult(&self.z, w)
    }

    fn precondition(&mut self, v: &Vector<'p>, x: &mut Vector<'p>) -> Result<(), LaError> {
        self.tangent.solve(v, x)
    }
}
