//! Stage 5c: the noise matrix. Per operating point (pressure, speed, friction, contact law,
//! temperature) the static state is re-solved, warm-started from the nearest finished point
//! (from the unloaded state when that fails), the contact tangent re-projected on the fixed
//! real modes of the nominal state and the dense complex modes solved; each mode is labelled
//! by the nominal mode it continues (MAC), so a label means the same at every point whatever
//! the order, the slice or the resumption that computed it. A point that fails is recorded
//! with its reason and the matrix goes on.

use std::collections::HashMap;
use std::time::Instant;

use super::reduce::Reduced;
use super::statics::Preloaded;
use super::RunError;
use crate::contact::{ContactModel, ContactState, ResolvedInterface};
use crate::eigen::complex_modes::{
    frequency_hz, projected_coordinates, solve_dense, ComplexModeSettings, DampingSettings,
    DenseEigenpair,
};
use crate::eigen::real_modes::RealModes;
use crate::eigen::stability::{project_operator, ProjectedStability};
use crate::eigen::sweep::{apply_to_laws, SweepParameter};
use crate::eigen::tracking::pair_modes;
use crate::la::{Petsc, SparseMatrix, Vector};
use crate::matrix::point::{FullCheck, Outcome, PointMode, PointResult, SolvedPoint};
use crate::matrix::sample::{points, warm_order, Slice};
use crate::matrix::saturation::{study, SaturationInputs};
use crate::matrix::{Axis, MatrixSettings, Sampling, StaticsModel};
use crate::post::pseudo_contact::ContactPseudoSystem;
use crate::statics::{Factored, Start, StaticError, StaticSettings, StaticState};

pub use super::matrix_lining::lining_stiffness;
use super::matrix_lining::{LiningOperator, LiningParts};
use super::matrix_share::{share_dense, PointFailure};

/// What the matrix needs from the earlier stages.
pub struct MatrixInputs<'a, 'p> {
    pub k0: &'a SparseMatrix<'p>,
    pub modes: &'a RealModes<'p>,
    pub preload: &'a Preloaded<'p>,
    /// The scene's brake pressure (bar): the load scales from it.
    pub pressure_bar: f64,
    pub statics: &'a StaticSettings,
    pub complex: &'a ComplexModeSettings,
    pub damping: DampingSettings,
    /// The superelement, for `statics = "reduced"`.
    pub reduced: Option<&'a Reduced<'p>>,
    /// The lining blocks' part of K0, when a point scales the lining's stiffness.
    pub lining: Option<&'a SparseMatrix<'p>>,
    /// With `matrix.saturation_modes`: the pseudo trajectories' settings and the radiator.
    pub saturation: Option<SaturationInputs<'a, 'p>>,
}

/// Which points this run computes: a slice, less those a journal already holds.
pub struct MatrixRun {
    pub slice: Slice,
    /// Points finished by an earlier run of this slice (from its journal).
    pub done: Vec<PointResult>,
}

/// The points of one run (a slice, or the whole matrix).
#[derive(Debug, Clone)]
pub struct MatrixOutput {
    pub axes: Vec<Axis>,
    pub sampling: Sampling,
    pub slice: Slice,
    /// Points of the whole matrix.
    pub total: usize,
    /// This slice's points by index: those resumed and those computed.
    pub points: Vec<PointResult>,
    /// Of which taken from the journal.
    pub resumed: usize,
    /// The nominal parameter values (the scene's), in axis order.
    pub nominal: Vec<f64>,
    /// Damping ratio below -margin counts as unstable.
    pub margin: f64,
}

/// The scene's value of each axis (temperature: none, NaN).
pub fn nominal_values(axes: &[Axis], input: &MatrixInputs) -> Vec<f64> {
    let contact = &input.preload.contact;
    let sliding = contact
        .interfaces()
        .iter()
        .find(|i| i.friction.is_sliding());
    axes.iter()
        .map(|a| match a {
            Axis::PressureBar => input.pressure_bar,
            Axis::DiscSpeed => contact.disc_speed(),
            Axis::Mu => sliding.map_or(f64::NAN, |i| i.friction.mu()),
            Axis::P0 | Axis::Lambda => sliding.map_or(f64::NAN, |i| match i.normal {
                crate::contact::law::NormalLaw::Exponential { p0, lambda, .. } => {
                    if *a == Axis::P0 {
                        p0
                    } else {
                        lambda
                    }
                }
                _ => f64::NAN,
            }),
            Axis::Temperature => f64::NAN,
            Axis::LiningModulus => 1.0,
        })
        .collect()
}

