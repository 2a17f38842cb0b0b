//! The driver: runs the stages a scene asks for (`crate::stages`, in order), times them and
//! hands each output to its writer (`crate::io::output`). No physics and no output code here.

use std::path::Path;
use std::time::Instant;

use crate::io::output;
use crate::io::results::ResultsFile;
use crate::la::{MatrixFormat, Petsc};
use crate::scene::{ModelSource, Scene};
use crate::stages::summary::{
    ComplexSummary, ReductionSummary, StaticSummary, SweepSummary, TransientSummary,
};
use crate::stages::{self, RunError, Timings};

pub use crate::stages::model::build_model;
pub use crate::stages::summary::RunSummary;

/// How to run beyond the scene.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Resume the transient from output/checkpoint.h5 (everything before it is recomputed,
    /// deterministically, and written again).
    pub restart: bool,
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

/// A stage's prerequisite (the scene's validation already asked for it).
fn need<T>(x: Option<T>, key: &'static str, what: &str) -> Result<T, RunError> {
    x.ok_or_else(|| RunError::scene(key, format!("needs {what}")))
}

/// [`run`] with options.
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
    if options.restart && scene.transient.is_none() {
        return Err(RunError::scene(
            "transient",
            "--restart resumes a transient: the scene has none",
        ));
    }
    if petsc.rank() == 0 {
        std::fs::create_dir_all(output).map_err(|source| RunError::Io {
            path: output.to_path_buf(),
            source,
        })?;
    }
    crate::parallel::barrier(petsc.world());
    let mut timings = Timings::default();
    let rank0 = petsc.rank() == 0;
    let damping = scene.damping.unwrap_or_default();

    let (model, quality, ops) = match &scene.model {
        source @ ModelSource::Matrices { .. } => {
            let ops = timings.time("read matrices", || {
                let complex = scene.complex_modes.is_some();
                stages::operators::read_matrices(petsc, source, complex, scene_dir)
            })?;
            (None, Vec::new(), ops)
        }
        source => {
            let model = timings.time("mesh", || build_model(source, scene_dir))?;
            let model = need(model, "model", "a mesh")?;
            let quality =
                timings.time("mesh quality", || crate::mesh::quality::check(&model.mesh))?;
            if scene.output.write_inp && rank0 {
                output::write_inp(output, &model)?;
            }
            // The static Newton's tangent K0 + contact is unsymmetric (LU): AIJ then.
            let format = scene.statics.as_ref().map(|_| MatrixFormat::Aij);
            let ops = timings.time("assembly", || {
                stages::operators::assemble(petsc, &model, format)
            })?;
            (Some(model), quality, ops)
        }
    };
    let mut preload = match (&scene.statics, &model) {
        (Some(settings), Some(model)) => Some(stages::statics::preload(
            petsc,
            model,
            &ops,
            &scene.contact.clone().unwrap_or_default(),
            settings,
            &mut timings,
        )?),
        (Some(_), None) => return Err(RunError::scene("statics", "needs a mesh model")),
        _ => None,
    };
    for format in &scene.output.export_matrices {
        let k = stages::modes::symmetric_stiffness(&ops, preload.as_ref());
        timings.time("export matrices", || {
            output::export_matrices(petsc, format, k, &ops.m, output)
        })?;
    }
    let modes = match &scene.real_modes {
        Some(request) => Some(timings.time("real modes", || {
            stages::modes::real_modes(petsc, &ops, preload.as_ref(), request)
        })?),
        None => None,
    };
    let complex = match &scene.complex_modes {
        Some(settings) => stages::complex::complex_modes(
            petsc,
            settings,
            &damping,
            &ops,
            preload.as_ref(),
            modes.as_ref(),
            &mut timings,
        )?,
        None => Vec::new(),
    };
    let sweep = match &scene.sweep {
        Some(sweep) => {
            let input = stages::sweep::SweepInputs {
                k0: &ops.k0,
                dofs: need(ops.dofs.as_ref(), "sweep", "a mesh model")?,
                modes: need(modes.as_ref(), "sweep", "[real_modes]")?,
                pressure_bar: model.as_ref().map_or(0.0, |m| m.pressure / 1e5),
            };
            let preload = need(preload.as_mut(), "sweep", "[statics]")?;
            let statics = need(scene.statics.as_ref(), "sweep", "[statics]")?;
            let settings = scene.complex_modes.clone().unwrap_or_default();
            Some(timings.time("sweep", || {
                stages::sweep::sweep(petsc, sweep, &settings, &damping, statics, preload, input)
            })?)
        }
        None => None,
    };
    let reduced = match &scene.reduction {
        Some(settings) => {
            let model = need(model.as_ref(), "reduction", "a mesh model")?;
            let preload = need(preload.as_ref(), "reduction", "[statics]")?;
            let modes = need(modes.as_ref(), "reduction", "[real_modes]")?;
            Some(timings.time("reduction", || {
                stages::reduce::reduce(petsc, settings, model, &ops, preload, modes)
            })?)
        }
        None => None,
    };

    // What the stages before the transient found goes to results.h5 before it starts.
    let start = Instant::now();
    let file = ResultsFile::create(petsc.world(), &output.join("results.h5"))?;
    output::write_header(
        &file,
        scene_text,
        petsc_options,
        petsc.size() as usize,
        ops.dofs(),
    )?;
    if let Some(model) = &model {
        output::write_model(&file, model, &quality, ops.balance.as_ref())?;
    }
    let static_summary = match (&preload, &model, &ops.dofs) {
        (Some(p), Some(model), Some(dofs)) => {
            output::statics::write_static(petsc, &file, p, dofs, model, output)?;
            Some(StaticSummary::of(p, model))
        }
        _ => None,
    };
    if let Some(modes) = &modes {
        file.write_real_modes(modes, ops.dofs.as_ref())?;
    }
    for c in &complex {
        output::modes::write_complex(petsc, &file, c, ops.dofs.as_ref(), output)?;
    }
    if let Some(sw) = &sweep {
        output::sweep::write_sweep(petsc, &file, sw, output)?;
    }
    let reduction_summary = match &reduced {
        Some(r) => {
            let summary = ReductionSummary::of(petsc, r, ops.dofs())?;
            output::reduction::write_reduction(&file, r, &summary)?;
            Some(summary)
        }
        None => None,
    };
    let before_transient = start.elapsed().as_secs_f64();
    file.flush()?;

    // The transient streams into transient.h5 (linked as /transient) while it runs.
    let trajectory = match &scene.transient {
        Some(settings) => {
            let preload = need(preload.as_ref(), "transient", "[statics]")?;
            let modes = need(modes.as_ref(), "transient", "[real_modes] (its start)")?;
            Some(timings.time("transient", || {
                stages::transient::transient(
                    petsc,
                    settings,
                    &damping,
                    model.as_ref(),
                    &ops,
                    preload,
                    modes,
                    reduced.as_ref(),
                    output,
                    options.restart,
                )
            })?)
        }
        None => None,
    };
    let start = Instant::now();
    if let (Some(t), Some(settings)) = (&trajectory, &scene.transient) {
        output::transient::write_transient(petsc, &file, &t.signals, settings, output)?;
    }
    if let (Some(model), true) = (&model, rank0) {
        output::write_xdmf_and_preview(output, model, modes.as_ref(), &complex)?;
    }
    let seconds_output = before_transient + start.elapsed().as_secs_f64();
    timings.stages.push(("output".into(), seconds_output));
    output::write_timings(&file, &timings)?;
    drop(file);
    // Reported after the results are written: the steps before the failure are kept.
    let (signals, failure) = match trajectory {
        Some(t) => (Some(t.signals), t.failure),
        None => (None, None),
    };
    if let Some(e) = failure {
        return Err(RunError::Time(e));
    }

    let peak = crate::parallel::max(petsc.world(), petsc.peak_memory());
    let mut summary = RunSummary::new(
        &ops,
        model.as_ref(),
        quality,
        modes.as_ref(),
        timings,
        peak,
        output,
    );
    summary.statics = static_summary;
    summary.complex = complex.iter().map(ComplexSummary::of).collect();
    summary.sweep = sweep.as_ref().map(SweepSummary::of);
    summary.transient = signals.as_ref().map(TransientSummary::of);
    summary.reduction = reduction_summary;
    Ok(summary)
}
