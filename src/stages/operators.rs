//! Stage 2: the operators. The elastic stiffness K0 and the mass M, assembled from a mesh
//! model (distributed, constraints eliminated) or summed from the user's Matrix Market files.

use std::path::Path;

use super::model::Model;
use super::{RunError, Timings};
use crate::fem::dofmap::DofMap;
use crate::fem::petsc::{assemble_system_as, AssembledSystem};
use crate::io::user_matrices::{load_sum, MatrixTerm};
use crate::la::{MatrixFormat, Petsc, SparseMatrix};
use crate::mesh::partition;
use crate::scene::{ModelSource, Scene};

/// K0 and M with what later stages need to know about them.
pub struct Operators<'p> {
    /// Elastic stiffness K0 (or the user's symmetric stiffness sum).
    pub k0: SparseMatrix<'p>,
    pub m: SparseMatrix<'p>,
    /// The DOF map of a mesh model; None for user matrices.
    pub dofs: Option<DofMap>,
    /// K0 is singular (free-free bodies): the real-mode solver shifts below zero.
    pub free_free: bool,
    /// Components not held against rigid-body motion (their modes sit at 0 Hz).
    pub unsupported: Vec<String>,
    pub balance: Option<LoadBalance>,
    /// User matrices for the complex modes: full stiffness (symmetric + circulatory) and
    /// damping.
    pub user_complex: Option<(SparseMatrix<'p>, Option<SparseMatrix<'p>>)>,
}

impl Operators<'_> {
    pub fn dofs(&self) -> usize {
        self.k0.global_rows()
    }
}

/// How evenly the ranks share the work.
#[derive(Debug, Clone)]
pub struct LoadBalance {
    pub rows: Vec<usize>,
    pub elements: Vec<usize>,
    pub row_imbalance: f64,
    pub element_imbalance: f64,
}

/// Assembles K0 and M of a mesh model; `format` None picks SBAIJ where every node is fully
/// free or clamped (the static Newton's unsymmetric tangent wants AIJ).
///
/// # Collective
pub fn assemble<'p>(
    petsc: &'p Petsc,
    model: &Model,
    format: Option<MatrixFormat>,
) -> Result<Operators<'p>, RunError> {
    let s = assemble_system_as(petsc, &model.mesh, &model.clamps, format)?;
    let fixed: Vec<[bool; 3]> = s.dofs.node_dofs.iter().map(|d| d.map(|x| x < 0)).collect();
    let unsupported = partition::unsupported_parts(&model.mesh, &fixed);
    let balance = load_balance(petsc, &s);
    // Parts not held against rigid motion make K singular: shift below zero.
    let free_free = s.is_free_free() || !unsupported.is_empty();
    Ok(Operators {
        k0: s.stiffness,
        m: s.mass,
        dofs: Some(s.dofs),
        free_free,
        unsupported,
        balance: Some(balance),
        user_complex: None,
    })
}

/// The user's matrices of a `matrices` model: sums of Matrix Market terms at the disc speed;
/// with `complex` also the full (circulatory) stiffness and the damping.
///
/// # Collective
pub fn read_matrices<'p>(
    petsc: &'p Petsc,
    source: &ModelSource,
    complex: bool,
    scene_dir: &Path,
) -> Result<Operators<'p>, RunError> {
    let ModelSource::Matrices {
        stiffness,
        mass,
        circulatory,
        damping,
        disc_speed,
    } = source
    else {
        return Err(RunError::scene("model", "not a 'matrices' model"));
    };
    let disc_speed = *disc_speed;
    let at_speed =
        |terms: &[MatrixTerm]| -> Vec<_> { terms.iter().map(|t| t.at_speed(disc_speed)).collect() };
    let k = load_sum(petsc, &at_speed(stiffness), scene_dir)?;
    let m = load_sum(petsc, &at_speed(mass), scene_dir)?;
    let mut user_complex = None;
    if complex {
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
    if k.asymmetry > 1e-12 || m.asymmetry > 1e-12 {
        return Err(RunError::Unsymmetric {
            stiffness: k.asymmetry,
            mass: m.asymmetry,
        });
    }
    Ok(Operators {
        k0: k.matrix,
        m: m.matrix,
        dofs: None,
        free_free: false,
        unsupported: Vec::new(),
        balance: None,
        user_complex,
    })
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

/// The model (generated or imported, quality-checked) and its assembled operators, or the
/// user's matrices.
///
/// # Collective
pub fn from_scene<'p>(
    petsc: &'p Petsc,
    scene: &Scene,
    scene_dir: &Path,
    timings: &mut Timings,
) -> Result<super::ModelAndOperators<'p>, RunError> {
    if let source @ ModelSource::Matrices { .. } = &scene.model {
        let complex = scene.complex_modes.is_some();
        let ops = timings.stage("read matrices", || {
            read_matrices(petsc, source, complex, scene_dir)
        })?;
        return Ok((None, Vec::new(), ops));
    }
    let model = timings.stage("mesh", || {
        super::model::build_model(&scene.model, scene_dir)
    })?;
    let model = model.ok_or_else(|| RunError::scene("model", "needs a mesh"))?;
    let imported_from = match &scene.model {
        ModelSource::Abaqus { file, .. } | ModelSource::Gmsh { file, .. } => {
            Some(scene_dir.join(file))
        }
        _ => None,
    };
    let quality = timings.stage("mesh quality", || {
        crate::fem::quality::check(&model.mesh).map_err(|source| match &imported_from {
            Some(file) => RunError::ImportedQuality {
                file: file.clone(),
                source,
            },
            None => RunError::Quality(source),
        })
    })?;
    // The static Newton's tangent K0 + contact is unsymmetric (LU): AIJ then.
    let format = scene.statics.as_ref().map(|_| MatrixFormat::Aij);
    let ops = timings.stage("assembly", || assemble(petsc, &model, format))?;
    Ok((Some(model), quality, ops))
}
