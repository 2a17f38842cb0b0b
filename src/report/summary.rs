//! The run's summary: what each stage found, in one type with `Display` (the one-screen
//! summary printed at the end of a run), and its parts, which the report shows section by
//! section. The formatter of each stage's part is in `sections.rs`.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::eigen::complex_modes::{ComplexMode, ComplexModes};
use crate::eigen::real_modes::RealModes;
use crate::fem::quality::BlockQuality;
use crate::la::{LaError, Petsc};
use crate::stages::complex::route_name;
use crate::stages::model::Model;
use crate::stages::operators::{LoadBalance, Operators};
use crate::stages::reduce::Reduced;
use crate::stages::statics::Preloaded;
use crate::stages::sweep::SweepOutput;
use crate::stages::{Analyses, Timings};
use crate::time::transient::Transient;

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
    /// The limit cycle of the transient, when `[post.limit_cycle]` asked for it.
    pub limit_cycle: Option<crate::stages::post::LimitCycleReport>,
    /// Modal energies and dynamic stability along the run, when `[post]` asked for them.
    pub link: crate::stages::link::Link,
    /// The pseudo trajectories, when `[post.pseudo_trajectory]` asked for them.
    pub pseudo: Option<crate::stages::pseudo::PseudoReport>,
    /// Radiated sound power and levels, when `[post.loudness]` asked for them.
    pub loudness: Option<crate::stages::loudness::LoudnessReport>,
    /// The noise matrix, when `[matrix]` asked for one.
    pub matrix: Option<crate::report::matrix::MatrixReport>,
    /// Why the run stopped early (the transient's error), when it did.
    pub failure: Option<String>,
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
    pub points_per_rank: Vec<usize>,
    pub misses: Vec<(String, usize, usize)>,
    pub interfaces: Vec<(String, crate::contact::InterfaceSummary)>,
    pub newton_iterations: usize,
    pub load_steps: usize,
    pub factorizations: usize,
    pub solves: usize,
    pub krylov_corrections: usize,
    pub krylov_iterations: usize,
    pub factor_entries: f64,
    /// The factors were single-precision (`[statics] factor = "single"`).
    pub single_precision: bool,
    pub pairing_seconds: f64,
    pub seconds: f64,
    pub seconds_factorizing: f64,
    pub piston_force: f64,
    pub final_residual: f64,
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
    /// Of `seconds_factorizing`: assembling the Jacobians.
    pub seconds_assembling_jacobians: f64,
    pub cuts: usize,
    pub refreshes: usize,
    pub krylov_retries: usize,
    pub full_newton_retries: usize,
    pub krylov_iterations: usize,
    pub updated_retries: usize,
    /// The nonlinear eliminations of this process's run.
    pub eliminations: crate::time::transient::EliminationCounts,
    /// Steps of this process's run (fewer than `steps` after a restart) and their accepted
    /// iterations per step.
    pub steps_run: usize,
    pub iterations_per_step_run: f64,
    /// Of this process's steps, those accepted on the step's truncation error.
    pub steps_on_step_error: usize,
    /// Per step of this process's run, counting the attempts that failed too: iterations
    /// and solves with the factor (GMRES' and the update's column solves included).
    pub all_iterations_per_step: f64,
    pub all_solves_per_step: f64,
    /// Per step of this process's run: the attempts that failed (wall time), and what
    /// follows each accepted step (signals, states and checkpoints written, progress).
    pub seconds_failed_per_step: f64,
    pub seconds_recording_per_step: f64,
    pub factorizations: usize,
    /// One fixed-Jacobian iteration (forces, residual, solve) and one solve with the factor.
    pub seconds_per_iteration: f64,
    pub seconds_per_solve: f64,
    /// Solves with the factor in all, and where the factor lives.
    pub factor_solves: usize,
    pub jacobian_solver: &'static str,
    /// Per step: force evaluations (contact), operator products (the predictor's linear
    /// force, the contact tangent's correction), and the rest (vector updates, reductions,
    /// recording).
    pub seconds_forces_per_step: f64,
    pub seconds_products_per_step: f64,
    /// The static residual removed from the load (N), and where the run stopped because the
    /// torque had saturated.
    pub static_residual: f64,
    pub stopped_at_saturation: Option<f64>,
    pub cost: StepCost,
    /// Where the sensors and the impulse landed.
    pub notes: Vec<String>,
}

