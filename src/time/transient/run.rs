//! One transient run as an object: the forces and their contact state, the Jacobian builder,
//! the eliminator, the recorder, the progress and the step log, the stage's monitor. It is
//! the [`StepProblem`] the adaptive integrator steps and the [`StepHooks`] it reports to.

use std::time::Instant;

use super::checkpoint::Checkpoint;
use super::eliminate::Eliminator;
use super::hooks::Monitor;
use super::jacobian::JacobianBuilder;
use super::recorder::{Recorder, StepLog};
use super::settings::TransientSettings;
use super::start::ContactForces;
use super::{Transient, TransientFiles, TransientInputs};
use crate::fault::end_on_write_failure;
use crate::la::{LaError, Petsc, SparseMatrix, TangentChange, Vector};
use crate::measure::nan_max;
use crate::progress::Progress;
use crate::time::adaptive::{Flow, StepControl, StepHooks, StepProblem};
use crate::time::newmark::{
    Elimination, Jacobian, NewmarkSettings, RetiredJacobian, State, StepReport, TimeError,
};

/// The run's clock and progress: the bar, where it resumed, the wall time of earlier parts
/// of the run (a restart's), and the step log (transient.log).
struct Watch {
    bar: Progress,
    first_step: usize,
    clock: Instant,
    wall_before: f64,
    end_time: f64,
    log: StepLog,
}

/// A transient run between its start and its result.
pub(super) struct TransientRun<'r, 'p> {
    petsc: &'p Petsc<'p>,
    settings: &'r TransientSettings,
    input: &'r TransientInputs<'r, 'p>,
    files: &'r TransientFiles<'r>,
    k0: &'r SparseMatrix<'p>,
    forces: ContactForces<'r, 'p>,
    builder: JacobianBuilder<'r, 'p>,
    eliminator: Option<Eliminator<'r, 'p>>,
    recorder: Recorder<'r, 'p>,
    monitor: &'r mut dyn Monitor,
    watch: Watch,
    /// The step control's failure counts at the start (a restart's), so the result counts
    /// this process's part.
    failed_before: (usize, usize, f64),
    checkpoint_failure: Option<TimeError>,
}

impl<'r, 'p> TransientRun<'r, 'p> {
    /// Opens the record (fresh, or resumed from the checkpoint: then `state` and `control`
    /// are the checkpoint's) and builds what the steps need; the stepping clock starts.
    ///
    /// # Collective
    #[allow(clippy::too_many_arguments)] // the run's model, files, monitor and start
    pub fn new(
        petsc: &'p Petsc<'p>,
        settings: &'r TransientSettings,
        input: &'r TransientInputs<'r, 'p>,
        k0: &'r SparseMatrix<'p>,
        files: &'r TransientFiles<'r>,
        monitor: &'r mut dyn Monitor,
        state: &mut State<'p>,
        control: &mut StepControl,
    ) -> Result<Self, TimeError> {
        let (recorder, restart_at) = open_record(petsc, settings, input, files, state, control)?;
        let builder = JacobianBuilder::new(
            petsc,
            input.contact,
            k0,
            input.k0,
            input.m,
            input.c,
            input.static_state,
            restart_at,
            settings.jacobian_factor.resolve(k0.global_rows()),
            settings.first_jacobian,
        )?;
        let eliminator = match settings.eliminate_points {
            0 => None,
            points => Some(Eliminator::new(
                petsc,
                input.contact,
                k0,
                input.m,
                input.c,
                points,
            )?),
        };
        let mut bar = Progress::new("transient", settings.steps, petsc.rank());
        let first_step = ((state.time / settings.step).round() as usize).min(settings.steps);
        bar.resume_from(first_step);
        let log_path = files.stream.with_file_name("transient.log");
        let watch = Watch {
            bar,
            first_step,
            wall_before: recorder.out.wall_seconds.last().copied().unwrap_or(0.0),
            end_time: settings.steps as f64 * settings.step,
            log: StepLog::new(petsc.rank() == 0, log_path, files.restart),
            clock: Instant::now(),
        };
        Ok(TransientRun {
            petsc,
            settings,
            input,
            files,
            k0,
            forces: ContactForces::new(input)?,
            builder,
            eliminator,
            recorder,
            monitor,
            watch,
            failed_before: (
                control.failed_iterations,
                control.failed_solves,
                control.failed_seconds,
            ),
            checkpoint_failure: None,
        })
    }

