//! The transient stage: nonlinear time response of the full model (small models; the reduced
//! model of the superelement reduction is the next step) from the static state plus a small
//! perturbation, with the contact and friction forces of the contact stage, and observation
//! signals (braking torque, normal and friction force per interface) at every step.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::newmark::{
    initial_acceleration, integrate_adaptive, jacobian, Adaptivity, Damping, Forces, Jacobian,
    ModalDamping, NewmarkSettings, State, StepControl, StepReport, TimeError,
};
use crate::contact::kernel::Part;
use crate::contact::{ContactModel, InterfaceSummary};
use crate::io::series::SeriesFile;
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
    /// The perturbation of the static state the run starts from (see [`Start`]).
    #[serde(default)]
    pub start: Start,
    /// `start = "mode"`: the real mode (1-based).
    #[serde(default = "default_mode")]
    pub mode: usize,
    /// `start = "mode"` or `"random"`: the largest nodal displacement of the kick (m).
    #[serde(default = "default_amplitude")]
    pub amplitude: f64,
    /// `start = "random"`: the seed of the modal coefficients.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// `start = "impulse"`: where and how much.
    #[serde(default)]
    pub impulse: Option<Impulse>,
    /// A failed step is halved (Jacobian refactorized) at most this many levels deep.
    #[serde(default = "default_max_cuts")]
    pub max_cuts: usize,
    /// Before cutting, rebuild the Jacobian with the contact tangent of the current state
    /// (normal and stick stiffness, friction damping of nearly sticking points).
    #[serde(default = "default_refresh")]
    pub refresh: bool,
    /// `"modified"` (default): the fixed Jacobian; `"full"`: J rebuilt with the contact tangent
    /// at every iterate (the reference the fixed-Jacobian iterations are checked against).
    #[serde(default)]
    pub newton: Newton,
    /// Displacement and velocity states go to transient.h5 every this much simulated time
    /// (s; 0: none). Default 1e-5 s (100 kHz).
    #[serde(default = "default_state_interval")]
    pub state_interval: f64,
    /// A checkpoint (checkpoint.h5, for `squeal run --restart`) every this many steps, and at
    /// the end or the failure of the run (0: never).
    #[serde(default = "default_checkpoint_every")]
    pub checkpoint_every: usize,
    /// Sensor points by name: displacement, velocity and acceleration (x, y, z) of the node
    /// nearest to each position (m) at every step.
    #[serde(default)]
    pub sensors: std::collections::BTreeMap<String, [f64; 3]>,
    /// Upper frequency of the spectrogram plot (Hz).
    #[serde(default = "default_spectrogram_max_hz")]
    pub spectrogram_max_hz: f64,
}

/// How the transient leaves the static state (the growth of unstable modes needs a seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Start {
    /// Displaced along one real mode shape (`mode`, `amplitude`).
    #[default]
    Mode,
    /// Displaced along a random combination of every computed real mode: coefficients
    /// uniform in [-1, 1] from `seed` (the same on any number of ranks), scaled to
    /// `amplitude`. Smooth (modal) rather than a per-DOF noise, whose strain energy would sit
    /// in the mesh's highest frequencies.
    Random,
    /// At rest at the static state, hit by an impulse (`[transient.impulse]`): v0 = M^-1 I.
    Impulse,
}

/// A force impulse at the node nearest to `point`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Impulse {
    /// Position (m).
    pub point: [f64; 3],
    /// Impulse vector (N s).
    pub value: [f64; 3],
}

/// The kick in the integrated unknowns.
pub enum Kick<'a, 'p> {
    /// Added to the static displacement, scaled so its largest entry is `amplitude`.
    Displacement(&'a Vector<'p>),
    /// A force impulse (N s): the initial velocity is M^-1 times it.
    Impulse(&'a Vector<'p>),
}

/// Coefficients uniform in [-1, 1] (splitmix64: one definition, identical on every platform
/// and rank count).
pub fn random_coefficients(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            // 53 random bits to [0, 1), then to [-1, 1).
            2.0 * ((z >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        })
        .collect()
}

fn default_seed() -> u64 {
    1
}