/// What a step's parts stream and how long they took: the cost model of benches/transient.rs
/// (bytes from the stored entries each part reads; the bound is bytes over the bandwidth the
/// bench measures in the same run).
#[derive(Debug, Clone, Copy, Default)]
pub struct StepCost {
    pub unknowns: usize,
    /// Solves with the factor: per step, bytes of the factor read per solve (values x passes:
    /// LU reads L and U once, LDL^T reads L twice; indices left out), seconds per solve.
    pub solves_per_step: f64,
    pub bytes_per_solve: f64,
    /// Of them, from the rank that holds most of the factor (each rank streams its own part).
    pub bytes_per_solve_largest_rank: f64,
    pub seconds_per_solve: f64,
    /// The linear force (the predictor's product with K, with M and C only where the damping
    /// needs them, not counted; with a single-precision factor also the accepted iterate's
    /// product with J, of about K's entries): per step, bytes and seconds per computation.
    pub linear_forces_per_step: f64,
    pub bytes_linear_force: f64,
    pub seconds_linear_force: f64,
    /// Contact force evaluations (5 products with observation rows, 3 with their
    /// transposes): per step, bytes and seconds per evaluation.
    pub force_evaluations_per_step: f64,
    pub bytes_per_force_evaluation: f64,
    pub seconds_per_force_evaluation: f64,
    /// Products with the contact tangent (every channel forward and transposed): per step,
    /// bytes and seconds per product.
    pub tangent_products_per_step: f64,
    pub bytes_per_tangent_product: f64,
    pub seconds_per_tangent_product: f64,
}

impl StepCost {
    fn of(t: &Transient) -> Self {
        let steps = t.steps_run.max(1) as f64;
        let entry = crate::la::SPARSE_ENTRY_BYTES;
        let [nor, tan, tan2, conv] = t.observation_entries;
        let per = |seconds: f64, calls: usize| seconds / calls.max(1) as f64;
        let tangent_seconds = t.seconds_in_products - t.seconds_in_linear_force;
        StepCost {
            unknowns: t.unknowns,
            solves_per_step: t.factor_solves as f64 / steps,
            bytes_per_solve: t.factor_entries * t.factor_value_bytes * t.factor_passes,
            bytes_per_solve_largest_rank: t.factor_entries_largest_rank
                * t.factor_value_bytes
                * t.factor_passes,
            seconds_per_solve: per(t.seconds_in_factor_solves, t.factor_solves),
            bytes_linear_force: t.operator_entries * entry + 3.0 * 8.0 * t.unknowns as f64,
            linear_forces_per_step: t.linear_force_calls as f64 / steps,
            seconds_linear_force: per(t.seconds_in_linear_force, t.linear_force_calls),
            force_evaluations_per_step: t.force_evaluations as f64 / steps,
            // The stacked channels forward and back, the tangent rows once more (velocity).
            bytes_per_force_evaluation: (2.0 * (nor + tan + tan2 + conv) + tan) * entry,
            seconds_per_force_evaluation: per(t.seconds_in_forces, t.force_evaluations),
            tangent_products_per_step: t.tangent_products as f64 / steps,
            bytes_per_tangent_product: 2.0 * (nor + tan + tan2 + conv) * entry,
            seconds_per_tangent_product: per(tangent_seconds, t.tangent_products),
        }
    }
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
    /// Points whose warm-started statics failed and were solved from the unloaded state.
    pub cold_restarts: Vec<usize>,
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

impl RunSummary {
    /// The figures of the model, the operators and the real modes; the later stages' fields
    /// start empty.
    ///
    /// # Collective (none: `peak_memory_per_rank` is already reduced)
    pub fn new(
        ops: &Operators,
        model: Option<&Model>,
        quality: Vec<BlockQuality>,
        modes: Option<&RealModes>,
        timings: Timings,
        peak_memory_per_rank: f64,
        output: &Path,
    ) -> Self {
        RunSummary {
            dofs: ops.dofs(),
            frequencies_hz: modes.map(|m| m.frequencies_hz.clone()).unwrap_or_default(),
            residual_norms: modes.map(|m| m.residual_norms.clone()).unwrap_or_default(),
            backward_errors: modes.map(|m| m.backward_errors.clone()).unwrap_or_default(),
            rigid: modes.map(|m| m.rigid.clone()).unwrap_or_default(),
            factor_entries: modes.and_then(|m| m.factorization.map(|f| f.factor_entries)),
            ordering: modes.and_then(|m| m.factorization.map(|f| f.ordering_name())),
            timings,
            notes: model.map(|m| m.notes.clone()).unwrap_or_default(),
            quality,
            balance: ops.balance.clone(),
            unsupported: ops.unsupported.clone(),
            peak_memory_per_rank,
            output: output.to_path_buf(),
            statics: None,
            complex: Vec::new(),
            sweep: None,
            transient: None,
            reduction: None,
            limit_cycle: None,
            link: Default::default(),
            pseudo: None,
            loudness: None,
            matrix: None,
            failure: None,
        }
    }
}

impl RunSummary {
    /// The summary of a run's stages.
    ///
    /// # Collective
    pub fn of(
        petsc: &Petsc,
        mut a: Analyses,
        signals: Option<&Transient>,
        timings: Timings,
        peak_memory_per_rank: f64,
        output: &Path,
    ) -> Result<Self, LaError> {
        let quality = std::mem::take(&mut a.quality);
        let model = a.model.as_ref();
        let mut s = RunSummary::new(
            &a.ops,
            model,
            quality,
            a.modes.as_ref(),
            timings,
            peak_memory_per_rank,
            output,
        );
        s.statics = a
            .preload
            .as_ref()
            .zip(model)
            .map(|(p, m)| StaticSummary::of(p, m));
        s.complex = a.complex.iter().map(ComplexSummary::of).collect();
        s.sweep = a.sweep.as_ref().map(SweepSummary::of);
        s.reduction = match &a.reduced {
            Some(r) => Some(ReductionSummary::of(petsc, r, a.ops.dofs())?),
            None => None,
        };
        s.transient = signals.map(TransientSummary::of);
        Ok(s)
    }
}

impl StaticSummary {
    /// The preload's figures: points, misses, per-interface sums, Newton counts.
    pub fn of(preload: &Preloaded, model: &Model) -> Self {
        let (contact, state) = (&preload.contact, &preload.state);
        let last = state
            .log
            .last()
            .expect("a converged static state has a Newton log");
        StaticSummary {
            points: contact.points().len(),
            points_per_rank: contact.points_per_rank().to_vec(),
            misses: contact
                .interfaces()
                .iter()
                .enumerate()
                .map(|(i, itf)| {
                    (
                        itf.name.clone(),
                        contact.misses()[i],
                        contact.candidates()[i],
                    )
                })
                .collect(),
            interfaces: contact
                .interfaces()
                .iter()
                .map(|i| i.name.clone())
                .zip(state.summaries.iter().cloned())
                .collect(),
            newton_iterations: state.log.iter().filter(|r| r.step_length > 0.0).count(),
            load_steps: last.load_step,
            factorizations: state.factorizations,
            solves: state.solves,
            krylov_corrections: state.krylov_corrections,
            krylov_iterations: state.krylov_iterations,
            factor_entries: state.factor_entries,
            single_precision: state.factor_precision == crate::statics::StaticFactor::Single,
            pairing_seconds: contact.pairing_seconds(),
            seconds: state.seconds,
            seconds_factorizing: state.seconds_factorizing,
            piston_force: model.piston_force(),
            final_residual: last.residual,
        }
    }

