//! Stage 9: the time/frequency link on the transient's stored states (DESIGN.md §2b): modal
//! sensors and dynamic stability along the cycle, each run when the scene's `[post]` asks.

use std::path::Path;

use super::transient::Trajectory;
use super::{Analyses, RunError};
use crate::eigen::complex_modes::{ComplexModeSettings, DampingSettings};
use crate::eigen::stability::ProjectedStability;
use crate::la::Petsc;
use crate::post::contact_cycle::{contact_cycle, phase_states, ContactCycle, ContactCycleSettings};
use crate::post::dynamic_stability::{
    choose_states, dynamic_stability, DynamicStability, DynamicStabilitySettings, Linearization,
};
use crate::post::limit_cycle::LimitCycle;
use crate::post::modal_energy::{modal_energy, ModalEnergy, ModalEnergySettings};
use crate::post::states::{ContactAt, Lift, StoredStates};

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

/// Modal energies of every real mode along the stored states.
///
/// # Collective
pub fn modal_energies<'p>(
    petsc: &'p Petsc,
    a: &Analyses<'p>,
    stream: &Path,
    settings: &ModalEnergySettings,
    cycle: &LimitCycle,
) -> Result<ModalEnergyReport, RunError> {
    let modes = super::need(a.modes.as_ref(), "post.modal_energy", "[real_modes]")?;
    let states = StoredStates::open(petsc, stream, 2)?;
    let samples = states.modal_samples(modes.eigenvalues.len())?;
    let omega2 = &modes.eigenvalues;
    let energy = modal_energy(&states.times, &samples, omega2, settings, period_of(cycle));
    Ok(ModalEnergyReport {
        energy,
        frequencies_hz: modes.frequencies_hz.clone(),
    })
}

