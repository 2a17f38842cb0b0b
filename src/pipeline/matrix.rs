//! The noise matrix in a run: its journal (new, or resumed with `--restart`), the stage, and
//! its statistics. A journal that holds points is never overwritten by accident.

use std::path::Path;

use crate::io::matrix_journal::{self, Journal, JournalHeader, JournalWriter, FORMAT, JOURNAL};
use crate::la::Petsc;
use crate::matrix::point::PointResult;
use crate::matrix::saturation::SaturationInputs;
use crate::matrix::MatrixSettings;
use crate::report::matrix::MatrixReport;
use crate::scene::Scene;
use crate::stages::matrix::{matrix, MatrixInputs, MatrixRun};
use crate::stages::{Analyses, RunError, Timings};

use super::RunOptions;

/// Runs the scene's `[matrix]` (None without one), appending each point to the journal.
///
/// # Collective
pub(super) fn noise_matrix<'p>(
    petsc: &'p Petsc,
    scene: &Scene,
    scene_text: &str,
    a: &Analyses<'p>,
    output: &Path,
    options: &RunOptions,
    timings: &mut Timings,
) -> Result<Option<MatrixReport>, RunError> {
    let Some(settings) = &scene.matrix else {
        return Ok(None);
    };
    let (Some(preload), Some(modes), Some(_), Some(statics)) =
        (&a.preload, &a.modes, a.ops.dofs.as_ref(), &scene.statics)
    else {
        return Err(RunError::scene(
            "matrix",
            "needs [statics] and [real_modes] of a mesh model",
        ));
    };
    if settings.varies_lining() && a.lining.is_none() {
        let message = "a lining_modulus axis or column scales the lining blocks of a mesh model";
        return Err(RunError::scene("matrix.axes", message));
    }
    let complex = scene.complex_modes.clone().unwrap_or_default();
    let post = scene.post.as_ref();
    let air = post.and_then(|p| p.loudness.as_ref());
    // The radiating surfaces, when the points' saturated modes get their levels.
    let radiator = match (settings.saturation_modes, air, &a.model, &a.ops.dofs) {
        (0, _, _, _) | (_, None, _, _) => None,
        (_, Some(air), Some(model), Some(dofs)) => Some(timings.stage("radiator", || {
            crate::stages::loudness::radiator(petsc, &model.mesh, dofs, air)
        })?),
        _ => {
            let message = "saturation_modes with [post.loudness] needs a mesh model";
            return Err(RunError::scene("matrix.saturation_modes", message));
        }
    };
    let saturation = (settings.saturation_modes > 0).then(|| SaturationInputs {
        modes: settings.saturation_modes,
        trajectory: post
            .and_then(|p| p.pseudo_trajectory.clone())
            .unwrap_or_default(),
        loudness: radiator.as_ref().zip(air),
    });
    let input = MatrixInputs {
        k0: &a.ops.k0,
        modes,
        preload,
        pressure_bar: a.model.as_ref().map_or(0.0, |m| m.pressure / 1e5),
        statics,
        complex: &complex,
        damping: scene.damping.unwrap_or_default(),
        reduced: a.reduced.as_ref(),
        lining: a.lining.as_ref(),
        saturation,
    };
    let nominal = crate::stages::matrix::nominal_values(&settings.axis_list(), &input);
    let header = JournalHeader {
        nominal: nominal
            .iter()
            .map(|v| v.is_finite().then_some(*v))
            .collect(),
        margin: complex.instability_margin,
        scene: scene_text.to_string(),
        ..journal_header(scene, settings, options)
    };
    let path = output.join(JOURNAL);
    let done = crate::fault::checked(earlier_points(&path, &header, options.restart))?;
    // Every rank has read the journal before rank 0 rewrites it.
    crate::parallel::barrier(petsc.world());

    let mut writer = None;
    if petsc.rank() == 0 {
        let opened = match &done {
            Some(journal) => JournalWriter::resume(journal),
            None => JournalWriter::create(&path, &header),
        };
        writer = Some(crate::fault::checked(opened.map_err(journal_error))?);
    }
    crate::parallel::barrier(petsc.world());
    let run = MatrixRun {
        slice: options.slice,
        done: done.map_or(Vec::new(), |j| j.points),
    };
    if petsc.rank() == 0 && !run.done.is_empty() {
        println!(
            "  matrix: {} points from {} (--restart)",
            run.done.len(),
            path.display()
        );
    }
    let record = |p: &PointResult| -> Result<(), RunError> {
        let written = writer.as_mut().map_or(Ok(()), |w| w.append(p));
        let failed = crate::parallel::any_rank(petsc.world(), written.is_err());
        match (written, failed) {
            (Err(e), _) => Err(journal_error(e)),
            (Ok(()), true) => Err(RunError::scene(
                "matrix",
                "rank 0 could not write the journal",
            )),
            (Ok(()), false) => Ok(()),
        }
    };
    let out = timings.stage("matrix", || matrix(petsc, settings, input, run, record))?;
    Ok(Some(MatrixReport::of(out)))
}

fn journal_error(e: matrix_journal::JournalError) -> RunError {
    RunError::scene("matrix", format!("journal: {e}"))
}

/// The journal header's identity of a run: what a resumption, a slice and a merge compare
/// (the nominal values, margin and scene text are filled in by the run).
fn journal_header(scene: &Scene, settings: &MatrixSettings, options: &RunOptions) -> JournalHeader {
    JournalHeader {
        squeal_matrix: FORMAT,
        fingerprint: scene.matrix_fingerprint(),
        sampling: settings.sampling,
        total: crate::matrix::sample::points(settings).len(),
        slice: options.slice.to_string(),
        nominal: Vec::new(),
        margin: 0.0,
        scene: String::new(),
        axes: settings.axis_list(),
    }
}

/// Fails early (before the model is built) where the journal in `output` would be refused.
pub(super) fn check_journal(
    scene: &Scene,
    output: &Path,
    options: &RunOptions,
) -> Result<(), RunError> {
    let Some(settings) = &scene.matrix else {
        return Ok(());
    };
    let header = journal_header(scene, settings, options);
    earlier_points(&output.join(JOURNAL), &header, options.restart).map(|_| ())
}

/// The points an earlier run of this scene and slice left in the journal (with `--restart`);
/// without `--restart`, a journal that holds points is an error rather than lost.
fn earlier_points(
    path: &Path,
    header: &JournalHeader,
    restart: bool,
) -> Result<Option<Journal>, RunError> {
    if !path.exists() {
        return Ok(None);
    }
    let journal = matrix_journal::read(path).map_err(journal_error)?;
    if !restart {
        if journal.points.is_empty() {
            return Ok(None);
        }
        let message = format!(
            "{} holds {} finished points of an earlier run: add --restart to resume them, or choose another --output (or remove the file) to start over",
            path.display(),
            journal.points.len()
        );
        return Err(RunError::scene("matrix", message));
    }
    let h = &journal.header;
    let mismatch = if h.fingerprint != header.fingerprint {
        Some(
            "another scene (its model, contact, statics, damping, modes or matrix differ)"
                .to_string(),
        )
    } else if h.slice != header.slice || h.total != header.total {
        Some(format!(
            "slice {} of {} points, not {} of {}",
            h.slice, h.total, header.slice, header.total
        ))
    } else {
        None
    };
    match mismatch {
        Some(what) => {
            let message = format!("--restart: {} was written by {what}: run without --restart into another --output, or restart with the scene and --slice it was computed with", path.display());
            Err(RunError::scene("matrix", message))
        }
        None => Ok(Some(journal)),
    }
}
