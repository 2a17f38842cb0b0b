//! The stages before the transient, in chain order, as the scene asks: model and operators,
//! preload, real modes, complex modes, sweep, reduction; and the matrix export a scene asks
//! for (`[output] export_matrices`), written here by the driver, not by a stage.

use std::path::Path;

use crate::la::Petsc;
use crate::matrix::StaticsModel;
use crate::scene::Scene;
use crate::stages::parameter_shapes::parameter_shapes;
use crate::stages::{complex, matrix, modes, operators, reduce, statics, sweep};
use crate::stages::{Analyses, RunError, Timings};

/// A stage's prerequisite. The scene's validation already asked for it (`Scene::validate`):
/// this is the driver's guard, not a user-facing check.
fn need<T>(x: Option<T>, key: &'static str, what: &str) -> Result<T, RunError> {
    x.ok_or_else(|| RunError::scene(key, format!("needs {what}")))
}

/// Runs the stages before the transient.
///
/// # Collective
pub fn analyses<'p>(
    petsc: &'p Petsc,
    scene: &Scene,
    scene_dir: &Path,
    output: &Path,
    timings: &mut Timings,
) -> Result<Analyses<'p>, RunError> {
    let damping = scene.damping.unwrap_or_default();
    let (model, quality, ops) = operators::from_scene(petsc, scene, scene_dir, timings)?;
    let preload = match (&scene.statics, &model) {
        (Some(settings), Some(model)) => {
            let contact = scene.contact.clone().unwrap_or_default();
            let p = statics::preload(petsc, model, &ops, &contact, settings, timings)?;
            Some(p)
        }
        (Some(_), None) => return Err(RunError::scene("statics", "needs a mesh model")),
        _ => None,
    };
    // The lining's stiffness, for a noise matrix that scales it (its reduced statics also
    // put the lining's static shape into the reduction's basis).
    let lining = match (&scene.matrix, &model, ops.dofs.as_ref()) {
        (Some(m), Some(model), Some(dofs)) if m.varies_lining() => {
            Some(timings.stage("lining stiffness", || {
                matrix::lining_stiffness(petsc, m, model, dofs, ops.k0.format())
            })?)
        }
        _ => None,
    };
    // The parameters' static shapes for a matrix on the superelement, right after the preload:
    // their factorization of the full tangent then has the memory the preload's had (at 600k
    // next to the 250 real modes and the other operators it was killed for memory).
    let shapes = match (&scene.matrix, &scene.reduction, preload.as_ref()) {
        (Some(m), Some(_), Some(preload))
            if m.statics == StaticsModel::Reduced && m.parameter_shapes =>
        {
            timings.stage("parameter shapes", || {
                parameter_shapes(petsc, m, &ops, preload, lining.as_ref())
            })?
        }
        _ => Vec::new(),
    };
    for format in &scene.output.export_matrices {
        let k = modes::symmetric_stiffness(&ops, preload.as_ref());
        timings.stage("export matrices", || {
            crate::report::export_matrices(petsc, format, k, &ops.m, output)
        })?;
    }
    let modes = match &scene.real_modes {
        Some(request) => Some(timings.stage("real modes", || {
            modes::real_modes(petsc, &ops, preload.as_ref(), request)
        })?),
        None => None,
    };
    // With complex modes, also the linearization they solve: the tangent stiffness
    // K0 + K_c + K_stick + K_f (unsymmetric) and the damping C, for a cross-check elsewhere.
    if scene.complex_modes.is_some() && !scene.output.export_matrices.is_empty() {
        let (kt, c) = timings.stage("linearization for export", || {
            complex::quadratic_operators(petsc, &damping, &ops, preload.as_ref())
        })?;
        for format in &scene.output.export_matrices {
            timings.stage("export linearization", || {
                let named = [("K_tangent", &kt), ("C", &c)];
                crate::report::export_named(petsc, format, &named, output)
            })?;
        }
    }
    let complex = match &scene.complex_modes {
        Some(settings) => {
            let (p, m) = (preload.as_ref(), modes.as_ref());
            let mut routes =
                complex::complex_modes(petsc, settings, &damping, &ops, p, m, timings)?;
            if let (Some(model), Some(dofs)) = (&model, &ops.dofs) {
                timings.stage("mode motion", || {
                    crate::stages::motion::unstable_mode_motion(
                        petsc,
                        &model.mesh,
                        dofs,
                        &ops.m,
                        &mut routes,
                    )
                })?;
            }
            routes
        }
        None => Vec::new(),
    };
    let sweep = match &scene.sweep {
        Some(sweep) => {
            let input = sweep::SweepInputs {
                k0: &ops.k0,
                dofs: need(ops.dofs.as_ref(), "sweep", "a mesh model")?,
                modes: need(modes.as_ref(), "sweep", "[real_modes]")?,
                pressure_bar: model.as_ref().map_or(0.0, |m| m.pressure / 1e5),
            };
            let preload = need(preload.as_ref(), "sweep", "[statics]")?;
            let statics = need(scene.statics.as_ref(), "sweep", "[statics]")?;
            let settings = scene.complex_modes.clone().unwrap_or_default();
            Some(timings.stage("sweep", || {
                sweep::sweep(petsc, sweep, &settings, &damping, statics, preload, input)
            })?)
        }
        None => None,
    };
    let reduced = match &scene.reduction {
        Some(settings) => {
            let model = need(model.as_ref(), "reduction", "a mesh model")?;
            let preload = need(preload.as_ref(), "reduction", "[statics]")?;
            let modes = need(modes.as_ref(), "reduction", "[real_modes]")?;
            Some(timings.stage("reduction", || {
                reduce::reduce(petsc, settings, model, &ops, preload, modes, &shapes)
            })?)
        }
        None => None,
    };
    Ok(Analyses {
        model,
        quality,
        ops,
        preload,
        modes,
        complex,
        sweep,
        reduced,
        lining,
    })
}
