//! Stage 9: the time/frequency link on the transient's stored states (DESIGN.md §2b): modal
//! sensors and dynamic stability along the cycle, each run when the scene's `[post]` asks.

use super::reduce::Reduced;
use super::statics::Preloaded;
use super::transient::Trajectory;
use super::RunError;
use crate::eigen::complex_modes::DampingSettings;
use crate::eigen::real_modes::RealModes;
use crate::eigen::stability::ProjectedStability;
use crate::la::Petsc;
use crate::post::contact_cycle::{contact_cycle, phase_states, ContactCycle, ContactCycleSettings};
use crate::post::dynamic_stability::{
    choose_states, dynamic_stability, DynamicStability, DynamicStabilitySettings, Linearization,
};
use crate::post::limit_cycle::LimitCycle;
use crate::post::modal_energy::{modal_energy, ModalEnergy, ModalEnergySettings};
use crate::post::states::{ContactAt, Lift, StoredStates};
use crate::scene::PostSettings;

/// The modal energies with the basis' frequencies.
pub struct ModalEnergyReport {
    pub energy: ModalEnergy,
    pub frequencies_hz: Vec<f64>,
}

/// A tracked mode's shape on the full model (this rank's part): name, time, frequency and
/// damping ratio, real and imaginary parts.
pub struct TrackedShape {
    pub label: String,
    pub dataset: String,
    pub parts: [Vec<f64>; 2],
}

/// Dynamic stability with what the summary says about its sampling.
pub struct DynamicStabilityReport {
    pub stability: DynamicStability,
    /// The headline modes' shapes where their frequency is highest and lowest (fig. 11).
    pub shapes: Vec<TrackedShape>,
    pub period: f64,
    pub states_per_period: f64,
    pub wanted_per_period: usize,
    pub state_interval: f64,
    pub margin: f64,
}

/// The period of the run's vibration: the cycle's, else that of the dominant frequency.
pub fn period_of(cycle: &LimitCycle) -> f64 {
    cycle
        .period
        .unwrap_or(1.0 / cycle.dominant_frequency.max(1e-300))
}

/// What the analyses of a trajectory build on: the static state (its contact model and
/// nominal contact state), the real modes (the basis of the projected linearizations) and the
/// reduced model when the transient ran on it (its states are lifted to the full model).
#[derive(Clone, Copy)]
pub struct Nominal<'a, 'p> {
    pub preload: &'a Preloaded<'p>,
    pub modes: &'a RealModes<'p>,
    pub reduced: Option<&'a Reduced<'p>>,
}

impl<'a, 'p> Nominal<'a, 'p> {
    /// The full model's contact at the stored states (recovered from the reduced unknowns
    /// when the transient ran reduced).
    pub fn contact_at(&self, petsc: &'p Petsc) -> ContactAt<'a, 'p> {
        let preload = self.preload;
        let (state_template, lift) = match self.reduced {
            Some(r) => (&r.q_static, Lift::Reduced(&r.model.reduction)),
            None => (&preload.state.displacement, Lift::Full),
        };
        ContactAt {
            petsc,
            contact: &preload.contact,
            lift,
            full_template: &preload.state.displacement,
            state_template,
        }
    }
}

/// Modal energies of every real mode along the stored states.
///
/// # Collective
pub fn modal_energies(
    modes: &RealModes,
    states: &StoredStates,
    settings: &ModalEnergySettings,
    cycle: &LimitCycle,
) -> Result<ModalEnergyReport, RunError> {
    let samples = states.modal_samples(modes.eigenvalues.len())?;
    let omega2 = &modes.eigenvalues;
    let energy = modal_energy(&states.times, &samples, omega2, settings, period_of(cycle));
    Ok(ModalEnergyReport {
        energy,
        frequencies_hz: modes.frequencies_hz.clone(),
    })
}

/// How the linearizations along the run are made and judged.
#[derive(Clone, Copy)]
pub struct LinearizationSettings {
    pub damping: DampingSettings,
    /// Damping ratio below -margin: unstable.
    pub margin: f64,
}

/// Dynamic stability at the stored states of the last periods (or the scene's times).
///
/// # Collective
pub fn dynamic_stability_along<'p>(
    petsc: &'p Petsc,
    nominal: Nominal<'_, 'p>,
    linearization: LinearizationSettings,
    trajectory: &Trajectory,
    states: &StoredStates,
    settings: &DynamicStabilitySettings,
    cycle: &LimitCycle,
) -> Result<DynamicStabilityReport, RunError> {
    let key = "post.dynamic_stability";
    let (modes, preload) = (nominal.modes, nominal.preload);
    let (contact, at_rest) = (&preload.contact, &preload.state.contact);
    let damping = linearization.damping;
    let stability = ProjectedStability::new(petsc.world(), contact, modes, at_rest, damping)?;
    let period = period_of(cycle);
    let indices = choose_states(states, settings, &cycle.cycle_starts, period);
    if indices.is_empty() {
        return Err(RunError::scene(
            key,
            format!(
                "no stored state in the last {} periods of {period:.4e} s (states every {:.1e} s); lower 'transient.state_interval'",
                settings.periods, trajectory.signals.state_interval
            ),
        ));
    }
    let tr = &trajectory.signals;
    let torque_signal = tr.braking_torque();
    let torque = indices
        .iter()
        .map(|&i| {
            let t = states.times[i];
            let k = tr.time.partition_point(|&x| x < t).min(tr.time.len() - 1);
            torque_signal[k]
        })
        .collect();
    let margin = linearization.margin;
    let lin = Linearization {
        at: nominal.contact_at(petsc),
        nominal: at_rest,
        stability: &stability,
        margin,
    };
    let stability = dynamic_stability(states, &indices, torque, &lin)?;
    let window = match &settings.times {
        Some(_) => f64::NAN,
        None => indices.len() as f64 / settings.periods as f64,
    };
    let shapes = tracked_shapes(&stability, modes, margin)?;
    Ok(DynamicStabilityReport {
        stability,
        shapes,
        period,
        states_per_period: window,
        wanted_per_period: settings.per_period,
        state_interval: trajectory.signals.state_interval,
        margin,
    })
}

