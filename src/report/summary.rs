//! The run's summary: what each stage found, in one type with `Display` (the one-screen
//! summary printed at the end of a run), and its parts, which the report shows section by
//! section. About 710 lines: one formatter per stage over one type; apart, each would need the
//! whole `RunSummary` anyway.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::eigen::complex_modes::{ComplexMode, ComplexModes};
use crate::eigen::real_modes::RealModes;
use crate::la::{LaError, Petsc};
use crate::mesh::quality::BlockQuality;
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
    pub factor_entries: f64,
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
    pub cuts: usize,
    pub refreshes: usize,
    pub krylov_retries: usize,
    pub full_newton_retries: usize,
    pub krylov_iterations: usize,
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
            factor_entries: state.factor_entries,
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
            cuts: t.cuts,
            refreshes: t.refreshes,
            krylov_retries: t.krylov_retries,
            full_newton_retries: t.full_newton_retries,
            krylov_iterations: t.krylov_iterations,
            factorizations: t.factorizations,
            seconds_per_iteration: stepping / iterations_run,
            seconds_per_solve: t.seconds_in_factor_solves / t.factor_solves.max(1) as f64,
            factor_solves: t.factor_solves,
            jacobian_solver: t.jacobian_solver,
            seconds_forces_per_step: t.seconds_in_forces / steps_run,
            seconds_products_per_step: t.seconds_in_products / steps_run,
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
    Timings,
}

