//! One scene, one pipeline: model -> assembled operators -> real modes -> output. Each stage is
//! timed; the timings go to the results file and the summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::eigen::complex_modes::{
    project_operators, ComplexMode, ComplexModeSettings, ComplexModes, DampingSettings,
    ModalProjection, Operators, Route,
};
use crate::eigen::real_modes::{real_modes, RealModes};
use crate::eigen::sweep::{SweepParameter, SweepSettings};
use crate::io::matrix_market::{self, MatrixMarketError};
use crate::io::results::{ResultsError, ResultsFile};
use crate::io::user_matrices::load_sum;
use crate::io::xdmf::{self, NodalField};
use crate::la::fem_assembly::{assemble_system_as, AssembledSystem, SystemError};
use crate::la::{LaError, Petsc, SparseMatrix};
use crate::mesh::partition;
use crate::mesh::quality::{self, BlockQuality};
use crate::mesh::structured::{annulus, block};
use crate::mesh::Clamp;
use crate::mesh::{Interface, InterfaceKind, Mesh, PressureLoad};
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
    #[error("mesh: {0}")]
    Msh(#[from] crate::mesh::gmsh_msh::MshError),
    #[error("{0}")]
    Quality(#[from] crate::mesh::quality::QualityError),
    #[error("model: {0}")]
    Model(String),
    #[error("{0}")]
    Contact(#[from] crate::contact::ContactError),
    #[error("{0}")]
    Statics(#[from] crate::statics::StaticError),
    #[error("transient: {0}")]
    Time(#[from] crate::time::newmark::TimeError),
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
    /// Model builder's notes (size, substituted constraints).
    pub notes: Vec<String>,
    pub quality: Vec<BlockQuality>,
    pub balance: Option<LoadBalance>,
    /// Blocks of parts not held against rigid-body motion (their modes sit at 0 Hz).
    pub unsupported: Vec<String>,
    pub peak_memory_per_rank: f64,
    pub factor_entries: Option<f64>,
    pub ordering: Option<&'static str>,
    pub output: PathBuf,
    /// The static preload, when the scene asked for one.
    pub statics: Option<StaticSummary>,
    /// Complex modes per route.
    pub complex: Vec<ComplexSummary>,
    pub sweep: Option<SweepSummary>,
    pub transient: Option<TransientSummary>,
    pub reduction: Option<ReductionSummary>,
}

/// The superelement reduction, for the summary.
#[derive(Debug, Clone)]
pub struct ReductionSummary {
    pub full_dofs: usize,
    pub kept: usize,
    pub modal: usize,
    pub offered: usize,
    pub dropped: usize,
    /// max |B^T M B - I|, and ||q0 - T x0|| / ||q0||.
    pub orthonormality: f64,
    pub static_error: f64,
    /// (full Hz, reduced Hz) of the real modes in the basis, and the largest relative gap.
    pub mode_check: Vec<(f64, f64)>,
    pub mode_error: f64,
    /// Stored entries of the reduced stiffness (the per-step product streams them).
    pub stiffness_entries: f64,
    /// Reduced unknowns per rank (the transient's load balance).
    pub rows_per_rank: Vec<usize>,
    pub seconds: f64,
}

/// What the static preload found, for the summary.
#[derive(Debug, Clone)]
pub struct StaticSummary {
    pub points: usize,
    pub misses: Vec<(String, usize, usize)>,
    pub interfaces: Vec<(String, crate::contact::InterfaceSummary)>,
    pub newton_iterations: usize,
    pub load_steps: usize,
    pub factorizations: usize,
    pub solves: usize,
    pub factor_entries: f64,
    pub pairing_seconds: f64,
    pub seconds: f64,
    pub seconds_factorizing: f64,
    pub piston_force: f64,
    pub final_residual: f64,
}

/// A finite-element model ready for assembly: mesh, constraints, contact interfaces and
/// pressure loads (the last two from the brake generator or `*CONTACT PAIR`s).
#[derive(Debug, Clone)]
pub struct Model {
    pub mesh: Mesh,
    pub clamps: Vec<Clamp>,
    pub interfaces: Vec<Interface>,
    pub loads: Vec<PressureLoad>,
    /// Brake-line pressure (Pa) of the loads.
    pub pressure: f64,
    /// What the model builder substituted or assumed, for the log.
    pub notes: Vec<String>,
}

impl Model {
    fn plain(mesh: Mesh, clamps: Vec<Clamp>) -> Self {
        Model {
            mesh,
            clamps,
            interfaces: Vec::new(),
            loads: Vec::new(),
            pressure: 0.0,
            notes: Vec::new(),
        }
    }
}

/// Builds (generates or imports) the model; None for a matrices model. Relative file names
/// are resolved from `scene_dir`. Nodes are renumbered by recursive coordinate bisection
/// (`mesh::partition`), and every element passes the quality check.
pub fn build_model(model: &ModelSource, scene_dir: &Path) -> Result<Option<Model>, RunError> {
    let mut built = match model {
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
            let mut m = Model::plain(inp.mesh, clamps);
            m.interfaces = inp
                .contact_pairs
                .iter()
                .map(|p| Interface {
                    name: format!("{}-{}", p.slave, p.master),
                    master: p.slave.clone(),
                    slave: p.master.clone(),
                    kind: InterfaceKind::Sliding,
                })
                .collect();
            m
        }
        ModelSource::Gmsh {
            file,
            materials,
            clamp,
        } => {
            let msh = crate::mesh::gmsh_msh::read(&scene_dir.join(file), materials)?;
            Model::plain(msh.mesh, clamp.iter().map(|s| Clamp::all(s)).collect())
        }
        ModelSource::Block {
            element,
            size,
            cells,
            material,
            clamp,
        } => Model::plain(
            block(*size, *cells, *element, material.clone()),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        ),
        ModelSource::Annulus {
            element,
            inner_radius,
            outer_radius,
            thickness,
            cells,
            material,
            clamp,
        } => Model::plain(
            annulus(
                *inner_radius,
                *outer_radius,
                *thickness,
                *cells,
                *element,
                material.clone(),
            ),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        ),
        ModelSource::Brake(spec) => {
            let b = crate::mesh::brake::generate(spec).map_err(RunError::Model)?;
            let mut notes = b.notes;
            notes.insert(
                0,
                format!(
                    "brake: {} nodes, {} elements, element size {:.2} mm",
                    b.mesh.node_count(),
                    b.mesh.element_count(),
                    b.element_size * 1e3
                ),
            );
            Model {
                mesh: b.mesh,
                clamps: b.clamps,
                interfaces: b.interfaces,
                loads: b.loads,
                pressure: b.pressure,
                notes,
            }
        }
        ModelSource::Matrices { .. } => return Ok(None),
    };
    let order = partition::bisection_order(&built.mesh.coords);
    partition::renumber(&mut built.mesh, &order);
    Ok(Some(built))
}

/// Rows and elements per rank of an assembled system, and their imbalance (max / mean).
///
/// # Collective
fn load_balance(petsc: &Petsc, s: &AssembledSystem) -> LoadBalance {
    let ranks = petsc.size() as usize;
    let rows: Vec<usize> = s.dofs.dof_ranges.windows(2).map(|w| w[1] - w[0]).collect();
    let mut elements = vec![0usize; ranks];
    elements[petsc.rank() as usize] = s.elements_on_rank;
    let elements: Vec<usize> = elements
        .iter()
        .map(|&e| crate::parallel::sum(petsc.world(), e as f64) as usize)
        .collect();
    LoadBalance {
        row_imbalance: partition::imbalance(&rows),
        element_imbalance: partition::imbalance(&elements),
        rows,
        elements,
    }
}

/// A transient run, for the summary.
#[derive(Debug, Clone)]
pub struct TransientSummary {
    pub steps: usize,
    pub simulated: f64,
    pub mean_iterations: f64,
    pub max_iterations: usize,
    /// Per step of this process's run, the Jacobian factorizations excluded (they are
    /// `seconds_factorizing`, paid once, or again at a refresh).
    pub seconds_per_step: f64,
    pub factor_entries: f64,
    pub seconds_factorizing: f64,
    pub cuts: usize,
    pub refreshes: usize,
    pub factorizations: usize,
    /// One fixed-Jacobian iteration (forces, residual, solve) and one solve with the factor.
    pub seconds_per_iteration: f64,
    pub seconds_per_solve: f64,
    /// Per step: force evaluations (contact), operator products (the predictor's linear
    /// force, the contact tangent's correction), and the rest (vector updates, reductions,
    /// recording).
    pub seconds_forces_per_step: f64,
    pub seconds_products_per_step: f64,
}

/// A parameter sweep, for the summary.
#[derive(Debug, Clone)]
pub struct SweepSummary {
    pub parameter: &'static str,
    pub points: usize,
    pub tracks: usize,
    pub values: Vec<f64>,
    pub unstable_per_point: Vec<usize>,
    /// Per point: static re-solve, and re-projection + dense complex modes.
    pub statics_seconds: Vec<f64>,
    pub modal_seconds: Vec<f64>,
}

/// Complex modes of one route, for the summary.
#[derive(Debug, Clone)]
pub struct ComplexSummary {
    pub route: &'static str,
    pub modes: Vec<ComplexMode>,
    pub basis: usize,
    pub seconds: f64,
    pub solve_seconds: f64,
}

/// How evenly the ranks share the work.
#[derive(Debug, Clone)]
pub struct LoadBalance {
    pub rows: Vec<usize>,
    pub elements: Vec<usize>,
    pub row_imbalance: f64,
    pub element_imbalance: f64,
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
    run_with(
        petsc,
        scene,
        scene_text,
        scene_dir,
        output,
        petsc_options,
        &RunOptions::default(),
    )
}

/// How to run beyond the scene.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Resume the transient from output/checkpoint.h5 (everything before it is recomputed,
    /// deterministically, and written again).
    pub restart: bool,
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
        return Err(RunError::Model(
            "--restart resumes a transient: the scene has no [transient]".into(),
        ));
    }
    let mut timings = Timings::default();
    if petsc.rank() == 0 {
        std::fs::create_dir_all(output).map_err(|source| RunError::Io {
            path: output.to_path_buf(),
            source,
        })?;
    }
    crate::parallel::barrier(petsc.world());

    // Model and operators.
    let mut model: Option<Model> = None;
    let mut system: Option<AssembledSystem> = None;
    let mut user: Option<(SparseMatrix, SparseMatrix)> = None;
    let mut user_complex: Option<(SparseMatrix, Option<SparseMatrix>)> = None;
    let mut quality_stats = Vec::new();
    let mut balance = None;
    let mut unsupported = Vec::new();
    let built = match &scene.model {
        ModelSource::Matrices { .. } => None,
        source => timings.time("mesh", || build_model(source, scene_dir))?,
    };
    if let Some(built) = built {
        quality_stats = timings.time("mesh quality", || quality::check(&built.mesh))?;
        if scene.output.write_inp && petsc.rank() == 0 {
            let path = output.join("model.inp");
            let named: Vec<(String, [bool; 3])> = built
                .clamps
                .iter()
                .map(|c| (c.node_set.clone(), c.components))
                .collect();
            crate::mesh::abaqus_inp::write(&path, &built.mesh, &named)
                .map_err(|source| RunError::Io { path, source })?;
        }
        // The Newton tangent K0 + contact is unsymmetric (LU): assemble K0 as AIJ then.
        let format = scene.statics.as_ref().map(|_| crate::la::MatrixFormat::Aij);
        let s = timings.time("assembly", || {
            assemble_system_as(petsc, &built.mesh, &built.clamps, format)
        })?;
        let fixed: Vec<[bool; 3]> = s.dofs.node_dofs.iter().map(|d| d.map(|x| x < 0)).collect();
        unsupported = partition::unsupported_parts(&built.mesh, &fixed);
        balance = Some(load_balance(petsc, &s));
        model = Some(built);
        system = Some(s);
    } else if let ModelSource::Matrices {
        stiffness,
        mass,
        circulatory,
        damping,
        disc_speed,
    } = &scene.model
    {
        let at_speed = |terms: &[crate::io::user_matrices::MatrixTerm]| -> Vec<_> {
            terms.iter().map(|t| t.at_speed(*disc_speed)).collect()
        };
        let (k, m) = timings.time("read matrices", || -> Result<_, RunError> {
            let k = load_sum(petsc, &at_speed(stiffness), scene_dir)?;
            let m = load_sum(petsc, &at_speed(mass), scene_dir)?;
            if scene.complex_modes.is_some() {
                // The full operators: symmetric + circulatory stiffness, and the damping.
                let mut all = at_speed(stiffness);
                all.extend(at_speed(circulatory));
                let k_full = if circulatory.is_empty() {
                    k.matrix.try_clone()?
                } else {
                    load_sum(petsc, &all, scene_dir)?.matrix
                };
                let c = if damping.is_empty() {
                    None
                } else {
                    Some(load_sum(petsc, &at_speed(damping), scene_dir)?.matrix)
                };
                user_complex = Some((k_full, c));
            }
            Ok((k, m))
        })?;
        if k.asymmetry > 1e-12 || m.asymmetry > 1e-12 {
            return Err(LaError::Invalid(format!(
                "real modes need symmetric K and M; the stiffness sum has relative asymmetry {:.2e} and the mass {:.2e} (unsymmetric terms go under model.circulatory)",
                k.asymmetry, m.asymmetry
            ))
            .into());
        }
        user = Some((k.matrix, m.matrix));
    }
    let (k, m, free_free) = match (&system, &user) {
        // Parts not held against rigid motion make K singular: shift below zero.
        (Some(s), _) => (
            &s.stiffness,
            &s.mass,
            s.is_free_free() || !unsupported.is_empty(),
        ),
        (None, Some((k, m))) => (k, m, false),
        _ => unreachable!("a scene has a model"),
    };
    let dofs = k.global_rows();

    // Static preload with contact, and the tangent stiffness of that state.
    let mut preload: Option<(crate::contact::ContactModel, crate::statics::StaticState)> = None;
    let mut static_load: Option<crate::la::Vector> = None;
    let mut tangent: Option<SparseMatrix> = None;
    if let (Some(settings), Some(model), Some(system)) = (&scene.statics, &model, &system) {
        let contact_settings = scene.contact.clone().unwrap_or_default();
        if model.interfaces.is_empty() {
            return Err(RunError::Model(
                "key 'statics': the model has no contact interfaces (a brake model or an .inp with *CONTACT PAIR has them)".into(),
            ));
        }
        let interfaces = contact_settings
            .resolve(&model.interfaces)
            .map_err(RunError::Model)?;
        let contact = timings.time("contact pairing", || {
            crate::contact::ContactModel::new(
                petsc,
                &model.mesh,
                &system.dofs,
                interfaces,
                &contact_settings,
            )
        })?;
        let f_ext = crate::statics::pressure_load(
            petsc,
            &model.mesh,
            &system.dofs,
            &model.loads,
            model.pressure,
        )
        .map_err(RunError::Model)?;
        let rank0 = petsc.rank() == 0;
        let state = timings.time("static preload", || {
            crate::statics::solve(petsc, k, &system.dofs, &contact, &f_ext, settings, None, |r| {
                if rank0 {
                    println!(
                        "  static step {} (pressure {:>3.0} %, friction {:>3.0} %) iteration {:>2}: residual {:.3e} N (of {:.3e}){}",
                        r.load_step,
                        100.0 * r.pressure_fraction,
                        100.0 * r.friction_fraction,
                        r.iteration,
                        r.residual,
                        r.reference,
                        if r.step_length > 0.0 && r.step_length < 1.0 { format!(", step {:.3}", r.step_length) } else { String::new() }
                    );
                }
            })
        })?;
        let kt = timings.time("tangent state", || -> Result<SparseMatrix, LaError> {
            let mut kt = contact.joined_matrix(petsc, k)?;
            contact.add_tangent(
                &state.contact,
                &[
                    crate::contact::kernel::Part::Normal,
                    crate::contact::kernel::Part::Stick,
                ],
                &mut kt,
            )?;
            kt.assemble()?;
            kt.set_symmetric(true)?;
            Ok(kt)
        })?;
        tangent = Some(kt);
        preload = Some((contact, state));
        static_load = Some(f_ext);
    }
    let k0 = k;
    let k = tangent.as_ref().unwrap_or(k);

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
    let complex: Vec<ComplexModes> = match &scene.complex_modes {
        Some(settings) => complex_stage(
            petsc,
            settings,
            &scene.damping.unwrap_or_default(),
            ComplexInputs {
                k0,
                k_symmetric: k,
                m,
                modes: modes.as_ref(),
                preload: preload.as_ref().map(|(c, s)| (c, &s.contact)),
                dofs: system.as_ref().map(|s| &s.dofs),
                user: user_complex.as_ref().map(|(k, c)| (k, c.as_ref())),
            },
            &mut timings,
        )?,
        None => Vec::new(),
    };
    let mut sweep_result = None;
    if let Some(sweep) = &scene.sweep {
        let settings = scene.complex_modes.clone().unwrap_or_default();
        let (
            Some((contact, state)),
            Some(f_ext),
            Some(system),
            Some(modes),
            Some(statics),
            Some(model),
        ) = (
            preload.as_mut(),
            static_load.as_ref(),
            system.as_ref(),
            modes.as_ref(),
            scene.statics.as_ref(),
            model.as_ref(),
        )
        else {
            return Err(RunError::Model(
                "key 'sweep': a sweep needs a brake (or mesh) model with [statics] and [real_modes]".into(),
            ));
        };
        sweep_result = Some(timings.time("sweep", || {
            sweep_stage(
                petsc,
                sweep,
                &settings,
                &scene.damping.unwrap_or_default(),
                statics,
                SweepInputs {
                    k0,
                    contact,
                    nominal: state,
                    f_ext,
                    pressure_bar: model.pressure / 1e5,
                    dofs: &system.dofs,
                    modes,
                },
            )
        })?);
    }

    // Superelement reduction of the preloaded model (for the time response).
    let mut reduced = None;
    if let Some(settings) = &scene.reduction {
        let (Some((contact, state)), Some(f_ext), Some(system), Some(modes), Some(model)) = (
            preload.as_ref(),
            static_load.as_ref(),
            system.as_ref(),
            modes.as_ref(),
            model.as_ref(),
        ) else {
            return Err(RunError::Model(
                "key 'reduction': the reduction needs a brake (or mesh) model with [statics] and [real_modes]".into(),
            ));
        };
        reduced = Some(timings.time("reduction", || {
            reduction_stage(
                petsc,
                settings,
                k0,
                m,
                &model.mesh,
                &system.dofs,
                contact,
                state,
                f_ext,
                modes,
            )
        })?);
    }

    // Output.
    let start = Instant::now();
    let h5 = output.join("results.h5");
    let file = ResultsFile::create(petsc.world(), &h5)?;
    file.set_text("/", "scene", scene_text)?;
    file.set_text("/", "petsc_options", &petsc_options.join(" "))?;
    file.set_text("/", "squeal_version", env!("CARGO_PKG_VERSION"))?;
    file.set_number("/", "ranks", petsc.size() as f64)?;
    file.set_number("/", "dofs", dofs as f64)?;
    let mesh = model.as_ref().map(|m| &m.mesh);
    if let Some(model) = &model {
        file.write_mesh(&model.mesh)?;
        for i in &model.interfaces {
            let group = format!("model/interfaces/{}", i.name);
            file.set_text(&group, "master", &i.master)?;
            file.set_text(&group, "slave", &i.slave)?;
            file.set_text(&group, "kind", &format!("{:?}", i.kind).to_lowercase())?;
        }
        for l in &model.loads {
            let group = format!("model/loads/{}", l.surface);
            file.set_number(&group, "hydraulic_area_m2", l.area)?;
            file.set_number(&group, "pressure_pa", model.pressure)?;
        }
        for q in &quality_stats {
            let group = format!("model/quality/{}", q.block);
            file.set_number(&group, "elements", q.elements as f64)?;
            file.set_number(&group, "min_scaled_jacobian", q.min_scaled_jacobian)?;
            file.set_number(&group, "max_aspect_ratio", q.max_aspect_ratio)?;
            file.set_number(&group, "mean_aspect_ratio", q.mean_aspect_ratio)?;
            file.set_number(&group, "max_warping_deg", q.max_warping_deg)?;
        }
    }
    if let Some(b) = &balance {
        let rows: Vec<f64> = b.rows.iter().map(|&r| r as f64).collect();
        let elements: Vec<f64> = b.elements.iter().map(|&e| e as f64).collect();
        file.write_table("partition/rows_per_rank", &rows, "1")?;
        file.write_table("partition/elements_per_rank", &elements, "1")?;
    }
    let mut static_summary = None;
    if let (Some((contact, state)), Some(system), Some(model)) = (&preload, &system, &model) {
        let settings = scene.contact.clone().unwrap_or_default();
        static_summary = Some(write_static(
            petsc,
            &file,
            contact,
            state,
            &system.dofs,
            model,
            &settings,
            output,
        )?);
    }
    if let Some(modes) = &modes {
        file.write_real_modes(modes, system.as_ref().map(|s| &s.dofs))?;
    }
    for c in &complex {
        write_complex(petsc, &file, c, system.as_ref().map(|s| &s.dofs), output)?;
    }
    if let Some(sw) = &sweep_result {
        write_sweep(petsc, &file, sw, output)?;
    }
    let reduction_summary = match &reduced {
        Some(r) => Some(write_reduction(petsc, &file, r, dofs)?),
        None => None,
    };
    let before_transient = start.elapsed().as_secs_f64();

    // The transient streams into transient.h5 (linked as /transient) while it runs; what the
    // earlier stages found is already in results.h5.
    file.flush()?;
    let mut transient = None;
    let mut transient_error = None;
    if let Some(settings) = &scene.transient {
        let (Some((contact, state)), Some(f_ext), Some(system), Some(modes)) = (
            preload.as_ref(),
            static_load.as_ref(),
            system.as_ref(),
            modes.as_ref(),
        ) else {
            return Err(RunError::Model(
                "key 'transient': a transient needs a brake (or mesh) model with [statics] and [real_modes] (its start)".into(),
            ));
        };
        let damping = scene.damping.unwrap_or_default();
        let sensors = match &model {
            Some(model) if !settings.sensors.is_empty() => Some(sensor_rows(
                petsc,
                settings,
                &model.mesh,
                &system.dofs,
                reduced.as_ref().map(|r| &r.model.reduction),
            )?),
            _ => None,
        };
        let kick = transient_kick(petsc, settings, modes, model.as_ref(), &system.dofs)?;
        // The full model, or the reduced one in its own unknowns.
        let kick_t = match (&reduced, settings.start) {
            (Some(r), crate::time::transient::Start::Impulse) => {
                Some(r.model.reduction.project_force(petsc, &kick)?)
            }
            (Some(r), _) => Some(r.model.reduction.restrict(petsc, &kick)?),
            (None, _) => None,
        };
        let (k0_t, m_t, contact_t, f_t, q_t, state_t, kick_t) = match (&reduced, &kick_t) {
            (Some(r), Some(s)) => (
                &r.model.stiffness,
                &r.model.mass,
                &r.contact,
                &r.f_ext,
                &r.q_static,
                &r.static_state,
                s,
            ),
            _ => (
                k0,
                m,
                contact,
                f_ext,
                &state.displacement,
                &state.contact,
                &kick,
            ),
        };
        // Rayleigh damping on the integrated operators (never assembled).
        let c = if damping.rayleigh_alpha != 0.0 || damping.rayleigh_beta != 0.0 {
            crate::time::newmark::Damping::Rayleigh {
                alpha: damping.rayleigh_alpha,
                beta: damping.rayleigh_beta,
            }
        } else {
            crate::time::newmark::Damping::None
        };
        let modal_damping = if damping.has_modal() {
            let reduction = reduced.as_ref().map(|r| &r.model.reduction);
            let modal = modal_damping(petsc, &damping, modes, m_t, reduction)?;
            if petsc.rank() == 0 {
                let [low, high] = damping.modal_band_hz.unwrap_or_default();
                println!(
                    "modal damping: ratio {} on the {} real modes in [{low}, {high}] Hz",
                    damping.modal_ratio,
                    modal.modes()
                );
            }
            Some(modal)
        } else {
            None
        };
        let (signals, failure) = timings.time("transient", || {
            crate::time::transient::run(
                petsc,
                settings,
                crate::time::transient::TransientInputs {
                    k0: k0_t,
                    m: m_t,
                    c,
                    contact: contact_t,
                    f_ext: f_t,
                    q_static: q_t,
                    static_state: state_t,
                    kick: match settings.start {
                        crate::time::transient::Start::Impulse => {
                            crate::time::transient::Kick::Impulse(kick_t)
                        }
                        _ => crate::time::transient::Kick::Displacement(kick_t),
                    },
                    sensors: sensors.as_ref(),
                    modal_damping: modal_damping.as_ref(),
                },
                &crate::time::transient::TransientFiles::in_directory(output, options.restart),
            )
        })?;
        transient = Some(signals);
        // Reported after the results are written: the steps before the failure are kept.
        transient_error = failure;
    }

    let start = Instant::now();
    if let (Some(tr), Some(settings)) = (&transient, &scene.transient) {
        write_transient(petsc, &file, tr, settings, output)?;
    }

    if let (Some(mesh), 0) = (mesh, petsc.rank()) {
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
            .chain(complex.iter().take(1).flat_map(|c| {
                c.modes
                    .iter()
                    .take(c.shapes.len())
                    .enumerate()
                    .flat_map(move |(i, mode)| {
                        ["re", "im"].map(|part| NodalField {
                            label: format!(
                                "{} {part} ({:.1} Hz, zeta {:.2e})",
                                mode.name, mode.frequency_hz, mode.damping_ratio
                            ),
                            dataset: format!(
                                "/modes/complex/{}/shapes/mode_{:04}_{part}",
                                route_name(c.route),
                                i + 1
                            ),
                        })
                    })
            }))
            .collect();
        let path = output.join("results.xdmf");
        xdmf::write(&path, "results.h5", mesh, &fields)
            .map_err(|source| RunError::Io { path, source })?;
        let path = output.join("model.png");
        crate::io::preview::write_png(&path, mesh, 1200, 900)
            .map_err(|source| RunError::Io { path, source })?;
    }
    timings.stages.push((
        "output".into(),
        before_transient + start.elapsed().as_secs_f64(),
    ));
    for (name, secs) in &timings.stages {
        file.set_number("timings", &name.replace(' ', "_"), *secs)?;
    }
    drop(file);
    if let Some(e) = transient_error {
        return Err(RunError::Time(e));
    }

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
        notes: model.as_ref().map(|m| m.notes.clone()).unwrap_or_default(),
        quality: quality_stats,
        balance,
        unsupported,
        peak_memory_per_rank: peak,
        output: output.to_path_buf(),
        statics: static_summary,
        transient: transient.as_ref().map(|t| {
            // Index 0 of the signals is the start; steps follow.
            let its = &t.iterations[1.min(t.iterations.len())..];
            // The factorizations are counted once, not spread over the steps.
            let stepping = (t.seconds_stepping - t.seconds_jacobians).max(0.0);
            TransientSummary {
                steps: its.len(),
                simulated: t.time.last().copied().unwrap_or(0.0),
                mean_iterations: its.iter().sum::<usize>() as f64 / its.len().max(1) as f64,
                max_iterations: its.iter().copied().max().unwrap_or(0),
                seconds_per_step: stepping / t.steps_run.max(1) as f64,
                factor_entries: t.factor_entries,
                seconds_factorizing: t.seconds_factorizing,
                cuts: t.cuts,
                refreshes: t.refreshes,
                factorizations: t.factorizations,
                seconds_per_iteration: stepping / t.iterations_run.max(1) as f64,
                seconds_per_solve: t.seconds_solving / t.iterations_run.max(1) as f64,
                seconds_forces_per_step: t.seconds_in_forces / t.steps_run.max(1) as f64,
                seconds_products_per_step: t.seconds_in_products / t.steps_run.max(1) as f64,
            }
        }),
        reduction: reduction_summary,
        sweep: sweep_result.map(|s| SweepSummary {
            parameter: s.parameter.name(),
            points: s.values.len(),
            tracks: s.tracks.tracks.len(),
            unstable_per_point: s.unstable,
            statics_seconds: s.statics_seconds,
            modal_seconds: s.modal_seconds,
            values: s.values,
        }),
        complex: complex
            .iter()
            .map(|c| ComplexSummary {
                route: route_name(c.route),
                modes: c.modes.clone(),
                basis: c.basis,
                seconds: c.seconds,
                solve_seconds: c.solve_seconds,
            })
            .collect(),
    })
}

