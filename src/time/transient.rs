//! The transient stage: nonlinear time response of the full model (small models; the reduced
//! model of the superelement reduction is the next step) from the static state plus a small
//! perturbation, with the contact and friction forces of the contact stage, and observation
//! signals (braking torque, normal and friction force per interface) at every step.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::newmark::{
    initial_acceleration, integrate_adaptive, jacobian, Forces, NewmarkSettings, State, StepReport,
    TimeError,
};
use crate::contact::kernel::Part;
use crate::contact::{ContactModel, InterfaceSummary};
use crate::la::{DirectSolver, Factorization, LaError, Petsc, SparseMatrix, Vector};

/// The `[transient]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransientSettings {
    /// Time step (s).
    #[serde(default = "default_step")]
    pub step: f64,
    /// Number of steps.
    pub steps: usize,
    /// Relative tolerance of the fixed-Jacobian iterations.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Start: the static state plus `amplitude` (m, largest nodal displacement) times a real
    /// mode shape (`mode`, 1-based).
    #[serde(default = "default_mode")]
    pub mode: usize,
    #[serde(default = "default_amplitude")]
    pub amplitude: f64,
    /// A failed step is halved (Jacobian refactorized) at most this many levels deep.
    #[serde(default = "default_max_cuts")]
    pub max_cuts: usize,
}

fn default_max_cuts() -> usize {
    6
}

fn default_step() -> f64 {
    1e-6
}
fn default_tolerance() -> f64 {
    1e-8
}
fn default_max_iterations() -> usize {
    30
}
fn default_mode() -> usize {
    1
}
fn default_amplitude() -> f64 {
    1e-7
}

impl TransientSettings {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.step > 0.0 && self.step.is_finite()) {
            return Err(format!(
                "key 'transient.step' = {}: must be a positive time step (s)",
                self.step
            ));
        }
        if self.steps == 0 {
            return Err("key 'transient.steps' must be at least 1".into());
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1e-2) {
            return Err(format!(
                "key 'transient.tolerance' = {}: must be in (0, 0.01)",
                self.tolerance
            ));
        }
        if self.mode == 0 {
            return Err("key 'transient.mode' is 1-based: the first real mode is 1".into());
        }
        if !self.amplitude.is_finite() {
            return Err("key 'transient.amplitude' must be finite".into());
        }
        Ok(())
    }
}

/// The time response: signals at every step (index 0 = start).
pub struct Transient {
    pub time: Vec<f64>,
    /// Per interface (in the contact model's order): normal force, friction force, torque.
    pub normal_force: Vec<Vec<f64>>,
    pub friction_force: Vec<Vec<f64>>,
    pub torque: Vec<Vec<f64>>,
    pub iterations: Vec<usize>,
    /// Step cuts after failed steps, and Jacobian factorizations in all.
    pub cuts: usize,
    pub factorizations: usize,
    pub factor_entries: f64,
    pub seconds_factorizing: f64,
    pub seconds_stepping: f64,
}

/// Everything the stage needs.
pub struct TransientInputs<'a, 'p> {
    pub k0: &'a SparseMatrix<'p>,
    pub m: &'a SparseMatrix<'p>,
    pub c: Option<&'a SparseMatrix<'p>>,
    pub contact: &'a ContactModel<'p>,
    pub f_ext: &'a Vector<'p>,
    pub q_static: &'a Vector<'p>,
    pub static_state: &'a crate::contact::ContactState,
    pub shape: &'a Vector<'p>,
}

