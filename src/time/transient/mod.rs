//! The transient stage: nonlinear time response of the model (full, or the reduced model of
//! the superelement reduction) from the static state plus a perturbation, with the contact and
//! friction forces of the contact stage, and observation signals (braking torque, normal and
//! friction force per interface, sensors) at every step, streamed to transient.h5.
//!
//! `run` wires the parts: `settings` (the scene table), `jacobian` (J and its refreshes),
//! `recorder` (signals, states, the stream), `checkpoint` (restart).

mod checkpoint;
mod eliminate;
pub use checkpoint::check_resumable;
pub use eliminate::EliminationCounts;
mod jacobian;
mod local_jacobian;
mod local_newton;
mod parts;
mod recorder;
mod settings;

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::adaptive::{integrate_adaptive, Adaptivity, Flow, StepControl};
use super::newmark::{
    initial_acceleration, Damping, Forces, ModalDamping, NewmarkSettings, State, StepReport,
    TimeError,
};
use crate::contact::{ContactModel, ContactState};
use crate::fault::end_on_write_failure;
use crate::la::{DirectSolver, Factorization, LaError, Petsc, SparseMatrix, Vector};
use crate::measure::nan_max;
use crate::time::store::Storage;
use checkpoint::Checkpoint;
use jacobian::JacobianBuilder;
use recorder::{Recorder, StepLog};
pub use settings::{
    random_coefficients, Impulse, Newton, Start, ToleranceReference, TransientSettings,
    SATURATION_CHECK_EVERY,
};

/// The kick in the integrated unknowns.
pub enum Kick<'a, 'p> {
    /// Added to the static displacement, scaled so its largest entry is `amplitude`.
    Displacement(&'a Vector<'p>),
    /// A force impulse (N s): the initial velocity is M^-1 times it.
    Impulse(&'a Vector<'p>),
}

/// Sensor rows: three per sensor (x, y, z of its node) over the integrated unknowns.
pub struct Sensors<'p> {
    pub names: Vec<String>,
    pub rows: crate::la::ObservationMatrix<'p>,
    /// Rows are grouped by owning rank: row block k belongs to sensor `order[k]`.
    pub order: Vec<usize>,
}

/// The time response: signals at every step (index 0 = start).
pub struct Transient {
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
    /// removed from the load so the run starts from an equilibrium ([`balanced_load`]).
    pub static_residual: f64,
    /// The time the run ended at because the torque had saturated that many cycles before
    /// (`transient.stop_after_saturation`); None: it ran its steps (or failed).
    pub stopped_at_saturation: Option<f64>,
}

/// Everything the stage needs.
pub struct TransientInputs<'a, 'p> {
    pub k0: &'a SparseMatrix<'p>,
    pub m: &'a SparseMatrix<'p>,
    pub c: Damping<'a, 'p>,
    pub contact: &'a ContactModel<'p>,
    pub f_ext: &'a Vector<'p>,
    pub q_static: &'a Vector<'p>,
    pub static_state: &'a crate::contact::ContactState,
    pub kick: Kick<'a, 'p>,
    pub sensors: Option<&'a Sensors<'p>>,
    /// Modal damping over a band, applied as a force (on top of `c`).
    pub modal_damping: Option<&'a ModalDamping<'p>>,
    /// The reduction the unknowns are coordinates of (None: the full model's unknowns); a
    /// checkpoint keeps the full-model state too, so a restart whose basis came out rotated
    /// (parallel MUMPS is not bitwise reproducible) re-projects it.
    pub reduction: Option<&'a crate::reduce::Reduction>,
    /// The real modes whose coordinates go with every stored state (None: not taken).
    pub modal_sensors: Option<&'a crate::post::modal_energy::ModalSensors<'a, 'p>>,
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
    fn count_sizes(&mut self, k: &SparseMatrix, contact: &ContactModel) -> Result<(), LaError> {
        self.operator_entries = k.info()?.nonzeros;
        self.observation_entries = contact.observation_entries()?;
        self.unknowns = k.global_rows();
        Ok(())
    }

