//! Nonlinear Newmark (average acceleration: beta = 1/4, gamma = 1/2) with a modified Newton
//! whose Jacobian is fixed: J = M / (beta h^2) + gamma / (beta h) C + K + K_mock, factorized
//! once (MUMPS over the ranks, or PETSc's LU whole on every rank for a small reduced model:
//! `[transient] jacobian_factor`) and reused for every iteration of every step (DESIGN.md §2).
//!
//! Per step, with q1 the unknown displacement at t + h:
//!   a1 = (q1 - q0 - h v0) / (beta h^2) - (1 / (2 beta) - 1) a0
//!   v1 = v0 + h ((1 - gamma) a0 + gamma a1)
//!   R(q1) = M a1 + C v1 + K q1 - f(t + h, q1, v1)
//! iterated as q1 <- q1 - J^-1 R(q1) from the constant-acceleration predictor, until
//! ||R|| <= tolerance x max(||f||, ||z||) (or with an equilibrium force the departure from it,
//! `line_search.rs`), or until the correction is below
//! tolerance x ||q1 - q0||: R carries M (q1 - q0) / (beta h^2), whose round-off (eps times
//! that, ~1e-9 of the forces at h = 1e-3) no iteration removes, while the correction shows
//! convergence of q1 itself; with `step_error_fraction` also once the iteration's remaining
//! error is below that fraction of the step's own truncation error (`step_error.rs`). A step
//! that does not converge is an error naming the step, the time and the residual: never
//! accepted silently.
//!
//! The linear part z = M a1 + C v1 + K q1 is carried from step to step with the state: at
//! the predictor it is z_n + C h a_n + K (h v_n + h^2/2 a_n) (one sparse product with
//! Rayleigh damping C = beta_R K, two with alpha_R M), recomputed from scratch every
//! LINEAR_FORCE_REFRESH steps; within the step it is updated from the solve itself: with
//! J = L + X (L = M / (beta h^2) + gamma / (beta h) C + K, X the contact stiffness J was built
//! with) and J dq = R, the correction changes z by -L dq = -(R - X dq). X is applied through
//! the contact observation rows (a few products over contact points), so an iteration costs
//! one force evaluation, one solve and no product with the model's operators. The identity
//! holds to the solve's backward error (~1e-16 relative), far below the tolerance; with a
//! single-precision factor it holds only to ~6e-8, so there the step recomputes z by products
//! before it accepts an iterate wherever that drift could matter (`carried.rs`).
//!
//! The step and the carried linear force are here; the step's corrections (modified Newton
//! with the fixed factor, full Newton) in `correction.rs`, Newton-Krylov with its GMRES and
//! the Woodbury preconditioner in `krylov.rs`, the residual and the line search in
//! `line_search.rs`, the damping operators in `damping.rs`, the acceptance on the step's own
//! error in `step_error.rs`; all work on the same iterate vectors
//! of one `Newmark`. The adaptive control around the step is in `super::adaptive`.

use crate::la::{DirectSolver, LaError, LowRankUpdate, Operator, SparseMatrix, Vector};

/// Newmark parameters and the Newton tolerance.
#[derive(Debug, Clone, Copy)]
pub struct NewmarkSettings {
    pub beta: f64,
    pub gamma: f64,
    /// Time step (s).
    pub step: f64,
    /// Relative residual tolerance of the modified Newton iterations.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Earlier iterates the eliminated iteration (`Correction::Eliminated`) combines
    /// (`anderson.rs`; 0: the plain modified Newton).
    pub anderson: usize,
    /// Also accept an iterate once the iteration's remaining error, estimated from the
    /// contraction of its last two full moves, is below this fraction of the step's own
    /// truncation error (`step_error.rs`); 0: the residual tolerance alone.
    pub step_error_fraction: f64,
}

impl Default for NewmarkSettings {
    fn default() -> Self {
        NewmarkSettings {
            beta: 0.25,
            gamma: 0.5,
            step: 1e-6,
            tolerance: 1e-8,
            max_iterations: 30,
            anderson: 0,
            step_error_fraction: 0.0,
        }
    }
}