/// A point's operating conditions: the contact laws, the disc speed, the load scale (of the
/// scene's pressure) and the lining-stiffness factor (of the scene's lining).
struct Conditions {
    laws: Vec<ResolvedInterface>,
    speed: f64,
    scale: f64,
    lining: f64,
}

/// The operating conditions of a point.
fn point_conditions(
    settings: &MatrixSettings,
    axes: &[Axis],
    values: &[f64],
    input: &MatrixInputs,
) -> Result<Conditions, RunError> {
    let contact = &input.preload.contact;
    let mut c = Conditions {
        laws: contact.interfaces().to_vec(),
        speed: contact.disc_speed(),
        scale: 1.0,
        lining: 1.0,
    };
    for (&axis, &v) in axes.iter().zip(values) {
        let (parameter, value) = match axis {
            Axis::PressureBar => {
                c.scale = v / input.pressure_bar;
                continue;
            }
            Axis::DiscSpeed => {
                c.speed = v;
                continue;
            }
            Axis::LiningModulus => {
                c.lining = v;
                continue;
            }
            Axis::Temperature => {
                let table = settings.temperature.as_ref().expect("validated: a table");
                if let Some(e) = table.lining_modulus(v) {
                    c.lining = e;
                }
                match table.mu(v) {
                    Some(mu) => (SweepParameter::Mu, mu),
                    None => continue,
                }
            }
            other => (other.as_sweep().expect("a law parameter"), v),
        };
        apply_to_laws(parameter, value, &mut c.laws)
            .map_err(|e| RunError::scene("matrix.axes", e.to_string()))?;
    }
    Ok(c)
}