fn default_spectrogram_max_hz() -> f64 {
    20_000.0
}

/// Sensor rows: three per sensor (x, y, z of its node) over the integrated unknowns.
pub struct Sensors<'p> {
    pub names: Vec<String>,
    pub rows: crate::la::ObservationMatrix<'p>,
    /// Rows are grouped by owning rank: row block k belongs to sensor `order[k]`.
    pub order: Vec<usize>,
}

fn default_state_interval() -> f64 {
    1e-5
}
fn default_checkpoint_every() -> usize {
    10_000
}

/// The Newton variant of the transient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Newton {
    #[default]
    Modified,
    Full,
}

fn default_refresh() -> bool {
    true
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
        for (name, p) in &self.sensors {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(format!(
                    "key 'transient.sensors.{name}': the position must be three finite coordinates (m)"
                ));
            }
        }
        if self.spectrogram_max_hz.is_nan() || self.spectrogram_max_hz <= 0.0 {
            return Err("key 'transient.spectrogram_max_hz' must be positive (Hz)".into());
        }
        if !(self.state_interval >= 0.0 && self.state_interval.is_finite()) {
            return Err(format!(
                "key 'transient.state_interval' = {}: must be a time (s) >= 0 (0: no states)",
                self.state_interval
            ));
        }
        if !self.amplitude.is_finite() {
            return Err("key 'transient.amplitude' must be finite".into());
        }
        match (self.start, &self.impulse) {
            (Start::Impulse, None) => {
                return Err(
                    "key 'transient.start' = \"impulse\" needs [transient.impulse] with point = [x, y, z] (m) and value = [Ix, Iy, Iz] (N s)"
                        .into(),
                )
            }
            (_, Some(i)) if i.point.iter().chain(&i.value).any(|x| !x.is_finite()) => {
                return Err(
                    "key 'transient.impulse': point and value must be three finite numbers each"
                        .into(),
                )
            }
            _ => {}
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
    /// The step size of each step (0 at the start).
    pub step_size: Vec<f64>,
    /// Per sensor: displacement, velocity, acceleration (x, y, z per sample, row-major).
    pub sensor_names: Vec<String>,
    pub sensor_values: Vec<[Vec<f64>; 3]>,
    /// States written (every state_interval), and the time a restart resumed from.
    pub states: usize,
    pub resumed_at: Option<f64>,
    /// Step cuts after failed steps, and Jacobian factorizations in all.
    pub cuts: usize,
    pub refreshes: usize,
    pub factorizations: usize,
    pub factor_entries: f64,
    pub seconds_factorizing: f64,
    /// The stepping loop, and the Jacobian factorizations within it.
    pub seconds_stepping: f64,
    pub seconds_jacobians: f64,
    /// Time in the factor's solves, steps and iterations (solves), over this process's steps.
    pub seconds_solving: f64,
    /// Time in the force evaluations and in the operator products (predictor, contact
    /// tangent), steps and iterations.
    pub seconds_in_forces: f64,
    pub seconds_in_products: f64,
    pub steps_run: usize,
    pub iterations_run: usize,
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
}

