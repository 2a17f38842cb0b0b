//! The TOML scene: what model to build, which analyses to run, where to write. Unknown keys
//! are rejected; every error names the file and the key.

use crate::invalid::InvalidSetting;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::eigen::real_modes::RealModeRequest;
use crate::io::user_matrices::MatrixTerm;
use crate::mesh::brake::BrakeSpec;
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

/// The scene `squeal run` uses when given none.
pub const DEFAULT_SCENE: &str = include_str!("../jobs/default.toml");

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub model: ModelSource,
    /// Contact laws and disc speed (used when `[statics]` is present).
    #[serde(default)]
    pub contact: Option<crate::contact::ContactSettings>,
    /// Static preload with contact and friction; real modes are then those of the tangent
    /// state (K0 + K_c + K_stick).
    #[serde(default)]
    pub statics: Option<crate::statics::StaticSettings>,
    #[serde(default)]
    pub real_modes: Option<RealModeRequest>,
    /// Complex modes of the tangent state (projected on the real modes and/or full).
    #[serde(default)]
    pub complex_modes: Option<crate::eigen::complex_modes::ComplexModeSettings>,
    /// Rayleigh damping of the structure.
    #[serde(default)]
    pub damping: Option<crate::eigen::complex_modes::DampingSettings>,
    /// A parameter sweep of the projected complex modes (needs [statics], [real_modes]).
    #[serde(default)]
    pub sweep: Option<crate::eigen::sweep::SweepSettings>,
    /// The noise matrix: static state and projected complex modes at many operating points
    /// (needs [statics], [real_modes]).
    #[serde(default)]
    pub matrix: Option<crate::matrix::MatrixSettings>,
    /// Nonlinear time response from the static state (needs [statics], [real_modes]).
    #[serde(default)]
    pub transient: Option<crate::time::transient::TransientSettings>,
    /// Superelement reduction of the model for the time response (needs [statics],
    /// [real_modes]): the contact zone kept, the rest on the real modes + static shape.
    #[serde(default)]
    pub reduction: Option<crate::reduce::ReductionSettings>,
    /// Analyses of the transient's trajectory (DESIGN.md §2b), each asked for by its key.
    #[serde(default)]
    pub post: Option<PostSettings>,
    #[serde(default)]
    pub output: Output,
}

/// The `[post]` table: one key per analysis of the trajectory.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PostSettings {
    /// Growth, saturation, frequency, period and amplitude per cycle of the braking torque.
    #[serde(default)]
    pub limit_cycle: Option<crate::post::limit_cycle::LimitCycleSettings>,
    /// Modal coordinates and energies of every real mode along the stored states.
    #[serde(default)]
    pub modal_energy: Option<crate::post::modal_energy::ModalEnergySettings>,
    /// Complex modes of the tangent at stored states along the last periods, tracked.
    #[serde(default)]
    pub dynamic_stability: Option<crate::post::dynamic_stability::DynamicStabilitySettings>,
    /// Contact pressure and stiffness per point at phases of the last cycle, per pad.
    #[serde(default)]
    pub contact_cycle: Option<crate::post::contact_cycle::ContactCycleSettings>,
    /// Pseudo complex-mode trajectories of the unstable modes: the predicted saturation
    /// amplitude (needs no transient; compared with it when there is one).
    #[serde(default)]
    pub pseudo_trajectory: Option<crate::post::pseudo_trajectory::PseudoTrajectorySettings>,
    /// Radiated sound power (ERP) and levels of the pseudo trajectories' modes at alpha_sat
    /// and of the transient's last cycles (DESIGN.md §2c).
    #[serde(default)]
    pub loudness: Option<crate::post::loudness::LoudnessSettings>,
}