    /// The Jacobian counts and times of a finished run (`seconds_start`: the mass
    /// factorization of the start).
    fn count_factorizations(
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

    fn empty(steps: usize, interfaces: usize, sensor_names: Vec<String>) -> Self {
        let series = || vec![Vec::with_capacity(steps + 1); interfaces];
        Transient {
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

/// Where the stream and the checkpoint go, whether to resume from the checkpoint, and what
/// the run's state depends on in the scene ([`crate::scene::Scene::restart_fingerprint`]; a
/// restart must match it).
pub struct TransientFiles<'s> {
    pub stream: PathBuf,
    pub checkpoint: PathBuf,
    pub restart: bool,
    pub scene: Vec<(&'static str, u64)>,
    /// What creates and opens the stream and the checkpoint (HDF5: `crate::io::series`).
    pub storage: &'s dyn Storage,
}

impl<'s> TransientFiles<'s> {
    pub fn in_directory(storage: &'s dyn Storage, dir: &Path, restart: bool) -> Self {
        TransientFiles {
            stream: dir.join("transient.h5"),
            checkpoint: dir.join("checkpoint.h5"),
            restart,
            scene: Vec::new(),
            storage,
        }
    }

    /// With the scene's restart fingerprint.
    pub fn with_scene(mut self, scene: Vec<(&'static str, u64)>) -> Self {
        self.scene = scene;
        self
    }
}

/// Runs the transient. A step that fails ends the run: the signals up to the last converged
/// step come back with the error, so the caller can write them before reporting it.
///
/// Long (~255 lines): the step callback, the log, the factorization and elimination
/// closures share the recorder, the Jacobian builder and the last contact state of this one
/// run; apart, they would need a struct of RefCells to say the same.
///
/// # Collective
pub fn run<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: TransientInputs<'_, 'p>,
    files: &TransientFiles,
) -> Result<(Transient, Option<TimeError>), TimeError> {
    let newmark = NewmarkSettings {
        step: settings.step,
        tolerance: settings.tolerance,
        max_iterations: settings.max_iterations,
        anderson: settings.anderson,
        step_error_fraction: settings.step_error_fraction,
        ..Default::default()
    };
    let contact = input.contact;
    let t = Instant::now();
    let k0 = contact.joined_matrix(petsc, input.k0)?;
    let (balanced, static_residual) = balanced_load(&input, &k0)?;
    let input = TransientInputs {
        f_ext: &balanced,
        ..input
    };
    let mut state = start_state(petsc, settings, &input, &k0)?;
    // K q_s, the force of the static equilibrium on both sides of the equation of motion
    // (z = K q_s at rest there, and f = the balanced load + f_c(q_s, 0), the same).
    let equilibrium = match settings.tolerance_reference {
        ToleranceReference::Total => None,
        ToleranceReference::Vibration => {
            let mut force = input.q_static.duplicate()?;
            k0.mult(input.q_static, &mut force)?;
            Some(force)
        }
    };
    let seconds_start = t.elapsed().as_secs_f64();

    // The contact state of the last force evaluation and where it was taken: the step's
    // record reuses it when the step ended there, an elimination when it starts there.
    let last_contact = RefCell::new(None::<Evaluated<'p>>);
    // Contact points whose status (open / stick: inside the friction law's regularization
    // band / slip) changed between consecutive force evaluations since the last accepted
    // step: the evidence a stalled step's log line gives.
    let status_changes = std::cell::Cell::new(0usize);
    let mut fc = input.f_ext.duplicate()?;
    let mut forces = |_t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &mut Vector<'p>| {
        contact_forces(&input, &mut fc, q, v, f, &last_contact, &status_changes)
    };

    let mut control = StepControl::default();
    let (mut recorder, restart_at) =
        open_record(petsc, settings, &input, files, &mut state, &mut control)?;
    let failed_before = (
        control.failed_iterations,
        control.failed_solves,
        control.failed_seconds,
    );
    let builder = RefCell::new(JacobianBuilder::new(
        petsc,
        contact,
        &k0,
        input.k0,
        input.m,
        input.c,
        input.static_state,
        restart_at,
        settings.jacobian_factor.resolve(k0.global_rows()),
        settings.first_jacobian,
    )?);
    let mut factorize = |ns: &NewmarkSettings, at: Option<&State<'p>>, retired| {
        builder.borrow_mut().factorize(ns, at, retired)
    };
    let mut linearize = |ns: &NewmarkSettings, at: &State<'p>| {
        let op = builder.borrow().linearize(ns, at)?;
        Ok(Box::new(op) as Box<dyn crate::la::TangentChange<'p> + '_>)
    };

    let eliminator = match settings.eliminate_points {
        0 => None,
        points => Some(RefCell::new(eliminate::Eliminator::new(
            petsc, contact, &k0, input.m, input.c, points,
        )?)),
    };
    let mut eliminate = |ns: &NewmarkSettings, at: &State<'p>, r: &Vector<'p>, target: f64| {
        let clock = Instant::now();
        // An elimination starts where the residual was just evaluated: the tangent's change
        // from that evaluation's contact state (a contact evaluation fewer per elimination).
        let tangent = match last_contact.borrow().as_ref() {
            Some(e) if e.q.equals(&at.q)? && e.v.equals(&at.v)? => {
                builder.borrow().linearize_at(ns, &e.state)?
            }
            _ => builder.borrow().linearize(ns, at)?,
        };
        let mut e = eliminator
            .as_ref()
            .expect("only with an eliminator")
            .borrow_mut();
        let seconds = clock.elapsed().as_secs_f64();
        e.counts.seconds_tangent += seconds;
        e.counts.seconds += seconds;
        e.solve(ns, at, r, &tangent, target)
    };

    let mut bar = crate::progress::Progress::new("transient", settings.steps, petsc.rank());
    let first_step = ((state.time / settings.step).round() as usize).min(settings.steps);
    bar.resume_from(first_step);
    let t = Instant::now();
    let wall_before = recorder.out.wall_seconds.last().copied().unwrap_or(0.0);
    let end_time = settings.steps as f64 * settings.step;
    let world = petsc.world();
    let mut checkpoint_failure = None;
    let mut on_step =
        |s: &State<'p>, report: &StepReport, c: &StepControl| -> Result<Flow, TimeError> {
            let recording = Instant::now();
            let h = settings.step / f64::from(1u32 << c.level);
            status_changes.set(0);
            let out = &mut recorder.out;
            out.seconds_solving += report.solve_seconds;
            out.seconds_in_forces += report.force_seconds;
            out.seconds_in_products += report.product_seconds + report.linear_force_seconds;
            out.seconds_in_linear_force += report.linear_force_seconds;
            out.linear_force_calls += report.linear_force_calls;
            out.force_evaluations += report.force_calls;
            out.tangent_products += report.product_calls;
            out.steps_run += 1;
            out.iterations_run += report.iterations;
            out.steps_on_step_error += usize::from(report.on_step_error);
            out.krylov_iterations += report.krylov_iterations;
            out.factor_solves += report.factor_solves;
            out.seconds_in_factor_solves += report.factor_solve_seconds;
            if let Some(e) = &eliminator {
                let counts = &mut e.borrow_mut().counts;
                counts.worst_mismatch = nan_max(counts.worst_mismatch, report.elimination_mismatch);
            }
            let evaluated = last_contact.borrow();
            let evaluated = evaluated
                .as_ref()
                .map(|e| &e.state)
                .filter(|_| report.forces_current);
            let wall = wall_before + t.elapsed().as_secs_f64();
            let recorded = recorder.record(s, h, report.iterations, wall, evaluated);
            end_on_write_failure(recorded, "transient.h5");
            end_on_write_failure(recorder.sample_state(s, h), "transient.h5");
            let stop = settings.stop_after_saturation.is_some_and(|cycles| {
                c.steps.is_multiple_of(SATURATION_CHECK_EVERY)
                    && saturated_for(&recorder.out, settings.step, cycles, world)
            });
            if stop {
                recorder.out.stopped_at_saturation = Some(s.time);
            }
            let at_end = stop || s.time >= end_time - 0.25 * h;
            end_on_write_failure(recorder.flush_if_due(at_end), "transient.h5");
            if settings.checkpoint_every > 0
                && (c.steps.is_multiple_of(settings.checkpoint_every) || at_end)
            {
                end_on_write_failure(recorder.flush(), "transient.h5");
                // After a step restore J is rebuilt at this state; otherwise it stays the one
                // built at `built_at`.
                let b = builder.borrow();
                let j = if c.good == 0 {
                    None
                } else {
                    b.built_at.as_ref()
                };
                if let Err(e) =
                    Checkpoint::write(petsc, files, settings, &input, s, c, j, &recorder.out)
                {
                    checkpoint_failure = Some(e);
                }
            }
            if recorder.out.time.len().is_multiple_of(50) || at_end {
                let done = ((s.time / settings.step).round() as usize).min(settings.steps);
                let rate = (done - first_step) as f64 / t.elapsed().as_secs_f64().max(1e-9);
                bar.update(done, &progress_line(&recorder.out, s.time, rate));
            }
            recorder.out.seconds_recording += recording.elapsed().as_secs_f64();
            Ok(if stop { Flow::Stop } else { Flow::Continue })
        };
    let rank0 = petsc.rank() == 0;
    let log_path = files.stream.with_file_name("transient.log");
    let mut step_log = StepLog::new(rank0, log_path, files.restart);
    let mut log = |line: &str| {
        // Collective: every rank logs at the same points of the step control.
        let changes = crate::parallel::sum(world, status_changes.get() as f64);
        let in_band = last_contact.borrow().as_ref().map_or(0, |e| {
            e.state
                .response
                .iter()
                .filter(|r| r.in_friction_band())
                .count()
        });
        let in_band = crate::parallel::sum(world, in_band as f64);
        step_log.write(&format!(
            "{line} [{changes:.0} contact status changes between iterates since the last step; {in_band:.0} sliding points inside the friction regularization band]"
        ));
    };
    let forces: &mut Forces<'_, 'p> = &mut forces;
    let result = integrate_adaptive(
        newmark,
        input.m,
        input.c,
        &k0,
        &mut factorize,
        Some(&mut linearize),
        eliminator
            .is_some()
            .then_some(&mut eliminate as &mut crate::time::newmark::Eliminate<'_, 'p>),
        &mut state,
        forces,
        equilibrium.as_ref(),
        end_time,
        Adaptivity {
            max_cuts: settings.max_cuts,
            restore_after: 100,
            refresh: settings.refresh,
            full_newton: settings.newton == Newton::Full,
            update: settings.update_factor,
        },
        &mut control,
        &mut on_step,
        &mut log,
    );
    bar.finish();
    if let Some(e) = &eliminator {
        recorder.out.eliminations = e.borrow().counts;
    }
    // Whatever happened, the signals recorded so far go to the file, and a failed run leaves
    // a checkpoint at its last converged step (to restart with other settings).
    end_on_write_failure(recorder.flush(), "transient.h5");
    if result.is_err() && settings.checkpoint_every > 0 {
        let b = builder.borrow();
        let at = b.built_at.as_ref();
        Checkpoint::write(
            petsc,
            files,
            settings,
            &input,
            &state,
            &control,
            at,
            &recorder.out,
        )?;
    }
    if let Some(e) = checkpoint_failure {
        return Err(e);
    }
    let mut out = recorder.out;
    out.static_residual = static_residual;
    out.seconds_stepping = t.elapsed().as_secs_f64();
    out.count_factorizations(&builder.into_inner(), &control, seconds_start);
    // This process's part, like `iterations_run` and `factor_solves`.
    out.failed_iterations = control.failed_iterations - failed_before.0;
    out.failed_solves = control.failed_solves - failed_before.1;
    out.seconds_in_failed_attempts = control.failed_seconds - failed_before.2;
    out.count_sizes(&k0, contact)?;
    Ok((out, result.err()))
}

/// The record of the run: a fresh stream, or the checkpoint's state, step control and
/// Jacobian state (returned) with the stream cut back to the checkpoint's rows.
///
/// # Collective
fn open_record<'a, 'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: &TransientInputs<'a, 'p>,
    files: &TransientFiles,
    state: &mut State<'p>,
    control: &mut StepControl,
) -> Result<(Recorder<'a, 'p>, Option<(Vector<'p>, Vector<'p>)>), TimeError> {
    let contact = input.contact;
    let sensor_names = input.sensors.map(|s| s.names.clone()).unwrap_or_default();
    let out = Transient::empty(settings.steps, contact.interfaces().len(), sensor_names);
    let interval = settings.state_interval;
    if files.restart {
        let checkpoint = Checkpoint::read(petsc, files, settings, input, state)?;
        if let (Some(note), 0) = (&checkpoint.note, petsc.rank()) {
            println!("  transient: restart: {note}");
        }
        let r = Recorder::resume(petsc, files, input, interval, out, &checkpoint)?;
        *control = checkpoint.control;
        *state = checkpoint.state;
        Ok((r, checkpoint.jacobian_at))
    } else {
        let r = Recorder::create(petsc, files, input, interval, out, state)?;
        Ok((r, None))
    }
}

