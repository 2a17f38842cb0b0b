//! Static preload (DESIGN.md §2): Newton on K0 q - f_N(q) - f_T(q) = f_ext with a backtracking
//! line search and load stepping (pressure ramp, then friction ramp with the disc sliding at
//! Omega): a modified Newton on a MUMPS LU of the unsymmetric tangent, GMRES preconditioned
//! by that LU once it stops contracting, a new LU when GMRES would cost more
//! ([`tangent`]).

use crate::invalid::InvalidSetting;

use serde::{Deserialize, Serialize};

use crate::contact::surface::Face;
use crate::contact::{ContactModel, ContactState, InterfaceSummary};
use crate::fem::dofmap::DofMap;
use crate::la::{BlockAddPlan, DirectSolver, LaError, Petsc, SparseMatrix, Vector};
use crate::mesh::{Mesh, PressureLoad};

mod newton;
pub mod tangent;
pub use newton::solve_from;

/// The `[statics]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticSettings {
    /// Equal pressure increments up to the full brake pressure.
    #[serde(default = "default_pressure_steps")]
    pub pressure_steps: usize,
    /// Equal friction increments after the pressure (0: friction at once with the pressure).
    #[serde(default = "default_friction_steps")]
    pub friction_steps: usize,
    /// Converged when |residual| <= tolerance x max(|f_ext|, |f_contact|).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Modified Newton: an LU factor is reused while every iteration cuts the residual at
    /// least by this factor (0: a new factor each iteration, full Newton).
    #[serde(default = "default_reuse_contraction")]
    pub reuse_contraction: f64,
    /// Once the factor stops contracting: GMRES on the iterate's tangent preconditioned by it
    /// before a new factorization (false: a new factorization at once, as before).
    /// (Not written when true: the restart fingerprints of scenes written before this key
    /// stay the same.)
    #[serde(default = "default_krylov", skip_serializing_if = "is_true")]
    pub krylov: bool,
    /// The precision of the tangent's LU factor: `"double"` (default) or `"single"` (MUMPS
    /// in single precision: half the factor's memory and bytes per solve, a faster
    /// elimination; the residual, the line search and GMRES stay in double precision, so the
    /// iteration reaches the same tolerance, the factor's rounding costing at most a few
    /// more iterations). (Not written when double: earlier restart fingerprints stay.)
    #[serde(default, skip_serializing_if = "StaticFactor::is_double")]
    pub factor: StaticFactor,
}

/// The precision of the static tangent's factor (`[statics] factor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StaticFactor {
    #[default]
    Double,
    Single,
}

impl StaticFactor {
    fn is_double(&self) -> bool {
        *self == StaticFactor::Double
    }
}

fn default_pressure_steps() -> usize {
    4
}
fn default_friction_steps() -> usize {
    2
}
fn default_tolerance() -> f64 {
    // Round-off leaves about 1e-10 of the force on the brake (K0 q sums terms ~1e4 x larger).
    1e-9
}
fn default_max_iterations() -> usize {
    40
}
fn default_krylov() -> bool {
    true
}
fn is_true(value: &bool) -> bool {
    *value
}
fn default_reuse_contraction() -> f64 {
    // Fewer factorizations for more solves, fastest of those measured on the 30k brake
    // (benches/decisions-results.md, "statics-reuse").
    0.3
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            pressure_steps: default_pressure_steps(),
            friction_steps: default_friction_steps(),
            tolerance: default_tolerance(),
            max_iterations: default_max_iterations(),
            reuse_contraction: default_reuse_contraction(),
            krylov: default_krylov(),
            factor: StaticFactor::Double,
        }
    }
}

impl StaticSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.pressure_steps == 0 {
            return Err(InvalidSetting::new(
                "statics.pressure_steps",
                " must be at least 1",
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1e-2) {
            return Err(InvalidSetting::new(
                "statics.tolerance",
                format!(" = {}: must be in (0, 0.01)", self.tolerance),
            ));
        }
        if self.max_iterations == 0 {
            return Err(InvalidSetting::new(
                "statics.max_iterations",
                " must be at least 1",
            ));
        }
        if !(0.0..1.0).contains(&self.reuse_contraction) {
            return Err(InvalidSetting::new(
                "statics.reuse_contraction",
                format!(
                    " = {}: must be in [0, 1) (0 = full Newton)",
                    self.reuse_contraction
                ),
            ));
        }
        Ok(())
    }

    /// (pressure fraction, friction fraction) of every load step.
    pub fn schedule(&self, friction: bool) -> Vec<(f64, f64)> {
        let n = self.pressure_steps;
        let m = if friction { self.friction_steps } else { 0 };
        let full_friction = if friction && m == 0 { 1.0 } else { 0.0 };
        let mut s: Vec<(f64, f64)> = (1..=n)
            .map(|i| (i as f64 / n as f64, full_friction))
            .collect();
        s.extend((1..=m).map(|j| (1.0, j as f64 / m as f64)));
        s
    }
}