/// The sensor rows of the transient: the node nearest to each sensor position, its x, y, z
/// over the integrated unknowns (the full model's DOFs, or a row of T for the reduced one).
///
/// # Collective
/// The node nearest to a point and its distance.
fn nearest_node(mesh: &crate::mesh::Mesh, p: &[f64; 3]) -> Option<(usize, f64)> {
    mesh.coords
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let d = (0..3).map(|k| (c[k] - p[k]).powi(2)).sum::<f64>().sqrt();
            (i, d)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The transient's kick in full-model unknowns: a real mode shape, a seeded random
/// combination of all of them, or an impulse vector (N s) at a node.
///
/// # Collective
fn transient_kick<'p>(
    petsc: &'p Petsc,
    settings: &crate::time::transient::TransientSettings,
    modes: &crate::eigen::real_modes::RealModes<'p>,
    model: Option<&Model>,
    dofs: &crate::fem::dofmap::DofMap,
) -> Result<crate::la::Vector<'p>, RunError> {
    use crate::time::transient::Start;
    let first = modes.shapes.first().ok_or_else(|| {
        RunError::Model("key 'transient': the start needs at least one real mode".into())
    })?;
    // A mode's sign is the eigensolver's choice (it may differ with the number of ranks):
    // each kick shape is signed so that its product with a fixed field of the node positions
    // is positive, so the same scene starts the same way on any number of ranks.
    let sign_field = first.duplicate()?;
    if let Some(model) = model {
        let start = sign_field.ownership().start;
        let mut local = sign_field.local_mut()?;
        for node in dofs.owned_nodes() {
            let x = model.mesh.coords[node];
            for (k, &d) in dofs.node_dofs[node].iter().enumerate() {
                if d >= 0 {
                    local[d as usize - start] =
                        (37.0 * x[0] + 53.0 * x[1] + 71.0 * x[2] + 1.1 * k as f64 + 0.3).sin();
                }
            }
        }
    } else {
        sign_field.set_all(1.0)?;
    }
    let signed = |shape: &crate::la::Vector<'p>| -> Result<f64, RunError> {
        Ok(if shape.dot(&sign_field)? < 0.0 {
            -1.0
        } else {
            1.0
        })
    };
    match settings.start {
        Start::Mode => {
            let shape = modes.shapes.get(settings.mode - 1).ok_or_else(|| {
                RunError::Model(format!(
                    "key 'transient.mode' = {}: only {} real modes were computed",
                    settings.mode,
                    modes.shapes.len()
                ))
            })?;
            let kick = shape.try_clone()?;
            kick.scale(signed(shape)?)?;
            Ok(kick)
        }
        Start::Random => {
            let field = first.duplicate()?;
            field.set_all(0.0)?;
            let coefficients =
                crate::time::transient::random_coefficients(settings.seed, modes.shapes.len());
            for (c, shape) in coefficients.iter().zip(&modes.shapes) {
                field.axpy(c * signed(shape)?, shape)?;
            }
            Ok(field)
        }
        Start::Impulse => {
            let (Some(impulse), Some(model)) = (&settings.impulse, model) else {
                return Err(RunError::Model(
                    "key 'transient.impulse': an impulse start needs [transient.impulse] and a mesh"
                        .into(),
                ));
            };
            let (node, distance) = nearest_node(&model.mesh, &impulse.point)
                .ok_or_else(|| RunError::Model("an impulse needs a mesh with nodes".into()))?;
            if petsc.rank() == 0 {
                let c = model.mesh.coords[node];
                println!(
                    "  impulse ({:.3e}, {:.3e}, {:.3e}) N s at node {node} ({:.4}, {:.4}, {:.4}) m, {distance:.2e} m from the position asked",
                    impulse.value[0], impulse.value[1], impulse.value[2], c[0], c[1], c[2]
                );
            }
            let force = first.duplicate()?;
            force.set_all(0.0)?;
            if dofs.owner_of_node(node) == dofs.rank {
                let (rows, values): (Vec<i32>, Vec<f64>) = dofs.node_dofs[node]
                    .iter()
                    .zip(impulse.value)
                    .filter(|(d, _)| **d >= 0)
                    .map(|(&d, v)| (d, v))
                    .unzip();
                if rows.is_empty() {
                    return Err(RunError::Model(format!(
                        "key 'transient.impulse': node {node} nearest to the point is clamped; move the point"
                    )));
                }
                force.add_values(&rows, &values)?;
            }
            force.assemble()?;
            Ok(force)
        }
    }
}

