//! Stage 11: how loud (DESIGN.md §2c). The radiating surfaces (the exterior faces of the
//! components the scene names; default the disc and the pads' backplates) observed by a
//! distributed normal-velocity matrix N (rows: face quadrature points, split evenly over the
//! ranks), then the equivalent radiated power of every unstable mode the pseudo trajectories
//! followed (at 1 um of contact amplitude and at its predicted alpha_sat) and of the
//! transient's stored states (over time, and in 1/3-octave bands over its last cycles), with
//! the sound pressure at the scene's microphones by the Rayleigh integral.

use std::collections::BTreeMap;

use super::link::{period_of, Nominal};
use super::pseudo::{PseudoReport, UnitMode};
use super::RunError;
use crate::la::Petsc;
use crate::post::limit_cycle::LimitCycle;
use crate::post::loudness::{
    a_weighting, band_powers, erp_instant, power_level, pressure_series, series_levels, Band,
    LoudnessSettings,
};
pub use crate::post::radiator::{
    mode_loudness, radiator, ModeLoudness, Radiator, RadiatorError, UNIT_AMPLITUDE,
};
use crate::post::states::{Lift, StoredStates};

/// The transient's radiated power.
#[derive(Debug, Clone)]
pub struct TransientLoudness {
    /// ERP at stored states (s, W).
    pub times: Vec<f64>,
    pub power: Vec<f64>,
    /// The window of the last cycles, their mean power and its 1/3-octave bands.
    pub window: (f64, f64),
    pub states: usize,
    pub mean_power: f64,
    pub bands: Vec<(Band, f64)>,
    /// Per microphone: name and the pressure level over the window (dB re 20 uPa), plain and
    /// A-weighted (the Rayleigh integral in the time domain).
    pub microphones: Vec<(String, f64, f64)>,
}

impl TransientLoudness {
    /// L_W(A) of the last cycles from the bands (dB).
    pub fn level_a(&self) -> f64 {
        let total: f64 = self
            .bands
            .iter()
            .map(|(b, p)| p * 10f64.powf(a_weighting(b.centre) / 10.0))
            .sum();
        power_level(total)
    }

