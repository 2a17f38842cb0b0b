//! The transient stage: nonlinear time response of the model (full, or the reduced model of
//! the superelement reduction) from the static state plus a perturbation, with the contact and
//! friction forces of the contact stage, and observation signals (braking torque, normal and
//! friction force per interface, sensors) at every step, streamed to transient.h5.
//!
//! `run` wires the parts: `start` (the kicked static state, the forces), `run` (the run as
//! the adaptive integrator's step problem and hooks), `jacobian` (J and its refreshes),
//! `eliminate` (the nonlinear elimination), `recorder` (signals, states, the stream),
//! `checkpoint` (restart), `hooks` (what a stage lends the run: its monitor, the sampler of
//! stored states), `settings` (the scene table), `result` (the [`Transient`]).

mod checkpoint;
mod eliminate;
pub use checkpoint::check_resumable;
pub use eliminate::EliminationCounts;
mod hooks;
mod jacobian;
mod local_jacobian;
mod local_newton;
mod parts;
mod recorder;
mod result;
mod run;
mod settings;
mod start;

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::adaptive::{AdaptiveNewmark, Adaptivity, StepControl};
use super::newmark::{Damping, ModalDamping, NewmarkSettings, TimeError};
use crate::contact::ContactModel;
use crate::la::{Petsc, SparseMatrix, Vector};
use crate::time::store::Storage;
pub use hooks::{ModalSample, Monitor, StateSampler, ToTheEnd};
pub use result::Transient;
use run::TransientRun;
pub use settings::{
    random_coefficients, Impulse, Newton, Start, ToleranceReference, TransientSettings,
    SATURATION_CHECK_EVERY,
};
use start::{balanced_load, start_state};

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
    /// What samples every stored state (the real modes' coordinates; None: nothing).
    pub modal_sensors: Option<&'a dyn StateSampler<'p>>,
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
/// `monitor` is asked after every step whether to stop (the stage's saturation stop).
///
/// # Collective
pub fn run<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: TransientInputs<'_, 'p>,
    files: &TransientFiles,
    monitor: &mut dyn Monitor,
) -> Result<(Transient, Option<TimeError>), TimeError> {
    let clock = Instant::now();
    let k0 = input.contact.joined_matrix(petsc, input.k0)?;
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
    let seconds_start = clock.elapsed().as_secs_f64();
    let mut control = StepControl::default();
    let mut run = TransientRun::new(
        petsc,
        settings,
        &input,
        &k0,
        files,
        monitor,
        &mut state,
        &mut control,
    )?;
    let integrator = AdaptiveNewmark {
        settings: NewmarkSettings {
            step: settings.step,
            tolerance: settings.tolerance,
            max_iterations: settings.max_iterations,
            anderson: settings.anderson,
            step_error_fraction: settings.step_error_fraction,
            ..Default::default()
        },
        m: input.m,
        c: input.c,
        k: &k0,
        equilibrium: equilibrium.as_ref(),
        adaptivity: Adaptivity {
            max_cuts: settings.max_cuts,
            restore_after: 100,
            refresh: settings.refresh,
            full_newton: settings.newton == Newton::Full,
            update: settings.update_factor,
        },
    };
    let end_time = run.end_time();
    let result = integrator.integrate(&mut run, &mut state, end_time, &mut control);
    let (mut out, failure) = run.finish(result, &state, &control, seconds_start)?;
    out.static_residual = static_residual;
    Ok((out, failure))
}
