//! The transient's checkpoint: the state, the step control, the state the Jacobian was built
//! at and how many rows the stream held, written atomically (temporary file, then rename).

use super::{Transient, TransientFiles, TransientInputs, TransientSettings};
use crate::la::{LaError, Petsc, Vector};
use crate::measure::nan_max;
use crate::time::adaptive::StepControl;
use crate::time::newmark::{State, TimeError};
use crate::time::store::Series;

/// w^T K w and w^T M w of the integrated operators for a fixed w (w_i = sin(0.7 i + 0.3) over
/// global indices): they change when the operators do (another model, or a reduction basis
/// that came out rotated inside a doublet).
///
/// # Collective
fn operator_fingerprint<'p>(
    input: &TransientInputs<'_, 'p>,
    like: &Vector<'p>,
) -> Result<[f64; 2], LaError> {
    let mut w = like.duplicate()?;
    let start = like.ownership().start;
    for (i, x) in w.local_mut()?.iter_mut().enumerate() {
        *x = (0.7 * (start + i) as f64 + 0.3).sin();
    }
    let mut product = like.duplicate()?;
    input.k0.mult(&w, &mut product)?;
    let k = product.dot(&w)?;
    input.m.mult(&w, &mut product)?;
    Ok([k, product.dot(&w)?])
}

/// A 52-bit hash as an exact f64 (the checkpoint stores numbers).
fn hash_number(h: u64) -> f64 {
    (h >> 12) as f64
}

/// Whether a `--restart` can resume from the checkpoint: both files there, written by a
/// squeal that records its scene, for a scene with the same restart fingerprint, on as many
/// ranks, with the same nominal step (and, once the model is built, as many unknowns). Run
/// before the stages ahead of the transient too, so a refusal costs seconds and not the
/// front (12.5 min at 600k).
///
/// # Collective
pub fn check_resumable(
    petsc: &Petsc,
    files: &TransientFiles,
    settings: &TransientSettings,
    unknowns: Option<usize>,
) -> Result<(), TimeError> {
    let path = &files.checkpoint;
    let refuse = |reason: String| TimeError::Restart {
        file: path.to_path_buf(),
        reason,
    };
    if !path.exists() || !files.stream.exists() {
        return Err(refuse(format!(
            "--restart: {} or {} is missing; run without --restart to start from the static state",
            path.display(),
            files.stream.display()
        )));
    }
    let f = files.storage.open(path)?;
    let expect = |name: &str, value: f64, what: &str| -> Result<(), TimeError> {
        let stored = f.number(name)?;
        if stored != value {
            return Err(refuse(format!(
                "--restart: {} was written with {what} = {stored}, this run has {value}; \
                 restart with the same {what}",
                path.display()
            )));
        }
        Ok(())
    };
    if f.number("operators_k").is_err() {
        return Err(refuse(format!(
            "--restart: {} was written by an older squeal (it does not say which scene \
             and model it belongs to); run without --restart",
            path.display()
        )));
    }
    for (table, hash) in &files.scene {
        if f.number(&format!("scene_{table}"))? != hash_number(*hash) {
            return Err(refuse(format!(
                "--restart: the scene's [{table}] differs from the one that wrote {}; \
                 restart with that scene (only the number of steps, the solver's \
                 controls, outputs, sensors and [post] may change) or run without \
                 --restart",
                path.display()
            )));
        }
    }
    expect("ranks", petsc.size() as f64, "number of MPI ranks")?;
    expect("nominal_step", settings.step, "key 'transient.step'")?;
    if let Some(n) = unknowns {
        expect("unknowns", n as f64, "model (unknowns)")?;
    }
    Ok(())
}

/// A resumable point of the run: the state, the step control, the state J was built at, and
/// how many rows the stream held.
pub(super) struct Checkpoint<'p> {
    pub state: State<'p>,
    pub control: StepControl,
    pub jacobian_at: Option<(Vector<'p>, Vector<'p>)>,
    pub signal_rows: usize,
    pub state_rows: usize,
    pub state_time: f64,
    /// What the restart had to do beyond reading (a re-projection), for the log.
    pub note: Option<String>,
}