impl PostSettings {
    /// Whether an analysis of the stored states is asked for (they need the period).
    pub fn uses_states(&self) -> bool {
        self.modal_energy.is_some()
            || self.dynamic_stability.is_some()
            || self.contact_cycle.is_some()
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "source", rename_all = "lowercase", deny_unknown_fields)]
pub enum ModelSource {
    /// A rectangular block [0, size] meshed with `cells`; node sets u0/u1 (x faces),
    /// v0/v1 (y), w0/w1 (z).
    Block {
        element: ElementKind,
        size: [f64; 3],
        cells: [usize; 3],
        material: Material,
        #[serde(default)]
        clamp: Vec<String>,
    },
    /// An annular plate around the z axis; node sets inner, outer, bottom, top.
    Annulus {
        element: ElementKind,
        inner_radius: f64,
        outer_radius: f64,
        thickness: f64,
        cells: [usize; 3],
        material: Material,
        #[serde(default)]
        clamp: Vec<String>,
    },
    /// An Abaqus input file (the subset of `mesh::abaqus_inp`); its *BOUNDARY clamps apply.
    /// `constraint_penalty`: the penalty factor of its *EQUATION and *TIE constraints
    /// (`mesh::constraint`, default 1e5).
    Abaqus {
        file: PathBuf,
        #[serde(default = "default_constraint_penalty")]
        constraint_penalty: f64,
    },
    /// A Gmsh 4.1 ASCII mesh: physical volumes are components (each needs a material here,
    /// by name), physical surfaces are surfaces and node sets; `clamp` names node sets.
    Gmsh {
        file: PathBuf,
        materials: std::collections::BTreeMap<String, Material>,
        #[serde(default)]
        clamp: Vec<String>,
    },
    /// The parametric disc brake (`mesh::brake`): components, size, element, geometry,
    /// materials, pressure.
    Brake(Box<BrakeSpec>),
    /// Assembled matrices from another code, each a sum of Matrix Market files. `stiffness`
    /// is the symmetric part (real modes); `circulatory` (unsymmetric, e.g. friction) and
    /// `damping` enter the complex modes. A term's coefficient is multiplied by
    /// disc_speed^speed_power (gyroscopic terms: 1, centrifugal: 2).
    Matrices {
        stiffness: Vec<MatrixTerm>,
        mass: Vec<MatrixTerm>,
        #[serde(default)]
        circulatory: Vec<MatrixTerm>,
        #[serde(default)]
        damping: Vec<MatrixTerm>,
        /// rad/s; needed by terms with a speed_power.
        #[serde(default)]
        disc_speed: Option<f64>,
    },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    #[serde(default = "default_directory")]
    pub directory: PathBuf,
    /// Export the assembled K and M (and, with complex modes, the tangent K_tangent and the
    /// damping C of the static state): any of "mtx" (Matrix Market), "petsc" (PETSc binary).
    #[serde(default)]
    pub export_matrices: Vec<String>,
    /// Also write the model as an Abaqus input file (`model.inp`), to open it in other tools.
    #[serde(default)]
    pub write_inp: bool,
    /// The transient's vibration on the mesh (vibration.xdmf): the stored states of the last
    /// `frame_periods` periods of the vibration (0: none), thinned to about
    /// `frames_per_period` a period (every stored state when they are fewer).
    #[serde(default = "default_frame_periods")]
    pub frame_periods: f64,
    #[serde(default = "default_frames_per_period")]
    pub frames_per_period: usize,
}

fn default_frame_periods() -> f64 {
    4.0
}

fn default_frames_per_period() -> usize {
    24
}

fn default_directory() -> PathBuf {
    PathBuf::from("results")
}