fn sensor_rows<'p>(
    petsc: &'p Petsc,
    settings: &crate::time::transient::TransientSettings,
    mesh: &crate::mesh::Mesh,
    dofs: &crate::fem::dofmap::DofMap,
    reduction: Option<&crate::reduce::Reduction>,
) -> Result<crate::time::transient::Sensors<'p>, RunError> {
    let mut names = Vec::new();
    let mut rows = Vec::new();
    let mut first_row = 0;
    let mut owners = Vec::new();
    for (name, p) in &settings.sensors {
        let (node, distance) = nearest_node(mesh, p)
            .ok_or_else(|| RunError::Model("sensors need a mesh with nodes".into()))?;
        if petsc.rank() == 0 {
            let c = mesh.coords[node];
            println!(
                "  sensor '{name}': node {node} at ({:.4}, {:.4}, {:.4}) m, {distance:.2e} m from the position asked",
                c[0], c[1], c[2]
            );
        }
        let owner = dofs.owner_of_node(node);
        owners.push(owner);
        if owner < dofs.rank {
            first_row += 3;
        } else if owner == dofs.rank {
            for &d in &dofs.node_dofs[node] {
                rows.push(match (d, reduction) {
                    (d, _) if d < 0 => Vec::new(),
                    (d, Some(r)) => r.recovery_row(d as usize),
                    (d, None) => vec![(d, 1.0)],
                });
            }
        }
        names.push(name.clone());
    }
    let columns = match reduction {
        Some(r) => r.columns.clone(),
        None => dofs.owned_dofs(),
    };
    let rows = crate::la::ObservationMatrix::from_rows(petsc, first_row, &rows, columns)?;
    // Rows go rank by rank: block k of the gathered values is sensor order[k].
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by_key(|&i| owners[i]);
    Ok(crate::time::transient::Sensors { names, rows, order })
}

