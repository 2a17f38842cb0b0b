//! The summary's part of each stage, one formatter per stage over the run's summary.

use std::fmt;

use super::summary::RunSummary;

impl RunSummary {
    /// Builder notes, size, mesh quality, partition.
    pub(super) fn fmt_model(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        for note in &s.notes {
            writeln!(f, "{note}")?;
        }
        writeln!(f, "model: {} DOF", s.dofs)?;
        if !s.quality.is_empty() {
            writeln!(f, "mesh quality (sJ: scaled Jacobian, AR: aspect ratio):")?;
            for line in crate::fem::quality::table(&s.quality).lines() {
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
    pub(super) fn fmt_statics(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self;
        if let Some(st) = &s.statics {
            writeln!(f,
                "static preload: {} contact points (per rank {:?}), {} load steps, {} Newton iterations ({} solves; {} by GMRES with an earlier factor, {} GMRES iterations), {} LU factorizations{} ({:.3e} entries, {:.1} s), final residual {:.2e} N",
                st.points, st.points_per_rank, st.load_steps, st.newton_iterations, st.solves, st.krylov_corrections, st.krylov_iterations, st.factorizations, if st.single_precision { " in single precision" } else { "" }, st.factor_entries, st.seconds_factorizing, st.final_residual
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
    pub(super) fn fmt_modes(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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
            let rigid = s.rigid.iter().filter(|&&r| r).count();
            if rigid > 0 && s.statics.is_some() {
                writeln!(
                    f,
                    "    {rigid} rigid-body mode(s) of the preloaded brake: contact leaves a part free along them, so the static state is not unique there (the preload balances at any position along them); hold the part: friction in its joints ([contact.sticking] friction) or clamps"
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

    pub(super) fn fmt_reduction(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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

    pub(super) fn fmt_transient(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(t) = &self.transient {
            // A run resumed at its last step (--restart with no steps left) solved nothing.
            let solve = if t.factor_solves > 0 {
                format!(
                    "one solve with the factor {:.3} ms ({} solves; ratio {:.2})",
                    1e3 * t.seconds_per_solve,
                    t.factor_solves,
                    t.seconds_per_iteration / t.seconds_per_solve
                )
            } else {
                "no solve with the factor in this process (resumed at the run's end)".to_string()
            };
            writeln!(f,
                "transient: {} steps to t = {:.4e} s, {:.2} iterations per step (max {}), {:.2} ms per step; {} step cuts, {} Jacobian refreshes, {} updated-factor retries, {} Newton-Krylov retries ({} GMRES iterations), {} full-Newton retries; this process's {} steps {:.2} iterations each ({} accepted on the step's truncation error), with the failed attempts {:.2} iterations and {:.2} solves with the factor per step; {} Jacobian factorizations ({}, {:.3e} entries, {:.2} s, of which {:.2} s assembling J); one iteration {:.2} ms vs {}; per step {:.2} ms in forces, {:.2} ms in operator products, {:.2} ms in the failed attempts, {:.2} ms writing the signals, states and checkpoints",
                t.steps,
                t.simulated,
                t.mean_iterations,
                t.max_iterations,
                1e3 * t.seconds_per_step,
                t.cuts,
                t.refreshes,
                t.updated_retries,
                t.krylov_retries,
                t.krylov_iterations,
                t.full_newton_retries,
                t.steps_run,
                t.iterations_per_step_run,
                t.steps_on_step_error,
                t.all_iterations_per_step,
                t.all_solves_per_step,
                t.factorizations,
                t.jacobian_solver,
                t.factor_entries,
                t.seconds_factorizing,
                t.seconds_assembling_jacobians,
                1e3 * t.seconds_per_iteration,
                solve,
                1e3 * t.seconds_forces_per_step,
                1e3 * t.seconds_products_per_step,
                1e3 * t.seconds_failed_per_step,
                1e3 * t.seconds_recording_per_step
            )?;
            let e = &t.eliminations;
            if e.eliminations > 0 {
                let per = |x: usize| x as f64 / e.eliminations as f64;
                writeln!(
                    f,
                    "    {} nonlinear eliminations of contact points (the updated-factor retries above made them in place of the update): {:.1} points and {:.1} unknowns each in {:.1} independent parts (the largest {:.1} unknowns; each part solved on one rank; {} parts started from a kept factor), {:.2} local Newton iterations (its slowest part's) and {:.2} LU factorizations (all its parts') each (sparse, {:.0} entries each, {} of them by the numerical phase alone; {} dense after a zero pivot; {} ended unconverged), {:.1} s (the tangent's change at the iterate {:.1} s, ranking the points {:.1} s, their operator blocks and the local Jacobian's pattern {:.1} s, local Newton {:.1} s (on the slowest rank {:.1} s), of which local Jacobians and their LU {:.1} s; the linear force's change of the moves {:.2} s, combining the parts' moves over the ranks {:.2} s); the global residual on the eliminated unknowns after them at most {:.2} of the target (0.1 when consistent)",
                    e.eliminations,
                    per(e.points),
                    per(e.unknowns),
                    per(e.parts),
                    per(e.largest_parts),
                    e.parts_on_kept_factors,
                    per(e.local_iterations),
                    per(e.local_factorizations),
                    e.factor_entries / (e.local_factorizations - e.dense_factorizations).max(1) as f64,
                    e.numeric_refactorizations,
                    e.dense_factorizations,
                    e.unconverged,
                    e.seconds,
                    e.seconds_tangent,
                    e.seconds_ranking,
                    e.seconds_blocks,
                    e.seconds_local_newton,
                    e.seconds_local_newton_slowest,
                    e.seconds_factorizing,
                    e.seconds_linear_change,
                    e.seconds_combining,
                    e.worst_mismatch
                )?;
            }
            writeln!(
                f,
                "    started from the static state as an equilibrium (its residual {:.2e} N taken off the load)",
                t.static_residual
            )?;
            if let Some(at) = t.stopped_at_saturation {
                writeln!(f, "    stopped at t = {at:.4e} s: the torque had saturated transient.stop_after_saturation cycles before")?;
            }
            if t.cuts + t.refreshes + t.updated_retries + t.krylov_retries + t.full_newton_retries
                > 0
            {
                writeln!(f, "    each change of the step control above (a step whose iterations stalled, then retried, refactorized or cut) has its line in transient.log")?;
            }
            for note in &t.notes {
                writeln!(f, "    {note}")?;
            }
        }
        Ok(())
    }

    pub(super) fn fmt_sweep(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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
    pub(super) fn fmt_limit_cycle(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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
    pub(super) fn fmt_timings(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
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
            "results: {0}/results.h5 (+ results.xdmf and the other .xdmf files for ParaView, figures as PNG and SVG), report: {0}/report.html",
            s.output.display()
        )?;
        Ok(())
    }
}
