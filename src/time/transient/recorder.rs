//! What the transient keeps of every step: the signals (time, step size, iterations, forces
//! and torque per interface, sensors) in memory and streamed to transient.h5 in chunks, and
//! the states every `state_interval` of simulated time.

use super::checkpoint::Checkpoint;
use super::hooks::StateSampler;
use super::{Sensors, Transient, TransientFiles, TransientInputs};
use crate::contact::{ContactModel, ContactState, InterfaceSummary};
use crate::la::{LaError, Petsc, Vector};
use crate::time::newmark::{State, TimeError};
use crate::time::store::Series;
use std::path::PathBuf;

/// Signal rows buffered before they are appended to the file.
const FLUSH_ROWS: usize = 1000;
/// Stored states buffered before they are appended (at most; every flush of the signals
/// takes them too): five appends per state each cost more than the small brake's state
/// (written one by one, they took 0.11 of its 1.05 ms per step),
/// and 64 of the 600k model's reduced states are ~18 MB per rank.
const FLUSH_STATES: usize = 64;
const STATE_PATHS: [&str; 3] = ["states/time", "states/displacement", "states/velocity"];
/// The real modes' coordinates at the stored states, taken as the run goes: the stored
/// states are coordinates on a reduction basis that a restart may recompute rotated, the
/// modal coordinates are not (their own real modes).
const MODAL_PATHS: [&str; 3] = [
    "states/modal_coordinate",
    "states/modal_velocity",
    "states/kinetic_energy",
];