/// The modal damping of `[damping]` over the real modes in its band, in the integrated
/// unknowns: M phi_i of the full model, or M_r x_i with x_i the reduced coordinates of phi_i
/// (exact: the modes lie in the reduction's span).
///
/// # Collective
fn modal_damping<'p>(
    petsc: &'p Petsc,
    damping: &DampingSettings,
    modes: &crate::eigen::real_modes::RealModes<'p>,
    m: &SparseMatrix<'p>,
    reduction: Option<&crate::reduce::Reduction>,
) -> Result<crate::time::newmark::ModalDamping<'p>, RunError> {
    let [low, high] = damping.modal_band_hz.unwrap_or([0.0, 0.0]);
    let highest = modes.frequencies_hz.iter().copied().fold(0.0, f64::max);
    if high > highest {
        return Err(RunError::Model(format!(
            "key 'damping.modal_band_hz' = [{low}, {high}]: the band reaches {high} Hz but the {} real modes stop at {highest:.1} Hz; raise 'real_modes.count' (or lower the band)",
            modes.frequencies_hz.len()
        )));
    }
    let mut shapes = Vec::new();
    let mut coefficients = Vec::new();
    for (shape, &f) in modes.shapes.iter().zip(&modes.frequencies_hz) {
        let c = damping.modal_coefficient(2.0 * std::f64::consts::PI * f);
        if c <= 0.0 {
            continue;
        }
        let x = match reduction {
            Some(r) => r.restrict(petsc, shape)?,
            None => shape.try_clone()?,
        };
        let mass_shape = x.duplicate()?;
        m.mult(&x, &mass_shape)?;
        shapes.push(mass_shape);
        coefficients.push(c);
    }
    if shapes.is_empty() {
        return Err(RunError::Model(format!(
            "key 'damping.modal_band_hz' = [{low}, {high}]: no real mode in the band (modes from {:.1} to {highest:.1} Hz)",
            modes.frequencies_hz.first().copied().unwrap_or(0.0)
        )));
    }
    Ok(crate::time::newmark::ModalDamping::new(
        shapes,
        coefficients,
    ))
}