/// Runs the transient. A step that fails ends the run: the signals up to the last converged
/// step come back with the error, so the caller can write them before reporting it.
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
    // The contact state of the last force evaluation: the step's record reuses it when the
    // step ended there.
    let last_contact = std::cell::RefCell::new(None::<crate::contact::ContactState>);
    let mut forces =
        |_t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &Vector<'p>| -> Result<(), LaError> {
            let state = contact.evaluate(q, Some(v), 1.0)?;
            contact.force(&state, &fc)?;
            *last_contact.borrow_mut() = Some(state);
            f.copy_from(input.f_ext)?;
            f.axpy(1.0, &fc)?;
            match input.modal_damping {
                Some(modal) => modal.subtract_force(v, f),
                None => Ok(()),
            }
        };
    let forces: &mut Forces<'_, 'p> = &mut forces;

    // Start: the static state + amplitude x the kick's shape (scaled to its largest entry),
    // or at rest there with the velocity of an impulse.
    let q = input.q_static.try_clone()?;
    let v = q.duplicate()?;
    v.set_all(0.0)?;
    match input.kick {
        Kick::Displacement(shape) => {
            let largest = shape.norm_inf()?;
            if largest > 0.0 {
                q.axpy(settings.amplitude / largest, shape)?;
            }
        }
        Kick::Impulse(impulse) => mass.solve(impulse, &v)?,
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
    initial_acceleration(input.m, input.c, &k0, &mut state, forces, &mass)?;
    drop(mass);

    let n_if = contact.interfaces.len();
    let mut out = Transient {
        time: Vec::with_capacity(settings.steps + 1),
        step_size: Vec::with_capacity(settings.steps + 1),
        normal_force: vec![Vec::with_capacity(settings.steps + 1); n_if],
        friction_force: vec![Vec::with_capacity(settings.steps + 1); n_if],
        torque: vec![Vec::with_capacity(settings.steps + 1); n_if],
        iterations: Vec::with_capacity(settings.steps + 1),
        cuts: 0,
        refreshes: 0,
        factorizations: 0,
        factor_entries: 0.0,
        seconds_factorizing,
        seconds_stepping: 0.0,
        seconds_jacobians: 0.0,
        seconds_solving: 0.0,
        seconds_in_forces: 0.0,
        seconds_in_products: 0.0,
        steps_run: 0,
        iterations_run: 0,
        states: 0,
        resumed_at: None,
        sensor_names: input.sensors.map(|s| s.names.clone()).unwrap_or_default(),
        sensor_values: vec![Default::default(); input.sensors.map_or(0, |s| s.names.len())],
    };
    let sensor_buffer = match input.sensors {
        Some(s) => Some(s.rows.new_point_vector()?),
        None => None,
    };
    let record = |out: &mut Transient,
                  s: &State<'p>,
                  h: f64,
                  its: usize,
                  evaluated: Option<&crate::contact::ContactState>|
     -> Result<(), LaError> {
        let sums: Vec<InterfaceSummary> = match evaluated {
            Some(cs) => contact.summarize(petsc, cs),
            None => contact.summarize(petsc, &contact.evaluate(&s.q, Some(&s.v), 1.0)?),
        };
        out.time.push(s.time);
        out.step_size.push(h);
        out.iterations.push(its);
        for (i, sum) in sums.iter().enumerate() {
            out.normal_force[i].push(sum.normal_force);
            out.friction_force[i].push(sum.friction_force);
            out.torque[i].push(sum.torque);
        }
        if let (Some(sensors), Some(y)) = (input.sensors, &sensor_buffer) {
            // Each rank's rows into their place, then one sum over the ranks for all three.
            let n = y.global_len();
            let mut values = vec![0.0; 3 * n];
            let range = y.ownership();
            for (kind, x) in [&s.q, &s.v, &s.a].into_iter().enumerate() {
                sensors.rows.mult(x, y)?;
                values[kind * n + range.start..kind * n + range.end].copy_from_slice(&y.local()?);
            }
            crate::parallel::sum_in_place(petsc.world(), &mut values);
            for (kind, values) in values.chunks(n).enumerate() {
                for (k, v) in values.chunks(3).enumerate() {
                    out.sensor_values[sensors.order[k]][kind].extend_from_slice(v);
                }
            }
        }
        Ok(())
    };

    // The stream (transient.h5) and the checkpoint: a fresh start, or the checkpoint's state,
    // step control and Jacobian state, with the stream cut back to the checkpoint's rows.
    let names: Vec<String> = contact.interfaces.iter().map(|i| i.name.clone()).collect();
    let world = petsc.world();
    let mut control = StepControl::default();
    let mut jacobian_at: Option<(Vector<'p>, Vector<'p>)> = None;
    let stream = if files.restart {
        let checkpoint = Checkpoint::read(petsc, files, settings, &state)?;
        let stream = SeriesFile::open(world, &files.stream).map_err(io_error)?;
        let rows = checkpoint.signal_rows;
        for path in signal_paths(&names) {
            stream.truncate(&path, rows).map_err(io_error)?;
        }
        for path in STATE_PATHS {
            stream
                .truncate(path, checkpoint.state_rows)
                .map_err(io_error)?;
        }
        for path in sensor_paths(&out.sensor_names) {
            stream.truncate(&path, rows).map_err(io_error)?;
        }
        stream.flush().map_err(io_error)?;
        // The signals so far, for the summary and the plots.
        let read = |p: &str| stream.read(p).map_err(io_error);
        out.time = read("time")?;
        out.step_size = read("step_size")?;
        out.iterations = read("iterations")?
            .into_iter()
            .map(|x| x as usize)
            .collect();
        for (i, name) in names.iter().enumerate() {
            out.normal_force[i] = read(&format!("interfaces/{name}/normal_force"))?;
            out.friction_force[i] = read(&format!("interfaces/{name}/friction_force"))?;
            out.torque[i] = read(&format!("interfaces/{name}/torque"))?;
        }
        let sensor_series = sensor_paths(&out.sensor_names);
        for (i, chunk) in sensor_series.chunks(3).enumerate() {
            for (kind, path) in chunk.iter().enumerate() {
                out.sensor_values[i][kind] = read(path)?;
            }
        }
        out.states = checkpoint.state_rows;
        out.resumed_at = Some(checkpoint.state_time);
        control = checkpoint.control;
        jacobian_at = checkpoint.jacobian_at;
        state = checkpoint.state;
        stream
    } else {
        let stream = SeriesFile::create(world, &files.stream).map_err(io_error)?;
        for path in signal_paths(&names) {
            let units = match path.rsplit('/').next().unwrap_or("") {
                "time" | "step_size" => "s",
                "iterations" => "1",
                "torque" | "braking_torque" => "N m",
                _ => "N",
            };
            stream.create_series(&path, 1, units).map_err(io_error)?;
        }
        for (k, path) in sensor_paths(&out.sensor_names).iter().enumerate() {
            let units = ["m", "m/s", "m/s^2"][k % 3];
            stream.create_series(path, 3, units).map_err(io_error)?;
        }
        stream
            .create_series("states/time", 1, "s")
            .map_err(io_error)?;
        let n = state.q.global_len();
        stream
            .create_series("states/displacement", n, "m")
            .map_err(io_error)?;
        stream
            .create_series("states/velocity", n, "m/s")
            .map_err(io_error)?;
        record(&mut out, &state, 0.0, 0, None)?;
        stream
    };
    let mut written = stream.rows("time").map_err(io_error)?;
    let flush = |out: &Transient, written: &mut usize| -> Result<(), TimeError> {
        let from = *written;
        let its: Vec<f64> = out.iterations[from..].iter().map(|&i| i as f64).collect();
        let torque: Vec<f64> = (from..out.time.len())
            .map(|k| out.torque.iter().map(|t| t[k]).sum())
            .collect();
        let mut series: Vec<(String, &[f64])> = vec![
            ("time".into(), &out.time[from..]),
            ("step_size".into(), &out.step_size[from..]),
            ("iterations".into(), &its),
            ("braking_torque".into(), &torque),
        ];
        for (i, name) in names.iter().enumerate() {
            series.push((
                format!("interfaces/{name}/normal_force"),
                &out.normal_force[i][from..],
            ));
            series.push((
                format!("interfaces/{name}/friction_force"),
                &out.friction_force[i][from..],
            ));
            series.push((format!("interfaces/{name}/torque"), &out.torque[i][from..]));
        }
        for (path, values) in series {
            stream.append(&path, values).map_err(io_error)?;
        }
        let sensor_series = sensor_paths(&out.sensor_names);
        for (i, chunk) in sensor_series.chunks(3).enumerate() {
            for (kind, path) in chunk.iter().enumerate() {
                let v = &out.sensor_values[i][kind];
                stream.append(path, &v[3 * from..]).map_err(io_error)?;
            }
        }
        stream.flush().map_err(io_error)?;
        *written = out.time.len();
        Ok(())
    };
    let write_state = |s: &State<'p>| -> Result<(), TimeError> {
        let range = s.q.ownership();
        stream.append("states/time", &[s.time]).map_err(io_error)?;
        stream
            .append_distributed("states/displacement", &s.q.local()?, range.clone())
            .map_err(io_error)?;
        stream
            .append_distributed("states/velocity", &s.v.local()?, range)
            .map_err(io_error)
    };
    // States every state_interval of simulated time (the first at the start).
    let interval = settings.state_interval;
    let next_sample = |states: usize| states as f64 * interval;
    if !files.restart && interval > 0.0 {
        write_state(&state)?;
        out.states = 1;
    }

    let mut bar = crate::progress::Progress::new("transient", settings.steps, petsc.rank());
    let first_step = ((state.time / settings.step).round() as usize).min(settings.steps);
    bar.resume_from(first_step);
    let t = Instant::now();
    let end_time = settings.steps as f64 * settings.step;
    let mut factor_entries = 0.0;
    // Every factorization (adaptive ones, and one per iterate with a full Newton).
    let mut built = 0usize;
    let mut seconds_factorizing = seconds_factorizing;
    let mut seconds_jacobians = 0.0;
    // J with the contact tangent of a state: K_c + K_stick + K_f (friction: unsymmetric, LU)
    // and the friction damping C_f (w dt/dw c_t c_t^T, large where points nearly stick)
    // through gamma / (beta h). The state J was built at is kept for the checkpoint (a restart
    // rebuilds the same J).
    let mut current = input.contact.joined_matrix(petsc, input.k0)?;
    let mut restart_jacobian = jacobian_at.take();
    let jacobian_at = std::cell::RefCell::new(None::<(Vector<'p>, Vector<'p>)>);
    let mut factorize =
        |ns: &NewmarkSettings, at: Option<&State<'p>>| -> Result<Jacobian<'_, 'p>, LaError> {
            let t = Instant::now();
            let saved = restart_jacobian.take();
            let at: Option<(&Vector<'p>, &Vector<'p>)> = match (&saved, at) {
                (Some((q, v)), _) => Some((q, v)),
                (None, Some(s)) => Some((&s.q, &s.v)),
                (None, None) => None,
            };
            let c1 = ns.gamma / (ns.beta * ns.step);
            let extra = if let Some((q, v)) = at {
                let cs = contact.evaluate(q, Some(v), 1.0)?;
                current.zero_entries()?;
                contact.add_tangent(
                    &cs,
                    &[Part::Normal, Part::Stick, Part::Friction],
                    &mut current,
                )?;
                current.assemble()?;
                let mut damping = contact.joined_matrix(petsc, input.k0)?;
                damping.zero_entries()?;
                contact.add_tangent(&cs, &[Part::Damping], &mut damping)?;
                damping.assemble()?;
                current.axpy(c1, &damping)?;
                let copy = (q.try_clone()?, v.try_clone()?);
                *jacobian_at.borrow_mut() = Some(copy);
                contact.tangent_operator(
                    petsc,
                    &cs,
                    &[
                        (&[Part::Normal, Part::Stick, Part::Friction], 1.0),
                        (&[Part::Damping], c1),
                    ],
                )?
            } else {
                contact.tangent_operator(
                    petsc,
                    input.static_state,
                    &[(&[Part::Normal, Part::Stick], 1.0)],
                )?
            };
            let mock = if at.is_some() { &current } else { &mock };
            let j = jacobian(ns, input.m, input.c, &k0, Some(mock))?;
            // The static mock is symmetric (Cholesky); a state's tangent has the friction part.
            let kind = if at.is_some() {
                Factorization::Lu
            } else {
                j.set_symmetric(true)?;
                Factorization::Cholesky
            };
            let factor = DirectSolver::factorize(petsc, &j, kind, "time_")?;
            factor_entries = factor.report().factor_entries;
            built += 1;
            seconds_factorizing += t.elapsed().as_secs_f64();
            seconds_jacobians += t.elapsed().as_secs_f64();
            Ok(Jacobian {
                factor,
                extra: Some(Box::new(extra)),
            })
        };
    let rank0 = petsc.rank() == 0;
    let mut checkpoint_failure = None;
    let mut on_step =
        |s: &State<'p>, report: &StepReport, c: &StepControl| -> Result<(), TimeError> {
            let h = settings.step / f64::from(1u32 << c.level);
            out.seconds_solving += report.solve_seconds;
            out.seconds_in_forces += report.force_seconds;
            out.seconds_in_products += report.product_seconds;
            out.steps_run += 1;
            out.iterations_run += report.iterations;
            let evaluated = last_contact.borrow();
            let evaluated = evaluated.as_ref().filter(|_| report.forces_current);
            record(&mut out, s, h, report.iterations, evaluated)?;
            if interval > 0.0 && s.time >= next_sample(out.states) - 1e-3 * h {
                write_state(s)?;
                out.states += 1;
            }
            let done = ((s.time / settings.step).round() as usize).min(settings.steps);
            let at_end = s.time >= end_time - 0.25 * h;
            if out.time.len() - written >= FLUSH_ROWS || at_end {
                flush(&out, &mut written)?;
            }
            if settings.checkpoint_every > 0
                && (c.steps.is_multiple_of(settings.checkpoint_every) || at_end)
            {
                flush(&out, &mut written)?;
                // After a step restore J is rebuilt at this state; otherwise it stays the one
                // built at `jacobian_at`.
                let at = jacobian_at.borrow();
                let j = if c.good == 0 { None } else { at.as_ref() };
                if let Err(e) = Checkpoint::write(petsc, files, settings, s, c, j, &out) {
                    checkpoint_failure = Some(e.to_string());
                }
            }
            if out.time.len().is_multiple_of(50) || at_end {
                let recent = &out.iterations[out.iterations.len().saturating_sub(500)..];
                let mean = recent.iter().sum::<usize>() as f64 / recent.len().max(1) as f64;
                let rate = (done - first_step) as f64 / t.elapsed().as_secs_f64().max(1e-9);
                bar.update(
                    done,
                    &format!(
                        "t = {:.3e} s, {rate:.1} steps/s, {mean:.2} iterations/step",
                        s.time
                    ),
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
        Adaptivity {
            max_cuts: settings.max_cuts,
            restore_after: 100,
            refresh: settings.refresh,
            full_newton: settings.newton == Newton::Full,
        },
        &mut control,
        &mut on_step,
        &mut log,
    );
    bar.finish();
    // Whatever happened, the signals recorded so far go to the file, and a failed run leaves
    // a checkpoint at its last converged step (to restart with other settings).
    flush(&out, &mut written)?;
    if result.is_err() && settings.checkpoint_every > 0 {
        let at = jacobian_at.borrow();
        Checkpoint::write(petsc, files, settings, &state, &control, at.as_ref(), &out)?;
    }
    if let Some(e) = checkpoint_failure {
        return Err(TimeError::Output(e));
    }
    out.seconds_stepping = t.elapsed().as_secs_f64();
    out.factor_entries = factor_entries;
    out.seconds_factorizing = seconds_factorizing;
    out.seconds_jacobians = seconds_jacobians;
    out.cuts = control.cuts;
    out.refreshes = control.refreshes;
    out.factorizations = control.factorizations.max(built);
    match result {
        Ok(()) => Ok((out, None)),
        Err(e) => Ok((out, Some(e))),
    }
}