/// Dynamic stability at the stored states of the last periods (or the scene's times).
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the run's parts it joins
pub fn dynamic_stability_along<'p>(
    petsc: &'p Petsc,
    a: &Analyses<'p>,
    damping: DampingSettings,
    trajectory: &Trajectory,
    stream: &Path,
    settings: &DynamicStabilitySettings,
    complex: Option<&ComplexModeSettings>,
    state_interval: f64,
    cycle: &LimitCycle,
) -> Result<DynamicStabilityReport, RunError> {
    let key = "post.dynamic_stability";
    let modes = super::need(a.modes.as_ref(), key, "[real_modes]")?;
    let preload = super::need(a.preload.as_ref(), key, "[statics]")?;
    let (contact, nominal) = (&preload.contact, &preload.state.contact);
    let stability = ProjectedStability::new(petsc.world(), contact, modes, nominal, damping)?;
    let states = StoredStates::open(petsc, stream, 2)?;
    let period = period_of(cycle);
    let indices = choose_states(&states, settings, &cycle.cycle_starts, period);
    if indices.is_empty() {
        return Err(RunError::scene(
            key,
            format!(
                "no stored state in the last {} periods of {period:.4e} s (states every {state_interval:.1e} s); lower 'transient.state_interval'",
                settings.periods
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
    let margin = complex.map_or(ComplexModeSettings::default().instability_margin, |c| {
        c.instability_margin
    });
    let lin = Linearization {
        at: contact_at(petsc, a, preload),
        nominal,
        stability: &stability,
        margin,
    };
    let stability = dynamic_stability(&states, &indices, torque, &lin)?;
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
        state_interval,
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
    a: &Analyses<'p>,
    stream: &Path,
    settings: &ContactCycleSettings,
    cycle: &LimitCycle,
) -> Result<ContactCycleReport, RunError> {
    let preload = super::need(a.preload.as_ref(), "post.contact_cycle", "[statics]")?;
    let contact = &preload.contact;
    let states = StoredStates::open(petsc, stream, 2)?;
    let (indices, period) = phase_states(
        &states,
        settings.phases,
        &cycle.cycle_starts,
        period_of(cycle),
    );
    let at = contact_at(petsc, a, preload);
    let pads: Vec<(usize, String)> = contact
        .interfaces
        .iter()
        .enumerate()
        .filter(|(_, i)| i.friction.is_sliding())
        .map(|(k, i)| (k, i.name.clone()))
        .collect();
    Ok(ContactCycleReport {
        cycle: contact_cycle(&states, &at, &indices, period, &pads)?,
        wanted_phases: settings.phases,
    })
}

/// The full model's contact at the stored states (recovered from the reduced unknowns when
/// the transient ran reduced).
pub(crate) fn contact_at<'a, 'p>(
    petsc: &'p Petsc,
    a: &'a Analyses<'p>,
    preload: &'a super::statics::Preloaded<'p>,
) -> ContactAt<'a, 'p> {
    let (state_template, lift) = match &a.reduced {
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

/// The link analyses `[post]` asks for, timed; `limit_cycle`: the run's characterization if
/// `[post.limit_cycle]` made one (else the torque is characterized here for the period).
///
/// # Collective
pub fn link<'p>(
    petsc: &'p Petsc,
    scene: &crate::scene::Scene,
    a: &Analyses<'p>,
    trajectory: &Trajectory,
    limit_cycle: Option<&LimitCycle>,
    stream: &Path,
    timings: &mut super::Timings,
) -> Result<Link, RunError> {
    let (Some(post), Some(transient)) = (&scene.post, &scene.transient) else {
        return Ok(Link::default());
    };
    if !post.uses_states() {
        return Ok(Link::default());
    }
    let own;
    let cycle = match limit_cycle {
        Some(c) => c,
        None => {
            own = characterize(trajectory, transient.step);
            &own
        }
    };
    let mut out = Link::default();
    if let Some(settings) = &post.modal_energy {
        out.modal_energy = Some(timings.stage("modal energy", || {
            modal_energies(petsc, a, stream, settings, cycle)
        })?);
    }
    if let Some(settings) = &post.contact_cycle {
        out.contact_cycle = Some(timings.stage("contact cycle", || {
            contact_over_cycle(petsc, a, stream, settings, cycle)
        })?);
    }
    if let Some(settings) = &post.dynamic_stability {
        let damping = scene.damping.unwrap_or_default();
        out.dynamic_stability = Some(timings.stage("dynamic stability", || {
            dynamic_stability_along(
                petsc,
                a,
                damping,
                trajectory,
                stream,
                settings,
                scene.complex_modes.as_ref(),
                transient.state_interval,
                cycle,
            )
        })?);
    }
    Ok(out)
}

/// The braking torque's characterization with the default settings (when the scene did not
/// ask for `[post.limit_cycle]`, the analyses still need the run's period).
pub fn characterize(trajectory: &Trajectory, step: f64) -> LimitCycle {
    let tr = &trajectory.signals;
    let settings = crate::post::limit_cycle::LimitCycleSettings::default();
    crate::post::limit_cycle::characterize(&tr.time, &tr.braking_torque(), step, &settings)
}

/// The modal energies' summary lines (nothing when not asked for).
pub fn fmt_modal_energy(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.modal_energy {
        let e = &r.energy;
        let i = e
            .times
            .partition_point(|&t| t < e.at)
            .min(e.times.len() - 1);
        writeln!(
            f,
            "modal energy at t = {:.4e} s: {:.3e} J in the {} real modes, which hold {:.1} % of the kinetic energy; largest:",
            e.at,
            e.total(i),
            e.energy.len(),
            100.0 * e.kinetic_in_basis[i] / e.kinetic[i]
        )?;
        for m in &e.ranked {
            writeln!(
                f,
                "    R{:<4} {:9.1} Hz {:6.1} % of the modal energy, oscillating by {:5.1} % over [{:.4e}, {:.4e}] s",
                m.mode + 1,
                r.frequencies_hz[m.mode],
                100.0 * m.share,
                100.0 * m.oscillation,
                e.window.0,
                e.window.1
            )?;
        }
    }
    Ok(())
}

/// The contact cycle's summary lines (nothing when not asked for).
pub fn fmt_contact_cycle(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.contact_cycle {
        let c = &r.cycle;
        writeln!(
            f,
            "contact over the last cycle ({} phases of {} asked, period {:.4e} s, from {:.4e} s):",
            c.times.len(),
            r.wanted_phases,
            c.period,
            c.times.first().copied().unwrap_or(f64::NAN)
        )?;
        for p in &c.pads {
            let (hi, lo) = p.extreme_phases;
            writeln!(
                f,
                "    {:26} largest stiffness {:.3e}..{:.3e} Pa/m (varies by {:.0} %), open {:.1} %, sticking {:.1} %, sliding {:.1} %",
                p.name,
                p.largest_stiffness[lo],
                p.largest_stiffness[hi],
                100.0 * p.variation,
                100.0 * p.fractions[0],
                100.0 * p.fractions[1],
                100.0 * p.fractions[2]
            )?;
        }
    }
    Ok(())
}

/// The dynamic stability's summary lines (nothing when not asked for).
pub fn fmt_dynamic_stability(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.dynamic_stability {
        let s = &r.stability;
        let sampling = if r.states_per_period.is_nan() {
            "at the scene's times".to_string()
        } else if r.states_per_period + 0.5 < r.wanted_per_period as f64 {
            format!(
                "{:.1} per period, fewer than the {} wanted: lower 'transient.state_interval' ({:.1e} s) to {:.1e} s",
                r.states_per_period,
                r.wanted_per_period,
                r.state_interval,
                r.period / r.wanted_per_period as f64
            )
        } else {
            format!("{:.1} per period", r.states_per_period)
        };
        writeln!(
            f,
            "dynamic stability at {} states from {:.4e} to {:.4e} s ({sampling}; period {:.4e} s), {:.3} s per linearization; {} nominal modes tracked, {} lost on the way:",
            s.times.len(),
            s.times.first().copied().unwrap_or(f64::NAN),
            s.times.last().copied().unwrap_or(f64::NAN),
            r.period,
            s.seconds_per_point,
            s.followed,
            s.lost
        )?;
        if s.tracks.is_empty() {
            writeln!(
                f,
                "    no mode is unstable at the static state or along the run"
            )?;
        }
        for t in s.tracks.iter().filter(|t| t.headline(r.margin)) {
            let (fr, z) = (t.frequencies_hz(), t.damping_ratios());
            let range = |x: &[f64]| {
                x[1..]
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    })
            };
            let ((f0, f1), (z0, z1)) = (range(&fr), range(&z));
            let rest = if t.unstable_at_rest(r.margin) {
                "unstable"
            } else {
                "stable"
            };
            // Steps where the track's shape changed abruptly: its identity there is doubtful.
            let jumps = t.mac[1..]
                .iter()
                .filter(|&&m| m.is_nan() || m < 0.5)
                .count();
            let jumps = match jumps {
                0 => String::new(),
                n => format!("; MAC < 0.5 with the previous state at {n} states"),
            };
            writeln!(
                f,
                "    {:5} at rest {:.1} Hz, zeta {:.2e} ({rest}); along the run {:.1}..{:.1} Hz, zeta {:.2e}..{:.2e}, unstable {:.0} % of the time, mean zeta {:.2e}, correlation of zeta with the torque {:.2}{jumps}",
                t.name, fr[0], z[0], f0, f1, z0, z1,
                100.0 * t.unstable_fraction,
                t.mean_damping_ratio,
                t.torque_correlation
            )?;
        }
        let flickering: Vec<_> = s.tracks.iter().filter(|t| !t.headline(r.margin)).collect();
        if let Some(most) = flickering
            .iter()
            .max_by(|a, b| a.unstable_fraction.total_cmp(&b.unstable_fraction))
        {
            writeln!(
                f,
                "    {} more modes, stable at rest and on average, are unstable for part of the time (longest: {} for {:.0} %; all in /post/dynamic_stability)",
                flickering.len(),
                most.name,
                100.0 * most.unstable_fraction
            )?;
        }
    }
    Ok(())
}