/// One Newton iteration in the convergence log.
#[derive(Debug, Clone, Copy)]
pub struct NewtonRecord {
    pub load_step: usize,
    pub pressure_fraction: f64,
    pub friction_fraction: f64,
    pub iteration: usize,
    pub residual: f64,
    pub reference: f64,
    /// Line-search step length taken after this residual (0 on the converged record).
    pub step_length: f64,
}

/// The preloaded state.
pub struct StaticState<'p> {
    pub displacement: Vector<'p>,
    pub contact: ContactState,
    pub summaries: Vec<InterfaceSummary>,
    pub log: Vec<NewtonRecord>,
    pub factorizations: usize,
    /// The precision of the last factor.
    pub factor_precision: StaticFactor,
    /// Solves with those factors: one per correction with a factor, one per GMRES iteration
    /// and one more per GMRES correction.
    pub solves: usize,
    /// Of the corrections, those by GMRES preconditioned by an earlier factor, and their GMRES
    /// iterations (each one solve; counted in `solves`).
    pub krylov_corrections: usize,
    pub krylov_iterations: usize,
    /// Load increments that were halved after a stall.
    pub cut_steps: usize,
    /// MUMPS factor entries of the last factorization.
    pub factor_entries: f64,
    pub seconds_factorizing: f64,
    /// In solves with the factors (GMRES' products and orthogonalization excluded).
    pub seconds_solving: f64,
    /// MUMPS' elimination flops of the last factorization (0 when not reported).
    pub factor_flops: f64,
    pub seconds: f64,
    /// |f_ext| at full pressure (N).
    pub load_norm: f64,
}

/// Why the pressure load cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("loaded surface: {0}")]
    Surface(#[from] crate::mesh::MeshError),
    #[error("loaded surface '{0}' has no area")]
    NoArea(String),
    #[error(transparent)]
    La(#[from] LaError),
}

#[derive(Debug, thiserror::Error)]
pub enum StaticError {
    #[error(
        "static preload did not converge at load step {step} (pressure {pressure:.0} %, friction {friction:.0} %) after {iterations} Newton iterations: residual {residual:.3e} N > tolerance {target:.3e} N; the largest residual sits on interface '{interface}'. Try more statics.pressure_steps, a softer contact law (smaller lambda) or a closer initial fit of the surfaces"
    )]
    NotConverged {
        step: usize,
        pressure: f64,
        friction: f64,
        iterations: usize,
        residual: f64,
        target: f64,
        interface: String,
    },
    #[error(
        "static preload, load step {step}: the residual at the last converged state is not \
         finite (NaN or Inf); check the materials, the pressure and the contact law's values"
    )]
    NotFinite { step: usize },
    #[error(
        "static preload, load step {step} (pressure {pressure:.0} %, friction {friction:.0} %), Newton iteration {iteration} (residual {residual:.3e} N): the tangent stiffness is {how}, so no equilibrium is near this state. Either a part held only by contact has lost it (check the clamps and the contact surfaces' fit), or friction has made the static state unstable at these conditions (a divergence: lower mu or the pressure)"
    )]
    SingularTangent {
        /// "singular" or "nearly singular" and MUMPS' evidence.
        how: String,
        step: usize,
        pressure: f64,
        friction: f64,
        iteration: usize,
        residual: f64,
    },
    #[error(
        "static solve gave up after its budget of {iterations} Newton iterations in all, at load step {step} (pressure {pressure:.0} %, friction {friction:.0} %): residual {residual:.3e} N > tolerance {target:.3e} N"
    )]
    BudgetSpent {
        iterations: usize,
        step: usize,
        pressure: f64,
        friction: f64,
        residual: f64,
        target: f64,
    },
    #[error("static preload: {0}")]
    La(#[from] LaError),
}

/// The consistent nodal forces of the brake-line pressure: on each loaded surface a uniform
/// traction pressure x area / (surface area), pushing into the surface.
///
/// # Collective
pub fn pressure_load<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    loads: &[PressureLoad],
    pressure: f64,
) -> Result<Vector<'p>, LoadError> {
    let mut f = Vector::new(petsc, dofs.local_dofs())?;
    if petsc.rank() == 0 {
        for load in loads {
            let faces: Vec<Face> = mesh
                .surface(&load.surface)?
                .iter()
                .map(|&(e, s)| Face::new(mesh, e, s))
                .collect();
            let area: f64 = faces.iter().map(|f| f.area(3)).sum();
            if area.is_nan() || area <= 0.0 {
                return Err(LoadError::NoArea(load.surface.clone()));
            }
            let traction = pressure * load.area / area;
            let (mut idx, mut val) = (Vec::new(), Vec::new());
            for face in &faces {
                for (xi, w) in face.shape.rule(3) {
                    let p = face.at(xi);
                    let (n, j) = p.normal();
                    for (a, &node) in face.nodes.iter().enumerate() {
                        for c in 0..3 {
                            let d = dofs.node_dofs[node][c];
                            if d >= 0 {
                                idx.push(d);
                                val.push(-traction * n[c] * p.n[a] * w * j);
                            }
                        }
                    }
                }
            }
            f.add_values(&idx, &val)?;
        }
    }
    f.assemble()?;
    Ok(f)
}