/// Signal rows buffered before they are appended to the file.
const FLUSH_ROWS: usize = 1000;
const STATE_PATHS: [&str; 3] = ["states/time", "states/displacement", "states/velocity"];

/// The full-rate series of the stream.
fn signal_paths(interfaces: &[String]) -> Vec<String> {
    let mut v: Vec<String> = ["time", "step_size", "iterations", "braking_torque"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for name in interfaces {
        for s in ["normal_force", "friction_force", "torque"] {
            v.push(format!("interfaces/{name}/{s}"));
        }
    }
    v
}

/// Displacement, velocity, acceleration series of every sensor (3 per sensor, in order).
fn sensor_paths(names: &[String]) -> Vec<String> {
    names
        .iter()
        .flat_map(|n| {
            ["displacement", "velocity", "acceleration"].map(|k| format!("sensors/{n}/{k}"))
        })
        .collect()
}

fn io_error(e: crate::io::results::ResultsError) -> TimeError {
    TimeError::Output(e.to_string())
}

/// Where the stream and the checkpoint go, and whether to resume from the checkpoint.
pub struct TransientFiles {
    pub stream: PathBuf,
    pub checkpoint: PathBuf,
    pub restart: bool,
}

impl TransientFiles {
    pub fn in_directory(dir: &Path, restart: bool) -> Self {
        TransientFiles {
            stream: dir.join("transient.h5"),
            checkpoint: dir.join("checkpoint.h5"),
            restart,
        }
    }
}

/// A resumable point of the run: the state, the step control, the state J was built at, and
/// how many rows the stream held.
struct Checkpoint<'p> {
    state: State<'p>,
    control: StepControl,
    jacobian_at: Option<(Vector<'p>, Vector<'p>)>,
    signal_rows: usize,
    state_rows: usize,
    state_time: f64,
}

