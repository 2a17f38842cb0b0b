//! The analyses after the transient that `[post]` asks for: the time/frequency link on the
//! stored states and the pseudo trajectories (compared with the transient when it stored
//! states). The stored states are opened once, here, and handed to the stages.

use std::path::{Path, PathBuf};

use crate::eigen::complex_modes::ComplexModeSettings;
use crate::fault::end_on_write_failure;
use crate::io::results::ResultsFile;
use crate::io::series::SeriesFile;
use crate::la::Petsc;
use crate::post::limit_cycle::LimitCycle;
use crate::post::states::{Lift, StoredStates};
use crate::report::vibration::{self, Frames};
use crate::scene::Scene;
use crate::stages::link::{self, LinearizationSettings, Link, Nominal};
use crate::stages::loudness::{self, LoudnessReport, StoredRun};
use crate::stages::post::LimitCycleReport;
use crate::stages::pseudo::{self, PseudoReport};
use crate::stages::transient::Trajectory;
use crate::stages::{Analyses, RunError, Timings};

/// What the analyses after the transient work on.
pub(super) struct AfterTransient<'a, 'p> {
    petsc: &'p Petsc<'p>,
    scene: &'a Scene,
    nominal: Option<Nominal<'a, 'p>>,
    trajectory: Option<&'a Trajectory>,
    /// The run's characterization: `[post.limit_cycle]`'s, else the torque's with the
    /// default settings (the analyses need the run's period).
    cycle: Option<std::borrow::Cow<'a, LimitCycle>>,
    stream: PathBuf,
    /// The mesh and DOF map the radiating surfaces live on.
    mesh: Option<&'a crate::mesh::Mesh>,
    dofs: Option<&'a crate::fem::dofmap::DofMap>,
}

/// What the analyses after the transient found; each failure is kept for after the results
/// are written.
pub(super) struct After {
    pub link: Result<Link, RunError>,
    pub pseudo: Result<Option<PseudoReport>, RunError>,
    pub loudness: Result<Option<LoudnessReport>, RunError>,
}

pub(super) fn after_transient<'a, 'p>(
    petsc: &'p Petsc<'p>,
    scene: &'a Scene,
    a: &'a Analyses<'p>,
    trajectory: Option<&'a Trajectory>,
    limit_cycle: &'a Option<LimitCycleReport>,
    output: &Path,
) -> AfterTransient<'a, 'p> {
    let nominal = match (&a.preload, &a.modes) {
        (Some(preload), Some(modes)) => Some(Nominal {
            preload,
            modes,
            reduced: a.reduced.as_ref(),
        }),
        _ => None,
    };
    let cycle = trajectory.map(|t| match limit_cycle {
        Some(r) => std::borrow::Cow::Borrowed(&r.cycle),
        None => std::borrow::Cow::Owned(link::characterize(t)),
    });
    AfterTransient {
        petsc,
        scene,
        nominal,
        trajectory,
        cycle,
        stream: output.join("transient.h5"),
        mesh: a.model.as_ref().map(|m| &m.mesh),
        dofs: a.ops.dofs.as_ref(),
    }
}

impl AfterTransient<'_, '_> {
    /// The link analyses and the pseudo trajectories; each failure is kept for after the
    /// results are written.
    ///
    /// # Collective
    pub fn run(&self, timings: &mut Timings) -> After {
        let post = self.scene.post.as_ref();
        let wants_link = post.is_some_and(|p| p.uses_states()) && self.trajectory.is_some();
        let stored = self
            .trajectory
            .is_some_and(|t| t.signals.state_interval > 0.0 && self.scene.transient.is_some());
        let wants_pseudo = post.is_some_and(|p| p.pseudo_trajectory.is_some());
        let wants_loudness = post.is_some_and(|p| p.loudness.is_some());
        let compared = (wants_pseudo || wants_loudness) && stored;
        let opened = match (wants_link || compared, self.nominal) {
            (true, Some(_)) => Some(self.open_states()),
            _ => None,
        };
        // A failure to read the states goes to the first analysis that needed them.
        let (states, mut failure) = match opened {
            Some(Ok(s)) => (Some(s), None),
            Some(Err(e)) => (None, Some(e)),
            None => (None, None),
        };
        let link = match (&states, wants_link) {
            (_, false) => Ok(Link::default()),
            (Some(s), true) => self.link(s, timings),
            (None, true) => failure.take().map_or(Ok(Link::default()), Err),
        };
        let pseudo = match failure.take() {
            Some(e) => Err(e),
            None => self.pseudo(states.as_ref().filter(|_| stored), timings),
        };
        let loudness = match &pseudo {
            Err(_) => Ok(None),
            Ok(p) => self.loudness(p.as_ref(), states.as_ref().filter(|_| stored), timings),
        };
        After {
            link,
            pseudo,
            loudness,
        }
    }