impl<'p> Checkpoint<'p> {
    /// Writes checkpoint.h5 (through a temporary file renamed when complete, so an
    /// interruption while writing keeps the previous checkpoint).
    ///
    /// # Collective
    #[allow(clippy::too_many_arguments)] // the run's files, settings, model, state and record
    pub fn write(
        petsc: &'p Petsc,
        files: &TransientFiles,
        settings: &TransientSettings,
        input: &TransientInputs<'_, 'p>,
        s: &State<'p>,
        c: &StepControl,
        jacobian_at: Option<&(Vector<'p>, Vector<'p>)>,
        out: &Transient,
    ) -> Result<(), TimeError> {
        let world = petsc.world();
        let tmp = files.checkpoint.with_extension("h5.tmp");
        {
            let f = files.storage.create(&tmp)?;
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
                ("krylov_retries", c.krylov_retries as f64),
                ("full_newton_retries", c.full_newton_retries as f64),
                ("fallback", f64::from(c.fallback)),
                ("updated_retries", c.updated_retries as f64),
                ("failed_iterations", c.failed_iterations as f64),
                ("failed_solves", c.failed_solves as f64),
                ("failed_seconds", c.failed_seconds),
                ("signal_rows", out.time.len() as f64),
                ("state_rows", out.states as f64),
                ("jacobian_state", f64::from(u8::from(jacobian_at.is_some()))),
                ("linear_state", f64::from(u8::from(s.linear.is_some()))),
            ];
            for (name, value) in numbers {
                f.set_number(name, value)?;
            }
            for (table, hash) in &files.scene {
                f.set_number(&format!("scene_{table}"), hash_number(*hash))?;
            }
            let [k, m] = operator_fingerprint(input, &s.q)?;
            f.set_number("operators_k", k)?;
            f.set_number("operators_m", m)?;
            write_states(petsc, &*f, input, s, jacobian_at)?;
            f.flush()?;
        }
        crate::parallel::barrier(world);
        if petsc.rank() == 0 {
            std::fs::rename(&tmp, &files.checkpoint).map_err(|e| TimeError::Checkpoint {
                file: files.checkpoint.clone(),
                source: e,
            })?;
        }
        crate::parallel::barrier(world);
        Ok(())
    }

    /// Reads checkpoint.h5 for a run with `settings` on this layout (`like` gives the vector
    /// layout): the ranks, the number of unknowns and the nominal step must match.
    ///
    /// # Collective
    pub fn read(
        petsc: &'p Petsc,
        files: &TransientFiles,
        settings: &TransientSettings,
        input: &TransientInputs<'_, 'p>,
        like: &State<'p>,
    ) -> Result<Self, TimeError> {
        check_resumable(petsc, files, settings, Some(like.q.global_len()))?;
        let path = &files.checkpoint;
        let f = files.storage.open(path)?;
        let number = |name: &str| f.number(name);
        let range = like.q.ownership();
        let vector = |name: &str| -> Result<Vector<'p>, TimeError> {
            let mut x = like.q.duplicate()?;
            let values = f.read_vector(name, range.clone())?;
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
            krylov_retries: number("krylov_retries")? as usize,
            full_newton_retries: number("full_newton_retries")? as usize,
            fallback: number("fallback")? as u8,
            // (Absent from checkpoints written before these counts existed.)
            updated_retries: number("updated_retries").unwrap_or(0.0) as usize,
            failed_iterations: number("failed_iterations").unwrap_or(0.0) as usize,
            failed_solves: number("failed_solves").unwrap_or(0.0) as usize,
            failed_seconds: number("failed_seconds").unwrap_or(0.0),
        };
        let state_rows = number("state_rows")? as usize;
        let mut checkpoint = Checkpoint {
            state_time: state.time,
            state,
            control,
            jacobian_at,
            signal_rows: number("signal_rows")? as usize,
            state_rows,
            note: None,
        };
        let stored = [number("operators_k")?, number("operators_m")?];
        let now = operator_fingerprint(input, &like.q)?;
        let same = (0..2).all(|i| (stored[i] - now[i]).abs() <= 1e-10 * now[i].abs());
        if !same {
            let Some(r) = input.reduction else {
                return Err(TimeError::Restart {
                    file: path.to_path_buf(),
                    reason: format!(
                        "--restart: the model's operators differ from those that wrote {} \
                     (w'Kw {:.12e} vs {:.12e}); restart with the same scene and model",
                        path.display(),
                        now[0],
                        stored[0]
                    ),
                });
            };
            checkpoint.note = Some(checkpoint.reproject(petsc, &*f, r, stored, now, path)?);
        }
        Ok(checkpoint)
    }

    /// The reduction basis came out different from the one that wrote the checkpoint (MUMPS
    /// in parallel is not bitwise reproducible, and the disc's doublets may rotate): the
    /// reduced coordinates are recomputed from the full-model state the checkpoint keeps, and
    /// the carried linear force is recomputed at the first step. Fails when the new basis
    /// does not hold that state (then the model changed).
    ///
    /// # Collective
    fn reproject(
        &mut self,
        petsc: &'p Petsc,
        f: &dyn Series,
        r: &crate::reduce::Reduction,
        stored: [f64; 2],
        now: [f64; 2],
        path: &std::path::Path,
    ) -> Result<String, TimeError> {
        let mut full = r.full_vector(petsc)?;
        let range = full.ownership();
        let mut recovered = full.duplicate()?;
        let mut worst = 0.0f64;
        let mut project = |name: &str| -> Result<Vector<'p>, TimeError> {
            let values = f.read_vector(name, range.clone())?;
            full.local_mut()?.copy_from_slice(&values);
            let x = r.restrict(petsc, &full)?;
            r.recover(petsc, &x, &mut recovered)?;
            let size = full.norm2()?;
            recovered.axpy(-1.0, &full)?;
            if size > 0.0 {
                worst = nan_max(worst, recovered.norm2()? / size);
            }
            Ok(x)
        };
        self.state.q = project("full_q")?;
        self.state.v = project("full_v")?;
        self.state.a = project("full_a")?;
        self.state.linear = None;
        if self.jacobian_at.is_some() {
            self.jacobian_at = Some((project("full_jacobian_q")?, project("full_jacobian_v")?));
        }
        // The span must hold the state (to the basis' orthonormality, ~1e-9).
        if worst.is_nan() || worst > 1e-6 {
            return Err(TimeError::Restart {
                file: path.to_path_buf(),
                reason: format!(
                    "--restart: the reduction basis of this run does not hold the checkpoint's \
                 state (relative error {worst:.1e}): the model changed; restart with the same \
                 scene or run without --restart"
                ),
            });
        }
        Ok(format!(
            "the reduced operators differ from the checkpoint's (w'Kw {:.9e} vs {:.9e}, \
             w'Mw {:.9e} vs {:.9e}: the real modes came out rotated or perturbed); the state \
             was re-projected from its full-model values (relative error {worst:.1e})",
            now[0], stored[0], now[1], stored[1]
        ))
    }
}

/// The state (and the state J was built at) into a checkpoint, and on a reduced run the
/// full-model state as well: what the reduced coordinates mean.
///
/// # Collective
fn write_states<'p>(
    petsc: &'p Petsc,
    f: &dyn Series,
    input: &TransientInputs<'_, 'p>,
    s: &State<'p>,
    jacobian_at: Option<&(Vector<'p>, Vector<'p>)>,
) -> Result<(), TimeError> {
    if let Some(r) = input.reduction {
        let mut states = vec![("full_q", &s.q), ("full_v", &s.v), ("full_a", &s.a)];
        if let Some((q, v)) = jacobian_at {
            states.push(("full_jacobian_q", q));
            states.push(("full_jacobian_v", v));
        }
        let mut full = r.full_vector(petsc)?;
        for (name, x) in states {
            r.recover(petsc, x, &mut full)?;
            let (range, n) = (full.ownership(), full.global_len());
            f.write_vector(name, &full.local()?, range, n)?;
        }
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
        f.write_vector(name, &x.local()?, range.clone(), n)?;
    }
    Ok(())
}
