//! Modal sensors along a run (DESIGN.md §2b; the paper's fig. 6 right): for every real mode
//! k of the basis, the modal coordinate eta_k(t) = phi_k^T M (q(t) - q_static) and its energy
//! E_k = (etadot_k^2 + omega_k^2 eta_k^2) / 2 at every stored state; the modes that hold the
//! most energy before a chosen time, their share and how much it oscillates over the last
//! cycles. The transient takes the samples as it runs (with every stored state): a restart
//! may recompute a reduction basis rotated, which the stored states' coordinates are on, but
//! not the modes' own coordinates.
//! On a reduced model phi_k is the mode's exact reduced representation (the modes lie in the
//! reduction's span) and M the reduced mass, so eta_k is the same number as on the full model.

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

use super::states::nearest;
use crate::la::{LaError, SparseMatrix, Vector};

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
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.top == 0 {
            return Err(InvalidSetting::new(
                "post.modal_energy.top",
                " = 0: rank at least one mode",
            ));
        }
        if self.cycles == 0 {
            return Err(InvalidSetting::new(
                "post.modal_energy.cycles",
                " = 0: must be at least 1",
            ));
        }
        if let Some(at) = self.at {
            if !(at.is_finite() && at >= 0.0) {
                return Err(InvalidSetting::new(
                    "post.modal_energy.at",
                    format!(" = {at}: must be a time (s) >= 0"),
                ));
            }
        }
        Ok(())
    }
}

/// The real modes as sensors, in the integrated unknowns: M x_k (x_k the mode's coordinates)
/// and omega_k^2. The transient takes a sample at every stored state.
pub struct ModalSensors<'a, 'p> {
    pub mass_shapes: &'a [Vector<'p>],
    pub omega2: &'a [f64],
    pub mass: &'a SparseMatrix<'p>,
    pub q_static: &'a Vector<'p>,
}

/// The modal coordinates and velocities of one state, and its kinetic energy v'Mv/2.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalSample {
    pub eta: Vec<f64>,
    pub eta_dot: Vec<f64>,
    pub kinetic: f64,
}

impl ModalSensors<'_, '_> {
    /// eta_k = (M x_k)'(q - q_static), etadot_k = (M x_k)'v, and v'Mv/2.
    ///
    /// # Collective
    pub fn sample(&self, q: &Vector, v: &Vector) -> Result<ModalSample, LaError> {
        let shapes: Vec<&Vector> = self.mass_shapes.iter().collect();
        let at_rest = self.q_static.mdot(&shapes)?;
        let eta = q.mdot(&shapes)?;
        let eta_dot = v.mdot(&shapes)?;
        let mut mv = v.duplicate()?;
        self.mass.mult(v, &mut mv)?;
        Ok(ModalSample {
            eta: eta.iter().zip(&at_rest).map(|(e, r)| e - r).collect(),
            eta_dot,
            kinetic: 0.5 * v.dot(&mv)?,
        })
    }
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

/// The modal energies from the samples taken at `times`; `period`: of the run's dominant
/// vibration (s), for the oscillation window.
pub fn modal_energy(
    times: &[f64],
    samples: &[ModalSample],
    omega2: &[f64],
    settings: &ModalEnergySettings,
    period: f64,
) -> ModalEnergy {
    let modes = omega2.len();
    let n = samples.len();
    let mut energy = vec![Vec::with_capacity(n); modes];
    let (mut kinetic, mut kinetic_in_basis) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for s in samples {
        let mut basis_kinetic = 0.0;
        for k in 0..modes {
            let e = s.eta[k];
            energy[k].push(0.5 * (s.eta_dot[k].powi(2) + omega2[k] * e * e));
            basis_kinetic += 0.5 * s.eta_dot[k].powi(2);
        }
        kinetic.push(s.kinetic);
        kinetic_in_basis.push(basis_kinetic);
    }
    let times = times[..n].to_vec();
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
    ModalEnergy {
        times,
        energy,
        kinetic,
        kinetic_in_basis,
        at,
        window,
        ranked,
    }
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