    /// The time the run ends at.
    pub fn end_time(&self) -> f64 {
        self.watch.end_time
    }

    /// The result, after the integration ended with `result`: whatever happened, the
    /// signals recorded so far go to the file, and a failed run leaves a checkpoint at its
    /// last converged step (to restart with other settings).
    ///
    /// # Collective
    pub fn finish(
        mut self,
        result: Result<(), TimeError>,
        state: &State<'p>,
        control: &StepControl,
        seconds_start: f64,
    ) -> Result<(Transient, Option<TimeError>), TimeError> {
        self.watch.bar.finish();
        if let Some(e) = &self.eliminator {
            self.recorder.out.eliminations = e.counts;
        }
        end_on_write_failure(self.recorder.flush(), "transient.h5");
        if result.is_err() && self.settings.checkpoint_every > 0 {
            self.write_checkpoint(state, control, self.builder.built_at.as_ref())?;
        }
        if let Some(e) = self.checkpoint_failure {
            return Err(e);
        }
        let mut out = self.recorder.out;
        out.seconds_stepping = self.watch.clock.elapsed().as_secs_f64();
        out.count_factorizations(&self.builder, control, seconds_start);
        // This process's part, like `iterations_run` and `factor_solves`.
        out.failed_iterations = control.failed_iterations - self.failed_before.0;
        out.failed_solves = control.failed_solves - self.failed_before.1;
        out.seconds_in_failed_attempts = control.failed_seconds - self.failed_before.2;
        out.count_sizes(self.k0, self.input.contact)?;
        Ok((out, result.err()))
    }

    /// # Collective
    fn write_checkpoint(
        &self,
        s: &State<'p>,
        c: &StepControl,
        jacobian_at: Option<&(Vector<'p>, Vector<'p>)>,
    ) -> Result<(), TimeError> {
        let (petsc, files, settings) = (self.petsc, self.files, self.settings);
        let out = &self.recorder.out;
        Checkpoint::write(petsc, files, settings, self.input, s, c, jacobian_at, out)
    }

    /// Adds an accepted step's counts and times to the result.
    fn count(&mut self, report: &StepReport) {
        let out = &mut self.recorder.out;
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
        if let Some(e) = &mut self.eliminator {
            let counts = &mut e.counts;
            counts.worst_mismatch = nan_max(counts.worst_mismatch, report.elimination_mismatch);
        }
    }

    /// A checkpoint every `checkpoint_every` steps and at the end. After a step restore J is
    /// rebuilt at this state; otherwise it stays the one built at `built_at`. A failed write
    /// ends the run after the integration (the record is kept).
    ///
    /// # Collective
    fn checkpoint_if_due(&mut self, s: &State<'p>, c: &StepControl, at_end: bool) {
        let every = self.settings.checkpoint_every;
        if every == 0 || !(c.steps.is_multiple_of(every) || at_end) {
            return;
        }
        end_on_write_failure(self.recorder.flush(), "transient.h5");
        let j = if c.good == 0 {
            None
        } else {
            self.builder.built_at.as_ref()
        };
        if let Err(e) = self.write_checkpoint(s, c, j) {
            self.checkpoint_failure = Some(e);
        }
    }

    /// The progress bar every 50 rows and at the end.
    fn show_progress(&mut self, time: f64, at_end: bool) {
        let out = &self.recorder.out;
        if !(out.time.len().is_multiple_of(50) || at_end) {
            return;
        }
        let w = &mut self.watch;
        let done = ((time / self.settings.step).round() as usize).min(self.settings.steps);
        let rate = (done - w.first_step) as f64 / w.clock.elapsed().as_secs_f64().max(1e-9);
        w.bar.update(done, &progress_line(out, time, rate));
    }
}

