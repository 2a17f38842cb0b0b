//! The transient's result: the signals at every step and what the run cost.

use super::eliminate::EliminationCounts;
use super::jacobian::JacobianBuilder;
use super::settings::TransientSettings;
use crate::contact::ContactModel;
use crate::la::{LaError, SparseMatrix};
use crate::time::adaptive::StepControl;

/// The time response: signals at every step (index 0 = start).
pub struct Transient {
    /// The nominal step the run was made with (s: the grid its signals are analysed on; a
    /// cut step is shorter, `step_size`), and the simulated time between stored states (s;
    /// 0: none stored).
    pub nominal_step: f64,
    pub state_interval: f64,
    pub time: Vec<f64>,
    /// Per interface (in the contact model's order): normal force, friction force, torque.
    pub normal_force: Vec<Vec<f64>>,
    pub friction_force: Vec<Vec<f64>>,
    pub torque: Vec<Vec<f64>>,
    /// Per interface: points open, sticking (inside the friction band, or a joint) and
    /// slipping at every step.
    pub status_points: Vec<[Vec<f64>; 3]>,
    pub iterations: Vec<usize>,
    /// The step size of each step (0 at the start).
    pub step_size: Vec<f64>,
    /// Wall time of the stepping when each step was accepted (s; 0 at the start, summed over
    /// restarts): the cost of each phase of the run (growth, saturation).
    pub wall_seconds: Vec<f64>,
    /// Per sensor: displacement, velocity, acceleration (x, y, z per sample, row-major).
    pub sensor_names: Vec<String>,
    pub sensor_values: Vec<[Vec<f64>; 3]>,
    /// States written (every state_interval), and the time a restart resumed from.
    pub states: usize,
    pub resumed_at: Option<f64>,
    /// Step cuts after failed steps, and Jacobian factorizations in all.
    pub cuts: usize,
    pub refreshes: usize,
    /// Steps retried on the consistent tangent with line search: Newton-Krylov, full Newton.
    pub krylov_retries: usize,
    pub full_newton_retries: usize,
    /// Steps retried with the factor updated at the dominant contact points, and the
    /// iterations and solves with a factor of every attempt that failed (beyond the accepted
    /// attempts' `iterations_run` and `factor_solves`).
    pub updated_retries: usize,
    pub failed_iterations: usize,
    pub failed_solves: usize,
    /// Wall time of the attempts that failed (their eliminations too, which
    /// `eliminations.seconds` also counts).
    pub seconds_in_failed_attempts: f64,
    /// Wall time after each accepted step: the signals and states written, checkpoints, the
    /// saturation check, progress.
    pub seconds_recording: f64,
    /// GMRES iterations of the Newton-Krylov retries.
    pub krylov_iterations: usize,
    /// The nonlinear eliminations of this process's run (`transient.eliminate_points`).
    pub eliminations: EliminationCounts,
    pub factorizations: usize,
    pub factor_entries: f64,
    /// Of them, on the rank that holds most.
    pub factor_entries_largest_rank: f64,
    /// Where J was factorized (MUMPS over all ranks, or LU on every rank).
    pub jacobian_solver: &'static str,
    pub seconds_factorizing: f64,
    /// The stepping loop, and the Jacobian factorizations within it.
    pub seconds_stepping: f64,
    pub seconds_jacobians: f64,
    /// Of the factorizations' time: assembling the Jacobians (before the factor).
    pub seconds_assembling_jacobians: f64,
    /// Time in the factor's solves, steps and iterations (solves), over this process's steps.
    pub seconds_solving: f64,
    /// Solves with the factor, and the time inside them alone.
    pub factor_solves: usize,
    pub seconds_in_factor_solves: f64,
    /// Time in the force evaluations and in the operator products (predictor, contact
    /// tangent), steps and iterations.
    pub seconds_in_forces: f64,
    pub seconds_in_products: f64,
    /// Of which the predictor's linear force (products with M, C, K), and how many force
    /// evaluations and contact-tangent products there were.
    pub seconds_in_linear_force: f64,
    pub linear_force_calls: usize,
    pub force_evaluations: usize,
    pub tangent_products: usize,
    /// What those stream (for the cost model of benches/transient.rs): the stored entries of
    /// the stiffness the linear force multiplies (M and C are products too when the
    /// damping needs them), of each contact channel's observation rows (normal, tangent,
    /// second tangent, convection), and the unknowns.
    pub operator_entries: f64,
    pub observation_entries: [f64; 4],
    pub unknowns: usize,
    /// Bytes per value of the factor, and how often a solve reads it (LU: L then U, once
    /// each; LDL^T: L twice), for the last factorization.
    pub factor_value_bytes: f64,
    pub factor_passes: f64,
    pub steps_run: usize,
    pub iterations_run: usize,
    /// Of this process's steps, those accepted on the truncation-error criterion
    /// (`transient.step_error_fraction`) with their residual above the tolerance.
    pub steps_on_step_error: usize,
    /// |K0 q_s - f_c(q_s) - f_ext| at the static state (N): what the static Newton left,
    /// removed from the load so the run starts from an equilibrium (`start::balanced_load`).
    pub static_residual: f64,
    /// The time the run ended at because the torque had saturated that many cycles before
    /// (`transient.stop_after_saturation`); None: it ran its steps (or failed).
    pub stopped_at_saturation: Option<f64>,
}