impl<'p> Checkpoint<'p> {
    /// Writes checkpoint.h5 (through a temporary file renamed when complete, so an
    /// interruption while writing keeps the previous checkpoint).
    ///
    /// # Collective
    fn write(
        petsc: &'p Petsc,
        files: &TransientFiles,
        settings: &TransientSettings,
        s: &State<'p>,
        c: &StepControl,
        jacobian_at: Option<&(Vector<'p>, Vector<'p>)>,
        out: &Transient,
    ) -> Result<(), TimeError> {
        let world = petsc.world();
        let tmp = files.checkpoint.with_extension("h5.tmp");
        {
            let f = SeriesFile::create(world, &tmp).map_err(io_error)?;
            let numbers = [
                ("ranks", petsc.size() as f64),
                ("unknowns", s.q.global_len() as f64),
                ("nominal_step", settings.step),
                ("time", s.time),
                ("step", s.step as f64),
                ("steps", c.steps as f64),
                ("cuts", c.cuts as f64),
                ("restores", c.restores as f64),
                ("refreshes", c.refreshes as f64),
                ("factorizations", c.factorizations as f64),
                ("level", f64::from(c.level)),
                ("good", c.good as f64),
                ("refreshed", f64::from(u8::from(c.refreshed))),
                ("fresh", f64::from(u8::from(c.fresh))),
                ("signal_rows", out.time.len() as f64),
                ("state_rows", out.states as f64),
                ("jacobian_state", f64::from(u8::from(jacobian_at.is_some()))),
                ("linear_state", f64::from(u8::from(s.linear.is_some()))),
            ];
            for (name, value) in numbers {
                f.set_number(name, value).map_err(io_error)?;
            }
            let n = s.q.global_len();
            let range = s.q.ownership();
            let mut vectors = vec![("q", &s.q), ("v", &s.v), ("a", &s.a)];
            if let Some(z) = &s.linear {
                vectors.push(("linear", z));
            }
            if let Some((q, v)) = jacobian_at {
                vectors.push(("jacobian_q", q));
                vectors.push(("jacobian_v", v));
            }
            for (name, x) in vectors {
                f.write_vector(name, &x.local()?, range.clone(), n)
                    .map_err(io_error)?;
            }
            f.flush().map_err(io_error)?;
        }
        crate::parallel::barrier(world);
        if petsc.rank() == 0 {
            std::fs::rename(&tmp, &files.checkpoint).map_err(|e| {
                TimeError::Output(format!(
                    "{}: cannot replace the checkpoint: {e}",
                    files.checkpoint.display()
                ))
            })?;
        }
        crate::parallel::barrier(world);
        Ok(())
    }