/// Writes /reduced (sizes, checks) and returns the summary.
fn write_reduction(
    petsc: &Petsc,
    file: &ResultsFile,
    r: &ReducedStage,
    full_dofs: usize,
) -> Result<ReductionSummary, RunError> {
    let red = &r.model.reduction;
    let mut rows = vec![0.0; petsc.size() as usize];
    rows[petsc.rank() as usize] = red.columns.len() as f64;
    crate::parallel::sum_in_place(petsc.world(), &mut rows);
    let mode_error = r
        .mode_check
        .iter()
        .map(|(f, g)| (g - f).abs() / f.abs().max(1e-300))
        .fold(0.0, f64::max);
    let summary = ReductionSummary {
        full_dofs,
        kept: red.kept,
        modal: red.modal,
        offered: red.offered,
        dropped: red.dropped,
        orthonormality: red.orthonormality,
        static_error: r.static_error,
        mode_check: r.mode_check.clone(),
        mode_error,
        stiffness_entries: r.model.stiffness.info()?.nonzeros,
        rows_per_rank: rows.iter().map(|&x| x as usize).collect(),
        seconds: red.seconds,
    };
    let g = "reduced";
    file.set_number(g, "full_dofs", full_dofs as f64)?;
    file.set_number(g, "size", red.size() as f64)?;
    file.set_number(g, "kept_dofs", red.kept as f64)?;
    file.set_number(g, "modal_coordinates", red.modal as f64)?;
    file.set_number(g, "basis_offered", red.offered as f64)?;
    file.set_number(g, "basis_dropped", red.dropped as f64)?;
    file.set_number(g, "mass_orthonormality", red.orthonormality)?;
    file.set_number(g, "static_state_error", r.static_error)?;
    file.set_number(g, "stiffness_entries", summary.stiffness_entries)?;
    file.set_number(g, "seconds", red.seconds)?;
    let full: Vec<f64> = r.mode_check.iter().map(|m| m.0).collect();
    let reduced: Vec<f64> = r.mode_check.iter().map(|m| m.1).collect();
    file.write_table("reduced/check/full_frequency", &full, "Hz")?;
    file.write_table("reduced/check/reduced_frequency", &reduced, "Hz")?;
    Ok(summary)
}

/// The reduced model with everything the time response needs in its unknowns.
struct ReducedStage<'p> {
    model: crate::reduce::ReducedModel<'p>,
    contact: crate::contact::ContactModel<'p>,
    f_ext: crate::la::Vector<'p>,
    q_static: crate::la::Vector<'p>,
    static_state: crate::contact::ContactState,
    /// Representation error of the static state, ||q0 - T x0|| / ||q0||.
    static_error: f64,
    /// Real modes of the reduced tangent vs the full ones in the basis: (full Hz, reduced Hz).
    mode_check: Vec<(f64, f64)>,
}

/// Keeps every element touching a contact surface (all interfaces: their forces act on kept
/// DOFs only), reduces the rest on the real modes of the tangent state and the static shape,
/// and checks the reduced model's real modes against the full ones.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the stages it joins
fn reduction_stage<'p>(
    petsc: &'p Petsc,
    settings: &crate::reduce::ReductionSettings,
    k0: &SparseMatrix<'p>,
    m: &SparseMatrix<'p>,
    mesh: &crate::mesh::Mesh,
    dofs: &crate::fem::dofmap::DofMap,
    contact: &crate::contact::ContactModel<'p>,
    state: &crate::statics::StaticState<'p>,
    f_ext: &crate::la::Vector<'p>,
    modes: &RealModes<'p>,
) -> Result<ReducedStage<'p>, RunError> {
    use crate::contact::kernel::Part;
    let surfaces: Vec<&str> = contact
        .interfaces
        .iter()
        .flat_map(|i| [i.master.as_str(), i.slave.as_str()])
        .collect();
    // The DOFs some contact point couples (every point is known on every rank).
    let mut coupled = vec![false; dofs.global_dofs()];
    for &d in contact.point_columns.iter().flatten() {
        if d >= 0 {
            coupled[d as usize] = true;
        }
    }
    let kept =
        crate::reduce::kept_dofs(mesh, dofs, &surfaces, Some(&coupled)).map_err(RunError::Model)?;
    let model = crate::reduce::reduce(
        petsc,
        k0,
        m,
        &kept,
        &modes.shapes,
        settings.static_shape.then_some(&state.displacement),
        settings,
    )?;
    let r = &model.reduction;
    let reduced_contact = contact
        .restricted(petsc, &r.map, r.columns.clone())
        .map_err(|e| RunError::Model(e.to_string()))?;
    let f_ext = r.project_force(petsc, f_ext)?;
    let q_static = r.restrict(petsc, &state.displacement)?;
    let recovered = state.displacement.duplicate()?;
    r.recover(petsc, &q_static, &recovered)?;
    recovered.axpy(-1.0, &state.displacement)?;
    let static_error = recovered.norm2()? / state.displacement.norm2()?.max(f64::MIN_POSITIVE);
    let static_state = reduced_contact.evaluate(&q_static, None, state.contact.friction_scale)?;
    // The reduced tangent's real modes: those of the full model in the basis, exactly.
    let mut kt = reduced_contact.joined_matrix(petsc, &model.stiffness)?;
    reduced_contact.add_tangent(&static_state, &[Part::Normal, Part::Stick], &mut kt)?;
    kt.assemble()?;
    kt.set_symmetric(true)?;
    let request = crate::eigen::real_modes::RealModeRequest {
        count: modes.shapes.len(),
        tolerance: 1e-10,
        ..Default::default()
    };
    let check = real_modes(petsc, &kt, &model.mass, false, &request, "reduced_")?;
    let mode_check = modes
        .frequencies_hz
        .iter()
        .copied()
        .zip(check.frequencies_hz.iter().copied())
        .collect();
    Ok(ReducedStage {
        model,
        contact: reduced_contact,
        f_ext,
        q_static,
        static_state,
        static_error,
        mode_check,
    })
}

/// What the complex-mode stage needs from the earlier ones.
struct ComplexInputs<'a, 'p> {
    /// Elastic stiffness (Rayleigh damping, full operator).
    k0: &'a SparseMatrix<'p>,
    /// The symmetric tangent of the real modes (K0 + K_c + K_stick, or the user's stiffness).
    k_symmetric: &'a SparseMatrix<'p>,
    m: &'a SparseMatrix<'p>,
    modes: Option<&'a RealModes<'p>>,
    preload: Option<(
        &'a crate::contact::ContactModel<'p>,
        &'a crate::contact::ContactState,
    )>,
    dofs: Option<&'a crate::fem::dofmap::DofMap>,
    /// User matrices: full stiffness (symmetric + circulatory) and damping.
    user: Option<(&'a SparseMatrix<'p>, Option<&'a SparseMatrix<'p>>)>,
}

pub fn route_name(route: Route) -> &'static str {
    match route {
        Route::Projected => "projected",
        Route::Full => "full",
        Route::Both => "both",
    }
}