    /// The band that carries the most power.
    pub fn dominant_band(&self) -> Option<&(Band, f64)> {
        self.bands.iter().max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// What the loudness stage found.
pub struct LoudnessReport {
    pub components: Vec<String>,
    pub faces: usize,
    pub points: usize,
    pub area: f64,
    pub density: f64,
    pub sound_speed: f64,
    /// The modes: those with an alpha_sat first, then the unstable ones per unit amplitude,
    /// loudest (L_W(A)) first in each.
    pub modes: Vec<ModeLoudness>,
    pub transient: Option<TransientLoudness>,
}

/// The transient's stored states and what places its last cycles.
pub struct StoredRun<'a, 's> {
    pub states: &'a StoredStates<'s>,
    pub cycle: &'a LimitCycle,
}

/// The levels of the static state's unstable modes (at 1 um of contact amplitude, and at
/// alpha_sat for those the pseudo trajectories followed, with any stable mode they followed
/// too) and of the transient.
///
/// # Collective
pub fn loudness<'p>(
    petsc: &'p Petsc,
    radiator: &Radiator<'p>,
    settings: &LoudnessSettings,
    nominal: Nominal<'_, 'p>,
    unstable: &[UnitMode],
    pseudo: Option<&PseudoReport>,
    run: Option<StoredRun>,
) -> Result<LoudnessReport, RunError> {
    let studies = pseudo.map_or(&[][..], |p| &p.studies);
    let mut modes = Vec::new();
    for study in studies {
        let t = &study.trajectory;
        let shape = (&t.name[..], t.nominal, &t.psi[..]);
        let sat = t.alpha_sat.alpha();
        let shapes = &nominal.modes.shapes;
        modes.push(mode_loudness(
            petsc, radiator, settings, shapes, shape, sat,
        )?);
    }
    for mode in unstable {
        if studies.iter().any(|s| s.trajectory.name == mode.name) {
            continue;
        }
        let shape = (&mode.name[..], mode.nominal, &mode.psi[..]);
        let shapes = &nominal.modes.shapes;
        modes.push(mode_loudness(
            petsc, radiator, settings, shapes, shape, None,
        )?);
    }
    // The levels at alpha_sat first, then those per unit amplitude: loudest first in each.
    modes.sort_by(|a, b| {
        (a.alpha_sat.is_none(), -a.level_a())
            .partial_cmp(&(b.alpha_sat.is_none(), -b.level_a()))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let transient = match run {
        Some(run) => Some(transient_loudness(petsc, radiator, settings, nominal, run)?),
        None => None,
    };
    Ok(LoudnessReport {
        components: radiator.components.clone(),
        faces: radiator.faces,
        points: radiator.points,
        area: radiator.area,
        density: settings.density,
        sound_speed: settings.sound_speed,
        modes,
        transient,
    })
}

/// The ERP at the stored states (at most ~400 over the run, every state of the window), and
/// the bands of the last `settings.cycles` periods.
///
/// # Collective
fn transient_loudness<'p>(
    petsc: &'p Petsc,
    radiator: &Radiator<'p>,
    settings: &LoudnessSettings,
    nominal: Nominal<'_, 'p>,
    run: StoredRun,
) -> Result<TransientLoudness, RunError> {
    let comm = petsc.world();
    let air = settings.air();
    let states = run.states;
    let end = states.window_end(&run.cycle.cycle_starts);
    let from = end - settings.cycles as f64 * period_of(run.cycle);
    let window = states.between(from, end);
    let stride = states.len().div_ceil(400).max(1);
    let mut chosen: BTreeMap<usize, bool> = (0..states.len())
        .step_by(stride)
        .map(|i| (i, false))
        .collect();
    for &i in &window {
        chosen.insert(i, true);
    }
    let at = nominal.contact_at(petsc);
    let mut x = at.state_template.duplicate()?;
    let mut xv = at.state_template.duplicate()?;
    let mut v = at.full_template.duplicate()?;
    let (mut times, mut power) = (Vec::new(), Vec::new());
    let mut series: Vec<Vec<f64>> = vec![Vec::with_capacity(window.len()); radiator.weights.len()];
    for (&i, &in_window) in &chosen {
        states.read(i, &mut x, &mut xv)?;
        let velocity = match at.lift {
            Lift::Full => &xv,
            Lift::Reduced(r) => {
                r.recover(petsc, &xv, &mut v)?;
                &v
            }
        };
        let vn = radiator.normal_velocity(velocity)?;
        let mut erp = [erp_instant(&air, &radiator.weights, &vn)];
        crate::parallel::sum_in_place(comm, &mut erp);
        times.push(states.times[i]);
        power.push(erp[0]);
        if in_window {
            for (s, value) in series.iter_mut().zip(&vn) {
                s.push(*value);
            }
        }
    }
    let dt = match window.len() {
        0 | 1 => f64::NAN,
        n => (states.times[window[n - 1]] - states.times[window[0]]) / (n - 1) as f64,
    };
    let mut bands = band_powers(&air, &radiator.weights, &series, dt);
    let microphones = transient_microphones(petsc, radiator, settings, &series, dt);
    let mut sums: Vec<f64> = bands.iter().map(|b| b.1).collect();
    crate::parallel::sum_in_place(comm, &mut sums);
    for (b, s) in bands.iter_mut().zip(sums) {
        b.1 = s;
    }
    let in_window: Vec<f64> = times
        .iter()
        .zip(&power)
        .filter(|(t, _)| **t >= from && **t <= end)
        .map(|(_, p)| *p)
        .collect();
    let mean_power = in_window.iter().sum::<f64>() / in_window.len().max(1) as f64;
    Ok(TransientLoudness {
        times,
        power,
        window: (from, end),
        states: window.len(),
        mean_power,
        bands,
        microphones,
    })
}

/// The microphones' levels over the window: the Rayleigh integral in the time domain (the
/// retarded accelerations of every point, summed over the ranks), from the largest delay on.
///
/// # Collective
fn transient_microphones(
    petsc: &Petsc,
    radiator: &Radiator,
    settings: &LoudnessSettings,
    series: &[Vec<f64>],
    dt: f64,
) -> Vec<(String, f64, f64)> {
    let air = settings.air();
    let comm = petsc.world();
    settings
        .microphones
        .iter()
        .map(|(name, at)| {
            let local_delay = radiator
                .local
                .iter()
                .map(|p| p.distance_to(*at) / air.sound_speed)
                .fold(0.0, crate::measure::nan_max);
            let delay = crate::parallel::max(comm, local_delay);
            let first = (delay / dt).ceil() as usize + 2;
            let mut p = pressure_series(&air, &radiator.local, series, dt, *at, first);
            let length = crate::parallel::max(comm, p.len() as f64) as usize;
            p.resize(length, 0.0);
            crate::parallel::sum_in_place(comm, &mut p);
            let (plain, weighted) = series_levels(&p, dt);
            (name.clone(), plain, weighted)
        })
        .collect()
}
