//! One scene, one pipeline: model -> assembled operators -> real modes -> output. Each stage is
//! timed; the timings go to the results file and the summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::eigen::real_modes::{real_modes, RealModes};
use crate::fem::system::{assemble_system, AssembledSystem, Clamp, SystemError};
use crate::io::matrix_market::{self, MatrixMarketError};
use crate::io::results::{ResultsError, ResultsFile};
use crate::io::user_matrices::load_sum;
use crate::io::xdmf::{self, NodalField};
use crate::la::{LaError, Petsc, SparseMatrix};
use crate::mesh::structured::{annulus, block};
use crate::mesh::Mesh;
use crate::scene::{ModelSource, Scene};

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("model: {0}")]
    System(#[from] SystemError),
    #[error("matrices: {0}")]
    Matrices(#[from] MatrixMarketError),
    #[error("{0}")]
    La(#[from] LaError),
    #[error("results: {0}")]
    Results(#[from] ResultsError),
    #[error("mesh: {0}")]
    Inp(#[from] crate::mesh::abaqus_inp::InpError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Wall-clock seconds per stage, in order.
#[derive(Debug, Clone, Default)]
pub struct Timings {
    pub stages: Vec<(String, f64)>,
}

impl Timings {
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.stages
            .push((name.to_string(), start.elapsed().as_secs_f64()));
        out
    }
}

/// What a run produced, for the summary.
pub struct RunSummary {
    pub dofs: usize,
    pub frequencies_hz: Vec<f64>,
    pub residual_norms: Vec<f64>,
    pub backward_errors: Vec<f64>,
    pub rigid: Vec<bool>,
    pub timings: Timings,
    pub peak_memory_per_rank: f64,
    pub factor_entries: Option<f64>,
    pub ordering: Option<&'static str>,
    pub output: PathBuf,
}

/// Builds (generates or imports) the mesh of a model; None for a matrices model. Relative
/// file names are resolved from `scene_dir`.
pub fn build_mesh(
    model: &ModelSource,
    scene_dir: &Path,
) -> Result<Option<(Mesh, Vec<Clamp>)>, RunError> {
    Ok(match model {
        ModelSource::Abaqus { file } => {
            let inp = crate::mesh::abaqus_inp::read(&scene_dir.join(file))?;
            let clamps = inp
                .clamps
                .iter()
                .map(|(set, components)| Clamp {
                    node_set: set.clone(),
                    components: *components,
                })
                .collect();
            Some((inp.mesh, clamps))
        }
        ModelSource::Block {
            element,
            size,
            cells,
            material,
            clamp,
        } => Some((
            block(*size, *cells, *element, material.clone()),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        )),
        ModelSource::Annulus {
            element,
            inner_radius,
            outer_radius,
            thickness,
            cells,
            material,
            clamp,
        } => Some((
            annulus(
                *inner_radius,
                *outer_radius,
                *thickness,
                *cells,
                *element,
                material.clone(),
            ),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        )),
        ModelSource::Matrices { .. } => None,
    })
}

/// Runs a scene. `scene_dir` resolves relative paths of matrix files; `scene_text` is stored
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
    let mut timings = Timings::default();
    if petsc.rank() == 0 {
        std::fs::create_dir_all(output).map_err(|source| RunError::Io {
            path: output.to_path_buf(),
            source,
        })?;
    }
    crate::parallel::barrier(petsc.world());

    // Model and operators.
    let mut mesh = None;
    let mut system: Option<AssembledSystem> = None;
    let mut user: Option<(SparseMatrix, SparseMatrix)> = None;
    let generated = match &scene.model {
        ModelSource::Matrices { .. } => None,
        model => timings.time("mesh", || build_mesh(model, scene_dir))?,
    };
    if let Some((m, clamps)) = generated {
        if scene.output.write_inp && petsc.rank() == 0 {
            let path = output.join("model.inp");
            let named: Vec<(String, [bool; 3])> = clamps
                .iter()
                .map(|c| (c.node_set.clone(), c.components))
                .collect();
            crate::mesh::abaqus_inp::write(&path, &m, &named)
                .map_err(|source| RunError::Io { path, source })?;
        }
        let s = timings.time("assembly", || assemble_system(petsc, &m, &clamps))?;
        mesh = Some(m);
        system = Some(s);
    } else if let ModelSource::Matrices { stiffness, mass } = &scene.model {
        let (k, m) = timings.time("read matrices", || -> Result<_, RunError> {
            let k = load_sum(petsc, stiffness, scene_dir)?;
            let m = load_sum(petsc, mass, scene_dir)?;
            Ok((k, m))
        })?;
        if k.asymmetry > 1e-12 || m.asymmetry > 1e-12 {
            return Err(LaError::Invalid(format!(
                "real modes need symmetric K and M; the stiffness sum has relative asymmetry {:.2e} and the mass {:.2e}",
                k.asymmetry, m.asymmetry
            ))
            .into());
        }
        user = Some((k.matrix, m.matrix));
    }
    let (k, m, free_free) = match (&system, &user) {
        (Some(s), _) => (&s.stiffness, &s.mass, s.is_free_free()),
        (None, Some((k, m))) => (k, m, false),
        _ => unreachable!("a scene has a model"),
    };
    let dofs = k.global_rows();

    for format in &scene.output.export_matrices {
        timings.time("export matrices", || -> Result<(), RunError> {
            for (name, a) in [("K", k), ("M", m)] {
                if format == "mtx" {
                    matrix_market::write(petsc.world(), a, &output.join(format!("{name}.mtx")))?;
                } else {
                    a.save_binary(petsc, &output.join(format!("{name}.petsc")))?;
                }
            }
            Ok(())
        })?;
    }

    // Analyses.
    let modes: Option<RealModes> = match &scene.real_modes {
        Some(request) => Some(timings.time("real modes", || {
            real_modes(petsc, k, m, free_free, request, "")
        })?),
        None => None,
    };

    // Output.
    let start = Instant::now();
    let h5 = output.join("results.h5");
    let file = ResultsFile::create(petsc.world(), &h5)?;
    file.set_text("/", "scene", scene_text)?;
    file.set_text("/", "petsc_options", &petsc_options.join(" "))?;
    file.set_text("/", "squeal_version", env!("CARGO_PKG_VERSION"))?;
    file.set_number("/", "ranks", petsc.size() as f64)?;
    file.set_number("/", "dofs", dofs as f64)?;
    if let Some(mesh) = &mesh {
        file.write_mesh(mesh)?;
    }
    if let Some(modes) = &modes {
        file.write_real_modes(modes, system.as_ref().map(|s| &s.dofs))?;
    }
    if let (Some(mesh), 0) = (&mesh, petsc.rank()) {
        let fields: Vec<NodalField> = modes
            .iter()
            .flat_map(|modes| {
                modes
                    .frequencies_hz
                    .iter()
                    .enumerate()
                    .map(|(i, f)| NodalField {
                        label: format!("mode {:03} ({f:.1} Hz)", i + 1),
                        dataset: format!("/modes/real/shapes/mode_{:04}", i + 1),
                    })
            })
            .collect();
        let path = output.join("results.xdmf");
        xdmf::write(&path, "results.h5", mesh, &fields)
            .map_err(|source| RunError::Io { path, source })?;
    }
    timings
        .stages
        .push(("output".into(), start.elapsed().as_secs_f64()));
    for (name, secs) in &timings.stages {
        file.set_number("timings", &name.replace(' ', "_"), *secs)?;
    }
    drop(file);

    let peak = crate::parallel::max(petsc.world(), petsc.peak_memory());
    let modes_ref = modes.as_ref();
    Ok(RunSummary {
        dofs,
        frequencies_hz: modes_ref
            .map(|m| m.frequencies_hz.clone())
            .unwrap_or_default(),
        residual_norms: modes_ref
            .map(|m| m.residual_norms.clone())
            .unwrap_or_default(),
        backward_errors: modes_ref
            .map(|m| m.backward_errors.clone())
            .unwrap_or_default(),
        rigid: modes_ref.map(|m| m.rigid.clone()).unwrap_or_default(),
        factor_entries: modes_ref.and_then(|m| m.factorization.map(|f| f.factor_entries)),
        ordering: modes_ref.and_then(|m| m.factorization.map(|f| f.ordering_name())),
        timings,
        peak_memory_per_rank: peak,
        output: output.to_path_buf(),
    })
}
