//! Stage 10: pseudo complex-mode trajectories of the static state's unstable modes
//! (DESIGN.md §2b), and, when the scene also ran the transient, the same modes' amplitude in
//! its last cycles next to the predicted alpha_sat.

use crate::measure::nan_max;

use super::link::{LinearizationSettings, Nominal};
use super::RunError;
use crate::eigen::complex_modes::{damping_ratio, projected_coordinates, Complex, DenseEigenpair};
use crate::eigen::stability::ProjectedStability;
use crate::la::Petsc;
use crate::post::limit_cycle::LimitCycle;
use crate::post::pseudo_contact::ContactPseudoSystem;
use crate::post::pseudo_trajectory::{
    parse_mode, pseudo_trajectory, unit_contact_shape, OrbitFit, PseudoTrajectory,
    PseudoTrajectorySettings,
};
use crate::post::states::StoredStates;

/// A mode's amplitude in the transient (alpha's units: the largest relative displacement at
/// a contact point, m) over a window of its last cycles.
#[derive(Debug, Clone)]
pub struct TransientAmplitude {
    pub mean: f64,
    pub min: f64,
    pub max: f64,
    pub window: (f64, f64),
    pub states: usize,
    /// The mean share of the contact motion's squared norm the fitted mode motion holds.
    pub share: f64,
    /// The largest relative displacement at a contact point over the window (about the
    /// centre): the motion's own amplitude in alpha's units, whatever its shape.
    pub largest: f64,
}

/// One mode's study, with the transient's amplitude of the mode when there is a transient.
pub struct PseudoStudy {
    pub trajectory: PseudoTrajectory,
    pub transient: Option<TransientAmplitude>,
}

pub struct PseudoReport {
    pub studies: Vec<PseudoStudy>,
    /// The static state's gap scale (m: the default alpha range is 1e-3 to 10 times it) and
    /// the instability margin of the damping ratio.
    pub gap_scale: f64,
    pub margin: f64,
    /// The transient's time, for the cost comparison (None without one).
    pub transient_seconds: Option<f64>,
}

/// What the comparison with a transient needs: its stored states, its cycle and its cost.
pub struct Comparison<'a, 's> {
    pub states: &'a StoredStates<'s>,
    pub cycle: &'a LimitCycle,
    pub transient_seconds: f64,
}

/// Periods of the run's cycle over which a mode's amplitude in the transient is averaged.
pub const CYCLES: f64 = 3.0;

/// The modes unstable beyond `margin` (damping ratio < -margin) in the order of the pairs,
/// or only the `limit` with the largest Re(s) (in that order).
pub(crate) fn most_unstable(
    pairs: &[DenseEigenpair],
    margin: f64,
    limit: Option<usize>,
) -> Vec<usize> {
    let mut unstable: Vec<usize> = (0..pairs.len())
        .filter(|&k| damping_ratio(pairs[k].0) < -margin)
        .collect();
    if let Some(n) = limit {
        unstable.sort_by(|&a, &b| pairs[b].0 .0.total_cmp(&pairs[a].0 .0));
        unstable.truncate(n);
    }
    unstable
}

/// The projection at the static state and its complex modes (eigenvalues with coordinates).
///
/// # Collective
fn nominal_modes(
    petsc: &Petsc,
    basis: Nominal,
    linearization: LinearizationSettings,
) -> Result<(ProjectedStability, Vec<DenseEigenpair>), RunError> {
    let (contact, nominal) = (&basis.preload.contact, &basis.preload.state.contact);
    let comm = petsc.world();
    let stability =
        ProjectedStability::new(comm, contact, basis.modes, nominal, linearization.damping)?;
    let (kp, cp) = stability.operators_at(comm, contact, nominal);
    let size = stability.projection.size;
    let pairs = projected_coordinates(size, &kp, &cp).map_err(crate::la::LaError::from)?;
    Ok((stability, pairs))
}

/// A mode unstable at the static state, at contact amplitude 1 (psi's coordinates on the
/// real modes, normalized as the pseudo trajectories normalize them).
pub struct UnitMode {
    pub name: String,
    pub nominal: Complex,
    pub psi: Vec<Complex>,
}

/// The static state's unstable modes (projected on the real modes), at contact amplitude 1:
/// what can be ranked without a pseudo-trajectory study.
///
/// # Collective
pub fn unstable_modes<'p>(
    petsc: &'p Petsc,
    basis: Nominal<'_, 'p>,
    linearization: LinearizationSettings,
) -> Result<Vec<UnitMode>, RunError> {
    let margin = linearization.margin;
    let (contact, nominal) = (&basis.preload.contact, &basis.preload.state.contact);
    let comm = petsc.world();
    let (stability, pairs) = nominal_modes(petsc, basis, linearization)?;
    let system = ContactPseudoSystem::new(comm, contact, nominal, &stability);
    let mut out = Vec::new();
    for k in most_unstable(&pairs, margin, None) {
        let name = format!("C{}", k + 1);
        let (psi, _) = unit_contact_shape(&system, &name, &pairs[k].1)
            .map_err(|e| RunError::scene("post.loudness", format!("{name}: {e}")))?;
        out.push(UnitMode {
            name,
            nominal: pairs[k].0,
            psi,
        });
    }
    Ok(out)
}