impl Default for Output {
    fn default() -> Self {
        Output {
            directory: default_directory(),
            export_matrices: Vec::new(),
            write_inp: false,
            frame_periods: default_frame_periods(),
            frames_per_period: default_frames_per_period(),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read: {source}")]
    Read {
        file: String,
        source: std::io::Error,
    },
    /// Not TOML, or not the schema (serde's message names the line and key).
    #[error("{file}: {message}")]
    Invalid { file: String, message: String },
    /// A key out of range.
    #[error("{file}: {source}")]
    Setting {
        file: String,
        source: InvalidSetting,
    },
}

impl Scene {
    /// What a transient's state depends on, table by table, as stable hashes (a restart
    /// compares them with its checkpoint's): the model, contact, preload, damping, real modes,
    /// reduction and the transient's step and start. Left out: what a restart may change
    /// (the number of steps, the solver's controls, outputs, sensors and post-processing).
    pub fn restart_fingerprint(&self) -> Vec<(&'static str, u64)> {
        let transient = self.transient.clone().map(|mut t| {
            let defaults: crate::time::transient::TransientSettings =
                toml::from_str("steps = 0").expect("the transient's defaults parse");
            t.steps = 0;
            t.checkpoint_every = 0;
            t.stop_after_saturation = None;
            t.newton = defaults.newton;
            t.max_cuts = defaults.max_cuts;
            t.refresh = defaults.refresh;
            t.update_factor = defaults.update_factor;
            t.eliminate_points = defaults.eliminate_points;
            t.anderson = defaults.anderson;
            t.step_error_fraction = defaults.step_error_fraction;
            t.jacobian_factor = defaults.jacobian_factor;
            t.tolerance = defaults.tolerance;
            t.tolerance_reference = defaults.tolerance_reference;
            t.max_iterations = defaults.max_iterations;
            t.state_interval = 0.0;
            t.sensors.clear();
            t.spectrogram_max_hz = 0.0;
            t
        });
        let text = |value: Result<String, toml::ser::Error>| value.unwrap_or_default();
        let tables = [
            ("model", text(toml::to_string(&self.model))),
            ("contact", text(toml::to_string(&self.contact))),
            ("statics", text(toml::to_string(&self.statics))),
            ("damping", text(toml::to_string(&self.damping))),
            ("real_modes", text(toml::to_string(&self.real_modes))),
            ("reduction", text(toml::to_string(&self.reduction))),
            ("transient", text(toml::to_string(&transient))),
        ];
        tables
            .into_iter()
            .map(|(name, t)| (name, crate::fault::fnv1a(t.as_bytes())))
            .collect()
    }

    /// What a matrix point's result depends on, as one stable hash: the model, contact,
    /// preload, damping, real modes, complex modes and the matrix itself. A journal, a slice
    /// and a merge compare it (the output directory and the other analyses may differ).
    pub fn matrix_fingerprint(&self) -> String {
        let text = |value: Result<String, toml::ser::Error>| value.unwrap_or_default();
        let mut tables = vec![
            text(toml::to_string(&self.model)),
            text(toml::to_string(&self.contact)),
            text(toml::to_string(&self.statics)),
            text(toml::to_string(&self.damping)),
            text(toml::to_string(&self.real_modes)),
            text(toml::to_string(&self.complex_modes)),
            text(toml::to_string(&self.matrix)),
        ];
        // The reduced statics' superelement; the full route leaves it out, so journals of
        // full-model matrices keep their fingerprints.
        if let Some(m) = &self.matrix {
            if m.statics == crate::matrix::StaticsModel::Reduced {
                tables.push(text(toml::to_string(&self.reduction)));
            }
            // The saturated modes' studies and levels follow these tables.
            if m.saturation_modes > 0 {
                let post = self.post.as_ref();
                tables.push(text(toml::to_string(&post.map(|p| &p.pseudo_trajectory))));
                tables.push(text(toml::to_string(&post.map(|p| &p.loudness))));
            }
        }
        format!(
            "{:016x}",
            crate::fault::fnv1a(tables.join("\n[]\n").as_bytes())
        )
    }

    /// Parses and validates a scene; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| SceneError::Invalid {
            file: file.into(),
            message: e.to_string(),
        })?;
        scene.validate().map_err(|source| SceneError::Setting {
            file: file.into(),
            source,
        })?;
        Ok(scene)
    }

    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            file: file.clone(),
            source,
        })?;
        Scene::parse(&text, &file)
    }

    fn validate(&self) -> Result<(), InvalidSetting> {
        self.validate_model()?;
        self.validate_analyses()?;
        self.validate_frames()
    }

    /// `[output]`'s vibration frames.
    fn validate_frames(&self) -> Result<(), InvalidSetting> {
        let periods = self.output.frame_periods;
        if !(periods.is_finite() && (0.0..=1e4).contains(&periods)) {
            return Err(InvalidSetting::new(
                "output.frame_periods",
                format!(" = {periods}: must be in [0, 1e4] (0 writes no vibration frames)"),
            ));
        }
        if self.output.frames_per_period == 0 || self.output.frames_per_period > 1000 {
            return Err(InvalidSetting::new(
                "output.frames_per_period",
                format!(
                    " = {}: must be in [1, 1000] (frame_periods = 0 writes none)",
                    self.output.frames_per_period
                ),
            ));
        }
        Ok(())
    }

    /// The `[model]` table: dimensions, cells, materials, files, matrix terms.
    fn validate_model(&self) -> Result<(), InvalidSetting> {
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(InvalidSetting::new(
                    key,
                    format!(" = {v}: must be a positive finite length (m)"),
                ))
            }
        };
        let cells_ok = |cells: &[usize; 3]| {
            if cells.iter().all(|&c| c > 0) {
                Ok(())
            } else {
                Err(InvalidSetting::new(
                    "model.cells",
                    format!(" = {cells:?}: every entry must be at least 1"),
                ))
            }
        };
        match &self.model {
            ModelSource::Block {
                size,
                cells,
                material,
                ..
            } => {
                for (i, s) in size.iter().enumerate() {
                    positive(&format!("model.size[{i}]"), *s)?;
                }
                cells_ok(cells)?;
                material
                    .validate()
                    .map_err(|e| InvalidSetting::new("model.material", format!(": {e}")))?;
            }
            ModelSource::Annulus {
                inner_radius,
                outer_radius,
                thickness,
                cells,
                material,
                ..
            } => {
                positive("model.inner_radius", *inner_radius)?;
                positive("model.outer_radius", *outer_radius)?;
                positive("model.thickness", *thickness)?;
                if outer_radius <= inner_radius {
                    return Err(InvalidSetting::new(
                        "model.outer_radius",
                        format!(
                            " = {outer_radius}: must exceed model.inner_radius = {inner_radius}"
                        ),
                    ));
                }
                cells_ok(cells)?;
                if cells[1] < 3 {
                    return Err(InvalidSetting::new(
                        "model.cells[1]",
                        " (circumferential): at least 3",
                    ));
                }
                material
                    .validate()
                    .map_err(|e| InvalidSetting::new("model.material", format!(": {e}")))?;
            }
            ModelSource::Brake(spec) => spec.validate()?,
            ModelSource::Gmsh {
                file, materials, ..
            } => {
                if file.as_os_str().is_empty() {
                    return Err(InvalidSetting::new("model.file", ": name the .msh file"));
                }
                for (name, m) in materials {
                    m.validate().map_err(|e| {
                        InvalidSetting::new(format!("model.materials.{name}"), format!(": {e}"))
                    })?;
                }
            }
            ModelSource::Abaqus {
                file,
                constraint_penalty,
            } => {
                if file.as_os_str().is_empty() {
                    return Err(InvalidSetting::new("model.file", ": name the .inp file"));
                }
                if !(constraint_penalty.is_finite() && *constraint_penalty >= 1.0) {
                    return Err(InvalidSetting::new(
                        "model.constraint_penalty",
                        format!(
                            " = {constraint_penalty}: must be a finite factor >= 1 (default 1e5)"
                        ),
                    ));
                }
            }
            ModelSource::Matrices {
                stiffness,
                mass,
                circulatory,
                damping,
                disc_speed,
            } => {
                if stiffness.is_empty() || mass.is_empty() {
                    return Err(InvalidSetting::new(
                        "model.stiffness",
                        " and key 'model.mass' each need at least one { file, coefficient } term",
                    ));
                }
                if let Some(w) = disc_speed {
                    if !(w.is_finite() && *w > 0.0) {
                        return Err(InvalidSetting::new(
                            "model.disc_speed",
                            format!(" = {w}: must be positive (rad/s)"),
                        ));
                    }
                }
                let tables = [
                    ("stiffness", stiffness),
                    ("mass", mass),
                    ("circulatory", circulatory),
                    ("damping", damping),
                ];
                for (table, terms) in tables {
                    let key = format!("model.{table}");
                    for t in terms {
                        let file = t.file.display();
                        if !t.coefficient.is_finite() {
                            let detail = format!(": term '{file}': coefficient must be finite");
                            return Err(InvalidSetting::new(key, detail));
                        }
                        if t.speed_power != 0 && disc_speed.is_none() {
                            let detail = format!(
                                ": term '{file}' has speed_power {}: set key 'model.disc_speed' (rad/s)",
                                t.speed_power
                            );
                            return Err(InvalidSetting::new(key, detail));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The analysis tables and what each needs from the others.
    fn validate_analyses(&self) -> Result<(), InvalidSetting> {
        if let Some(r) = &self.real_modes {
            if r.count == 0 && r.f_max_hz.is_none() {
                return Err(InvalidSetting::new(
                    "real_modes.count",
                    " must be at least 1 (or set real_modes.f_max_hz)",
                ));
            }
            if let Some(f) = r.f_max_hz {
                if !(f.is_finite() && f > 0.0) {
                    return Err(InvalidSetting::new(
                        "real_modes.f_max_hz",
                        format!(" = {f}: must be positive"),
                    ));
                }
            }
            if !(r.tolerance > 0.0 && r.tolerance < 1.0) {
                return Err(InvalidSetting::new(
                    "real_modes.tolerance",
                    format!(" = {}: must be in (0, 1)", r.tolerance),
                ));
            }
        }
        if let Some(c) = &self.contact {
            c.validate()?;
        }
        if let Some(st) = &self.statics {
            st.validate()?;
            if matches!(self.model, ModelSource::Matrices { .. }) {
                return Err(InvalidSetting::new("statics", ": a static preload needs a mesh with contact interfaces, not assembled matrices"));
            }
        }
        if let Some(d) = &self.damping {
            d.validate()?;
            if d.has_modal() && (self.complex_modes.is_some() || self.sweep.is_some()) {
                return Err(InvalidSetting::new("damping.modal_ratio", ": modal damping is applied by [transient] only; the complex modes and the sweep use the assembled operators (Rayleigh damping). Run them from a scene without it"));
            }
            if d.has_modal() && self.transient.is_none() {
                return Err(InvalidSetting::new(
                    "damping.modal_ratio",
                    ": modal damping is applied by [transient]; this scene has none",
                ));
            }
        }
        if let Some(c) = &self.complex_modes {
            c.validate()?;
            let needs_basis = c.method != crate::eigen::complex_modes::Route::Full;
            if needs_basis && self.real_modes.is_none() {
                return Err(InvalidSetting::new("complex_modes.method", ": the projected route needs a [real_modes] table (its basis); or set method = \"full\""));
            }
            if let ModelSource::Brake(_)
            | ModelSource::Abaqus { .. }
            | ModelSource::Gmsh { .. }
            | ModelSource::Block { .. }
            | ModelSource::Annulus { .. } = &self.model
            {
                if self.statics.is_none() {
                    return Err(InvalidSetting::new("complex_modes", ": complex modes of a mesh need the tangent state of a [statics] preload (contact and friction); add [statics]"));
                }
            }
        }
        if let Some(t) = &self.transient {
            t.validate()?;
            if self.statics.is_none() || self.real_modes.is_none() {
                return Err(InvalidSetting::new("transient", ": the time response starts from the static state plus a real mode: it needs [statics] and [real_modes]"));
            }
        }
        if let Some(r) = &self.reduction {
            r.validate()?;
            if self.statics.is_none() || self.real_modes.is_none() {
                return Err(InvalidSetting::new("reduction", ": the reduction basis is the real modes of the preloaded model plus its static shape: it needs [statics] and [real_modes]"));
            }
        }
        if let Some(sw) = &self.sweep {
            sw.validate()?;
            if self.statics.is_none() || self.real_modes.is_none() {
                return Err(InvalidSetting::new("sweep", ": a sweep re-solves the static preload and re-projects on the real modes: it needs [statics] and [real_modes]"));
            }
        }
        if let Some(m) = &self.matrix {
            m.validate()?;
            if self.statics.is_none() || self.real_modes.is_none() {
                return Err(InvalidSetting::new("matrix", ": every point re-solves the static preload and re-projects on the real modes: it needs [statics] and [real_modes]"));
            }
            if self.damping.is_some_and(|d| d.has_modal()) {
                return Err(InvalidSetting::new("damping.modal_ratio", ": modal damping is applied by [transient] only; the matrix uses the assembled operators (Rayleigh damping)"));
            }
            if m.statics == crate::matrix::StaticsModel::Reduced && self.reduction.is_none() {
                return Err(InvalidSetting::new("matrix.statics", " = \"reduced\" solves every point on the superelement of [reduction]: add a [reduction] table (its defaults will do) or set statics = \"full\""));
            }
        }
        if let Some(post) = &self.post {
            let only_pseudo = post.limit_cycle.is_none() && !post.uses_states();
            if self.transient.is_none() && !only_pseudo {
                return Err(InvalidSetting::new("post", ": the analyses of a trajectory need a [transient] (only pseudo_trajectory runs without one)"));
            }
            if let Some(pt) = &post.pseudo_trajectory {
                pt.validate()?;
                if self.statics.is_none() || self.real_modes.is_none() {
                    return Err(InvalidSetting::new("post.pseudo_trajectory", ": linearizes the contact of the preloaded model on its real modes: it needs [statics] and [real_modes]"));
                }
            }
            if let Some(lc) = &post.limit_cycle {
                lc.validate()?;
            }
            if let Some(me) = &post.modal_energy {
                me.validate()?;
            }
            if let Some(ds) = &post.dynamic_stability {
                ds.validate()?;
            }
            if let Some(cc) = &post.contact_cycle {
                cc.validate()?;
            }
            if let Some(l) = &post.loudness {
                l.validate()?;
                if self.statics.is_none() || self.real_modes.is_none() {
                    return Err(InvalidSetting::new("post.loudness", ": radiates the preloaded model's vibration: it needs [statics] and [real_modes]"));
                }
            }
            let stored = self.transient.as_ref().map_or(0.0, |t| t.state_interval);
            if post.uses_states() && stored <= 0.0 {
                return Err(InvalidSetting::new("post", ": modal_energy, dynamic_stability and contact_cycle analyse the stored states: 'transient.state_interval' must be > 0"));
            }
            if post.uses_states() && (self.statics.is_none() || self.real_modes.is_none()) {
                return Err(InvalidSetting::new("post", ": modal_energy, dynamic_stability and contact_cycle work on the preloaded model and its real modes: they need [statics] and [real_modes]"));
            }
        }
        for e in &self.output.export_matrices {
            if e != "mtx" && e != "petsc" {
                return Err(InvalidSetting::new(
                    "output.export_matrices",
                    format!(": '{e}' is not one of \"mtx\", \"petsc\""),
                ));
            }
        }
        Ok(())
    }
}

fn default_constraint_penalty() -> f64 {
    crate::mesh::constraint::DEFAULT_PENALTY
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn restart_fingerprint_sees_the_model_and_not_the_run_length() {
        let base = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\n[statics]\n\
                    [real_modes]\ncount = 20\n[transient]\nstep = 2e-6\nsteps = 100\n";
        let print = |text: &str| Scene::parse(text, "t").unwrap().restart_fingerprint();
        let reference = print(base);
        let given = ["model", "statics", "real_modes", "transient"];
        for (table, hash) in &reference {
            assert_eq!(
                *hash != fnv1a_empty(),
                given.contains(table),
                "{reference:?}"
            );
        }
        let longer = print(&base.replace(
            "steps = 100",
            "steps = 900\nnewton = \"full\"\ntolerance = 1e-4\ntolerance_reference = \"vibration\"",
        ));
        assert_eq!(
            reference, longer,
            "a longer run with another Newton and tolerance is the same run"
        );
        for (changed, table) in [
            (base.replace("6000", "7000"), "model"),
            (base.replace("count = 20", "count = 30"), "real_modes"),
            (base.replace("step = 2e-6", "step = 1e-6"), "transient"),
        ] {
            let other = print(&changed);
            let differs: Vec<_> = reference
                .iter()
                .zip(&other)
                .filter(|(a, b)| a.1 != b.1)
                .map(|(a, _)| a.0)
                .collect();
            assert_eq!(differs, vec![table], "{changed}");
        }
    }

    fn fnv1a_empty() -> u64 {
        crate::fault::fnv1a(b"")
    }

    #[test]
    fn a_brake_scene_takes_defaults_and_names_unknown_keys() {
        let text = "[model]\nsource = \"brake\"\ncomponents = [\"disc\", \"inner_pad\"]\ntarget_dofs = 5000\n[model.geometry]\ndisc_thickness = 0.03\n";
        let s = Scene::parse(text, "b.toml").unwrap();
        let ModelSource::Brake(spec) = &s.model else {
            panic!("not a brake")
        };
        assert_eq!(spec.components.len(), 2);
        assert_eq!(spec.geometry.disc_thickness, 0.03);
        assert_eq!(spec.geometry.pad_arc_deg, 52.0);
        let e = Scene::parse(&text.replace("disc_thickness", "disc_thicknes"), "b.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.toml") && e.contains("disc_thicknes"), "{e}");
        let e = Scene::parse(&text.replace("0.03", "-0.03"), "b.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("model.geometry.disc_thickness"), "{e}");
        let e = Scene::parse(&text.replace("\"inner_pad\"", "\"rotor\""), "b.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("rotor") && e.contains("inner_pad"), "{e}");
    }

    #[test]
    fn every_scene_in_jobs_parses() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs");
        let mut count = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
                count += 1;
            }
        }
        assert!(count >= 4, "{count} scenes");
    }

    #[test]
    fn modal_damping_keys_are_checked() {
        let base = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs/brake-transient.toml"),
        )
        .unwrap();
        let with = |damping: &str| {
            base.replace(
                "rayleigh_beta = 1.0e-7",
                &format!("rayleigh_beta = 1.0e-7\n{damping}"),
            )
        };
        let ok = Scene::parse(
            &with("modal_ratio = 0.01\nmodal_band_hz = [1000.0, 8000.0]"),
            "t",
        )
        .unwrap();
        let d = ok.damping.unwrap();
        let omega = 2.0 * std::f64::consts::PI * 4000.0;
        assert_eq!(d.modal_coefficient(omega), 2.0 * 0.01 * omega);
        assert_eq!(
            d.modal_coefficient(2.0 * std::f64::consts::PI * 9000.0),
            0.0
        );
        for (damping, key) in [
            ("modal_ratio = 0.01", "damping.modal_band_hz"),
            (
                "modal_ratio = -0.01\nmodal_band_hz = [1.0, 2.0]",
                "damping.modal_ratio",
            ),
            (
                "modal_ratio = 0.01\nmodal_band_hz = [2.0, 1.0]",
                "damping.modal_band_hz",
            ),
        ] {
            let e = Scene::parse(&with(damping), "t.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(key) && e.contains("t.toml"), "{damping}: {e}");
        }
    }

    #[test]
    fn default_scene_parses() {
        let s = Scene::parse(DEFAULT_SCENE, "default").unwrap();
        assert!(s.real_modes.is_some());
    }

    #[test]
    fn unknown_key_is_named() {
        let text = DEFAULT_SCENE.replace("count = 60", "count = 60\nmodes = 4");
        let e = Scene::parse(&text, "x.toml").unwrap_err().to_string();
        assert!(e.contains("x.toml") && e.contains("modes"), "{e}");
    }

    #[test]
    fn negative_thickness_is_named() {
        let text = DEFAULT_SCENE.replace("disc_thickness = 0.028", "disc_thickness = -0.028");
        let e = Scene::parse(&text, "x.toml").unwrap_err().to_string();
        assert!(e.contains("model.geometry.disc_thickness"), "{e}");
    }

    #[test]
    fn nan_modulus_is_named() {
        let text = DEFAULT_SCENE.replace("e = 1.1e11", "e = nan");
        let e = Scene::parse(&text, "x.toml").unwrap_err().to_string();
        assert!(
            e.contains("model.materials.disc") && e.contains("NaN"),
            "{e}"
        );
    }
}
