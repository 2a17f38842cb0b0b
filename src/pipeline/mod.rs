//! The driver: runs the stages a scene asks for (`crate::stages`, in order), times them and
//! hands each output to its writer (`crate::report`). No physics and no output code here.
//! Every failure is agreed on by all ranks where it happens (`crate::fault::checked`), before
//! collective objects (HDF5 files, MUMPS factors) are dropped: a rank that fails alone ends
//! the run instead of hanging the others.

use std::path::Path;

use mpi::topology::SimpleCommunicator;
use mpi::traits::Communicator;
use std::time::Instant;

mod after;
mod front;
pub mod groups;
mod matrix;
pub mod merge;

use crate::fault::{checked, end_on_write_failure};
use crate::io::results::ResultsFile;
use crate::io::series::Hdf5Storage;
use crate::la::Petsc;
use crate::report::{self, contact_map::MapContext};
use crate::scene::Scene;
use crate::stages::{self, RunError, Timings};
use crate::time::store::Storage;
use crate::time::transient::TransientFiles;
use after::after_transient;

/// The results file's name in messages.
const RESULTS: &str = "results.h5";

pub use crate::report::summary::RunSummary;
pub use crate::stages::model::build_model;

/// How to run beyond the scene.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Resume the transient from output/checkpoint.h5 (everything before it is recomputed,
    /// deterministically, and written again), and the noise matrix from its journal.
    pub restart: bool,
    /// The part of the noise matrix' points this run computes.
    pub slice: crate::matrix::sample::Slice,
}

/// Runs a scene. `scene_dir` resolves relative paths of model files; `scene_text` is stored
/// in the results for reproducibility.
///
/// # Collective
pub fn run(
    petsc: &Petsc,
    scene: &Scene,
    scene_text: &str,
    scene_dir: &Path,
    output: &Path,
    petsc_options: &[String],
) -> Result<RunSummary, RunError> {
    let options = RunOptions::default();
    run_with(
        petsc,
        scene,
        scene_text,
        scene_dir,
        output,
        petsc_options,
        &options,
    )
}