/// The progress bar's line: time, steps per second, mean iterations over the last 500 steps.
fn progress_line(out: &Transient, time: f64, rate: f64) -> String {
    let recent = &out.iterations[out.iterations.len().saturating_sub(500)..];
    let mean = recent.iter().sum::<usize>() as f64 / recent.len().max(1) as f64;
    format!("t = {time:.3e} s, {rate:.1} steps/s, {mean:.2} iterations/step")
}

/// The start: the static state + amplitude x the kick's shape (scaled to its largest entry),
/// or at rest there with the velocity of an impulse; the acceleration from the equation of
/// motion.
///
/// # Collective
fn start_state<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: &TransientInputs<'_, 'p>,
    k0: &SparseMatrix<'p>,
) -> Result<State<'p>, TimeError> {
    let mass = DirectSolver::factorize(petsc, input.m, Factorization::Lu, "time_mass_")?;
    let mut q = input.q_static.try_clone()?;
    let mut v = q.duplicate()?;
    v.set_all(0.0)?;
    match input.kick {
        Kick::Displacement(shape) => {
            let largest = shape.norm_inf()?;
            if !largest.is_finite() {
                let what = "the start's kick (the real mode or the random shape)";
                return Err(TimeError::NotFinite {
                    step: 0,
                    time: 0.0,
                    what,
                });
            }
            if largest > 0.0 {
                q.axpy(settings.amplitude / largest, shape)?;
            }
        }
        Kick::Impulse(impulse) => mass.solve(impulse, &mut v)?,
    }
    let a = q.duplicate()?;
    let mut state = State {
        time: 0.0,
        step: 0,
        q,
        v,
        a,
        linear: None,
    };
    let mut fc = input.f_ext.duplicate()?;
    let last = RefCell::new(None);
    let changes = std::cell::Cell::new(0);
    let mut forces = |_t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &mut Vector<'p>| {
        contact_forces(input, &mut fc, q, v, f, &last, &changes)
    };
    initial_acceleration(input.m, input.c, k0, &mut state, &mut forces, &mass)?;
    Ok(state)
}

