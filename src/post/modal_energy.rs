//! Modal sensors along a run (DESIGN.md §2b; the paper's fig. 6 right): for every real mode
//! k of the basis, the modal coordinate eta_k(t) = phi_k^T M (q(t) - q_static) and its energy
//! E_k = (etadot_k^2 + omega_k^2 eta_k^2) / 2 at every stored state; the modes that hold the
//! most energy before a chosen time, their share and how much it oscillates over the last
//! cycles. The transient takes the samples as it runs (its stored states, a block of them at
//! a time, before they are written): a restart may recompute a reduction basis rotated, which
//! the stored states' coordinates are on, but not the modes' own coordinates.
//! On a reduced model phi_k is the mode's exact reduced representation (the modes lie in the
//! reduction's span) and M the reduced mass, so eta_k is the same number as on the full model.

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

use super::states::nearest;
use crate::la::{LaError, Petsc, SparseMatrix, Vector};

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
/// and omega_k^2. The transient takes a sample at every stored state, in blocks: the shapes
/// are kept as one dense block of this rank's rows, so a block of states reads them once (one
/// GEMM) instead of three times per state (at 600k, 250 shapes of 35,237 unknowns are 70 MB).
pub struct ModalSensors<'a, 'p> {
    /// This rank's rows of M x_k, column-major: `rows` x `count`.
    shapes: Vec<f64>,
    rows: usize,
    count: usize,
    /// (M x_k)' q_static, over all ranks.
    at_rest: Vec<f64>,
    pub omega2: &'a [f64],
    mass: &'a SparseMatrix<'p>,
    petsc: &'p Petsc<'p>,
}

pub use crate::time::transient::ModalSample;

impl<'a, 'p> ModalSensors<'a, 'p> {
    /// `mass_shapes`: M x_k of the modes, in the layout of the states to be sampled.
    ///
    /// # Collective
    pub fn new(
        petsc: &'p Petsc<'p>,
        mass_shapes: &[Vector<'p>],
        omega2: &'a [f64],
        mass: &'a SparseMatrix<'p>,
        q_static: &Vector<'p>,
    ) -> Result<Self, LaError> {
        let shapes: Vec<&Vector> = mass_shapes.iter().collect();
        let at_rest = q_static.mdot(&shapes)?;
        let rows = q_static.ownership().len();
        let mut block = Vec::with_capacity(rows * shapes.len());
        for shape in &shapes {
            block.extend_from_slice(&shape.local()?);
        }
        Ok(Self {
            shapes: block,
            rows,
            count: shapes.len(),
            at_rest,
            omega2,
            mass,
            petsc,
        })
    }

    /// The number of modes sampled.
    pub fn count(&self) -> usize {
        self.count
    }

    /// eta_k = (M x_k)'(q - q_static), etadot_k = (M x_k)'v, and v'Mv/2 of
    /// `states` states given by this rank's rows: `displacements` and
    /// `velocities` hold one state's rows after the other (as the recorder buffers them).
    ///
    /// # Collective
    pub fn sample_block(
        &self,
        displacements: &[f64],
        velocities: &[f64],
        states: usize,
    ) -> Result<Vec<ModalSample>, LaError> {
        let (rows, count) = (self.rows, self.count);
        assert!(
            displacements.len() == rows * states && velocities.len() == rows * states,
            "sample_block: {states} states of {rows} rows"
        );
        // [S'Q | S'V | this rank's v'Mv], summed over the ranks at once.
        let mut sums = crate::la::lapack::gemm_tn(rows, count, states, &self.shapes, displacements);
        sums.extend(crate::la::lapack::gemm_tn(
            rows,
            count,
            states,
            &self.shapes,
            velocities,
        ));
        sums.extend(self.mass.local_quadratic_forms(velocities, states)?);
        crate::parallel::sum_in_place(self.petsc.world(), &mut sums);
        let (eta, rest) = sums.split_at(count * states);
        let (eta_dot, vmv) = rest.split_at(count * states);
        Ok((0..states)
            .map(|j| ModalSample {
                eta: eta[j * count..(j + 1) * count]
                    .iter()
                    .zip(&self.at_rest)
                    .map(|(e, r)| e - r)
                    .collect(),
                eta_dot: eta_dot[j * count..(j + 1) * count].to_vec(),
                kinetic: 0.5 * vmv[j],
            })
            .collect())
    }
}

impl<'p> crate::time::transient::StateSampler<'p> for ModalSensors<'_, 'p> {
    fn count(&self) -> usize {
        ModalSensors::count(self)
    }