/// Runs the matrix' points of `run.slice` that `run.done` lacks, in warm-start order, handing
/// each finished point to `record` (the journal) before the next starts.
///
/// # Collective
pub fn matrix<'p>(
    petsc: &'p Petsc,
    settings: &MatrixSettings,
    input: MatrixInputs<'_, 'p>,
    run: MatrixRun,
    mut record: impl FnMut(&PointResult) -> Result<(), RunError>,
) -> Result<MatrixOutput, RunError> {
    let axes = settings.axis_list();
    let values = points(settings);
    let nominal = nominal_values(&axes, &input);
    // A law the axes cannot set fails here, before any point.
    point_conditions(settings, &axes, &values[0], &input)?;
    let done: HashMap<usize, PointResult> = run.done.into_iter().map(|p| (p.index, p)).collect();
    let todo: Vec<usize> = run
        .slice
        .range(values.len())
        .filter(|i| !done.contains_key(i))
        .collect();
    let ranges: Vec<(f64, f64)> = settings.axes.values().map(|r| r.range()).collect();
    // The nominal point itself, where the scene's value of an axis is inside its range
    // (temperature has none: the range's middle).
    let start: Vec<f64> = nominal
        .iter()
        .zip(&ranges)
        .map(|(&v, &(lo, hi))| if v.is_finite() { v } else { 0.5 * (lo + hi) })
        .collect();
    let order = warm_order(&values, &todo, &start, &ranges);
    // Warm starts are states in the unknowns of the model the points are solved on.
    let statics_state = match (settings.statics, input.reduced) {
        (StaticsModel::Reduced, Some(r)) => &r.q_static,
        (StaticsModel::Reduced, None) => {
            let message = "statics = \"reduced\" needs the superelement of [reduction]";
            return Err(RunError::scene("matrix.statics", message));
        }
        (StaticsModel::Full, _) => &input.preload.state.displacement,
    };
    let checks = settings.full_check_indices(values.len());
    let mut solver = PointSolver::new(petsc, input, checks, settings.statics)?;
    let mut kept: HashMap<usize, Vector<'p>> = HashMap::new();
    // The last use of each point's static state as a warm start (then it is dropped).
    let mut last_use: HashMap<usize, usize> = HashMap::new();
    for (k, &(_, from)) in order.iter().enumerate() {
        if let Some(f) = from {
            last_use.insert(f, k);
        }
    }
    let mut bar = crate::progress::Progress::new("matrix", order.len(), petsc.rank());
    let mut computed = Vec::with_capacity(order.len());
    // Points go in batches of the group's size: their static states and projected operators
    // together, then each rank solves one point's dense eigenproblem (the same order on any
    // rank, so it does not matter which) and shares it: at 600k the dense solve is a quarter
    // of a point, and every rank used to compute every point's.
    let comm = petsc.world();
    let (group, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let m = solver.stability.projection.size;
    for first in (0..order.len()).step_by(group) {
        let batch = &order[first..order.len().min(first + group)];
        let mut prepared = Vec::with_capacity(batch.len());
        for (b, &(i, from)) in batch.iter().enumerate() {
            let warm = from.and_then(|f| kept.get(&f)).unwrap_or(statics_state);
            let point = solver.prepare(petsc, settings, &axes, i, &values[i], warm)?;
            if let (Some(q), true) = (point.displacement(), last_use.contains_key(&i)) {
                kept.insert(i, q.try_clone()?);
            }
            if let Some(f) = from {
                if last_use.get(&f) == Some(&(first + b)) {
                    kept.remove(&f);
                }
            }
            prepared.push(point);
        }
        let mut own = prepared.get(rank).and_then(|p| p.solve_dense(m));
        for (b, point) in prepared.into_iter().enumerate() {
            let dense = point
                .statics
                .is_ok()
                .then(|| share_dense(comm, b, (b == rank).then(|| own.take()).flatten(), m));
            let result = solver.finish(petsc, settings, point, dense)?;
            record(&result)?;
            computed.push(result);
            bar.update(first + b + 1, &format!("point {}", batch[b].0 + 1));
        }
    }
    bar.finish();
    let resumed = done.len();
    let mut all: Vec<PointResult> = done.into_values().chain(computed).collect();
    all.sort_by_key(|p| p.index);
    Ok(MatrixOutput {
        axes,
        sampling: settings.sampling,
        slice: run.slice,
        total: values.len(),
        points: all,
        resumed,
        nominal,
        margin: solver.input.complex.instability_margin,
    })
}

/// A point's complex modes: those reported (below f_max, by frequency) with their index among
/// all the eigenpairs, which keep their coordinates on the basis.
struct PointModes {
    modes: Vec<(usize, PointMode)>,
    pairs: Vec<DenseEigenpair>,
}

/// A point's static state and projected operators (K_p, C_p) with the seconds they took, or
/// why its static state failed.
struct Prepared<'p> {
    index: usize,
    values: Vec<f64>,
    started: Instant,
    conditions: Conditions,
    statics: Result<Projected<'p>, PointFailure>,
}

/// A point's static state and its projected stiffness and damping (m x m, column-major).
struct Projected<'p> {
    point: PointStatics<'p>,
    kp: Vec<f64>,
    cp: Vec<f64>,
    seconds: f64,
}

impl<'p> Prepared<'p> {
    /// The static displacement, when solved.
    fn displacement(&self) -> Option<&Vector<'p>> {
        self.statics
            .as_ref()
            .ok()
            .map(|p| &p.point.state.displacement)
    }

    /// The dense complex modes of the projected operators (m coordinates) and the seconds
    /// they took; None without a static state.
    fn solve_dense(&self, m: usize) -> Option<Result<(Vec<DenseEigenpair>, f64), PointFailure>> {
        let projected = self.statics.as_ref().ok()?;
        let t = Instant::now();
        let pairs =
            solve_dense(m, &projected.kp, &projected.cp).map_err(PointFailure::ComplexModes);
        Some(pairs.map(|p| (p, t.elapsed().as_secs_f64())))
    }
}