/// [`run`] with options: the analyses, their results in results.h5, then the transient
/// (streamed), its plots, the XDMF and the timings.
///
/// # Collective
pub fn run_with(
    petsc: &Petsc,
    scene: &Scene,
    scene_text: &str,
    scene_dir: &Path,
    output: &Path,
    petsc_options: &[String],
    options: &RunOptions,
) -> Result<RunSummary, RunError> {
    if options.restart && scene.transient.is_none() && scene.matrix.is_none() {
        let message = "--restart resumes a transient or a noise matrix: the scene has neither";
        return Err(RunError::scene("transient", message));
    }
    if options.slice != crate::matrix::sample::Slice::WHOLE && scene.matrix.is_none() {
        let message = format!(
            "--slice {} divides the points of a noise matrix: the scene has none",
            options.slice
        );
        return Err(RunError::scene("matrix", message));
    }
    checked(matrix::check_journal(scene, output, options))?;
    // A restart the checkpoint refuses is refused now, not after the stages before it.
    if let (true, Some(settings)) = (options.restart, &scene.transient) {
        let storage = Hdf5Storage {
            comm: petsc.world(),
        };
        let files = TransientFiles::in_directory(&storage, output, true)
            .with_scene(scene.restart_fingerprint());
        let resumable = crate::time::transient::check_resumable(petsc, &files, settings, None);
        checked(resumable.map_err(RunError::from))?;
    }
    let created = prepare_output(petsc.world(), output)?;
    let mut timings = Timings::default();
    let a = front::analyses(petsc, scene, scene_dir, output, &mut timings).inspect_err(|_| {
        // A run that failed before writing leaves no empty folder behind.
        if created && petsc.rank() == 0 {
            let _ = std::fs::remove_dir(output);
        }
    })?;

    // What the stages before the transient found goes to results.h5 before it starts.
    let start = Instant::now();
    let file = checked(ResultsFile::create(
        petsc.world(),
        &output.join("results.h5"),
    ))?;
    let header = (scene_text, petsc_options);
    let write_inp = scene.output.write_inp;
    let maps = MapContext::of(&a);
    let written = report::write_analyses(petsc, &file, &a, maps, header, write_inp, output);
    end_on_write_failure(written, RESULTS);
    let seconds_output = start.elapsed().as_secs_f64();
    end_on_write_failure(file.flush(), RESULTS);
    let noise = matrix::noise_matrix(petsc, scene, scene_text, &a, output, options, &mut timings)?;
    let start = Instant::now();
    if let Some(m) = &noise {
        let written = report::matrix::write_matrix(petsc.rank(), &file, m, output);
        end_on_write_failure(written.and_then(|_| Ok(file.flush()?)), RESULTS);
    }
    let seconds_output = seconds_output + start.elapsed().as_secs_f64();

    // The transient streams into transient.h5 (linked as /transient) while it runs.
    // A transient that fails to start or stops early still gets the summary and report of
    // what the run computed; its error comes last.
    let storage = Hdf5Storage {
        comm: petsc.world(),
    };
    let mut failure = None;
    let trajectory = transient(petsc, scene, &a, &storage, output, options, &mut timings)
        .map_err(|e| failure = Some(e))
        .ok()
        .flatten();
    let limit_cycle = match (&trajectory, &scene.post) {
        (Some(t), Some(post)) => post.limit_cycle.map(|lc| {
            timings.time("limit cycle", || {
                stages::post::limit_cycle(t, &lc, &a.complex, &a.interface_names())
            })
        }),
        _ => None,
    };
    let stage = after_transient(petsc, scene, &a, trajectory.as_ref(), &limit_cycle, output);
    let after = stage.run(&mut timings);
    let (link, pseudo, loudness) = (after.link, after.pseudo, after.loudness);
    let start = Instant::now();
    if let (Some(t), Some(settings)) = (&trajectory, &scene.transient) {
        let signals = &t.signals;
        let written = report::transient::write_transient(petsc, &file, signals, settings, output);
        end_on_write_failure(written, RESULTS);
        if let Some(lc) = &limit_cycle {
            let written = report::post::write_limit_cycle(petsc, &file, lc, signals, output);
            end_on_write_failure(written, RESULTS);
        }
        if let Ok(link) = &link {
            let dofs = a.ops.dofs.as_ref();
            let written = report::link::write_link(petsc, &file, link, maps, dofs, output);
            end_on_write_failure(written, RESULTS);
        }
    }
    if let Ok(Some(p)) = &pseudo {
        end_on_write_failure(
            report::pseudo::write_pseudo(petsc, &file, p, output),
            RESULTS,
        );
    }
    if let Ok(Some(l)) = &loudness {
        let written = report::loudness::write_loudness(petsc, &file, l, output);
        end_on_write_failure(written, RESULTS);
    }
    let frames = stage.write_frames(&file, &mut timings);
    let frames = frames.map_err(|e| failure = failure.take().or(Some(e)));
    let frames = frames.ok().flatten();
    write_views(petsc, &a, link.as_ref().ok(), frames.as_ref(), output)?;
    let seconds_output = seconds_output + start.elapsed().as_secs_f64();
    timings.stages.push(("output".into(), seconds_output));
    timings.slowest_rank(petsc.world());
    end_on_write_failure(report::write_timings(&file, &timings), RESULTS);
    drop(file);
    // Reported after the results are written: the steps before the failure are kept.
    let link = link?;
    let pseudo = pseudo?;
    let loudness = loudness?;
    let (signals, notes) = trajectory.map_or((None, Vec::new()), |t| {
        failure = failure.take().or(t.failure.map(RunError::Time));
        (Some(t.signals), t.notes)
    });

    let peak = crate::parallel::max(petsc.world(), petsc.peak_memory());
    let mut summary = RunSummary::of(petsc, a, signals.as_ref(), timings, peak, output)?;
    if let Some(t) = summary.transient.as_mut() {
        t.notes = notes;
        if let Some(frames) = &frames {
            t.notes
                .push(format!("vibration.xdmf: {}", frames.describe()));
        }
    }
    summary.limit_cycle = limit_cycle;
    summary.link = link;
    summary.pseudo = pseudo;
    summary.loudness = loudness;
    summary.matrix = noise;
    summary.failure = failure.as_ref().map(ToString::to_string);
    write_report(petsc, &summary, scene_text, output)?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

/// The output folder, created when missing (its parent must exist: a typo'd path is not
/// made silently); true when this call created it. Rank 0 decides and every rank returns
/// the same answer at once, so a folder that cannot be made ends the run cleanly.
///
/// # Collective
pub fn prepare_output(comm: &SimpleCommunicator, output: &Path) -> Result<bool, RunError> {
    let mut answer = String::new();
    if comm.rank() == 0 {
        answer = match output_problem(output) {
            Ok(true) => "created".into(),
            Ok(false) => "exists".into(),
            Err(problem) => problem,
        };
    }
    crate::parallel::broadcast_string(comm, 0, &mut answer);
    match answer.as_str() {
        "created" => Ok(true),
        "exists" => Ok(false),
        problem => Err(RunError::Io {
            path: output.to_path_buf(),
            source: std::io::Error::other(problem.to_string()),
        }),
    }
}

/// Ok(true) when `output` was created, Ok(false) when it is a writable folder already, else
/// what is wrong and what to do.
fn output_problem(output: &Path) -> Result<bool, String> {
    let what = "choose another folder with --output (or [output] directory)";
    if output.exists() {
        if !output.is_dir() {
            return Err(format!("exists and is not a folder: {what}"));
        }
        let probe = output.join(".squeal-write-check");
        return match std::fs::write(&probe, b"") {
            Ok(()) => {
                let _ = std::fs::remove_file(&probe);
                Ok(false)
            }
            Err(e) => Err(format!("cannot write into this folder ({e}): {what}")),
        };
    }
    let parent = match output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(format!(
            "its parent folder {} does not exist: create it first, or {what}",
            parent.display()
        ));
    }
    std::fs::create_dir(output)
        .map(|()| true)
        .map_err(|e| format!("cannot be created ({e}): {what}"))
}