/// What one step took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    pub iterations: usize,
    /// Final residual and the reference it was compared with.
    pub residual: f64,
    pub reference: f64,
    /// Time inside the corrections (the factor's solves, and for Newton-Krylov the
    /// linearization and GMRES around them), the force evaluations (contact) and the products
    /// with the model's operators (predictor) and with the Jacobian's extra part; the rest of
    /// a step is vector updates and reductions.
    pub solve_seconds: f64,
    pub force_seconds: f64,
    /// The linear force at the predictor (products with M, C, K) and the products with the
    /// Jacobian's extra part (the contact tangent through the observation rows).
    pub linear_force_seconds: f64,
    pub product_seconds: f64,
    /// Linear force computations: the predictor's, and with a single-precision factor the
    /// accepted iterate's by a product with J.
    pub linear_force_calls: usize,
    /// Force evaluations and products with the Jacobian's extra part.
    pub force_calls: usize,
    pub product_calls: usize,
    /// The last force evaluation was at the accepted state (the caller may reuse what it
    /// computed there); false when the step ended on the correction criterion.
    pub forces_current: bool,
    /// GMRES iterations of Newton-Krylov corrections.
    pub krylov_iterations: usize,
    /// Solves with a factor (one per fixed-Jacobian iteration, one per GMRES iteration and
    /// one more per Newton-Krylov correction), and the time inside them alone.
    pub factor_solves: usize,
    pub factor_solve_seconds: f64,
    /// The largest |R_i| over the unknowns a nonlinear elimination moved, after its move,
    /// over the step's residual target (its local Newton zeroes those rows to 0.1 of it: more
    /// means the local residual is not the global one's rows); 0 without an elimination.
    pub elimination_mismatch: f64,
    /// The step was accepted on the truncation-error criterion (`step_error.rs`), its
    /// residual above the tolerance.
    pub on_step_error: bool,
}

/// A factorized J and X = J - L, the part beyond the linear operators (the contact stiffness
/// J was built with; None: J = L).
pub struct Jacobian<'x, 'p> {
    pub factor: DirectSolver<'p>,
    pub extra: Option<Box<dyn Operator<'p> + 'x>>,
    /// J itself (what was factorized), for Krylov iterations on the consistent tangent of
    /// another state: J(state) = J + (X(state) - extra), the change from [`Linearize`].
    pub matrix: Option<SparseMatrix<'p>>,
}

impl<'p> Jacobian<'_, 'p> {
    /// Its matrix and factor, for a builder to renew in place (None: no matrix kept).
    pub fn retire(self) -> Option<RetiredJacobian<'p>> {
        let factor = self.factor;
        self.matrix.map(|matrix| RetiredJacobian { matrix, factor })
    }
}

/// A replaced Jacobian's matrix and factor, handed back to its builder ([`Factorize`]).
pub struct RetiredJacobian<'p> {
    pub matrix: SparseMatrix<'p>,
    pub factor: DirectSolver<'p>,
}