/// Complex modes of the tangent state by the requested route(s).
///
/// # Collective
fn complex_stage<'p>(
    petsc: &'p Petsc,
    settings: &ComplexModeSettings,
    damping: &DampingSettings,
    input: ComplexInputs<'_, 'p>,
    timings: &mut Timings,
) -> Result<Vec<ComplexModes<'p>>, RunError> {
    use crate::contact::kernel::Part;
    let (kf, cf) = timings.time(
        "complex operators",
        || -> Result<(SparseMatrix<'p>, SparseMatrix<'p>), RunError> {
            match (input.preload, input.dofs, input.user) {
                (Some((contact, state)), Some(_), _) => {
                    let mut kf = contact.joined_matrix(petsc, input.k0)?;
                    contact.add_tangent(
                        state,
                        &[Part::Normal, Part::Stick, Part::Friction],
                        &mut kf,
                    )?;
                    kf.assemble()?;
                    let mut cf = contact.joined_matrix(petsc, input.k0)?;
                    cf.scale(damping.rayleigh_beta)?;
                    if damping.rayleigh_alpha != 0.0 {
                        cf.axpy(damping.rayleigh_alpha, input.m)?;
                    }
                    contact.add_tangent(state, &[Part::Damping], &mut cf)?;
                    cf.assemble()?;
                    Ok((kf, cf))
                }
                (_, _, Some((k_full, c))) => {
                    let kf = k_full.try_clone()?;
                    let mut cf = match c {
                        Some(c) => c.try_clone()?,
                        None => {
                            let mut z = input.m.try_clone()?;
                            z.zero_entries()?;
                            z
                        }
                    };
                    if damping.rayleigh_beta != 0.0 {
                        cf.axpy(damping.rayleigh_beta, input.k_symmetric)?;
                    }
                    if damping.rayleigh_alpha != 0.0 {
                        cf.axpy(damping.rayleigh_alpha, input.m)?;
                    }
                    Ok((kf, cf))
                }
                _ => Err(RunError::Model(
                    "key 'complex_modes': no tangent state (add [statics]) and no user matrices"
                        .into(),
                )),
            }
        },
    )?;
    let ops = Operators::new(&kf, &cf, input.m)?;
    let mut out = Vec::new();
    if settings.method != Route::Full {
        let modes = input.modes.ok_or_else(|| {
            RunError::Model("key 'complex_modes': the projected route needs [real_modes]".into())
        })?;
        let (kp, cp) = timings.time(
            "complex modes projection",
            || -> Result<(Vec<f64>, Vec<f64>), RunError> {
                match input.preload {
                    Some((contact, state)) => {
                        let world = petsc.world();
                        let channels = contact.observe_shapes(&modes.shapes)?;
                        let projection = ModalProjection::new(
                            world,
                            modes.eigenvalues.clone(),
                            channels,
                            contact.local.len(),
                            &contact.tangent_terms(state, &[Part::Normal, Part::Stick]),
                        );
                        Ok(projection.operators(
                            world,
                            &contact.tangent_terms(
                                state,
                                &[Part::Normal, Part::Stick, Part::Friction],
                            ),
                            &contact.tangent_terms(state, &[Part::Damping]),
                            damping,
                        ))
                    }
                    None => {
                        let (kp, cp, mp) = project_operators(&ops, &modes.shapes)?;
                        let n = modes.shapes.len();
                        let off = (0..n * n)
                            .map(|i| (mp[i] - f64::from(u8::from(i % (n + 1) == 0))).abs())
                            .fold(0.0f64, f64::max);
                        if off > 1e-8 {
                            return Err(RunError::Model(format!(
                                "projected complex modes: the real modes are not M-orthonormal (|Phi^T M Phi - I| = {off:.1e})"
                            )));
                        }
                        Ok((kp, cp))
                    }
                }
            },
        )?;
        let projected = timings.time("complex modes (projected)", || {
            crate::eigen::complex_modes::projected(&modes.shapes, &kp, &cp, Some(&ops), settings)
        })?;
        out.push(projected);
    }
    if settings.method != Route::Projected {
        let default_count = input.modes.map_or(20, |m| m.shapes.len());
        let full = timings.time("complex modes (full)", || {
            crate::eigen::complex_modes::full(petsc, &ops, settings, default_count)
        })?;
        out.push(full);
    }
    Ok(out)
}

/// Writes one route's complex modes: /modes/complex/<route>/ tables and shapes (real and
/// imaginary parts), `complex_modes_<route>.csv` and the stability diagram
/// `stability_<route>.png`.
///
/// # Collective
fn write_complex(
    petsc: &Petsc,
    file: &ResultsFile,
    c: &ComplexModes,
    dofs: Option<&crate::fem::dofmap::DofMap>,
    output: &Path,
) -> Result<(), RunError> {
    let route = route_name(c.route);
    let group = format!("modes/complex/{route}");
    let col = |f: &dyn Fn(&crate::eigen::complex_modes::ComplexMode) -> f64| -> Vec<f64> {
        c.modes.iter().map(f).collect()
    };
    file.write_table(
        &format!("{group}/eigenvalue_real"),
        &col(&|m| m.eigenvalue.0),
        "1/s",
    )?;
    file.write_table(
        &format!("{group}/eigenvalue_imag"),
        &col(&|m| m.eigenvalue.1),
        "rad/s",
    )?;
    file.write_table(
        &format!("{group}/frequency"),
        &col(&|m| m.frequency_hz),
        "Hz",
    )?;
    file.write_table(
        &format!("{group}/damping_ratio"),
        &col(&|m| m.damping_ratio),
        "1",
    )?;
    file.write_table(
        &format!("{group}/backward_error"),
        &col(&|m| m.backward_error),
        "1",
    )?;
    file.write_table(
        &format!("{group}/unstable"),
        &col(&|m| f64::from(u8::from(m.unstable))),
        "1 = unstable",
    )?;
    file.write_table(
        &format!("{group}/dominant_real_mode"),
        &col(&|m| m.dominant_real_mode.map_or(0.0, |k| (k + 1) as f64)),
        "real mode number (1-based; 0 = unknown)",
    )?;
    file.set_number(&group, "basis_size", c.basis as f64)?;
    file.set_number(&group, "seconds", c.seconds)?;
    for (i, (xr, xi)) in c.shapes.iter().enumerate() {
        for (part, v) in [("re", xr), ("im", xi)] {
            let name = format!("{group}/shapes/mode_{:04}_{part}", i + 1);
            match dofs {
                Some(dofs) => file.write_nodal(&name, dofs, &v.local()?, "m")?,
                None => file.write_dof_vector(&name, v, "1")?,
            }
        }
    }
    if petsc.rank() == 0 {
        let path = output.join(format!("complex_modes_{route}.csv"));
        let mut text = String::from(
            "name,frequency_hz,damping_ratio,re_s,im_s,backward_error,unstable,dominant_real_mode\n",
        );
        for m in &c.modes {
            text.push_str(&format!(
                "{},{:.10e},{:.10e},{:.10e},{:.10e},{:.3e},{},{}\n",
                m.name,
                m.frequency_hz,
                m.damping_ratio,
                m.eigenvalue.0,
                m.eigenvalue.1,
                m.backward_error,
                u8::from(m.unstable),
                m.dominant_real_mode
                    .map_or(String::new(), |k| format!("R{}", k + 1))
            ));
        }
        std::fs::write(&path, text).map_err(|source| RunError::Io {
            path: path.clone(),
            source,
        })?;
        let path = output.join(format!("stability_{route}.png"));
        crate::io::stability::write_diagram(&path, &c.modes, &format!("complex modes ({route})"))
            .map_err(|source| RunError::Io { path, source })?;
    }
    Ok(())
}