impl<'r, 'p> StepProblem<'r, 'p> for TransientRun<'r, 'p> {
    fn forces(
        &mut self,
        _t: f64,
        q: &Vector<'p>,
        v: &Vector<'p>,
        f: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        self.forces.evaluate(q, v, f)
    }

    fn factorize(
        &mut self,
        ns: &NewmarkSettings,
        at: Option<&State<'p>>,
        retired: Option<RetiredJacobian<'p>>,
    ) -> Result<Jacobian<'r, 'p>, LaError> {
        self.builder.factorize(ns, at, retired)
    }

    fn can_linearize(&self) -> bool {
        true
    }

    fn linearize(
        &mut self,
        ns: &NewmarkSettings,
        at: &State<'p>,
    ) -> Result<Box<dyn TangentChange<'p> + 'r>, LaError> {
        Ok(Box::new(self.builder.linearize(ns, at)?))
    }

    fn can_eliminate(&self) -> bool {
        self.eliminator.is_some()
    }

    /// An elimination starts where the residual was just evaluated: the tangent's change
    /// from that evaluation's contact state (a contact evaluation fewer per elimination).
    fn eliminate(
        &mut self,
        ns: &NewmarkSettings,
        at: &State<'p>,
        residual: &Vector<'p>,
        target: f64,
    ) -> Result<Option<Elimination<'p>>, LaError> {
        let clock = Instant::now();
        let tangent = match self.forces.last_at(at)? {
            Some(evaluated) => self.builder.linearize_at(ns, evaluated)?,
            None => self.builder.linearize(ns, at)?,
        };
        let e = self
            .eliminator
            .as_mut()
            .expect("called where can_eliminate");
        let seconds = clock.elapsed().as_secs_f64();
        e.counts.seconds_tangent += seconds;
        e.counts.seconds += seconds;
        e.solve(ns, at, residual, &tangent, target)
    }
}

impl<'p> StepHooks<'p> for TransientRun<'_, 'p> {
    /// Records the step (signals, a stored state when due), asks the monitor, flushes and
    /// checkpoints when due, shows progress.
    fn on_step(
        &mut self,
        s: &State<'p>,
        report: &StepReport,
        c: &StepControl,
        h: f64,
    ) -> Result<Flow, TimeError> {
        let recording = Instant::now();
        self.forces.status_changes = 0;
        self.count(report);
        let evaluated = self.forces.last().filter(|_| report.forces_current);
        let wall = self.watch.wall_before + self.watch.clock.elapsed().as_secs_f64();
        let recorded = self
            .recorder
            .record(s, h, report.iterations, wall, evaluated);
        end_on_write_failure(recorded, "transient.h5");
        end_on_write_failure(self.recorder.sample_state(s, h), "transient.h5");
        let stop = self.monitor.stop(c.steps, &self.recorder.out);
        if stop {
            self.recorder.out.stopped_at_saturation = Some(s.time);
        }
        let at_end = stop || s.time >= self.watch.end_time - 0.25 * h;
        end_on_write_failure(self.recorder.flush_if_due(at_end), "transient.h5");
        self.checkpoint_if_due(s, c, at_end);
        self.show_progress(s.time, at_end);
        self.recorder.out.seconds_recording += recording.elapsed().as_secs_f64();
        Ok(if stop { Flow::Stop } else { Flow::Continue })
    }

    /// Into transient.log with the contact's evidence (every rank logs at the same points of
    /// the step control).
    fn log(&mut self, line: &str) {
        let world = self.petsc.world();
        let changes = crate::parallel::sum(world, self.forces.status_changes as f64);
        let in_band = crate::parallel::sum(world, self.forces.in_friction_band() as f64);
        self.watch.log.write(&format!(
            "{line} [{changes:.0} contact status changes between iterates since the last step; {in_band:.0} sliding points inside the friction regularization band]"
        ));
    }
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
    let out = Transient::empty(settings, contact.interfaces().len(), sensor_names);
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
