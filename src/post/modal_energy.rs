//! Modal sensors along a run (DESIGN.md §2b; the paper's fig. 6 right): for every real mode
//! k of the basis, the modal coordinate eta_k(t) = phi_k^T M (q(t) - q_static) and its energy
//! E_k = (etadot_k^2 + omega_k^2 eta_k^2) / 2 at every stored state; the modes that hold the
//! most energy at a chosen time, their share and how much it oscillates over the last cycles.
//! On a reduced model phi_k is the mode's exact reduced representation (the modes lie in the
//! reduction's span) and M the reduced mass, so eta_k is the same number as on the full model.

use serde::{Deserialize, Serialize};

use super::states::{StatesError, StoredStates};
use crate::la::{SparseMatrix, Vector};

/// `[post.modal_energy]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModalEnergySettings {
    /// Modes ranked (by their mean energy over the window) and plotted.
    #[serde(default = "default_top")]
    pub top: usize,
    /// The time of the ranking (s); default: the last stored state.
    #[serde(default)]
    pub at: Option<f64>,
    /// Cycles (periods of the run's dominant frequency) before `at` over which each ranked
    /// mode's oscillation is measured.
    #[serde(default = "default_cycles")]
    pub cycles: usize,
}

fn default_top() -> usize {
    10
}
fn default_cycles() -> usize {
    3
}

impl Default for ModalEnergySettings {
    fn default() -> Self {
        toml::from_str("").expect("the defaults parse")
    }
}

impl ModalEnergySettings {
    pub fn validate(&self) -> Result<(), String> {
        if self.top == 0 {
            return Err("key 'post.modal_energy.top' = 0: rank at least one mode".into());
        }
        if self.cycles == 0 {
            return Err("key 'post.modal_energy.cycles' = 0: must be at least 1".into());
        }
        if let Some(at) = self.at {
            if !(at.is_finite() && at >= 0.0) {
                return Err(format!(
                    "key 'post.modal_energy.at' = {at}: must be a time (s) >= 0"
                ));
            }
        }
        Ok(())
    }
}

/// The real modes as sensors, in the integrated unknowns: M x_k (x_k the mode's coordinates)
/// and omega_k^2.
pub struct ModalSensors<'a, 'p> {
    pub mass_shapes: &'a [Vector<'p>],
    pub omega2: &'a [f64],
    pub mass: &'a SparseMatrix<'p>,
    pub q_static: &'a Vector<'p>,
}

/// One ranked mode over the window before the ranking time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RankedMode {
    /// Index into the basis (mode number - 1).
    pub mode: usize,
    /// Its mean energy over the window (J).
    pub energy: f64,
    /// Its mean energy over the mean of the sum of the modal energies of the basis.
    pub share: f64,
    /// Half peak-to-peak of E_k over the last cycles, relative to its mean there (NaN when the
    /// window holds fewer than 3 states).
    pub oscillation: f64,
}

#[derive(Debug, Clone)]
pub struct ModalEnergy {
    pub times: Vec<f64>,
    /// energy[k][i]: mode k at stored state i (J).
    pub energy: Vec<Vec<f64>>,
    /// The kinetic energy v^T M v / 2 and the part of it in the basis' modes
    /// (sum of etadot_k^2 / 2): how much of the motion the basis sees.
    pub kinetic: Vec<f64>,
    pub kinetic_in_basis: Vec<f64>,
    /// The ranking time (the stored state nearest to it) and the window of the oscillation.
    pub at: f64,
    pub window: (f64, f64),
    pub ranked: Vec<RankedMode>,
}

impl ModalEnergy {
    /// Sum of the modal energies at stored state i.
    pub fn total(&self, i: usize) -> f64 {
        self.energy.iter().map(|e| e[i]).sum()
    }
}