/// Runs the transient. A step that fails ends the run: the signals up to the last converged
/// step come back with the error, so the caller can write them before reporting it.
///
/// # Collective
pub fn run<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: TransientInputs<'_, 'p>,
) -> Result<(Transient, Option<TimeError>), TimeError> {
    let newmark = NewmarkSettings {
        step: settings.step,
        tolerance: settings.tolerance,
        max_iterations: settings.max_iterations,
        ..Default::default()
    };
    // The fixed Jacobian: the static state's contact stiffness (normal and stick) stands for
    // the mock contact stiffness of DESIGN.md.
    let t = Instant::now();
    let mut mock = input.contact.joined_matrix(petsc, input.k0)?;
    mock.zero_entries()?;
    input
        .contact
        .add_tangent(input.static_state, &[Part::Normal, Part::Stick], &mut mock)?;
    mock.assemble()?;
    let k0 = input.contact.joined_matrix(petsc, input.k0)?;
    let mass = DirectSolver::factorize(petsc, input.m, Factorization::Lu, "time_mass_")?;
    let seconds_factorizing = t.elapsed().as_secs_f64();

    let contact = input.contact;
    let fc = input.f_ext.duplicate()?;
    let mut forces =
        |_t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &Vector<'p>| -> Result<(), LaError> {
            let state = contact.evaluate(q, Some(v), 1.0)?;
            contact.force(&state, &fc)?;
            f.copy_from(input.f_ext)?;
            f.axpy(1.0, &fc)
        };
    let forces: &mut Forces<'_, 'p> = &mut forces;

    // Start: static state + amplitude x shape (scaled to its largest entry).
    let q = input.q_static.try_clone()?;
    let largest = input.shape.norm_inf()?;
    if largest > 0.0 {
        q.axpy(settings.amplitude / largest, input.shape)?;
    }
    let v = q.duplicate()?;
    v.set_all(0.0)?;
    let a = q.duplicate()?;
    let mut state = State {
        time: 0.0,
        step: 0,
        q,
        v,
        a,
    };
    initial_acceleration(input.m, input.c, &k0, &mut state, forces, &mass)?;
    drop(mass);

    let n_if = contact.interfaces.len();
    let mut out = Transient {
        time: Vec::with_capacity(settings.steps + 1),
        normal_force: vec![Vec::with_capacity(settings.steps + 1); n_if],
        friction_force: vec![Vec::with_capacity(settings.steps + 1); n_if],
        torque: vec![Vec::with_capacity(settings.steps + 1); n_if],
        iterations: Vec::with_capacity(settings.steps),
        cuts: 0,
        factorizations: 0,
        factor_entries: 0.0,
        seconds_factorizing,
        seconds_stepping: 0.0,
    };
    let record = |out: &mut Transient, s: &State<'p>| -> Result<(), LaError> {
        let cs = contact.evaluate(&s.q, Some(&s.v), 1.0)?;
        let sums: Vec<InterfaceSummary> = contact.summarize(petsc, &cs);
        out.time.push(s.time);
        for (i, sum) in sums.iter().enumerate() {
            out.normal_force[i].push(sum.normal_force);
            out.friction_force[i].push(sum.friction_force);
            out.torque[i].push(sum.torque);
        }
        Ok(())
    };
    record(&mut out, &state)?;
    let mut bar = crate::progress::Progress::new("transient", settings.steps, petsc.rank());
    let t = Instant::now();
    let end_time = settings.steps as f64 * settings.step;
    let mut factor_entries = 0.0;
    let mut seconds_factorizing = seconds_factorizing;
    let mut factorize = |ns: &NewmarkSettings| -> Result<DirectSolver<'p>, LaError> {
        let t = Instant::now();
        let j = jacobian(ns, input.m, input.c, &k0, Some(&mock))?;
        j.set_symmetric(true)?;
        let factor = DirectSolver::factorize(petsc, &j, Factorization::Cholesky, "time_")?;
        factor_entries = factor.report().factor_entries;
        seconds_factorizing += t.elapsed().as_secs_f64();
        Ok(factor)
    };
    let rank0 = petsc.rank() == 0;
    let mut on_step = |s: &State<'p>, report: &StepReport| -> Result<(), TimeError> {
        out.iterations.push(report.iterations);
        record(&mut out, s)?;
        let done = ((s.time / settings.step).round() as usize).min(settings.steps);
        if out.iterations.len().is_multiple_of(50) || done == settings.steps {
            let mean = out.iterations.iter().sum::<usize>() as f64 / out.iterations.len() as f64;
            bar.update(
                done,
                &format!("t = {:.3e} s, {mean:.2} iterations/step", s.time),
            );
        }
        Ok(())
    };
    let mut log = |line: &str| {
        if rank0 {
            println!("  transient: {line}");
        }
    };
    let result = integrate_adaptive(
        newmark,
        input.m,
        input.c,
        &k0,
        &mut factorize,
        &mut state,
        forces,
        end_time,
        settings.max_cuts,
        100,
        &mut on_step,
        &mut log,
    );
    bar.finish();
    out.seconds_stepping = t.elapsed().as_secs_f64();
    out.factor_entries = factor_entries;
    out.seconds_factorizing = seconds_factorizing;
    match result {
        Ok(control) => {
            out.cuts = control.cuts;
            out.factorizations = control.factorizations;
            Ok((out, None))
        }
        Err(e) => Ok((out, Some(e))),
    }
}