    /// The braking torque of all interfaces (N m).
    pub fn torque(&self) -> f64 {
        self.interfaces.iter().map(|(_, i)| i.torque).sum()
    }
}

impl ReductionSummary {
    /// # Collective
    pub fn of(petsc: &Petsc, r: &Reduced, full_dofs: usize) -> Result<Self, LaError> {
        let red = &r.model.reduction;
        let mut rows = vec![0.0; petsc.size() as usize];
        rows[petsc.rank() as usize] = red.columns.len() as f64;
        crate::parallel::sum_in_place(petsc.world(), &mut rows);
        Ok(ReductionSummary {
            full_dofs,
            kept: red.kept,
            modal: red.modal,
            offered: red.offered,
            dropped: red.dropped,
            orthonormality: red.orthonormality,
            static_error: r.static_error,
            mode_check: r.mode_check.clone(),
            mode_error: r.mode_error(),
            stiffness_entries: r.model.stiffness.info()?.nonzeros,
            rows_per_rank: rows.iter().map(|&x| x as usize).collect(),
            seconds: red.seconds,
        })
    }
}

impl TransientSummary {
    pub fn of(t: &Transient) -> Self {
        // Index 0 of the signals is the start; steps follow.
        let its = &t.iterations[1.min(t.iterations.len())..];
        // The factorizations are counted once, not spread over the steps.
        let stepping = (t.seconds_stepping - t.seconds_jacobians).max(0.0);
        let steps_run = t.steps_run.max(1) as f64;
        let iterations_run = t.iterations_run.max(1) as f64;
        TransientSummary {
            steps: its.len(),
            simulated: t.time.last().copied().unwrap_or(0.0),
            mean_iterations: its.iter().sum::<usize>() as f64 / its.len().max(1) as f64,
            max_iterations: its.iter().copied().max().unwrap_or(0),
            seconds_per_step: stepping / steps_run,
            factor_entries: t.factor_entries,
            seconds_factorizing: t.seconds_factorizing,
            seconds_assembling_jacobians: t.seconds_assembling_jacobians,
            cuts: t.cuts,
            refreshes: t.refreshes,
            krylov_retries: t.krylov_retries,
            full_newton_retries: t.full_newton_retries,
            krylov_iterations: t.krylov_iterations,
            updated_retries: t.updated_retries,
            eliminations: t.eliminations,
            steps_run: t.steps_run,
            steps_on_step_error: t.steps_on_step_error,
            iterations_per_step_run: t.iterations_run as f64 / steps_run,
            all_iterations_per_step: (t.iterations_run + t.failed_iterations) as f64 / steps_run,
            all_solves_per_step: (t.factor_solves + t.failed_solves) as f64 / steps_run,
            seconds_failed_per_step: t.seconds_in_failed_attempts / steps_run,
            seconds_recording_per_step: t.seconds_recording / steps_run,
            factorizations: t.factorizations,
            seconds_per_iteration: stepping / iterations_run,
            seconds_per_solve: t.seconds_in_factor_solves / t.factor_solves.max(1) as f64,
            factor_solves: t.factor_solves,
            jacobian_solver: t.jacobian_solver,
            seconds_forces_per_step: t.seconds_in_forces / steps_run,
            seconds_products_per_step: t.seconds_in_products / steps_run,
            static_residual: t.static_residual,
            stopped_at_saturation: t.stopped_at_saturation,
            cost: StepCost::of(t),
            notes: Vec::new(),
        }
    }
}

impl SweepSummary {
    pub fn of(s: &SweepOutput) -> Self {
        SweepSummary {
            parameter: s.parameter.name(),
            points: s.values.len(),
            tracks: s.tracks.tracks.len(),
            unstable_per_point: s.unstable.clone(),
            statics_seconds: s.statics_seconds.clone(),
            modal_seconds: s.modal_seconds.clone(),
            values: s.values.clone(),
            cold_restarts: s.cold_restarts.clone(),
        }
    }
}

impl ComplexSummary {
    pub fn of(c: &ComplexModes) -> Self {
        ComplexSummary {
            route: route_name(c.route),
            modes: c.modes.clone(),
            basis: c.basis,
            seconds: c.seconds,
            solve_seconds: c.solve_seconds,
        }
    }
}

impl fmt::Display for RunSummary {
    /// The one-screen summary of a run, section by section.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "answer:")?;
        for line in super::answer::answer_lines(self) {
            writeln!(f, "    {line}")?;
        }
        for part in Part::ALL {
            write!(f, "{}", self.part(part))?;
        }
        Ok(())
    }
}