/// Writes the static state under /static: displacement, every contact point (point-id order)
/// and per-interface sums; returns the summary.
///
/// # Collective
#[allow(clippy::too_many_arguments)]
fn write_static(
    petsc: &Petsc,
    file: &ResultsFile,
    contact: &crate::contact::ContactModel,
    state: &crate::statics::StaticState,
    dofs: &crate::fem::dofmap::DofMap,
    model: &Model,
    settings: &crate::contact::ContactSettings,
    output: &Path,
) -> Result<StaticSummary, RunError> {
    let q = state.displacement.local()?;
    file.write_nodal("static/displacement", dofs, &q, "m")?;
    drop(q);
    let c = &state.contact;
    let column =
        |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..contact.local.len()).map(f).collect() };
    let columns: Vec<(&str, Vec<f64>, &str)> = vec![
        ("gap", column(&|k| c.observed[k].gap), "m"),
        ("pressure", column(&|k| c.response[k].pressure), "Pa"),
        (
            "contact_stiffness",
            column(&|k| c.response[k].stiffness),
            "Pa/m",
        ),
        ("traction", column(&|k| c.response[k].traction[0]), "Pa"),
        ("sliding_speed", column(&|k| c.observed[k].speed), "m/s"),
        (
            "status",
            column(&|k| c.response[k].status as u8 as f64),
            "0 open, 1 stick, 2 slip",
        ),
    ];
    for (name, local, units) in columns {
        let all = contact.gather(petsc, &local)?;
        file.write_table(&format!("static/contact/{name}"), &all, units)?;
        // Maps of the sliding interfaces (the pads) in the disc plane.
        if petsc.rank() == 0 && (name == "pressure" || name == "contact_stiffness") {
            for (i, itf) in contact.interfaces.iter().enumerate() {
                if !itf.friction.is_sliding() {
                    continue;
                }
                let path = output.join(format!("contact_{name}_{}.png", itf.name));
                crate::io::contact_map::write_map(
                    &path,
                    &model.mesh,
                    &contact.points,
                    &all,
                    i,
                    settings.gauss_points,
                    settings.axis(),
                    &format!("{name} ({units}) on {}", itf.name),
                )
                .map_err(|source| RunError::Io { path, source })?;
            }
        }
    }
    let pts = &contact.points;
    for (d, axis) in ["x", "y", "z"].iter().enumerate() {
        let v: Vec<f64> = pts.iter().map(|p| p.position[d]).collect();
        file.write_table(&format!("static/contact/{axis}"), &v, "m")?;
    }
    let v: Vec<f64> = pts.iter().map(|p| p.interface as f64).collect();
    file.write_table(
        "static/contact/interface",
        &v,
        "index into /static/interfaces order",
    )?;
    let v: Vec<f64> = pts.iter().map(|p| p.weight).collect();
    file.write_table("static/contact/weight", &v, "m^2")?;
    let v: Vec<f64> = pts.iter().map(|p| p.radius).collect();
    file.write_table("static/contact/radius", &v, "m")?;
    for (i, (itf, s)) in contact.interfaces.iter().zip(&state.summaries).enumerate() {
        let g = format!("static/interfaces/{}", itf.name);
        file.set_number(&g, "index", i as f64)?;
        file.set_number(
            &g,
            "points",
            (contact.candidates[i] - contact.misses[i]) as f64,
        )?;
        file.set_number(&g, "missed_points", contact.misses[i] as f64)?;
        file.set_number(&g, "normal_force_n", s.normal_force)?;
        file.set_number(&g, "friction_force_n", s.friction_force)?;
        file.set_number(&g, "braking_torque_nm", s.torque)?;
        file.set_number(&g, "max_pressure_pa", s.max_pressure)?;
        file.set_number(&g, "min_gap_m", s.min_gap)?;
        file.set_number(&g, "open_points", s.open as f64)?;
        file.set_number(&g, "stick_points", s.stick as f64)?;
        file.set_number(&g, "slip_points", s.slip as f64)?;
        file.set_text(&g, "normal_law", &format!("{:?}", itf.normal))?;
        file.set_text(&g, "friction_law", &format!("{:?}", itf.friction))?;
    }
    let log = |f: &dyn Fn(&crate::statics::NewtonRecord) -> f64| -> Vec<f64> {
        state.log.iter().map(f).collect()
    };
    file.write_table(
        "static/newton/load_step",
        &log(&|r| r.load_step as f64),
        "1",
    )?;
    file.write_table(
        "static/newton/iteration",
        &log(&|r| r.iteration as f64),
        "1",
    )?;
    file.write_table("static/newton/residual", &log(&|r| r.residual), "N")?;
    file.write_table("static/newton/step_length", &log(&|r| r.step_length), "1")?;
    file.set_number("static", "factorizations", state.factorizations as f64)?;
    file.set_number("static", "solves", state.solves as f64)?;
    file.set_number("static", "factor_entries", state.factor_entries)?;
    let piston_force: f64 = model.loads.first().map_or(0.0, |l| l.area * model.pressure);
    file.set_number("static", "piston_force_n", piston_force)?;
    let torque: f64 = state.summaries.iter().map(|s| s.torque).sum();
    file.set_number("static", "braking_torque_nm", torque)?;
    let last = state.log.last().expect("a converged step");
    Ok(StaticSummary {
        points: pts.len(),
        misses: contact
            .interfaces
            .iter()
            .enumerate()
            .map(|(i, itf)| (itf.name.clone(), contact.misses[i], contact.candidates[i]))
            .collect(),
        interfaces: contact
            .interfaces
            .iter()
            .map(|i| i.name.clone())
            .zip(state.summaries.iter().cloned())
            .collect(),
        newton_iterations: state.log.iter().filter(|r| r.step_length > 0.0).count(),
        load_steps: last.load_step,
        factorizations: state.factorizations,
        solves: state.solves,
        factor_entries: state.factor_entries,
        pairing_seconds: contact.pairing_seconds,
        seconds: state.seconds,
        seconds_factorizing: state.seconds_factorizing,
        piston_force,
        final_residual: last.residual,
    })
}

/// What a sweep needs from the earlier stages.
struct SweepInputs<'a, 'p> {
    k0: &'a SparseMatrix<'p>,
    contact: &'a mut crate::contact::ContactModel<'p>,
    nominal: &'a crate::statics::StaticState<'p>,
    f_ext: &'a crate::la::Vector<'p>,
    pressure_bar: f64,
    dofs: &'a crate::fem::dofmap::DofMap,
    modes: &'a RealModes<'p>,
}

/// The result of a sweep: tracked projected complex modes per parameter value.
pub struct SweepOutput {
    pub parameter: SweepParameter,
    pub values: Vec<f64>,
    pub tracks: crate::eigen::sweep::Tracks,
    pub unstable: Vec<usize>,
    pub statics_seconds: Vec<f64>,
    pub modal_seconds: Vec<f64>,
    pub newton_iterations: Vec<usize>,
    pub margin: f64,
}

/// Sweeps one parameter: per value, the static state is re-solved (warm-started from the
/// previous point; cold when that fails), the contact tangent re-projected on the fixed real
/// modes of the nominal state (nothing of size n refactorized beyond the static solve), the
/// dense complex modes solved, and modes tracked by MAC. The nominal laws are restored after.
///
/// # Collective
fn sweep_stage<'p>(
    petsc: &'p Petsc,
    sweep: &SweepSettings,
    settings: &ComplexModeSettings,
    damping: &DampingSettings,
    statics: &crate::statics::StaticSettings,
    input: SweepInputs<'_, 'p>,
) -> Result<SweepOutput, RunError> {
    use crate::contact::kernel::Part;
    let world = petsc.world();
    let contact = input.contact;
    let projection = ModalProjection::new(
        world,
        input.modes.eigenvalues.clone(),
        contact.observe_shapes(&input.modes.shapes)?,
        contact.local.len(),
        &contact.tangent_terms(&input.nominal.contact, &[Part::Normal, Part::Stick]),
    );
    let nominal_laws = contact.interfaces.clone();
    let nominal_speed = contact.disc_speed;
    let values = sweep.values();
    let f = input.f_ext.duplicate()?;
    let mut q = input.nominal.displacement.try_clone()?;
    let mut out = SweepOutput {
        parameter: sweep.parameter,
        values: values.clone(),
        tracks: Default::default(),
        unstable: Vec::new(),
        statics_seconds: Vec::new(),
        modal_seconds: Vec::new(),
        newton_iterations: Vec::new(),
        margin: settings.instability_margin,
    };
    let mut points = Vec::with_capacity(values.len());
    let mut bar = crate::progress::Progress::new("sweep", values.len(), petsc.rank());
    let result = (|| -> Result<(), RunError> {
        for (i, &v) in values.iter().enumerate() {
            contact.interfaces = nominal_laws.clone();
            contact.disc_speed = nominal_speed;
            f.copy_from(input.f_ext)?;
            match sweep.parameter {
                SweepParameter::PressureBar => f.scale(v / input.pressure_bar)?,
                SweepParameter::DiscSpeed => contact.disc_speed = v,
                p => crate::eigen::sweep::apply_to_laws(p, v, &mut contact.interfaces)
                    .map_err(RunError::Model)?,
            }
            let t = Instant::now();
            let state = match crate::statics::solve(
                petsc,
                input.k0,
                input.dofs,
                contact,
                &f,
                statics,
                Some(&q),
                |_| {},
            ) {
                Ok(s) => s,
                Err(_) => crate::statics::solve(
                    petsc,
                    input.k0,
                    input.dofs,
                    contact,
                    &f,
                    statics,
                    None,
                    |_| {},
                )
                .map_err(|e| {
                    RunError::Model(format!(
                        "sweep point {} ({} = {v}): {e}",
                        i + 1,
                        sweep.parameter.name()
                    ))
                })?,
            };
            out.statics_seconds.push(t.elapsed().as_secs_f64());
            out.newton_iterations
                .push(state.log.iter().filter(|r| r.step_length > 0.0).count());
            let t = Instant::now();
            let (kp, cp) = projection.operators(
                world,
                &contact
                    .tangent_terms(&state.contact, &[Part::Normal, Part::Stick, Part::Friction]),
                &contact.tangent_terms(&state.contact, &[Part::Damping]),
                damping,
            );
            // Every mode is tracked (a mode may cross f_max within the sweep); the tracks
            // reported are those below f_max somewhere.
            let pairs = crate::eigen::complex_modes::solve_dense(projection.size, &kp, &cp)
                .map_err(RunError::Model)?;
            out.modal_seconds.push(t.elapsed().as_secs_f64());
            out.unstable.push(
                pairs
                    .iter()
                    .filter(|(s, _)| {
                        crate::eigen::complex_modes::damping_ratio(*s)
                            < -settings.instability_margin
                            && settings
                                .f_max_hz
                                .is_none_or(|f| crate::eigen::complex_modes::frequency_hz(*s) <= f)
                    })
                    .count(),
            );
            let mut sorted = pairs;
            sorted.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1));
            points.push(sorted);
            q = state.displacement;
            bar.update(i + 1, &format!("{} = {v:.4}", sweep.parameter.name()));
        }
        Ok(())
    })();
    bar.finish();
    contact.interfaces = nominal_laws;
    contact.disc_speed = nominal_speed;
    result?;
    let mut tracks = crate::eigen::sweep::track(&points);
    if let Some(f_max) = settings.f_max_hz {
        tracks.tracks.retain(|t| {
            t.iter()
                .flatten()
                .any(|(s, _)| crate::eigen::complex_modes::frequency_hz(*s) <= f_max)
        });
    }
    out.tracks = tracks;
    Ok(out)
}