#[derive(Debug, thiserror::Error)]
pub enum TimeError {
    #[error(
        "time step {step} (t = {time:.6e} s) did not converge in {iterations} iterations: \
         residual {residual:.3e} vs target {target:.3e}, after every retry the run allows \
         (refreshed Jacobian, Newton-Krylov, full Newton, step cuts: the log lines above); \
         a smaller transient.step, more transient.max_cuts or a smooth friction law (arctan) \
         may get through"
    )]
    NotConverged {
        step: usize,
        time: f64,
        iterations: usize,
        residual: f64,
        target: f64,
    },
    /// NaN or Inf where the run can only have finite numbers: not retried, the run stops.
    #[error(
        "time step {step} (t = {time:.6e} s): {what} is not finite (NaN or Inf); the run stops \
         here, its results up to the last step stay readable"
    )]
    NotFinite {
        step: usize,
        time: f64,
        what: &'static str,
    },
    #[error("transient output: {0}")]
    Store(#[from] crate::time::store::StoreError),
    /// `--restart` refused: the file and why (the reason names it and says what to do).
    #[error("{reason}")]
    Restart {
        file: std::path::PathBuf,
        reason: String,
    },
    #[error("{}: cannot replace the checkpoint: {source}", file.display())]
    Checkpoint {
        file: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    La(#[from] LaError),
}

/// The right-hand side f(t, q, v) (external plus nonlinear forces), written into `out`.
pub type Forces<'f, 'p> =
    dyn FnMut(f64, &Vector<'p>, &Vector<'p>, &mut Vector<'p>) -> Result<(), LaError> + 'f;

/// The state of the integrator: time, displacement, velocity, acceleration.
pub struct State<'p> {
    pub time: f64,
    pub step: usize,
    pub q: Vector<'p>,
    pub v: Vector<'p>,
    pub a: Vector<'p>,
    /// M a + C v + K q, carried by the integrator (None: computed at the next step).
    pub linear: Option<Vector<'p>>,
}

/// The carried linear force is recomputed from scratch at every step number that is a
/// multiple of this (so its update's round-off cannot drift, and a restart, which carries it
/// in the checkpoint, recomputes it at the same steps).
pub const LINEAR_FORCE_REFRESH: usize = 1000;

/// GMRES iterations at most per Newton-Krylov correction.
pub const KRYLOV_MAX: usize = 60;

mod anderson;
mod carried;
mod correction;
mod damping;
mod iteration;
mod krylov;
mod line_search;
mod step_error;

use correction::SolveCount;
pub use correction::{Correction, Eliminate, Elimination, Factorize, Linearize};
pub use damping::{Damping, ModalDamping};

/// A Newmark integrator over fixed operators M, C, K and a factor of J.
pub struct Newmark<'a, 'p> {
    pub settings: NewmarkSettings,
    m: &'a SparseMatrix<'p>,
    c: Damping<'a, 'p>,
    k: &'a SparseMatrix<'p>,
    jacobian: &'a Jacobian<'a, 'p>,
    // Work vectors; z = M a1 + C v1 + K q1.
    q1: Vector<'p>,
    a1: Vector<'p>,
    v1: Vector<'p>,
    z: Vector<'p>,
    r: Vector<'p>,
    f: Vector<'p>,
    tmp: Vector<'p>,
    dq: Vector<'p>,
    /// The linear force's change for a full correction, -(J - X) dq (line search).
    dz: Vector<'p>,
    /// GMRES basis (Newton-Krylov corrections), grown on first use.
    basis: Vec<Vector<'p>>,
    /// A GMRES solve of the last step attempt ended without reaching its tolerance.
    krylov_exhausted: bool,
    /// The factor's solves of the current step attempt.
    solves: SolveCount,
    /// Newton-Krylov's preconditioner: the factor updated by the tangent change's dominant
    /// points (their columns cached for this factor's life).
    low_rank: LowRankUpdate<'p>,
    /// Iterations of the last attempt that did not converge (its solves: `solves`), its
    /// residual at each iterate and its wall time.
    failed_iterations: usize,
    failed_residuals: Vec<f64>,
    failed_seconds: f64,
    /// The full Newton's last J, renewed in place at the next iterate.
    full_newton_spare: Option<RetiredJacobian<'p>>,
    /// The predictor and its linear force, kept when the factor solves only to single
    /// precision, what is known of the carried z's drift, and z before a recomputation
    /// (`carried.rs`).
    q_pred: Vector<'p>,
    z_pred: Vector<'p>,
    drift: carried::Drift,
    z_carried: Vector<'p>,
    /// The accelerated iteration's stored iterates, and the plain update's target and its
    /// linear force.
    anderson: anderson::Anderson<'p>,
    target_q: Vector<'p>,
    target_z: Vector<'p>,
    /// The iterate before the current iteration's moves, and the contraction of the moves
    /// (`step_error.rs`).
    q_before: Vector<'p>,
    contraction: step_error::Contraction,
    /// The static equilibrium's force K q_s, when the residual is judged against the forces'
    /// departure from it (`line_search.rs`, `reference_force`), and a work vector for it.
    equilibrium: Option<(Vector<'p>, Vector<'p>)>,
}

impl<'a, 'p> Newmark<'a, 'p> {
    /// `jacobian` must factor M / (beta h^2) + gamma / (beta h) C + K + its `extra` (a mock
    /// contact stiffness) for `settings.step`.
    ///
    /// # Collective
    pub fn new(
        settings: NewmarkSettings,
        m: &'a SparseMatrix<'p>,
        c: Damping<'a, 'p>,
        k: &'a SparseMatrix<'p>,
        jacobian: &'a Jacobian<'a, 'p>,
    ) -> Result<Self, LaError> {
        let q1 = k.new_vector()?;
        Ok(Newmark {
            settings,
            m,
            c,
            k,
            jacobian,
            a1: q1.duplicate()?,
            v1: q1.duplicate()?,
            z: q1.duplicate()?,
            r: q1.duplicate()?,
            f: q1.duplicate()?,
            tmp: q1.duplicate()?,
            dq: q1.duplicate()?,
            dz: q1.duplicate()?,
            basis: Vec::new(),
            krylov_exhausted: false,
            solves: SolveCount::default(),
            low_rank: LowRankUpdate::default(),
            failed_iterations: 0,
            failed_residuals: Vec::new(),
            failed_seconds: 0.0,
            full_newton_spare: None,
            q_pred: q1.duplicate()?,
            z_pred: q1.duplicate()?,
            drift: carried::Drift::default(),
            z_carried: q1.duplicate()?,
            anderson: anderson::Anderson::new(settings.anderson),
            target_q: q1.duplicate()?,
            target_z: q1.duplicate()?,
            q_before: q1.duplicate()?,
            contraction: step_error::Contraction::default(),
            equilibrium: None,
            q1,
        })
    }

    /// The step size h of every step this integrator takes.
    pub fn step_size(&self) -> f64 {
        self.settings.step
    }

    /// Judges the residual against the forces' departure from the static equilibrium's
    /// force `equilibrium` (K q_s = f(q_s, 0)) instead of the whole force.
    pub fn judge_against_equilibrium(&mut self, equilibrium: &Vector<'p>) -> Result<(), LaError> {
        self.equilibrium = Some((equilibrium.try_clone()?, equilibrium.duplicate()?));
        Ok(())
    }

    /// Sets a1 and v1 from q1 (the Newmark relations).
    fn kinematics(&mut self, s: &State<'p>) -> Result<(), LaError> {
        let NewmarkSettings {
            beta,
            gamma,
            step: h,
            ..
        } = self.settings;
        // a1 = (q1 - q0 - h v0) / (beta h^2) - (1/(2 beta) - 1) a0
        self.a1.copy_from(&self.q1)?;
        self.a1.axpy(-1.0, &s.q)?;
        self.a1.axpy(-h, &s.v)?;
        self.a1.scale(1.0 / (beta * h * h))?;
        self.a1.axpy(-(0.5 / beta - 1.0), &s.a)?;
        // v1 = v0 + h (1 - gamma) a0 + h gamma a1
        self.v1.copy_from(&s.v)?;
        self.v1.axpy(h * (1.0 - gamma), &s.a)?;
        self.v1.axpy(h * gamma, &self.a1)
    }

    /// z = M a1 + C v1 + K q1 from scratch.
    fn linear_force(&mut self) -> Result<(), LaError> {
        match self.c {
            Damping::Rayleigh { alpha, beta } => {
                // M (a + alpha v) + K (q + beta v)
                self.tmp.copy_from(&self.a1)?;
                self.tmp.axpy(alpha, &self.v1)?;
                self.m.mult(&self.tmp, &mut self.z)?;
                self.tmp.copy_from(&self.q1)?;
                self.tmp.axpy(beta, &self.v1)?;
                self.k.mult_add(&self.tmp, &mut self.z)
            }
            Damping::None | Damping::Matrix(_) => {
                self.m.mult(&self.a1, &mut self.z)?;
                self.k.mult_add(&self.q1, &mut self.z)?;
                if let Damping::Matrix(c) = self.c {
                    c.mult_add(&self.v1, &mut self.z)?;
                }
                Ok(())
            }
        }
    }

    /// z at the constant-acceleration predictor from z_n of the state:
    /// z_n + C h a_n + K (h v_n + h^2/2 a_n).
    fn predicted_linear_force(&mut self, s: &State<'p>, z_n: &Vector<'p>) -> Result<(), LaError> {
        let h = self.settings.step;
        self.z.copy_from(z_n)?;
        let (k_on_a, mass_on_a) = match self.c {
            Damping::Rayleigh { alpha, beta } => (0.5 * h * h + h * beta, h * alpha),
            Damping::None | Damping::Matrix(_) => (0.5 * h * h, 0.0),
        };
        self.tmp.copy_from(&s.v)?;
        self.tmp.scale(h)?;
        self.tmp.axpy(k_on_a, &s.a)?;
        self.k.mult_add(&self.tmp, &mut self.z)?;
        if mass_on_a != 0.0 {
            self.tmp.copy_from(&s.a)?;
            self.tmp.scale(mass_on_a)?;
            self.m.mult_add(&self.tmp, &mut self.z)?;
        }
        if let Damping::Matrix(c) = self.c {
            self.tmp.copy_from(&s.a)?;
            self.tmp.scale(h)?;
            c.mult_add(&self.tmp, &mut self.z)?;
        }
        Ok(())
    }

    /// Whether the iterate, after a move by `alpha` of the correction, is accepted without
    /// its residual: Some(false) when converged in q1 (the correction below the tolerance of
    /// the step's move: the residual's round-off floor reached, q1 itself known to its own
    /// round-off at best, 10 eps |q1|), Some(true) when only within the step's own error
    /// (`step_error.rs`, which sees every move when `judge_step_error`).
    ///
    /// # Collective
    fn accepted_on_moves(
        &mut self,
        state: &State<'p>,
        alpha: f64,
        judge_step_error: bool,
    ) -> Result<Option<bool>, LaError> {
        let correction = alpha * self.dq.norm2()?;
        self.tmp.copy_from(&self.q1)?;
        self.tmp.axpy(-1.0, &state.q)?;
        let floor = 10.0 * f64::EPSILON * self.q1.norm2()?;
        let converged = correction <= self.settings.tolerance * self.tmp.norm2()? + floor;
        let within_step_error = judge_step_error && self.within_step_error(state, alpha)?;
        Ok(match (converged, within_step_error) {
            (true, _) => Some(false),
            (false, true) => Some(true),
            (false, false) => None,
        })
    }

    /// max |R_i| over the unknowns the last move changed (dq_i != 0).
    ///
    /// # Collective
    fn residual_where_moved(&mut self) -> Result<f64, LaError> {
        {
            let (dq, r) = (self.dq.local()?, self.r.local()?);
            let mut masked = self.tmp.local_mut()?;
            for ((m, &d), &r) in masked.iter_mut().zip(dq.iter()).zip(r.iter()) {
                *m = if d != 0.0 { r } else { 0.0 };
            }
        }
        self.tmp.norm_inf()
    }

    /// Turns the correction (dq, dz) into the move to Anderson's combination of the
    /// plain-update targets (`anderson.rs`): the line search, where there is one, then
    /// backtracks along it.
    ///
    /// # Collective
    fn accelerate(&mut self, inexact: bool) -> Result<(), LaError> {
        self.target_q.copy_from(&self.q1)?;
        self.target_q.axpy(-1.0, &self.dq)?;
        self.target_z.copy_from(&self.z)?;
        self.target_z.axpy(1.0, &self.dz)?;
        let mixed = self
            .anderson
            .mix(&self.r, &mut self.target_q, &mut self.target_z)?;
        if inexact {
            self.drift.mixed(mixed.coefficient_sum);
        }
        // q1 - dq and z + dz are the combination.
        self.dq.copy_from(&self.q1)?;
        self.dq.axpy(-1.0, &self.target_q)?;
        self.dz.copy_from(&self.target_z)?;
        self.dz.axpy(-1.0, &self.z)
    }

    /// Iterations and solves with a factor of the last step attempt that did not converge
    /// (what a retry cost beyond the accepted attempt's report).
    pub fn failed_attempt(&self) -> (usize, usize) {
        (self.failed_iterations, self.solves.solves)
    }

    /// Records a failed attempt (its iterations, start and residuals) and restores the
    /// carried z's drift to the step's start (its solves do not count).
    fn fail(
        &mut self,
        iterations: usize,
        started: std::time::Instant,
        residuals: Vec<f64>,
        drift: carried::Drift,
    ) {
        self.failed_iterations = iterations;
        self.failed_seconds = started.elapsed().as_secs_f64();
        self.failed_residuals = residuals;
        self.drift = drift;
    }

    /// The last failed attempt's residual at each iterate (the predictor's first) and its
    /// wall time.
    pub fn failed_attempt_residuals(&self) -> (&[f64], f64) {
        (&self.failed_residuals, self.failed_seconds)
    }

    /// Accepts the iterate and completes the step's report.
    fn finish(
        &mut self,
        state: &mut State<'p>,
        t1: f64,
        mut report: StepReport,
    ) -> Result<StepReport, TimeError> {
        self.drift.accepted();
        self.accept(state, t1)?;
        report.factor_solves = self.solves.solves;
        report.factor_solve_seconds = self.solves.seconds;
        Ok(report)
    }

    /// The state becomes (q1, v1, a1) at t1.
    fn accept(&self, state: &mut State<'p>, t1: f64) -> Result<(), LaError> {
        state.q.copy_from(&self.q1)?;
        state.v.copy_from(&self.v1)?;
        state.a.copy_from(&self.a1)?;
        match &mut state.linear {
            Some(z) => z.copy_from(&self.z)?,
            None => state.linear = Some(self.z.try_clone()?),
        }
        state.time = t1;
        state.step += 1;
        Ok(())
    }
}

/// J = M / (beta h^2) + gamma / (beta h) C + K + mock, assembled into a copy of `k`'s pattern
/// joined with the others (DIFFERENT_NONZERO_PATTERN sums).
///
/// # Collective
pub fn jacobian<'p>(
    settings: &NewmarkSettings,
    m: &SparseMatrix<'p>,
    c: Damping<'_, 'p>,
    k: &SparseMatrix<'p>,
    mock: Option<&SparseMatrix<'p>>,
) -> Result<SparseMatrix<'p>, LaError> {
    let NewmarkSettings {
        beta,
        gamma,
        step: h,
        ..
    } = *settings;
    let c1 = gamma / (beta * h);
    let mut j = k.try_clone()?;
    match c {
        Damping::None => j.axpy(1.0 / (beta * h * h), m)?,
        Damping::Rayleigh { alpha, beta: b } => {
            j.scale(1.0 + c1 * b)?;
            j.axpy(1.0 / (beta * h * h) + c1 * alpha, m)?;
        }
        Damping::Matrix(c) => {
            j.axpy(1.0 / (beta * h * h), m)?;
            j.axpy(c1, c)?;
        }
    }
    if let Some(mock) = mock {
        j.axpy(1.0, mock)?;
    }
    Ok(j)
}

/// The initial acceleration M a0 = f(t0, q0, v0) - C v0 - K q0, solved with `mass_solver`
/// (a factor of M).
///
/// # Collective
pub fn initial_acceleration<'p>(
    m: &SparseMatrix<'p>,
    c: Damping<'_, 'p>,
    k: &SparseMatrix<'p>,
    state: &mut State<'p>,
    forces: &mut Forces<'_, 'p>,
    mass_solver: &DirectSolver<'p>,
) -> Result<(), LaError> {
    let mut f = m.new_vector()?;
    let mut tmp = f.duplicate()?;
    forces(state.time, &state.q, &state.v, &mut f)?;
    k.mult(&state.q, &mut tmp)?;
    f.axpy(-1.0, &tmp)?;
    match c {
        Damping::None => {}
        Damping::Rayleigh { alpha, beta } => {
            m.mult(&state.v, &mut tmp)?;
            f.axpy(-alpha, &tmp)?;
            k.mult(&state.v, &mut tmp)?;
            f.axpy(-beta, &tmp)?;
        }
        Damping::Matrix(c) => {
            c.mult(&state.v, &mut tmp)?;
            f.axpy(-1.0, &tmp)?;
        }
    }
    mass_solver.solve(&f, &mut state.a)
}
