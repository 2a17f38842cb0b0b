//! The transient's checkpoint: the state, the step control, the state the Jacobian was built
//! at and how many rows the stream held, written atomically (temporary file, then rename).

use super::{io_error, Transient, TransientFiles, TransientSettings};
use crate::io::series::SeriesFile;
use crate::la::{Petsc, Vector};
use crate::time::newmark::{State, StepControl, TimeError};

/// A resumable point of the run: the state, the step control, the state J was built at, and
/// how many rows the stream held.
pub(super) struct Checkpoint<'p> {
    pub state: State<'p>,
    pub control: StepControl,
    pub jacobian_at: Option<(Vector<'p>, Vector<'p>)>,
    pub signal_rows: usize,
    pub state_rows: usize,
    pub state_time: f64,
}

impl<'p> Checkpoint<'p> {
    /// Writes checkpoint.h5 (through a temporary file renamed when complete, so an
    /// interruption while writing keeps the previous checkpoint).
    ///
    /// # Collective
    pub fn write(
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
                ("krylov_retries", c.krylov_retries as f64),
                ("full_newton_retries", c.full_newton_retries as f64),
                ("fallback", f64::from(c.fallback)),
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
    pub fn read(
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
            let mut x = like.q.duplicate()?;
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
            krylov_retries: number("krylov_retries")? as usize,
            full_newton_retries: number("full_newton_retries")? as usize,
            fallback: number("fallback")? as u8,
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