/// The pseudo trajectories of the modes the scene names (default: those unstable at the
/// static state).
///
/// # Collective
pub fn pseudo_trajectories<'p>(
    petsc: &'p Petsc,
    basis: Nominal<'_, 'p>,
    linearization: LinearizationSettings,
    settings: &PseudoTrajectorySettings,
    comparison: Option<Comparison>,
) -> Result<PseudoReport, RunError> {
    let key = "post.pseudo_trajectory";
    let margin = linearization.margin;
    let (contact, nominal) = (&basis.preload.contact, &basis.preload.state.contact);
    let comm = petsc.world();
    let (stability, pairs) = nominal_modes(petsc, basis, linearization)?;
    let chosen: Vec<usize> = match &settings.modes {
        Some(names) => names
            .iter()
            .map(|n| {
                parse_mode(n).filter(|&k| k < pairs.len()).ok_or_else(|| {
                    RunError::scene(
                        "post.pseudo_trajectory.modes",
                        format!(
                            "'{n}': the projected complex modes are C1 to C{}",
                            pairs.len()
                        ),
                    )
                })
            })
            .collect::<Result<_, _>>()?,
        None => most_unstable(&pairs, margin, settings.most_unstable),
    };
    let system = ContactPseudoSystem::new(comm, contact, nominal, &stability);
    // The contact zone's relative motion over the transient's last cycles, read once.
    let motion = match &comparison {
        Some(c) => Some(observed_motion(petsc, basis, c)?),
        None => None,
    };
    let sum = |x: &mut [f64]| crate::parallel::sum_in_place(comm, x);
    let mut studies = Vec::new();
    for k in chosen {
        let name = format!("C{}", k + 1);
        let trajectory = pseudo_trajectory(&system, &name, &pairs, k, settings, margin)
            .map_err(|e| RunError::scene(key, format!("{name}: {e}")))?;
        let transient = match &motion {
            Some(m) if !m.states.is_empty() => {
                let channels = stability.projection.observe(&trajectory.psi);
                let psi: Vec<_> = (0..channels[0].len())
                    .flat_map(|j| [channels[0][j], channels[1][j], channels[2][j]])
                    .collect();
                let fit = OrbitFit::new(&psi, sum)
                    .map_err(|e| RunError::scene(key, format!("{name}: {e}")))?;
                let fitted: Vec<_> = m.states.iter().map(|x| fit.fit(x, sum)).collect();
                let values: Vec<f64> = fitted.iter().map(|f| f.alpha).collect();
                let share = fitted.iter().map(|f| f.share).sum::<f64>() / fitted.len() as f64;
                let (min, max) = values
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                        (a.min(x), b.max(x))
                    });
                Some(TransientAmplitude {
                    mean: values.iter().sum::<f64>() / values.len() as f64,
                    min,
                    max,
                    window: m.window,
                    states: values.len(),
                    share,
                    largest: m.largest,
                })
            }
            _ => None,
        };
        studies.push(PseudoStudy {
            trajectory,
            transient,
        });
    }
    use crate::post::pseudo_trajectory::PseudoSystem;
    Ok(PseudoReport {
        studies,
        gap_scale: system.gap_scale(),
        margin,
        transient_seconds: comparison.map(|c| c.transient_seconds),
    })
}

/// The relative displacement (gap, slip 1, slip 2 per local point) at the stored states of
/// the transient's last `CYCLES` periods (ending at the last cycle start found, else at the
/// last state), minus its mean over them.
struct ObservedMotion {
    states: Vec<Vec<f64>>,
    window: (f64, f64),
    largest: f64,
}

/// # Collective
fn observed_motion<'p>(
    petsc: &'p Petsc,
    nominal: Nominal<'_, 'p>,
    c: &Comparison,
) -> Result<ObservedMotion, RunError> {
    let states = c.states;
    let end = states.window_end(&c.cycle.cycle_starts);
    let from = end - CYCLES * super::link::period_of(c.cycle);
    let at = nominal.contact_at(petsc);
    let mut out = Vec::new();
    for i in states.between(from, end) {
        let state = at.state(states, i)?;
        out.push(
            state
                .observed
                .iter()
                .flat_map(|o| [o.gap, o.slip[0], o.slip[1]])
                .collect::<Vec<f64>>(),
        );
    }
    if let Some(first) = out.first() {
        let mut mean = vec![0.0; first.len()];
        for x in &out {
            for (m, v) in mean.iter_mut().zip(x) {
                *m += v / out.len() as f64;
            }
        }
        for x in &mut out {
            for (v, m) in x.iter_mut().zip(&mean) {
                *v -= m;
            }
        }
    }
    let mut largest = [out
        .iter()
        .flat_map(|x| {
            x.chunks(3)
                .map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt())
        })
        .fold(0.0f64, nan_max)];
    crate::parallel::max_in_place(petsc.world(), &mut largest);
    Ok(ObservedMotion {
        states: out,
        window: (from, end),
        largest: largest[0],
    })
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::most_unstable;

    #[test]
    fn most_unstable_keeps_the_largest_real_parts_and_skips_the_stable() {
        // Re(s) 5, -1 (stable), 30, 1e-9 (inside the margin), 12.
        let pairs: Vec<_> = [5.0, -1.0, 30.0, 1e-9, 12.0]
            .iter()
            .map(|&re| ((re, 1000.0), vec![]))
            .collect();
        assert_eq!(most_unstable(&pairs, 1e-6, None), vec![0, 2, 4]);
        assert_eq!(most_unstable(&pairs, 1e-6, Some(2)), vec![2, 4]);
        assert_eq!(most_unstable(&pairs, 1e-6, Some(9)), vec![2, 4, 0]);
    }
}
