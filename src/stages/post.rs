//! Stage 8: analyses of the transient's trajectory that the scene's `[post]` asks for
//! (DESIGN.md §2b). The limit cycle of the braking torque, set against the complex modes of
//! the same model.

use super::transient::Trajectory;
use crate::eigen::complex_modes::ComplexModes;
use crate::post::limit_cycle::{characterize, LimitCycle, LimitCycleSettings};

/// The limit cycle with what the frequency analysis predicted for it.
#[derive(Debug, Clone)]
pub struct LimitCycleReport {
    pub cycle: LimitCycle,
    /// The complex mode with the largest Re(s) > 0 (route, name, Re(s) 1/s, frequency Hz).
    pub predicted: Option<(&'static str, String, f64, f64)>,
    /// Per interface: the fraction of its points open, sticking, slipping, averaged over the
    /// last cycles (or the last fifth of the run when no cycle was found).
    pub contact_fractions: Vec<(String, [f64; 3])>,
    /// What the stepping cost before and after the saturation time (None: no saturation).
    pub phase_costs: Option<[PhaseCost; 2]>,
}

/// The stepping's cost over one phase of the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseCost {
    pub simulated: f64,
    pub steps: usize,
    pub iterations: usize,
    pub wall_seconds: f64,
}

/// The cost of the rows [from, to) of a trajectory (from the per-step wall times).
fn phase_cost(tr: &crate::time::transient::Transient, from: usize, to: usize) -> PhaseCost {
    PhaseCost {
        simulated: tr.time[to - 1] - tr.time[from.saturating_sub(1)],
        steps: to - from,
        iterations: tr.iterations[from..to].iter().sum(),
        wall_seconds: tr.wall_seconds[to - 1] - tr.wall_seconds[from.saturating_sub(1)],
    }
}

/// Characterizes the braking torque of the run.
pub fn limit_cycle(
    trajectory: &Trajectory,
    settings: &LimitCycleSettings,
    complex: &[ComplexModes],
    interfaces: &[String],
) -> LimitCycleReport {
    let tr = &trajectory.signals;
    let cycle = characterize(&tr.time, &tr.braking_torque(), tr.nominal_step, settings);
    let predicted = complex
        .iter()
        .flat_map(|c| {
            let route = super::complex::route_name(c.route);
            c.modes.iter().map(move |m| (route, m))
        })
        .filter(|(_, m)| m.eigenvalue.0 > 0.0)
        .max_by(|a, b| a.1.eigenvalue.0.total_cmp(&b.1.eigenvalue.0))
        .map(|(route, m)| (route, m.name.clone(), m.eigenvalue.0, m.frequency_hz));
    // The averaging window: the last `cycles` cycles found, else the last fifth.
    let end = tr.time.last().copied().unwrap_or(0.0);
    let from = match cycle.cycle_starts.len() {
        n if n > settings.cycles => cycle.cycle_starts[n - settings.cycles - 1],
        n if n >= 2 => cycle.cycle_starts[0],
        _ => end - 0.2 * (end - tr.time.first().copied().unwrap_or(0.0)),
    };
    let first = tr.time.partition_point(|&t| t < from);
    let contact_fractions = interfaces
        .iter()
        .zip(&tr.status_points)
        .map(|(name, counts)| {
            let mut f = [0.0; 3];
            let steps = (counts[0].len().saturating_sub(first)).max(1) as f64;
            for k in 0..3 {
                f[k] = counts[k].iter().skip(first).sum::<f64>();
            }
            let points = f.iter().sum::<f64>().max(1.0) / steps;
            (name.clone(), f.map(|x| x / steps / points))
        })
        .collect();
    // Growth [1, saturation) and saturated [saturation, end) rows (the wall times continue
    // across restarts; work lost after a checkpoint is not counted).
    let n = tr.time.len();
    let phase_costs = cycle
        .saturation_time
        .map(|t_sat| tr.time.partition_point(|&t| t < t_sat))
        .filter(|&k| k > 1 && k < n && tr.wall_seconds.len() == n)
        .map(|k| [phase_cost(tr, 1, k), phase_cost(tr, k, n)]);
    LimitCycleReport {
        cycle,
        predicted,
        contact_fractions,
        phase_costs,
    }
}