impl Transient {
    /// The braking torque (sum over the interfaces) at every recorded step.
    pub fn braking_torque(&self) -> Vec<f64> {
        self.braking_torque_from(0)
    }

    /// The braking torque from step row `from` on.
    pub fn braking_torque_from(&self, from: usize) -> Vec<f64> {
        (from..self.time.len())
            .map(|k| self.torque.iter().map(|t| t[k]).sum())
            .collect()
    }

    /// What a step streams: the stiffness' and the observation rows' stored entries.
    ///
    /// # Collective
    pub(super) fn count_sizes(
        &mut self,
        k: &SparseMatrix,
        contact: &ContactModel,
    ) -> Result<(), LaError> {
        self.operator_entries = k.info()?.nonzeros;
        self.observation_entries = contact.observation_entries()?;
        self.unknowns = k.global_rows();
        Ok(())
    }

    /// The Jacobian counts and times of a finished run (`seconds_start`: the mass
    /// factorization of the start).
    pub(super) fn count_factorizations(
        &mut self,
        b: &JacobianBuilder,
        control: &StepControl,
        seconds_start: f64,
    ) {
        self.factor_entries = b.factor_entries;
        self.factor_entries_largest_rank = b.factor_entries_largest_rank;
        self.jacobian_solver = b.solver_name();
        (self.factor_value_bytes, self.factor_passes) = b.factor_streaming;
        self.seconds_factorizing = seconds_start + b.seconds_factorizing;
        self.seconds_jacobians = b.seconds_in_loop;
        self.seconds_assembling_jacobians = b.seconds_assembling;
        self.cuts = control.cuts;
        self.refreshes = control.refreshes;
        self.krylov_retries = control.krylov_retries;
        self.full_newton_retries = control.full_newton_retries;
        self.updated_retries = control.updated_retries;
        self.factorizations = control.factorizations.max(b.built);
    }

    pub(super) fn empty(
        settings: &TransientSettings,
        interfaces: usize,
        sensor_names: Vec<String>,
    ) -> Self {
        let steps = settings.steps;
        let series = || vec![Vec::with_capacity(steps + 1); interfaces];
        Transient {
            nominal_step: settings.step,
            state_interval: settings.state_interval,
            time: Vec::with_capacity(steps + 1),
            step_size: Vec::with_capacity(steps + 1),
            wall_seconds: Vec::with_capacity(steps + 1),
            normal_force: series(),
            friction_force: series(),
            torque: series(),
            status_points: vec![Default::default(); interfaces],
            iterations: Vec::with_capacity(steps + 1),
            cuts: 0,
            refreshes: 0,
            krylov_retries: 0,
            full_newton_retries: 0,
            updated_retries: 0,
            failed_iterations: 0,
            failed_solves: 0,
            seconds_in_failed_attempts: 0.0,
            seconds_recording: 0.0,
            krylov_iterations: 0,
            eliminations: EliminationCounts::default(),
            factorizations: 0,
            factor_entries: 0.0,
            factor_entries_largest_rank: 0.0,
            jacobian_solver: "",
            seconds_factorizing: 0.0,
            seconds_stepping: 0.0,
            seconds_jacobians: 0.0,
            seconds_assembling_jacobians: 0.0,
            seconds_solving: 0.0,
            factor_solves: 0,
            seconds_in_factor_solves: 0.0,
            seconds_in_forces: 0.0,
            seconds_in_products: 0.0,
            seconds_in_linear_force: 0.0,
            linear_force_calls: 0,
            force_evaluations: 0,
            tangent_products: 0,
            operator_entries: 0.0,
            observation_entries: [0.0; 4],
            unknowns: 0,
            factor_value_bytes: 8.0,
            factor_passes: 1.0,
            steps_run: 0,
            iterations_run: 0,
            steps_on_step_error: 0,
            static_residual: 0.0,
            stopped_at_saturation: None,
            states: 0,
            resumed_at: None,
            sensor_values: vec![Default::default(); sensor_names.len()],
            sensor_names,
        }
    }
}