impl Part {
    pub const ALL: [Part; 12] = [
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

impl RunSummary {
    /// Builder notes, size, mesh quality, partition.
    fn fmt_model(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        for note in &s.notes {
            writeln!(f, "{note}")?;
        }
        writeln!(f, "model: {} DOF", s.dofs)?;
        if !s.quality.is_empty() {
            writeln!(f, "mesh quality (sJ: scaled Jacobian, AR: aspect ratio):")?;
            for line in crate::mesh::quality::table(&s.quality).lines() {
                writeln!(f, "    {line}")?;
            }
        }
        if let Some(b) = &s.balance {
            writeln!(f,
                "partition: rows per rank {:?} (imbalance {:.3}), elements per rank {:?} (imbalance {:.3})",
                b.rows, b.row_imbalance, b.elements, b.element_imbalance
            )?;
        }
        Ok(())
    }

    /// The static preload and the rigid parts without it.
    fn fmt_statics(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        if let Some(st) = &s.statics {
            writeln!(f,
                "static preload: {} contact points (per rank {:?}), {} load steps, {} Newton iterations ({} solves), {} LU factorizations ({:.3e} entries), final residual {:.2e} N",
                st.points, st.points_per_rank, st.load_steps, st.newton_iterations, st.solves, st.factorizations, st.factor_entries, st.final_residual
            )?;
            for (name, missed, of) in &st.misses {
                if *missed > 0 {
                    writeln!(f, "    {name}: {missed} of {of} master points have no partner within contact.search_distance (dropped)")?;
                }
            }
            writeln!(f, "    interface                          normal force (N)  friction (N)  torque (N m)  max p (MPa)  open/stick/slip")?;
            for (name, i) in &st.interfaces {
                writeln!(
                    f,
                    "    {name:34} {:16.3} {:13.3} {:13.4} {:12.4}  {}/{}/{}",
                    i.normal_force,
                    i.friction_force,
                    i.torque,
                    i.max_pressure * 1e-6,
                    i.open,
                    i.stick,
                    i.slip
                )?;
            }
            let torque = st.torque();
            writeln!(
                f,
                "    piston force {:.3} N, braking torque {:.4} N m",
                st.piston_force, torque
            )?;
        }
        if !s.unsupported.is_empty() && s.statics.is_none() {
            writeln!(f,
                "not held against rigid-body motion (no contact yet): {}; their modes at 0 Hz are flagged rigid",
                s.unsupported.join(", ")
            )?;
        }
        Ok(())
    }

    /// Real and complex modes.
    fn fmt_modes(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        if !s.frequencies_hz.is_empty() {
            writeln!(
                f,
                "real modes:    #   frequency (Hz)   ||K phi - w^2 M phi||   backward error"
            )?;
            for (i, hz) in s.frequencies_hz.iter().enumerate() {
                writeln!(
                    f,
                    "            {:4}   {:14.4}   {:21.3e}   {:14.3e}{}",
                    i + 1,
                    hz,
                    s.residual_norms[i],
                    s.backward_errors[i],
                    if s.rigid[i] { "   rigid-body mode" } else { "" }
                )?;
            }
            if let (Some(entries), Some(ordering)) = (s.factor_entries, s.ordering) {
                writeln!(
                    f,
                    "MUMPS factor: {entries:.3e} entries ({ordering} ordering)"
                )?;
            }
        }
        for c in &s.complex {
            let unstable = c.modes.iter().filter(|m| m.unstable).count();
            writeln!(
                f,
                "complex modes ({}{}): {} modes, {} unstable",
                c.route,
                if c.basis > 0 {
                    format!(", {} real modes in the basis", c.basis)
                } else {
                    String::new()
                },
                c.modes.len(),
                unstable
            )?;
            writeln!(f, "       name   frequency (Hz)   damping ratio        Re(s) (1/s)   backward error   real mode")?;
            for m in &c.modes {
                writeln!(
                    f,
                    "    {:>7}   {:14.4}   {:13.4e}   {:16.6e}   {:14.3e}   {:>9}{}",
                    m.name,
                    m.frequency_hz,
                    m.damping_ratio,
                    m.eigenvalue.0,
                    m.backward_error,
                    m.dominant_real_mode
                        .map_or(String::new(), |k| format!("R{}", k + 1)),
                    if m.unstable { "   UNSTABLE" } else { "" }
                )?;
            }
        }
        Ok(())
    }

    fn fmt_reduction(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(r) = &self.reduction {
            writeln!(f,
                "reduction: {} -> {} DOF ({} kept in the contact zone + {} modal coordinates of {} offered, {} dropped), {:.2} s; reduced real modes vs full: max relative error {:.1e} over {}; static state represented to {:.1e}; basis M-orthonormal to {:.1e}; reduced unknowns per rank {:?}",
                r.full_dofs,
                r.kept + r.modal,
                r.kept,
                r.modal,
                r.offered,
                r.dropped,
                r.seconds,
                r.mode_error,
                r.mode_check.len(),
                r.static_error,
                r.orthonormality,
                r.rows_per_rank
            )?;
        }
        Ok(())
    }

    fn fmt_transient(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(t) = &self.transient {
            writeln!(f,
                "transient: {} steps to t = {:.4e} s, {:.2} iterations per step (max {}), {:.2} ms per step; {} step cuts, {} Jacobian refreshes, {} Newton-Krylov retries ({} GMRES iterations), {} full-Newton retries; {} Jacobian factorizations ({}, {:.3e} entries, {:.2} s); one iteration {:.2} ms vs one solve with the factor {:.3} ms ({} solves; ratio {:.2}); per step {:.2} ms in forces, {:.2} ms in operator products",
                t.steps,
                t.simulated,
                t.mean_iterations,
                t.max_iterations,
                1e3 * t.seconds_per_step,
                t.cuts,
                t.refreshes,
                t.krylov_retries,
                t.krylov_iterations,
                t.full_newton_retries,
                t.factorizations,
                t.jacobian_solver,
                t.factor_entries,
                t.seconds_factorizing,
                1e3 * t.seconds_per_iteration,
                1e3 * t.seconds_per_solve,
                t.factor_solves,
                t.seconds_per_iteration / t.seconds_per_solve.max(1e-300),
                1e3 * t.seconds_forces_per_step,
                1e3 * t.seconds_products_per_step
            )?;
        }
        Ok(())
    }

    fn fmt_sweep(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(sw) = &self.sweep {
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            writeln!(f,
                "sweep over {}: {} points, {} tracked modes; per point {:.3} s static re-solve, {:.4} s re-projection + complex modes",
                sw.parameter,
                sw.points,
                sw.tracks,
                mean(&sw.statics_seconds),
                mean(&sw.modal_seconds)
            )?;
            writeln!(f, "    {:>14}   unstable modes", sw.parameter)?;
            for (v, u) in sw.values.iter().zip(&sw.unstable_per_point) {
                writeln!(f, "    {v:14.6}   {u}")?;
            }
            if !sw.cold_restarts.is_empty() {
                writeln!(
                    f,
                    "    points solved from the unloaded state after the warm start failed: {:?}",
                    sw.cold_restarts
                )?;
            }
        }
        Ok(())
    }

    /// The limit cycle against the complex modes.
    fn fmt_limit_cycle(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Some(r) = &self.limit_cycle else {
            return Ok(());
        };
        let c = &r.cycle;
        writeln!(f, "limit cycle of the braking torque: {}", c.verdict)?;
        let growth = match (c.growth_rate, c.growth_frequency) {
            (Some(g), Some(hz)) => format!("{g:.0} 1/s at {hz:.1} Hz"),
            (Some(g), None) => format!("{g:.0} 1/s"),
            _ => "not measured".into(),
        };
        let predicted = r.predicted.as_ref().map_or(String::new(), |p| {
            format!(
                " (complex mode {} of the {} route: Re(s) {:.0} 1/s at {:.1} Hz)",
                p.1, p.0, p.2, p.3
            )
        });
        writeln!(f, "    growth rate {growth}{predicted}")?;
        if let (Some(p), Some(growing)) = (&r.predicted, c.growth_frequency) {
            if (p.3 - growing).abs() > 0.1 * growing {
                writeln!(
                    f,
                    "    the run grows at {growing:.1} Hz but the most unstable complex mode computed is at {:.1} Hz: the modes near the growing frequency are missing (raise real_modes.count for the projected route) or the growth comes from the nonlinear response",
                    p.3
                )?;
            }
        }
        writeln!(
            f,
            "    dominant frequency {:.1} Hz, period {}, saturation at {}, amplitude {:.3e} N m (half peak-to-peak), {} cycles after saturation",
            c.dominant_frequency,
            c.period.map_or("-".into(), |p| format!("{:.4e} s", p)),
            c.saturation_time.map_or("-".into(), |t| format!("{:.4e} s", t)),
            c.saturated_amplitude,
            c.amplitudes.len()
        )?;
        if let Some(phases) = &r.phase_costs {
            for (phase, p) in ["growth", "saturated"].iter().zip(phases) {
                writeln!(
                    f,
                    "    {phase:9} phase: {:.4e} s simulated in {} steps, {:.2} iterations per step, {:.2} ms per step, {:.1} s wall ({:.3} s per simulated ms)",
                    p.simulated,
                    p.steps,
                    p.iterations as f64 / p.steps.max(1) as f64,
                    1e3 * p.wall_seconds / p.steps.max(1) as f64,
                    p.wall_seconds,
                    p.wall_seconds / (1e3 * p.simulated).max(1e-300)
                )?;
            }
        }
        for (name, fr) in &r.contact_fractions {
            writeln!(
                f,
                "    {name:34} open {:5.1} %, sticking {:5.1} %, slipping {:5.1} % of the points over the last cycles",
                100.0 * fr[0],
                100.0 * fr[1],
                100.0 * fr[2]
            )?;
        }
        Ok(())
    }

    /// Timings, memory, where the results are.
    fn fmt_timings(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        writeln!(f, "timings (s):")?;
        for (name, secs) in &s.timings.stages {
            writeln!(f, "    {name:26} {secs:9.3}")?;
        }
        writeln!(
            f,
            "peak memory per rank: {:.1} MiB",
            s.peak_memory_per_rank / (1024.0 * 1024.0)
        )?;
        writeln!(
            f,
            "results: {0}/results.h5 (+ results.xdmf for ParaView, figures as PNG and SVG), report: {0}/report.html",
            s.output.display()
        )?;
        Ok(())
    }
}