/// The load the transient balances, K0 q_s - f_c(q_s, v = 0), and its difference from f_ext,
/// the static residual's norm. The static state balances f_ext only to the static Newton's
/// tolerance; that residual, a constant force, would set the soft modes of the model vibrating
/// from the first step (a kick of 1 nm along one real mode sees it: 3 % of its radiated power
/// on the small frictionless brake). With this load the static state is an equilibrium of the
/// transient's own equations, whichever route the static solve took.
///
/// # Collective
fn balanced_load<'p>(
    input: &TransientInputs<'_, 'p>,
    k0: &SparseMatrix<'p>,
) -> Result<(Vector<'p>, f64), LaError> {
    let at_rest = input.q_static.duplicate()?;
    let state = input
        .contact
        .evaluate(input.q_static, Some(&at_rest), 1.0)?;
    let mut fc = input.q_static.duplicate()?;
    input.contact.force(&state, &mut fc)?;
    let mut load = input.q_static.duplicate()?;
    k0.mult(input.q_static, &mut load)?;
    load.axpy(-1.0, &fc)?;
    let mut residual = load.try_clone()?;
    residual.axpy(-1.0, input.f_ext)?;
    Ok((load, residual.norm2()?))
}

/// Whether the braking torque recorded so far saturated `cycles` cycles ago (every rank
/// decides alike: the record is the same on each, and the verdict is agreed on anyway).
///
/// # Collective
fn saturated_for(
    out: &Transient,
    step: f64,
    cycles: usize,
    world: &mpi::topology::SimpleCommunicator,
) -> bool {
    let verdict =
        crate::post::limit_cycle::saturated_for(&out.time, &out.braking_torque(), step, cycles);
    crate::parallel::any_rank(world, verdict)
}