/// The fixed parts of every point: the projection basis and the nominal modes that label.
struct PointSolver<'a, 'p> {
    input: MatrixInputs<'a, 'p>,
    stability: ProjectedStability,
    nominal: Vec<DenseEigenpair>,
    /// The last point's LU factor of its tangent, on the full model and on the superelement.
    factor: Option<Factored<'p>>,
    reduced_factor: Option<Factored<'p>>,
    /// Points also solved on the full model (reduced statics only).
    checks: Vec<usize>,
    /// The lining's stiffness on each model, when points scale it.
    lining: Option<LiningParts<'p>>,
    /// Newton iterations of a static solve from the unloaded state.
    cold_budget: usize,
}

/// What a static solve runs on: a stiffness, the contact points in its unknowns, the load at
/// the scene's pressure.
struct StaticProblem<'a, 'p> {
    k0: &'a SparseMatrix<'p>,
    contact: &'a ContactModel<'p>,
    load: &'a Vector<'p>,
}

/// Halved load increments a point's static solve from the unloaded state may take.
const COLD_CUTS: usize = 4;

/// Newton iterations a point's static solve from the unloaded state may take in all: twice
/// the preload's own from the same state (at least 20). The 600k superelement's solve of one
/// point spent 596 s within its 4 halvings (2026-11-27): halvings alone do not bound the cost.
fn cold_iteration_budget(preload: &StaticState) -> usize {
    let iterations = preload.log.iter().filter(|r| r.step_length > 0.0).count();
    (2 * iterations).max(20)
}

/// A point's static state on one model, with the contact model at the point's laws.
struct PointStatics<'p> {
    contact: ContactModel<'p>,
    state: StaticState<'p>,
    cold_restart: bool,
    seconds: f64,
}

impl<'a, 'p> PointSolver<'a, 'p> {
    /// # Collective
    fn new(
        petsc: &'p Petsc,
        input: MatrixInputs<'a, 'p>,
        checks: Vec<usize>,
        statics: StaticsModel,
    ) -> Result<Self, RunError> {
        let comm = petsc.world();
        let (contact, state) = (&input.preload.contact, &input.preload.state.contact);
        let stability = ProjectedStability::new(comm, contact, input.modes, state, input.damping)?;
        let (kp, cp) = stability.operators_at(comm, contact, state);
        let nominal = projected_coordinates(stability.projection.size, &kp, &cp)
            .map_err(crate::la::LaError::from)?;
        let lining = match input.lining {
            Some(k_l) => {
                let reduced = match (statics, input.reduced) {
                    (StaticsModel::Reduced, Some(r)) => {
                        let k_r = r.model.reduction.project_operator(petsc, k_l)?;
                        Some(LiningOperator::new(&r.model.stiffness, k_r)?)
                    }
                    _ => None,
                };
                Some(LiningParts {
                    projected: project_operator(comm, &input.modes.shapes, k_l)?,
                    full: LiningOperator::new(input.k0, k_l.try_clone()?)?,
                    reduced,
                })
            }
            None => None,
        };
        Ok(PointSolver {
            cold_budget: cold_iteration_budget(&input.preload.state),
            input,
            stability,
            nominal,
            factor: None,
            reduced_factor: None,
            checks,
            lining,
        })
    }

    /// The full model's static problem, or the superelement's when the matrix uses it.
    fn problem(&self, reduced: bool) -> StaticProblem<'a, 'p> {
        let input = &self.input;
        match (reduced, input.reduced) {
            (true, Some(r)) => StaticProblem {
                k0: &r.model.stiffness,
                contact: &r.contact,
                load: &r.f_ext,
            },
            _ => StaticProblem {
                k0: input.k0,
                contact: &input.preload.contact,
                load: &input.preload.load,
            },
        }
    }