/// Solves for the preloaded state. `k0` must be AIJ (LU). `progress` receives each record.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the operators, the load, the settings, a start, a log
pub fn solve<'p>(
    petsc: &'p Petsc,
    k0: &SparseMatrix<'p>,
    contact: &ContactModel<'p>,
    f_ext: &Vector<'p>,
    settings: &StaticSettings,
    start_from: Option<&Vector<'p>>,
    progress: impl FnMut(&NewtonRecord),
) -> Result<StaticState<'p>, StaticError> {
    let start = Start {
        displacement: start_from,
        factor: &mut None,
        cut_budget: None,
        iteration_budget: None,
    };
    solve_from(petsc, k0, contact, f_ext, settings, start, progress)
}

/// Where a static solve starts: a displacement (None: unloaded, with the load schedule) and
/// the tangent of a nearby state with its LU factor to begin the modified Newton iteration
/// with (a matrix' previous point, on the same contact points). The tangent and factor in use
/// at the end are left in `factor` for the next solve, whose refactorizations then skip the
/// analysis.
pub struct Start<'a, 'p> {
    pub displacement: Option<&'a Vector<'p>>,
    pub factor: &'a mut Option<Factored<'p>>,
    /// How many load increments may be halved in all (None: the preload's 24).
    pub cut_budget: Option<usize>,
    /// How many Newton iterations the solve may take in all, over its load steps and their
    /// cuts (None: no limit beyond `max_iterations` per step).
    pub iteration_budget: Option<usize>,
}

/// A tangent matrix (K0's pattern joined with the contacts) and its LU factor.
pub struct Factored<'p> {
    jac: SparseMatrix<'p>,
    /// Where the contact tangent's entries land in `jac`.
    plan: Option<BlockAddPlan>,
    solver: DirectSolver<'p>,
    /// What the factorization took (GMRES' budget with this factor).
    seconds: f64,
}

/// Whether a load step's Newton iteration has stalled at residual `r` after `history`
/// ((residual, step length) of each iteration): less than a halving over the last four
/// iterations, after eight, none of them shortened by the line search. Shortened steps that
/// lower the residual are a walk, not a stall: the pads dragged by friction onto their
/// abutments take several at 100k and more at 600k, each one a little further; halving the
/// increment then repeats the same walk in two parts (the 600k preload cut its friction step
/// again and again).
fn stalled(history: &[(f64, f64)], r: f64) -> bool {
    let n = history.len();
    n >= 8 && r > 0.5 * history[n - 4].0 && history[n - 4..].iter().all(|&(_, a)| a == 1.0)
}

/// A residual evaluation: |R|, the reference force, the contact state.
type Evaluation = (f64, f64, ContactState);

/// Backtracking along `dq` from `q` (residual norm `r`): the first step length with
/// sufficient decrease of |R| with its evaluation, else the best one tried if it lowers |R| at
/// all (to be re-evaluated: None), else None: the step has failed. The accepted trial's
/// evaluation is kept (it is the next iterate's residual and contact state).
///
/// # Collective
fn backtrack<'p>(
    q: &Vector<'p>,
    dq: &Vector<'p>,
    r: f64,
    trial: &mut Vector<'p>,
    mut eval: impl FnMut(&Vector<'p>) -> Result<Evaluation, LaError>,
) -> Result<Option<(f64, Option<Evaluation>)>, LaError> {
    let mut alpha = 1.0;
    let mut best: Option<(f64, f64)> = None;
    loop {
        trial.copy_from(q)?;
        trial.axpy(alpha, dq)?;
        let evaluated = eval(trial)?;
        let rt = evaluated.0;
        if rt.is_finite() && rt <= (1.0 - 1e-4 * alpha) * r {
            return Ok(Some((alpha, Some(evaluated))));
        }
        if rt.is_finite() && best.is_none_or(|b| rt < b.1) {
            best = Some((alpha, rt));
        }
        if alpha < 1.0 / 1024.0 {
            return Ok(best.filter(|b| b.1 < r).map(|b| (b.0, None)));
        }
        alpha *= 0.5;
    }
}

/// The interface whose contact DOFs carry the largest residual (for the error message).
/// Through the contact model's own columns, so it names the interface on a reduced model too.
///
/// # Collective
fn worst_interface(
    petsc: &Petsc,
    contact: &ContactModel,
    residual: &Vector,
) -> Result<String, LaError> {
    let own = contact.columns();
    let r = residual.local()?;
    let mut worst = vec![0.0f64; contact.interfaces().len()];
    for (p, columns) in contact.points().iter().zip(contact.point_columns()) {
        for &c in columns {
            if c >= 0 && own.contains(&(c as usize)) {
                let v = r[c as usize - own.start].abs();
                worst[p.interface] = worst[p.interface].max(v);
            }
        }
    }
    let worst: Vec<f64> = worst
        .iter()
        .map(|&w| crate::parallel::max(petsc.world(), w))
        .collect();
    Ok(worst
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| contact.interfaces()[i].name.clone())
        .unwrap_or_else(|| "(none)".into()))
}