/// The summary's parts, in order (the report shows each in its section).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Model,
    Statics,
    Modes,
    Reduction,
    Transient,
    Sweep,
    LimitCycle,
    ModalEnergy,
    ContactCycle,
    DynamicStability,
    Pseudo,
    Loudness,
    Matrix,
    Timings,
}

impl Part {
    pub const ALL: [Part; 14] = [
        Part::Model,
        Part::Statics,
        Part::Modes,
        Part::Reduction,
        Part::Transient,
        Part::Sweep,
        Part::LimitCycle,
        Part::ModalEnergy,
        Part::ContactCycle,
        Part::DynamicStability,
        Part::Pseudo,
        Part::Loudness,
        Part::Matrix,
        Part::Timings,
    ];
}

/// One part of a summary, displayed.
pub struct SummaryPart<'a>(&'a RunSummary, Part);

impl fmt::Display for SummaryPart<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0;
        match self.1 {
            Part::Model => s.fmt_model(f),
            Part::Statics => s.fmt_statics(f),
            Part::Modes => s.fmt_modes(f),
            Part::Reduction => s.fmt_reduction(f),
            Part::Transient => s.fmt_transient(f),
            Part::Sweep => s.fmt_sweep(f),
            Part::LimitCycle => s.fmt_limit_cycle(f),
            Part::ModalEnergy => super::text::fmt_modal_energy(&s.link, f),
            Part::ContactCycle => super::text::fmt_contact_cycle(&s.link, f),
            Part::DynamicStability => super::text::fmt_dynamic_stability(&s.link, f),
            Part::Pseudo => s
                .pseudo
                .as_ref()
                .map_or(Ok(()), |p| super::text::fmt_pseudo(p, f)),
            Part::Loudness => s
                .loudness
                .as_ref()
                .map_or(Ok(()), |l| super::text::fmt_loudness(l, f)),
            Part::Matrix => s.matrix.as_ref().map_or(Ok(()), |m| f.write_str(&m.text())),
            Part::Timings => s.fmt_timings(f),
        }
    }
}

impl RunSummary {
    /// One part of the summary, to display.
    pub fn part(&self, part: Part) -> SummaryPart<'_> {
        SummaryPart(self, part)
    }
}