    /// The static state of a point's laws and load scale on `problem`, from `warm` (a
    /// neighbour's state), else from the unloaded state: Err(reason) when neither converges.
    ///
    /// # Collective
    fn solve_static(
        petsc: &'p Petsc,
        problem: StaticProblem<'_, 'p>,
        statics: &StaticSettings,
        conditions: &Conditions,
        warm: &Vector<'p>,
        factor: &mut Option<Factored<'p>>,
        cold_budget: usize,
    ) -> Result<Result<PointStatics<'p>, PointFailure>, RunError> {
        let contact = problem
            .contact
            .with_laws(conditions.laws.clone(), conditions.speed)?;
        let mut f = problem.load.duplicate()?;
        f.copy_from(problem.load)?;
        f.scale(conditions.scale)?;
        let t = Instant::now();
        // Modified Newton from the previous point's factor (a neighbour's tangent): a new one
        // (numerical phase only) when it stops contracting. From the unloaded state afresh,
        // with at most COLD_CUTS halved load increments and `cold_budget` Newton iterations:
        // the 600k brake's superelement took 10+ minutes for one point at 38 bar, creeping
        // up the friction ramp by halvings.
        let mut solve = |displacement: Option<&Vector<'p>>| {
            let start = Start {
                displacement,
                factor: &mut *factor,
                cut_budget: displacement.is_none().then_some(COLD_CUTS),
                iteration_budget: displacement.is_none().then_some(cold_budget),
            };
            crate::statics::solve_from(petsc, problem.k0, &contact, &f, statics, start, |_| {})
        };
        let (state, cold_restart) = match solve(Some(warm)) {
            Ok(s) => (s, false),
            // A (nearly) singular tangent at the point's own load and laws: the neighbour's
            // branch of equilibria ends before this point (a divergence). Not retried from
            // the unloaded state, which reaches the same load and laws at 4-5x the cost. (The
            // 11 points of the 100k and 600k matrices that failed so on 2026-11-27, warm and
            // cold, had NaN in their tangent instead: a joint's stick law, since fixed.)
            Err(e @ StaticError::SingularTangent { .. }) => {
                return Ok(Err(PointFailure::SingularFromNeighbour(Box::new(e))));
            }
            Err(warm_error) => match solve(None) {
                Ok(s) => (s, true),
                Err(cold) => {
                    let (warm, cold) = (Box::new(warm_error), Box::new(cold));
                    return Ok(Err(PointFailure::NoStaticState { warm, cold }));
                }
            },
        };
        Ok(Ok(PointStatics {
            contact,
            state,
            cold_restart,
            seconds: t.elapsed().as_secs_f64(),
        }))
    }

    /// A point's static state and its projected operators (the dense eigenproblem is
    /// [`Prepared::solve_dense`]'s, on one rank of the group).
    ///
    /// # Collective
    fn prepare(
        &mut self,
        petsc: &'p Petsc,
        settings: &MatrixSettings,
        axes: &[Axis],
        index: usize,
        values: &[f64],
        warm: &Vector<'p>,
    ) -> Result<Prepared<'p>, RunError> {
        let started = Instant::now();
        let conditions = point_conditions(settings, axes, values, &self.input)?;
        let reduced = settings.statics == StaticsModel::Reduced;
        let mut problem = self.problem(reduced);
        let statics = self.input.statics;
        let lining = match (&mut self.lining, reduced) {
            (Some(l), true) => l.reduced.as_mut(),
            (Some(l), false) => Some(&mut l.full),
            (None, _) => None,
        };
        if let Some(l) = lining {
            problem.k0 = l.at(problem.k0, conditions.lining)?;
        }
        let factor = match reduced {
            true => &mut self.reduced_factor,
            false => &mut self.factor,
        };
        let budget = self.cold_budget;
        let solved =
            Self::solve_static(petsc, problem, statics, &conditions, warm, factor, budget)?;
        let statics = solved.map(|point| {
            let t = Instant::now();
            let extra = self.lining_extra(conditions.lining);
            let comm = petsc.world();
            let (contact, state) = (&point.contact, &point.state.contact);
            let (kp, cp) = self
                .stability
                .operators_with_stiffness(comm, contact, state, &extra);
            let seconds = t.elapsed().as_secs_f64();
            Projected {
                point,
                kp,
                cp,
                seconds,
            }
        });
        Ok(Prepared {
            index,
            values: values.to_vec(),
            started,
            conditions,
            statics,
        })
    }

    /// A prepared point finished with its dense complex modes (`dense`: eigenpairs and the
    /// seconds they took, or why they failed; None when the static state failed): its result.
    ///
    /// # Collective
    fn finish(
        &mut self,
        petsc: &'p Petsc,
        settings: &MatrixSettings,
        prepared: Prepared<'p>,
        dense: Option<Result<(Vec<DenseEigenpair>, f64), PointFailure>>,
    ) -> Result<PointResult, RunError> {
        let Prepared {
            index,
            values,
            started,
            conditions,
            statics,
        } = prepared;
        let failed = |reason: PointFailure, values: Vec<f64>| PointResult {
            index,
            values,
            outcome: Outcome::Failed {
                reason: reason.to_string(),
                seconds: started.elapsed().as_secs_f64(),
            },
        };
        let (point, seconds_operators) = match statics {
            Ok(p) => (p.point, p.seconds),
            Err(reason) => return Ok(failed(reason, values)),
        };
        let dense = dense.expect("dense modes for a solved static state");
        let modes = match dense.and_then(|(pairs, seconds)| Ok((self.label(pairs)?, seconds))) {
            Ok(m) => m,
            Err(reason) => return Ok(failed(reason, values)),
        };
        let (modes, seconds_dense) = modes;
        let lining = conditions.lining;
        let saturation = match &self.input.saturation {
            Some(inputs) => {
                let system = ContactPseudoSystem::new(
                    petsc.world(),
                    &point.contact,
                    &point.state.contact,
                    &self.stability,
                )
                .with_extra_stiffness(self.lining_extra(lining));
                let shapes = &self.input.modes.shapes;
                let margin = self.input.complex.instability_margin;
                let found = (&modes.pairs[..], &modes.modes[..]);
                study(petsc, inputs, &system, shapes, found, margin)?
            }
            None => Vec::new(),
        };
        let modes: Vec<PointMode> = modes.modes.into_iter().map(|(_, m)| m).collect();
        let reduced = settings.statics == StaticsModel::Reduced;
        let full_check = match reduced && self.checks.contains(&index) {
            true => Some(self.full_check(petsc, &conditions, &point.state.displacement)?),
            false => None,
        };
        let state = &point.state;
        let solved = SolvedPoint {
            modes,
            braking_torque: state.summaries.iter().map(|i| i.torque).sum(),
            normal_force: state.summaries.iter().map(|i| i.normal_force).sum(),
            newton_iterations: state.log.iter().filter(|r| r.step_length > 0.0).count(),
            factorizations: state.factorizations,
            cold_restart: point.cold_restart,
            seconds_statics: point.seconds,
            seconds_factorizing: state.seconds_factorizing,
            factor_solves: state.solves,
            seconds_solving: state.seconds_solving,
            seconds_modes: seconds_operators + seconds_dense,
            full_check,
            saturation,
        };
        Ok(PointResult {
            index,
            values,
            outcome: Outcome::Solved(solved),
        })
    }

    /// The labelled complex modes at a static contact state, or why they failed.
    ///
    /// # Collective
    fn modes(
        &self,
        petsc: &'p Petsc,
        contact: &ContactModel<'p>,
        state: &ContactState,
        lining: f64,
    ) -> Result<PointModes, PointFailure> {
        // The superelement's contact model has the full one's points, in the same order on
        // the same ranks: its state projects on the same observed modes.
        let extra = self.lining_extra(lining);
        let comm = petsc.world();
        let (kp, cp) = self
            .stability
            .operators_with_stiffness(comm, contact, state, &extra);
        let pairs = solve_dense(self.stability.projection.size, &kp, &cp)
            .map_err(PointFailure::ComplexModes)?;
        self.label(pairs)
    }

    /// Complex modes labelled, or why they cannot be.
    fn label(&self, mut pairs: Vec<DenseEigenpair>) -> Result<PointModes, PointFailure> {
        let modes = self.labelled(&mut pairs);
        if modes
            .iter()
            .any(|(_, m)| !(m.re.is_finite() && m.im.is_finite()))
        {
            return Err(PointFailure::NotFinite);
        }
        Ok(PointModes { modes, pairs })
    }

    /// (e - 1) Phi^T K_l Phi: the lining factor e's change of the projected stiffness (empty
    /// without a lining axis).
    fn lining_extra(&self, lining: f64) -> Vec<f64> {
        self.lining.as_ref().map_or(Vec::new(), |l| {
            l.projected.iter().map(|k| (lining - 1.0) * k).collect()
        })
    }

    /// The point solved again on the full model, from the superelement's static displacement
    /// `reduced_q` recovered, against it.
    ///
    /// # Collective
    fn full_check(
        &mut self,
        petsc: &'p Petsc,
        conditions: &Conditions,
        reduced_q: &Vector<'p>,
    ) -> Result<FullCheck, RunError> {
        let t = Instant::now();
        let mut problem = self.problem(false);
        if let Some(l) = &mut self.lining {
            problem.k0 = l.full.at(problem.k0, conditions.lining)?;
        }
        // From the superelement's state recovered: the full equilibrium nearest to it (joints
        // that stick hold a state that depends on the path; from the nominal state the full
        // solve may settle in another one, and the difference would not be the reduction's).
        let reduction = &self.input.reduced.expect("reduced statics").model.reduction;
        let mut start = self.input.preload.state.displacement.duplicate()?;
        reduction.recover(petsc, reduced_q, &mut start)?;
        let statics = self.input.statics;
        let factor = &mut self.factor;
        let budget = self.cold_budget;
        let solved =
            Self::solve_static(petsc, problem, statics, conditions, &start, factor, budget)?;
        let failed = |reason: PointFailure| FullCheck {
            displacement_error: f64::NAN,
            braking_torque: f64::NAN,
            normal_force: f64::NAN,
            modes: Vec::new(),
            seconds: t.elapsed().as_secs_f64(),
            failure: Some(reason.to_string()),
        };
        let point = match solved {
            Ok(p) => p,
            Err(reason) => return Ok(failed(reason)),
        };
        let modes = match self.modes(
            petsc,
            &point.contact,
            &point.state.contact,
            conditions.lining,
        ) {
            Ok(m) => m.modes.into_iter().map(|(_, m)| m).collect(),
            Err(reason) => return Ok(failed(reason)),
        };
        let q = &point.state.displacement;
        let mut difference = q.duplicate()?;
        reduction.recover(petsc, reduced_q, &mut difference)?;
        difference.axpy(-1.0, q)?;
        let state = &point.state;
        Ok(FullCheck {
            displacement_error: difference.norm2()? / q.norm2()?.max(f64::MIN_POSITIVE),
            braking_torque: state.summaries.iter().map(|i| i.torque).sum(),
            normal_force: state.summaries.iter().map(|i| i.normal_force).sum(),
            modes,
            seconds: t.elapsed().as_secs_f64(),
            failure: None,
        })
    }

    /// The modes below f_max by frequency, each labelled by the nominal mode it continues.
    /// `pairs` are sorted by frequency; each mode comes with its index among them.
    fn labelled(&self, pairs: &mut [DenseEigenpair]) -> Vec<(usize, PointMode)> {
        pairs.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1).then(a.0 .0.total_cmp(&b.0 .0)));
        let mut label = vec![None; pairs.len()];
        for (n, paired) in pair_modes(&self.nominal, pairs).into_iter().enumerate() {
            if let Some((j, mac)) = paired {
                label[j] = Some((n + 1, mac));
            }
        }
        let f_max = self.input.complex.f_max_hz;
        pairs
            .iter()
            .zip(label)
            .enumerate()
            .filter(|(_, (p, _))| f_max.is_none_or(|f| frequency_hz(p.0) <= f))
            .map(|(j, (p, l))| {
                let mode = PointMode {
                    label: l.map(|l| l.0),
                    re: p.0 .0,
                    im: p.0 .1,
                    mac: l.map_or(0.0, |l| l.1),
                };
                (j, mode)
            })
            .collect()
    }
}