    fn sample_block(
        &self,
        displacements: &[f64],
        velocities: &[f64],
        states: usize,
    ) -> Result<Vec<ModalSample>, LaError> {
        ModalSensors::sample_block(self, displacements, velocities, states)
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
    /// Its amplitude's growth rate over `ModalEnergy::growth_window` (1/s; see `growth`).
    pub growth_rate: f64,
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
    /// Per mode, its amplitude's growth rate (1/s) over `growth_window`, the last fifth of the
    /// stored states up to the ranking time: half the least-squares slope of ln E_k (the
    /// amplitude's rate, what a complex mode's Re(s) predicts). The ranking window's few
    /// cycles are too short for it: a rate of 60 1/s moves ln E by 0.2 over 2 ms, while E_k
    /// oscillates by tens of percent within a cycle.
    pub growth: Vec<f64>,
    pub growth_window: (f64, f64),
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
    let first = times.first().copied().unwrap_or(0.0);
    let growth_window = (at - 0.2 * (at - first), at);
    let in_growth: Vec<usize> = (0..n)
        .filter(|&i| times[i] >= growth_window.0 && times[i] <= growth_window.1)
        .collect();
    let growth: Vec<f64> = energy
        .iter()
        .map(|e| amplitude_growth_rate(&times, e, &in_growth))
        .collect();
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
            growth_rate: growth[k],
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
        growth,
        growth_window,
    }
}

/// Half the least-squares slope of ln `energy` against `times` over the indices `window`
/// (an energy's rate is twice its amplitude's): the amplitude's growth rate, 1/s. Zero
/// energies (a mode the motion does not reach) are left out; NaN below 3 values or when any
/// value is not finite.
fn amplitude_growth_rate(times: &[f64], energy: &[f64], window: &[usize]) -> f64 {
    if window.iter().any(|&i| !energy[i].is_finite()) {
        return f64::NAN;
    }
    let points: Vec<(f64, f64)> = window
        .iter()
        .filter(|&&i| energy[i] > 0.0)
        .map(|&i| (times[i], energy[i].ln()))
        .collect();
    if points.len() < 3 {
        return f64::NAN;
    }
    let m = points.len() as f64;
    let (tm, ym) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / m, b + p.1 / m));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + (p.0 - tm) * (p.1 - ym), b + (p.0 - tm) * (p.0 - tm))
    });
    0.5 * sxy / sxx
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
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn oscillation_is_half_peak_to_peak_over_the_mean() {
        let values = [1.0, 0.9, 1.1, 1.0, 5.0];
        assert!((oscillation(&values, &[0, 1, 2, 3]) - 0.1).abs() < 1e-15);
        assert!(oscillation(&values, &[0, 1]).is_nan());
        assert_eq!(nearest(&[0.0, 1.0, 2.0], 1.4), 1);
    }

    /// E(t) = exp(2 sigma t) exp(g(t)), g periodic (period P, |g| <= G): the least-squares
    /// slope of ln E over N whole periods (T = N P) is 2 sigma plus 12/T^3 times the integral
    /// of (t - T/2) g, which over whole periods is N times that of (tau - P/2) g over one,
    /// at most N G P^2 / 4 in magnitude: the rate is sigma within 3 G / (2 N^2 P).
    #[test]
    fn growth_rate_of_a_modulated_exponential_within_the_derived_bound() {
        let (sigma, period, amplitude): (f64, f64, f64) = (83.0, 1.0 / 905.0, 0.5);
        let g_max = (1.0 + amplitude).ln();
        let cycles = 20.0;
        let samples = 4000;
        let dt = cycles * period / samples as f64;
        let times: Vec<f64> = (0..samples).map(|i| 0.05 + i as f64 * dt).collect();
        let energy: Vec<f64> = times
            .iter()
            .map(|&t| {
                let phase = 2.0 * std::f64::consts::PI * t / period;
                1e-3 * (2.0 * sigma * t).exp() * (1.0 + amplitude * phase.sin())
            })
            .collect();
        let all: Vec<usize> = (0..samples).collect();
        let rate = amplitude_growth_rate(&times, &energy, &all);
        let bound = 1.5 * g_max / (cycles * cycles * period);
        assert!(
            (rate - sigma).abs() <= bound,
            "rate {rate} vs {sigma}, bound {bound}"
        );
        // A decaying mode, a NaN, too few values.
        let decaying: Vec<f64> = times.iter().map(|&t| (-2.0 * 40.0 * t).exp()).collect();
        assert!((amplitude_growth_rate(&times, &decaying, &all) + 40.0).abs() < 1e-9);
        let mut broken = energy.clone();
        broken[17] = f64::NAN;
        assert!(amplitude_growth_rate(&times, &broken, &all).is_nan());
        assert!(amplitude_growth_rate(&times, &energy, &all[..2]).is_nan());
    }
}