/// A contact state and the displacement and velocity it was evaluated at.
struct Evaluated<'p> {
    state: ContactState,
    q: Vector<'p>,
    v: Vector<'p>,
}

/// f = f_ext + f_contact(q, v) - modal damping force; keeps the contact state evaluated.
///
/// # Collective
fn contact_forces<'p>(
    input: &TransientInputs<'_, 'p>,
    fc: &mut Vector<'p>,
    q: &Vector<'p>,
    v: &Vector<'p>,
    f: &mut Vector<'p>,
    last: &RefCell<Option<Evaluated<'p>>>,
    changes: &std::cell::Cell<usize>,
) -> Result<(), LaError> {
    let state = input.contact.evaluate(q, Some(v), 1.0)?;
    input.contact.force(&state, fc)?;
    let mut last = last.borrow_mut();
    match last.as_mut() {
        Some(previous) => {
            let changed = previous
                .state
                .response
                .iter()
                .zip(&state.response)
                .filter(|(a, b)| a.status != b.status)
                .count();
            changes.set(changes.get() + changed);
            previous.state = state;
            previous.q.copy_from(q)?;
            previous.v.copy_from(v)?;
        }
        None => {
            *last = Some(Evaluated {
                state,
                q: q.try_clone()?,
                v: v.try_clone()?,
            })
        }
    }
    f.copy_from(input.f_ext)?;
    f.axpy(1.0, &*fc)?;
    match input.modal_damping {
        Some(modal) => modal.subtract_force(v, f),
        None => Ok(()),
    }
}