/// The modal energies along the stored states; `period`: of the run's dominant vibration (s),
/// for the oscillation window.
///
/// # Collective
pub fn modal_energy(
    states: &StoredStates,
    sensors: &ModalSensors,
    settings: &ModalEnergySettings,
    period: f64,
) -> Result<ModalEnergy, StatesError> {
    let shapes: Vec<&Vector> = sensors.mass_shapes.iter().collect();
    let modes = shapes.len();
    let eta_static = sensors.q_static.mdot(&shapes)?;
    let mut q = sensors.q_static.duplicate()?;
    let mut v = sensors.q_static.duplicate()?;
    let mut mv = sensors.q_static.duplicate()?;
    let n = states.len();
    let mut energy = vec![Vec::with_capacity(n); modes];
    let (mut kinetic, mut kinetic_in_basis) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        states.read(i, &mut q, &mut v)?;
        let eta = q.mdot(&shapes)?;
        let eta_dot = v.mdot(&shapes)?;
        let mut basis_kinetic = 0.0;
        for k in 0..modes {
            let e = eta[k] - eta_static[k];
            energy[k].push(0.5 * (eta_dot[k].powi(2) + sensors.omega2[k] * e * e));
            basis_kinetic += 0.5 * eta_dot[k].powi(2);
        }
        sensors.mass.mult(&v, &mut mv)?;
        kinetic.push(0.5 * v.dot(&mv)?);
        kinetic_in_basis.push(basis_kinetic);
    }
    let times = states.times.clone();
    let last = times.last().copied().unwrap_or(0.0);
    let at_index = nearest(&times, settings.at.unwrap_or(last));
    let at = times.get(at_index).copied().unwrap_or(0.0);
    let window = (at - settings.cycles as f64 * period, at);
    let in_window: Vec<usize> = (0..n)
        .filter(|&i| times[i] >= window.0 && times[i] <= window.1)
        .collect();
    // Ranked by the mean over the window (a mode's energy oscillates within a cycle), or
    // at the ranking time alone when the window holds a single state.
    let ranking = if in_window.is_empty() {
        vec![at_index]
    } else {
        in_window.clone()
    };
    let mean = |e: &[f64]| ranking.iter().map(|&i| e[i]).sum::<f64>() / ranking.len() as f64;
    let means: Vec<f64> = energy.iter().map(|e| mean(e)).collect();
    let total: f64 = means.iter().sum();
    let mut order: Vec<usize> = (0..modes).collect();
    order.sort_by(|&a, &b| means[b].total_cmp(&means[a]));
    let ranked = order
        .into_iter()
        .take(settings.top)
        .map(|k| RankedMode {
            mode: k,
            energy: means[k],
            share: means[k] / total,
            oscillation: oscillation(&energy[k], &in_window),
        })
        .collect();
    Ok(ModalEnergy {
        times,
        energy,
        kinetic,
        kinetic_in_basis,
        at,
        window,
        ranked,
    })
}

/// Index of the value nearest to `t` (0 for an empty list).
fn nearest(times: &[f64], t: f64) -> usize {
    (0..times.len())
        .min_by(|&a, &b| (times[a] - t).abs().total_cmp(&(times[b] - t).abs()))
        .unwrap_or(0)
}

/// Half peak-to-peak over the mean of the values at `window` (NaN below 3 values).
fn oscillation(values: &[f64], window: &[usize]) -> f64 {
    if window.len() < 3 {
        return f64::NAN;
    }
    let (lo, hi, sum) = window.iter().fold(
        (f64::INFINITY, f64::NEG_INFINITY, 0.0),
        |(lo, hi, s), &i| (lo.min(values[i]), hi.max(values[i]), s + values[i]),
    );
    0.5 * (hi - lo) / (sum / window.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oscillation_is_half_peak_to_peak_over_the_mean() {
        let values = [1.0, 0.9, 1.1, 1.0, 5.0];
        assert!((oscillation(&values, &[0, 1, 2, 3]) - 0.1).abs() < 1e-15);
        assert!(oscillation(&values, &[0, 1]).is_nan());
        assert_eq!(nearest(&[0.0, 1.0, 2.0], 1.4), 1);
    }
}