/// results.xdmf, surfaces.xdmf and vibration.xdmf for ParaView, and model.png (rank 0 writes).
///
/// # Collective
fn write_views(
    petsc: &Petsc,
    a: &stages::Analyses,
    link: Option<&stages::link::Link>,
    frames: Option<&report::vibration::Frames>,
    output: &Path,
) -> Result<(), RunError> {
    let written = match (&a.model, petsc.rank()) {
        (Some(model), 0) => {
            let shapes = link.map_or(Vec::new(), report::link::tracked_shape_fields);
            let (modes, complex) = (a.modes.as_ref(), &a.complex);
            let with_contact = a.preload.is_some();
            let views = report::Views {
                modes,
                complex,
                more: shapes,
                with_contact,
                frames,
            };
            report::write_views_and_preview(output, model, views)
        }
        _ => Ok(()),
    };
    Ok(checked(written)?)
}

/// The transient stage, when the scene has one (timed).
///
/// # Collective
fn transient<'p>(
    petsc: &'p Petsc,
    scene: &Scene,
    a: &stages::Analyses<'p>,
    storage: &dyn Storage,
    output: &Path,
    options: &RunOptions,
    timings: &mut Timings,
) -> Result<Option<stages::transient::Trajectory>, RunError> {
    let Some(settings) = &scene.transient else {
        return Ok(None);
    };
    // Scene::validate asked for both.
    let (Some(preload), Some(modes)) = (&a.preload, &a.modes) else {
        let message = "needs [statics] and [real_modes] (its start)";
        return Err(RunError::scene("transient", message));
    };
    let files = TransientFiles::in_directory(storage, output, options.restart)
        .with_scene(scene.restart_fingerprint());
    timings
        .stage("transient", || {
            stages::transient::transient(
                petsc,
                settings,
                &scene.damping.unwrap_or_default(),
                a.model.as_ref(),
                &a.ops,
                preload,
                modes,
                a.reduced.as_ref(),
                &files,
            )
        })
        .map(Some)
}

/// report.html, written by rank 0 when everything else is.
fn write_report(
    petsc: &Petsc,
    summary: &RunSummary,
    scene_text: &str,
    output: &Path,
) -> Result<(), RunError> {
    if petsc.rank() == 0 {
        let path = output.join("report.html");
        let written = report::html::write_report(summary, scene_text, output);
        checked(written.map_err(|source| RunError::Io { path, source }))?;
        // The console's summary, answer first, kept beside results.h5.
        let path = output.join("summary.txt");
        let written = std::fs::write(&path, summary.to_string());
        checked(written.map_err(|source| RunError::Io { path, source }))?;
    }
    Ok(())
}