    /// The transient's vibration on the mesh (`[output] frame_periods`, `frames_per_period`)
    /// written into `file`: None when the run stored no states, has no mesh, or no frame is
    /// asked for. A read failure is returned; a failed write ends the run (the shared file
    /// cannot be closed after it).
    ///
    /// # Collective
    pub fn write_frames(
        &self,
        file: &ResultsFile,
        timings: &mut Timings,
    ) -> Result<Option<Frames>, RunError> {
        let output = &self.scene.output;
        let stored = self
            .trajectory
            .is_some_and(|t| t.signals.state_interval > 0.0);
        let (Some(nominal), Some(dofs), Some(cycle), true) =
            (self.nominal, self.dofs, &self.cycle, stored)
        else {
            return Ok(None);
        };
        if output.frame_periods <= 0.0 {
            return Ok(None);
        }
        timings.stage(
            "vibration frames",
            || -> Result<Option<Frames>, RunError> {
                let states = self.open_states()?;
                let period = link::period_of(cycle);
                let (periods, per_period) = (output.frame_periods, output.frames_per_period);
                let Some(frames) = Frames::choose(&states.times, period, periods, per_period)
                else {
                    return Ok(None);
                };
                let at = nominal.contact_at(self.petsc);
                let mut x = at.state_template.duplicate()?;
                let mut xv = at.state_template.duplicate()?;
                let mut q = at.full_template.duplicate()?;
                let q_static = at.full_template.local()?.to_vec();
                for (k, &i) in frames.states.iter().enumerate() {
                    states.read(i, &mut x, &mut xv)?;
                    let full = match at.lift {
                        Lift::Full => &x,
                        Lift::Reduced(r) => {
                            r.recover(self.petsc, &x, &mut q)?;
                            &q
                        }
                    };
                    let local: Vec<f64> = (full.local()?.iter().zip(&q_static))
                        .map(|(a, b)| a - b)
                        .collect();
                    let written = vibration::write_frame(file, k, dofs, &local);
                    end_on_write_failure(written, "results.h5");
                }
                end_on_write_failure(vibration::write_times(file, &frames), "results.h5");
                Ok(Some(frames))
            },
        )
    }

    /// # Collective
    fn open_states(&self) -> Result<StoredStates<'static>, RunError> {
        let open = || -> Result<StoredStates<'static>, RunError> {
            let file = SeriesFile::open(self.petsc.world(), &self.stream)?;
            let name = self.stream.display().to_string();
            Ok(StoredStates::new(Box::new(file), name, 2)?)
        };
        crate::fault::checked(open())
    }

    fn linearization(&self) -> LinearizationSettings {
        let margin = self
            .scene
            .complex_modes
            .as_ref()
            .map_or(ComplexModeSettings::default().instability_margin, |c| {
                c.instability_margin
            });
        LinearizationSettings {
            damping: self.scene.damping.unwrap_or_default(),
            margin,
        }
    }

    /// # Collective
    fn link(&self, states: &StoredStates, timings: &mut Timings) -> Result<Link, RunError> {
        let (Some(post), Some(nominal), Some(t), Some(cycle)) =
            (&self.scene.post, self.nominal, self.trajectory, &self.cycle)
        else {
            return Ok(Link::default());
        };
        let lin = self.linearization();
        link::link(self.petsc, post, lin, nominal, t, states, cycle, timings)
    }

    /// # Collective
    fn pseudo(
        &self,
        states: Option<&StoredStates>,
        timings: &mut Timings,
    ) -> Result<Option<PseudoReport>, RunError> {
        let Some(settings) = self
            .scene
            .post
            .as_ref()
            .and_then(|p| p.pseudo_trajectory.as_ref())
        else {
            return Ok(None);
        };
        let Some(nominal) = self.nominal else {
            let message = "needs [statics] and [real_modes]";
            return Err(RunError::scene("post.pseudo_trajectory", message));
        };
        let comparison = match (states, self.trajectory, &self.cycle) {
            (Some(states), Some(t), Some(cycle)) => Some(pseudo::Comparison {
                states,
                cycle,
                // The stepping's wall time summed over restarts (a restart of a finished
                // run steps nothing).
                transient_seconds: t.signals.wall_seconds.last().copied().unwrap_or(f64::NAN),
            }),
            _ => None,
        };
        let lin = self.linearization();
        timings
            .stage("pseudo trajectories", || {
                pseudo::pseudo_trajectories(self.petsc, nominal, lin, settings, comparison)
            })
            .map(Some)
    }

    /// # Collective
    fn loudness(
        &self,
        pseudo: Option<&PseudoReport>,
        states: Option<&StoredStates>,
        timings: &mut Timings,
    ) -> Result<Option<LoudnessReport>, RunError> {
        let Some(settings) = self.scene.post.as_ref().and_then(|p| p.loudness.as_ref()) else {
            return Ok(None);
        };
        let (Some(nominal), Some(mesh), Some(dofs)) = (self.nominal, self.mesh, self.dofs) else {
            let message = "needs a mesh model, [statics] and [real_modes]";
            return Err(RunError::scene("post.loudness", message));
        };
        let run = match (states, &self.cycle) {
            (Some(states), Some(cycle)) => Some(StoredRun { states, cycle }),
            _ => None,
        };
        timings
            .stage("loudness", || {
                let radiator = loudness::radiator(self.petsc, mesh, dofs, settings)?;
                let lin = self.linearization();
                let mut unstable = pseudo::unstable_modes(self.petsc, nominal, lin)?;
                // The modes the complex-modes stage reports (below its f_max).
                let f_max = self.scene.complex_modes.as_ref().and_then(|c| c.f_max_hz);
                let top = f_max.unwrap_or(f64::INFINITY) * 2.0 * std::f64::consts::PI;
                unstable.retain(|m| m.nominal.1 <= top);
                let (p, s) = (self.petsc, settings);
                loudness::loudness(p, &radiator, s, nominal, &unstable, pseudo, run)
            })
            .map(Some)
    }
}