    /// Reads checkpoint.h5 for a run with `settings` on this layout (`like` gives the vector
    /// layout): the ranks, the number of unknowns and the nominal step must match.
    ///
    /// # Collective
    fn read(
        petsc: &'p Petsc,
        files: &TransientFiles,
        settings: &TransientSettings,
        like: &State<'p>,
    ) -> Result<Self, TimeError> {
        let path = &files.checkpoint;
        if !path.exists() || !files.stream.exists() {
            return Err(TimeError::Output(format!(
                "--restart: {} or {} is missing; run without --restart to start from the static state",
                path.display(),
                files.stream.display()
            )));
        }
        let f = SeriesFile::open(petsc.world(), path).map_err(io_error)?;
        let number = |name: &str| f.number(name).map_err(io_error);
        let expect = |name: &str, value: f64, what: &str| -> Result<(), TimeError> {
            let stored = number(name)?;
            if stored != value {
                return Err(TimeError::Output(format!(
                    "--restart: {} was written with {what} = {stored}, this run has {value}; restart with the same {what}",
                    path.display()
                )));
            }
            Ok(())
        };
        expect("ranks", petsc.size() as f64, "number of MPI ranks")?;
        expect("unknowns", like.q.global_len() as f64, "model (unknowns)")?;
        expect("nominal_step", settings.step, "key 'transient.step'")?;
        let range = like.q.ownership();
        let vector = |name: &str| -> Result<Vector<'p>, TimeError> {
            let x = like.q.duplicate()?;
            let values = f.read_vector(name, range.clone()).map_err(io_error)?;
            x.local_mut()?.copy_from_slice(&values);
            Ok(x)
        };
        let state = State {
            time: number("time")?,
            step: number("step")? as usize,
            q: vector("q")?,
            v: vector("v")?,
            a: vector("a")?,
            linear: if number("linear_state")? != 0.0 {
                Some(vector("linear")?)
            } else {
                None
            },
        };
        let jacobian_at = if number("jacobian_state")? != 0.0 {
            Some((vector("jacobian_q")?, vector("jacobian_v")?))
        } else {
            None
        };
        let control = StepControl {
            steps: number("steps")? as usize,
            cuts: number("cuts")? as usize,
            restores: number("restores")? as usize,
            refreshes: number("refreshes")? as usize,
            factorizations: number("factorizations")? as usize,
            level: number("level")? as u32,
            good: number("good")? as usize,
            refreshed: number("refreshed")? != 0.0,
            fresh: number("fresh")? != 0.0,
        };
        let state_rows = number("state_rows")? as usize;
        Ok(Checkpoint {
            state_time: state.time,
            state,
            control,
            jacobian_at,
            signal_rows: number("signal_rows")? as usize,
            state_rows,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(text: &str) -> TransientSettings {
        toml::from_str(text).expect("transient settings parse")
    }

    #[test]
    fn impulse_start_without_an_impulse_names_the_key() {
        let err = settings("steps = 10\nstart = \"impulse\"")
            .validate()
            .unwrap_err();
        assert!(err.contains("transient.impulse"), "{err}");
        let ok = settings(
            "steps = 10\nstart = \"impulse\"\n[impulse]\npoint = [0.0, 0.0, 0.0]\nvalue = [0.0, 0.0, 1.0e-3]",
        );
        assert!(ok.validate().is_ok());
        let nan = settings(
            "steps = 10\nstart = \"impulse\"\n[impulse]\npoint = [0.0, nan, 0.0]\nvalue = [0.0, 0.0, 1.0]",
        );
        assert!(nan.validate().unwrap_err().contains("finite"));
        assert!(toml::from_str::<TransientSettings>("steps = 1\nstart = \"noise\"").is_err());
    }

    #[test]
    fn random_coefficients_are_seeded_uniform_and_reproducible() {
        let a = random_coefficients(7, 20_000);
        assert_eq!(a, random_coefficients(7, 20_000));
        assert_ne!(a[..10], random_coefficients(8, 10)[..]);
        assert!(a.iter().all(|x| (-1.0..1.0).contains(x)));
        // Uniform on [-1, 1): mean 0 and variance 1/3, to a few standard errors.
        let n = a.len() as f64;
        let mean = a.iter().sum::<f64>() / n;
        let variance = a.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        assert!(mean.abs() < 4.0 * (1.0f64 / 3.0 / n).sqrt(), "mean {mean}");
        assert!((variance - 1.0 / 3.0).abs() < 0.01, "variance {variance}");
    }
}