/// The contact over the cycle with how many phases were asked.
pub struct ContactCycleReport {
    pub cycle: ContactCycle,
    pub wanted_phases: usize,
}

/// The contact state at phases of the last cycle.
///
/// # Collective
pub fn contact_over_cycle<'p>(
    petsc: &'p Petsc,
    nominal: Nominal<'_, 'p>,
    states: &StoredStates,
    settings: &ContactCycleSettings,
    cycle: &LimitCycle,
) -> Result<ContactCycleReport, RunError> {
    let contact = &nominal.preload.contact;
    let (indices, period) = phase_states(
        states,
        settings.phases,
        &cycle.cycle_starts,
        period_of(cycle),
    );
    let at = nominal.contact_at(petsc);
    let pads: Vec<(usize, String)> = contact
        .interfaces()
        .iter()
        .enumerate()
        .filter(|(_, i)| i.friction.is_sliding())
        .map(|(k, i)| (k, i.name.clone()))
        .collect();
    Ok(ContactCycleReport {
        cycle: contact_cycle(states, &at, &indices, period, &pads)?,
        wanted_phases: settings.phases,
    })
}

/// The headline tracks' shapes at their highest and lowest frequency, expanded on the real
/// modes of the full model.
///
/// # Collective
fn tracked_shapes(
    stability: &DynamicStability,
    modes: &crate::eigen::real_modes::RealModes,
    margin: f64,
) -> Result<Vec<TrackedShape>, RunError> {
    let mut out = Vec::new();
    for t in stability.tracks.iter().filter(|t| t.headline(margin)) {
        for (which, (i, y)) in ["highest", "lowest"].iter().zip(&t.extremes) {
            if y.is_empty() || *i == 0 {
                continue;
            }
            let (xr, xi) = crate::eigen::complex_modes::expand(&modes.shapes, y)?;
            let (f, z) = (t.frequencies_hz()[*i], t.damping_ratios()[*i]);
            let time = stability.times[*i - 1];
            out.push(TrackedShape {
                label: format!(
                    "{} at its {which} frequency ({f:.1} Hz, zeta {z:.2e}, t = {time:.5e} s)",
                    t.name
                ),
                dataset: format!("/post/dynamic_stability/modes/{}/shapes/{which}", t.name),
                parts: [xr.local()?.to_vec(), xi.local()?.to_vec()],
            });
        }
    }
    Ok(out)
}

/// What the link analyses produced (None: not asked for).
#[derive(Default)]
pub struct Link {
    pub modal_energy: Option<ModalEnergyReport>,
    pub dynamic_stability: Option<DynamicStabilityReport>,
    pub contact_cycle: Option<ContactCycleReport>,
}

/// The link analyses `[post]` asks for, timed, on the run's `cycle` (its characterization).
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the run's parts it joins
pub fn link<'p>(
    petsc: &'p Petsc,
    post: &PostSettings,
    linearization: LinearizationSettings,
    nominal: Nominal<'_, 'p>,
    trajectory: &Trajectory,
    states: &StoredStates,
    cycle: &LimitCycle,
    timings: &mut super::Timings,
) -> Result<Link, RunError> {
    let mut out = Link::default();
    if let Some(settings) = &post.modal_energy {
        out.modal_energy = Some(timings.stage("modal energy", || {
            modal_energies(nominal.modes, states, settings, cycle)
        })?);
    }
    if let Some(settings) = &post.contact_cycle {
        out.contact_cycle = Some(timings.stage("contact cycle", || {
            contact_over_cycle(petsc, nominal, states, settings, cycle)
        })?);
    }
    if let Some(settings) = &post.dynamic_stability {
        let (lin, t) = (linearization, trajectory);
        out.dynamic_stability = Some(timings.stage("dynamic stability", || {
            dynamic_stability_along(petsc, nominal, lin, t, states, settings, cycle)
        })?);
    }
    Ok(out)
}

/// The braking torque's characterization with the default settings (when the scene did not
/// ask for `[post.limit_cycle]`, the analyses still need the run's period).
pub fn characterize(trajectory: &Trajectory) -> LimitCycle {
    let tr = &trajectory.signals;
    let settings = crate::post::limit_cycle::LimitCycleSettings::default();
    let step = trajectory.signals.nominal_step;
    crate::post::limit_cycle::characterize(&tr.time, &tr.braking_torque(), step, &settings)
}