/// Writes a sweep: /sweep tables (parameter values; per track frequency, damping ratio, real
/// part, MAC; NaN where a track is lost), `sweep.csv`, and the plots `sweep_frequency.png`
/// and `sweep_real_part.png` (the coalescence picture; unstable points in red).
///
/// # Collective
fn write_sweep(
    petsc: &Petsc,
    file: &ResultsFile,
    sw: &SweepOutput,
    output: &Path,
) -> Result<(), RunError> {
    use crate::eigen::complex_modes::{damping_ratio, frequency_hz};
    file.write_table("sweep/values", &sw.values, sw.parameter.name())?;
    file.set_text("sweep", "parameter", sw.parameter.name())?;
    let per_point =
        |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..sw.values.len()).map(f).collect() };
    file.write_table(
        "sweep/unstable_modes",
        &per_point(&|i| sw.unstable[i] as f64),
        "1",
    )?;
    file.write_table("sweep/statics_seconds", &sw.statics_seconds, "s")?;
    file.write_table("sweep/modal_seconds", &sw.modal_seconds, "s")?;
    file.write_table(
        "sweep/newton_iterations",
        &per_point(&|i| sw.newton_iterations[i] as f64),
        "1",
    )?;
    let nan = f64::NAN;
    for (t, track) in sw.tracks.tracks.iter().enumerate() {
        let col = |f: &dyn Fn((f64, f64), f64) -> f64| -> Vec<f64> {
            track
                .iter()
                .map(|p| p.map_or(nan, |(s, m)| f(s, m)))
                .collect()
        };
        let g = format!("sweep/tracks/track_{:04}", t + 1);
        file.write_table(
            &format!("{g}/frequency"),
            &col(&|s, _| frequency_hz(s)),
            "Hz",
        )?;
        file.write_table(
            &format!("{g}/damping_ratio"),
            &col(&|s, _| damping_ratio(s)),
            "1",
        )?;
        file.write_table(&format!("{g}/real_part"), &col(&|s, _| s.0), "1/s")?;
        file.write_table(&format!("{g}/mac"), &col(&|_, m| m), "1")?;
    }
    if petsc.rank() != 0 {
        return Ok(());
    }
    let mut text = format!(
        "{},track,frequency_hz,damping_ratio,re_s,im_s,mac\n",
        sw.parameter.name()
    );
    for (t, track) in sw.tracks.tracks.iter().enumerate() {
        for (i, p) in track.iter().enumerate() {
            if let Some((s, m)) = p {
                text.push_str(&format!(
                    "{},{},{:.10e},{:.10e},{:.10e},{:.10e},{:.6}\n",
                    sw.values[i],
                    t + 1,
                    frequency_hz(*s),
                    damping_ratio(*s),
                    s.0,
                    s.1,
                    m
                ));
            }
        }
    }
    let path = output.join("sweep.csv");
    std::fs::write(&path, text).map_err(|source| RunError::Io {
        path: path.clone(),
        source,
    })?;
    for (name, y_of, y_label) in [
        ("sweep_frequency.png", 0usize, "frequency (Hz)"),
        ("sweep_real_part.png", 1, "Re(s) (1/s)"),
    ] {
        let path = output.join(name);
        crate::io::stability::write_sweep_plot(
            &path,
            &sw.values,
            &sw.tracks,
            y_of == 1,
            sw.margin,
            sw.parameter.label(),
            y_label,
        )
        .map_err(|source| RunError::Io { path, source })?;
    }
    Ok(())
}

/// Writes the transient signals under /transient (time; per interface normal force, friction
/// force, torque; iterations per step) and `torque.png` (braking torque against time).
///
/// # Collective
fn write_transient(
    petsc: &Petsc,
    file: &ResultsFile,
    tr: &crate::time::transient::Transient,
    settings: &crate::time::transient::TransientSettings,
    output: &Path,
) -> Result<(), RunError> {
    // The signals and states are in transient.h5, written as the run went.
    file.link_external("transient", "transient.h5")?;
    let g = "transient_run";
    file.set_number(g, "steps", tr.iterations.len().saturating_sub(1) as f64)?;
    file.set_number(
        g,
        "simulated_time_s",
        tr.time.last().copied().unwrap_or(0.0),
    )?;
    file.set_number(g, "step_cuts", tr.cuts as f64)?;
    file.set_number(g, "jacobian_refreshes", tr.refreshes as f64)?;
    file.set_number(g, "factorizations", tr.factorizations as f64)?;
    file.set_number(g, "factor_entries", tr.factor_entries)?;
    file.set_number(g, "states_written", tr.states as f64)?;
    file.set_number(g, "seconds_stepping", tr.seconds_stepping)?;
    file.set_number(g, "seconds_in_solves", tr.seconds_solving)?;
    file.set_number(g, "seconds_in_forces", tr.seconds_in_forces)?;
    file.set_number(g, "seconds_in_products", tr.seconds_in_products)?;
    file.set_number(g, "iterations_run", tr.iterations_run as f64)?;
    if let Some(t) = tr.resumed_at {
        file.set_number(g, "restarted_at_s", t)?;
    }
    let torque: Vec<f64> = (0..tr.time.len())
        .map(|k| tr.torque.iter().map(|t| t[k]).sum())
        .collect();
    if petsc.rank() == 0 {
        let path = output.join("torque.png");
        let (lo, hi) = torque
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let mut fig = crate::io::plot::Figure::new(
            1000,
            500,
            crate::io::plot::padded(0.0, tr.time.last().copied().unwrap_or(1.0), 0.0),
            crate::io::plot::padded(lo, hi, 0.05),
            "braking torque",
            "time (s)",
            "torque (N m)",
        );
        let points: Vec<(f64, f64)> = tr
            .time
            .iter()
            .copied()
            .zip(torque.iter().copied())
            .collect();
        fig.line(&points, crate::io::plot::BLUE);
        fig.save(&path)
            .map_err(|source| RunError::Io { path, source })?;
        write_spectrogram(tr, &torque, settings, output)?;
    }
    Ok(())
}

/// spectrogram.png: the short-time spectrum (80 dB range) of the sensor displacement component
/// that moves most (or of the braking torque without sensors), on the nominal step grid.
fn write_spectrogram(
    tr: &crate::time::transient::Transient,
    torque: &[f64],
    settings: &crate::time::transient::TransientSettings,
    output: &Path,
) -> Result<(), RunError> {
    use crate::post::spectrum;
    let spread = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
    };
    // The sensor component that moves most, or the torque without sensors.
    let mut best: Option<(f64, Vec<f64>, String)> = None;
    for (name, values) in tr.sensor_names.iter().zip(&tr.sensor_values) {
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let c: Vec<f64> = values[0].iter().skip(k).step_by(3).copied().collect();
            let sp = spread(&c);
            if best.as_ref().is_none_or(|b| sp > b.0) {
                best = Some((sp, c, format!("{name} {axis} displacement")));
            }
        }
    }
    let (signal, what) = match best {
        Some((_, c, what)) => (c, what),
        None => (torque.to_vec(), "braking torque".into()),
    };
    let uniform = spectrum::resample(&tr.time, &signal, settings.step);
    let window = (uniform.len() / 4).clamp(64, 4096).next_power_of_two() / 2;
    if uniform.len() < 2 * window || window < 32 {
        return Ok(()); // too short for a spectrogram
    }
    let s = spectrum::spectrogram(&uniform, tr.time[0], settings.step, window, window / 8);
    let rows = s
        .frequencies
        .iter()
        .take_while(|&&f| f <= settings.spectrogram_max_hz)
        .count()
        .max(2);
    let bins = s.frequencies.len();
    let columns = s.times.len();
    let mut db = Vec::with_capacity(columns * rows);
    for c in 0..columns {
        db.extend(
            s.power[c * bins..c * bins + rows]
                .iter()
                .map(|p| 10.0 * p.max(1e-300).log10()),
        );
    }
    let top = db.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let df = s.frequencies[1];
    let dt = s.times.get(1).map_or(1.0, |t| t - s.times[0]);
    let x = (s.times[0] - 0.5 * dt, s.times[columns - 1] + 0.5 * dt);
    let y = (0.0, rows as f64 * df);
    let mut fig = crate::io::plot::Figure::new(
        1000,
        500,
        x,
        y,
        &format!("spectrogram: {what} (dB)"),
        "time (s)",
        "frequency (Hz)",
    );
    fig.heatmap(
        columns,
        rows,
        &db,
        x,
        (y.0 - 0.5 * df, y.1 - 0.5 * df),
        (top - 80.0, top),
    );
    let path = output.join("spectrogram.png");
    fig.save(&path)
        .map_err(|source| RunError::Io { path, source })
}