/// The full-rate series of the stream.
fn signal_paths(interfaces: &[String]) -> Vec<String> {
    let mut v: Vec<String> = [
        "time",
        "step_size",
        "iterations",
        "wall_seconds",
        "braking_torque",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for name in interfaces {
        for s in [
            "normal_force",
            "friction_force",
            "torque",
            "open_points",
            "stick_points",
            "slip_points",
        ] {
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

/// The signals of the run so far and their stream.
pub(super) struct Recorder<'a, 'p> {
    petsc: &'p Petsc<'p>,
    contact: &'a ContactModel<'p>,
    sensors: Option<&'a Sensors<'p>>,
    modal: Option<&'a dyn StateSampler<'p>>,
    sensor_buffer: Option<Vector<'p>>,
    stream: Box<dyn Series>,
    names: Vec<String>,
    /// Signal rows already in the stream.
    written: usize,
    /// Simulated time between stored states (0: none).
    interval: f64,
    /// States sampled and not yet in the stream.
    pending: PendingStates,
    pub out: Transient,
}

/// Stored states not yet appended: each series' rows, row-major (this rank's columns of the
/// displacement and velocity).
#[derive(Default)]
struct PendingStates {
    rows: usize,
    columns: std::ops::Range<usize>,
    time: Vec<f64>,
    displacement: Vec<f64>,
    velocity: Vec<f64>,
}

impl<'a, 'p> Recorder<'a, 'p> {
    /// A fresh stream with the start recorded (and stored as the first state).
    ///
    /// # Collective
    pub fn create(
        petsc: &'p Petsc<'p>,
        files: &TransientFiles,
        input: &TransientInputs<'a, 'p>,
        interval: f64,
        out: Transient,
        start: &State<'p>,
    ) -> Result<Self, TimeError> {
        let stream = files.storage.create(&files.stream)?;
        let mut r = Self::new(petsc, input, interval, out, stream)?;
        for path in signal_paths(&r.names) {
            let units = match path.rsplit('/').next().unwrap_or("") {
                "time" | "step_size" | "wall_seconds" => "s",
                "iterations" => "1",
                "torque" | "braking_torque" => "N m",
                "open_points" | "stick_points" | "slip_points" => "1",
                _ => "N",
            };
            r.stream.create_series(&path, 1, units)?;
        }
        for (k, path) in sensor_paths(&r.out.sensor_names).iter().enumerate() {
            let units = ["m", "m/s", "m/s^2"][k % 3];
            r.stream.create_series(path, 3, units)?;
        }
        let n = start.q.global_len();
        for (path, width, units) in [
            ("states/time", 1, "s"),
            ("states/displacement", n, "m"),
            ("states/velocity", n, "m/s"),
        ] {
            r.stream.create_series(path, width, units)?;
        }
        if let Some(modal) = r.modal {
            let m = modal.count();
            for (path, width, units) in MODAL_PATHS
                .iter()
                .zip([m, m, 1])
                .zip(["m kg^0.5", "m kg^0.5/s", "J"])
                .map(|((p, w), u)| (p, w, u))
            {
                r.stream.create_series(path, width, units)?;
            }
        }
        r.record(start, 0.0, 0, 0.0, None)?;
        if interval > 0.0 {
            r.write_state(start)?;
            r.out.states = 1;
        }
        Ok(r)
    }

    /// The existing stream cut back to the checkpoint's rows, its signals read back (for the
    /// summary and the plots).
    ///
    /// # Collective
    pub fn resume(
        petsc: &'p Petsc<'p>,
        files: &TransientFiles,
        input: &TransientInputs<'a, 'p>,
        interval: f64,
        out: Transient,
        checkpoint: &Checkpoint<'p>,
    ) -> Result<Self, TimeError> {
        let stream = files.storage.open(&files.stream)?;
        let mut r = Self::new(petsc, input, interval, out, stream)?;
        let modal_missing = r.modal.is_some() && !r.stream.has(MODAL_PATHS[0]);
        if !r.stream.has("wall_seconds") || modal_missing {
            return Err(TimeError::Restart {
file: files.stream.clone(),
 reason: format!(
                "--restart: {} was written by an older squeal (it has no wall_seconds or modal coordinate series); run without --restart to start afresh",
                files.stream.display()
            ),
});
        }
        let rows = checkpoint.signal_rows;
        let sensor_series = sensor_paths(&r.out.sensor_names);
        for path in signal_paths(&r.names).iter().chain(&sensor_series) {
            r.stream.truncate(path, rows)?;
        }
        let modal_paths = if r.modal.is_some() {
            &MODAL_PATHS[..]
        } else {
            &[]
        };
        for path in STATE_PATHS.iter().chain(modal_paths) {
            r.stream.truncate(path, checkpoint.state_rows)?;
        }
        r.stream.flush()?;
        let read = |p: &str| r.stream.read(p);
        let out = &mut r.out;
        out.time = read("time")?;
        out.step_size = read("step_size")?;
        out.iterations = read("iterations")?
            .into_iter()
            .map(|x| x as usize)
            .collect();
        out.wall_seconds = read("wall_seconds")?;
        for (i, name) in r.names.iter().enumerate() {
            out.normal_force[i] = read(&format!("interfaces/{name}/normal_force"))?;
            out.friction_force[i] = read(&format!("interfaces/{name}/friction_force"))?;
            out.torque[i] = read(&format!("interfaces/{name}/torque"))?;
            for (k, status) in ["open", "stick", "slip"].iter().enumerate() {
                out.status_points[i][k] = read(&format!("interfaces/{name}/{status}_points"))?;
            }
        }
        for (i, chunk) in sensor_series.chunks(3).enumerate() {
            for (kind, path) in chunk.iter().enumerate() {
                out.sensor_values[i][kind] = read(path)?;
            }
        }
        out.states = checkpoint.state_rows;
        out.resumed_at = Some(checkpoint.state_time);
        r.written = r.stream.rows("time")?;
        Ok(r)
    }

    fn new(
        petsc: &'p Petsc<'p>,
        input: &TransientInputs<'a, 'p>,
        interval: f64,
        out: Transient,
        stream: Box<dyn Series>,
    ) -> Result<Self, TimeError> {
        let (contact, sensors) = (input.contact, input.sensors);
        let sensor_buffer = match sensors {
            Some(s) => Some(s.rows.new_point_vector()?),
            None => None,
        };
        Ok(Recorder {
            petsc,
            contact,
            sensors,
            modal: input.modal_sensors.filter(|_| interval > 0.0),
            sensor_buffer,
            stream,
            names: contact
                .interfaces()
                .iter()
                .map(|i| i.name.clone())
                .collect(),
            written: 0,
            interval,
            pending: PendingStates::default(),
            out,
        })
    }

    /// Appends one step's signals; `evaluated` is the contact state at `s` when the last
    /// force evaluation was there (saves one evaluation per step).
    ///
    /// # Collective
    pub fn record(
        &mut self,
        s: &State<'p>,
        h: f64,
        iterations: usize,
        wall_seconds: f64,
        evaluated: Option<&ContactState>,
    ) -> Result<(), LaError> {
        let contact = self.contact;
        let sums: Vec<InterfaceSummary> = match evaluated {
            Some(cs) => contact.summarize(self.petsc, cs),
            None => contact.summarize(self.petsc, &contact.evaluate(&s.q, Some(&s.v), 1.0)?),
        };
        let out = &mut self.out;
        out.time.push(s.time);
        out.step_size.push(h);
        out.iterations.push(iterations);
        out.wall_seconds.push(wall_seconds);
        for (i, sum) in sums.iter().enumerate() {
            out.normal_force[i].push(sum.normal_force);
            out.friction_force[i].push(sum.friction_force);
            out.torque[i].push(sum.torque);
            for (k, count) in [sum.open, sum.stick, sum.slip].into_iter().enumerate() {
                out.status_points[i][k].push(count as f64);
            }
        }
        if let (Some(sensors), Some(y)) = (self.sensors, &mut self.sensor_buffer) {
            // Each rank's rows into their place, then one sum over the ranks for all three.
            let n = y.global_len();
            let mut values = vec![0.0; 3 * n];
            let range = y.ownership();
            for (kind, x) in [&s.q, &s.v, &s.a].into_iter().enumerate() {
                sensors.rows.mult(x, y)?;
                values[kind * n + range.start..kind * n + range.end].copy_from_slice(&y.local()?);
            }
            crate::parallel::sum_in_place(self.petsc.world(), &mut values);
            for (kind, values) in values.chunks(n).enumerate() {
                for (k, v) in values.chunks(3).enumerate() {
                    out.sensor_values[sensors.order[k]][kind].extend_from_slice(v);
                }
            }
        }
        Ok(())
    }

    /// Stores the state when the next sampling time is reached.
    ///
    /// # Collective
    pub fn sample_state(&mut self, s: &State<'p>, h: f64) -> Result<(), TimeError> {
        let next = self.out.states as f64 * self.interval;
        if self.interval > 0.0 && s.time >= next - 1e-3 * h {
            self.write_state(s)?;
            self.out.states += 1;
        }
        Ok(())
    }

    /// Samples the state into the buffer, appended at the next flush or when full.
    ///
    /// # Collective
    fn write_state(&mut self, s: &State<'p>) -> Result<(), TimeError> {
        let p = &mut self.pending;
        p.columns = s.q.ownership();
        p.time.push(s.time);
        p.displacement.extend_from_slice(&s.q.local()?);
        p.velocity.extend_from_slice(&s.v.local()?);
        p.rows += 1;
        if p.rows >= FLUSH_STATES {
            self.write_pending_states()?;
        }
        Ok(())
    }

    /// Appends the buffered states to the stream.
    ///
    /// # Collective
    fn write_pending_states(&mut self) -> Result<(), TimeError> {
        let p = std::mem::take(&mut self.pending);
        if p.rows == 0 {
            return Ok(());
        }
        let stream = &self.stream;
        stream.append("states/time", &p.time)?;
        let columns = p.columns;
        stream.append_distributed(
            "states/displacement",
            &p.displacement,
            p.rows,
            columns.clone(),
        )?;
        stream.append_distributed("states/velocity", &p.velocity, p.rows, columns)?;
        if let Some(modal) = self.modal {
            // The modal samples of the whole block at once: the shapes are read once.
            let samples = modal.sample_block(&p.displacement, &p.velocity, p.rows)?;
            let eta: Vec<f64> = samples.iter().flat_map(|x| x.eta.iter().copied()).collect();
            let eta_dot: Vec<f64> = samples
                .iter()
                .flat_map(|x| x.eta_dot.iter().copied())
                .collect();
            let kinetic: Vec<f64> = samples.iter().map(|x| x.kinetic).collect();
            for (path, values) in MODAL_PATHS.iter().zip([eta, eta_dot, kinetic]) {
                stream.append(path, &values)?;
            }
        }
        Ok(())
    }

    /// Rows recorded but not yet in the stream.
    pub fn unwritten(&self) -> usize {
        self.out.time.len() - self.written
    }

    /// Appends the rows recorded since the last flush to the stream and flushes it.
    ///
    /// # Collective
    pub fn flush(&mut self) -> Result<(), TimeError> {
        let from = self.written;
        let out = &self.out;
        let its: Vec<f64> = out.iterations[from..].iter().map(|&i| i as f64).collect();
        let torque = out.braking_torque_from(from);
        let mut series: Vec<(String, &[f64])> = vec![
            ("time".into(), &out.time[from..]),
            ("step_size".into(), &out.step_size[from..]),
            ("iterations".into(), &its),
            ("wall_seconds".into(), &out.wall_seconds[from..]),
            ("braking_torque".into(), &torque),
        ];
        for (i, name) in self.names.iter().enumerate() {
            series.push((
                format!("interfaces/{name}/normal_force"),
                &out.normal_force[i][from..],
            ));
            series.push((
                format!("interfaces/{name}/friction_force"),
                &out.friction_force[i][from..],
            ));
            series.push((format!("interfaces/{name}/torque"), &out.torque[i][from..]));
            for (k, status) in ["open", "stick", "slip"].iter().enumerate() {
                series.push((
                    format!("interfaces/{name}/{status}_points"),
                    &out.status_points[i][k][from..],
                ));
            }
        }
        for (path, values) in series {
            self.stream.append(&path, values)?;
        }
        let sensor_series = sensor_paths(&out.sensor_names);
        for (i, chunk) in sensor_series.chunks(3).enumerate() {
            for (kind, path) in chunk.iter().enumerate() {
                let v = &out.sensor_values[i][kind];
                self.stream.append(path, &v[3 * from..])?;
            }
        }
        let written = out.time.len();
        self.write_pending_states()?;
        self.stream.flush()?;
        self.written = written;
        Ok(())
    }

    /// Flushes when a chunk is full or at the end.
    ///
    /// # Collective
    pub fn flush_if_due(&mut self, at_end: bool) -> Result<(), TimeError> {
        if self.unwritten() >= FLUSH_ROWS || at_end {
            self.flush()?;
        }
        Ok(())
    }
}

/// The step control's log (rank 0): every change in `transient.log` beside the stream (a
/// restart appends to it), the first few also on stdout, then one line saying where the rest
/// goes: a saturated run changes its step control hundreds of times; the summary counts them.
pub(super) struct StepLog {
    rank0: bool,
    file: Option<std::fs::File>,
    path: PathBuf,
    written: usize,
}

impl StepLog {
    pub(super) fn new(rank0: bool, path: PathBuf, append: bool) -> Self {
        let open = || {
            std::fs::OpenOptions::new()
                .create(true)
                .write(true)
                .append(append)
                .truncate(!append)
                .open(&path)
                .ok()
        };
        StepLog {
            rank0,
            file: if rank0 { open() } else { None },
            path,
            written: 0,
        }
    }

    /// A change of the step control: into transient.log (solver diagnostics stay off the
    /// console, which leads with the answer); on stdout only when the log cannot be written.
    pub(super) fn write(&mut self, line: &str) {
        use std::io::Write as _;
        if !self.rank0 {
            return;
        }
        let in_file = self
            .file
            .as_mut()
            .is_some_and(|f| writeln!(f, "{line}").is_ok());
        if !in_file {
            println!("  transient ({} not writable): {line}", self.path.display());
        }
        self.written += 1;
    }
}
