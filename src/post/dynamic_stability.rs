//! Dynamic stability along a trajectory (DESIGN.md §2b; the paper's figs. 9, 10): linearize
//! the contact at stored states (q, qdot) of the run: normal stiffness of the local gap,
//! sticking or sliding friction with the direction and slope of the local sliding velocity,
//! friction damping; project on the nominal real modes (O(points x modes^2), no
//! factorization of size n), solve the dense complex modes and track the nominal complex modes
//! through the states by MAC with continuity. A point that separated adds no stiffness, one
//! that sticks adds its stick tangent: the state decides, as in the time integration.

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

use super::states::{ContactAt, StatesError, StoredStates};
use crate::contact::ContactState;
use crate::eigen::complex_modes::{
    damping_ratio, frequency_hz, projected_coordinates, Complex, DenseEigenpair,
};
use crate::eigen::stability::ProjectedStability;
use crate::eigen::tracking::track;
use crate::la::LaError;

/// `[post.dynamic_stability]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicStabilitySettings {
    /// Periods of the run's dominant vibration, ending at the last cycle found.
    #[serde(default = "default_periods")]
    pub periods: usize,
    /// Stored states wanted per period (fewer stored: all of them, and the summary says so).
    #[serde(default = "default_per_period")]
    pub per_period: usize,
    /// Explicit times (s) instead (the nearest stored states).
    #[serde(default)]
    pub times: Option<Vec<f64>>,
}

fn default_periods() -> usize {
    2
}
fn default_per_period() -> usize {
    40
}

impl Default for DynamicStabilitySettings {
    fn default() -> Self {
        toml::from_str("").expect("the defaults parse")
    }
}

impl DynamicStabilitySettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.periods == 0 || self.per_period < 2 {
            return Err(InvalidSetting::new(
                "post.dynamic_stability",
                format!(
                    ": periods = {} and per_period = {}: need at least 1 and 2",
                    self.periods, self.per_period
                ),
            ));
        }
        if let Some(t) = &self.times {
            if t.is_empty() || t.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                return Err(InvalidSetting::new(
                    "post.dynamic_stability.times",
                    ": give times (s) >= 0, at least one",
                ));
            }
        }
        Ok(())
    }
}

/// One nominal complex mode followed along the states.
#[derive(Debug, Clone)]
pub struct TrackedMode {
    /// Its name among the nominal projected complex modes (C1 = lowest frequency).
    pub name: String,
    /// At the static state, then at every linearization time (NaN once the track is lost).
    pub eigenvalue: Vec<(f64, f64)>,
    /// MAC with the track's mode at the previous point (1 at the static state).
    pub mac: Vec<f64>,
    /// Fraction of the linearization times at which it is unstable, its mean damping ratio
    /// over them, and the correlation of its damping ratio with the braking torque.
    pub unstable_fraction: f64,
    pub mean_damping_ratio: f64,
    pub torque_correlation: f64,
    /// Its mean Re(s) over the later points (1/s): the amplitude's growth rate the
    /// linearizations predict on average, to compare with the run's modal energies.
    pub mean_re_s: f64,
    /// The real mode its static-state coordinates weigh most (index into the basis).
    pub dominant_real_mode: Option<usize>,
    /// Its modal coordinates (on the real modes) where its frequency is highest and lowest
    /// along the run: (point index into `eigenvalue`, coordinates).
    pub extremes: [(usize, Vec<Complex>); 2],
}

impl TrackedMode {
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| frequency_hz(s)).collect()
    }
    pub fn damping_ratios(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| damping_ratio(s)).collect()
    }
    /// Unstable at the static state.
    pub fn unstable_at_rest(&self, margin: f64) -> bool {
        damping_ratio(self.eigenvalue[0]) < -margin
    }

    /// What the summary and the plots show: unstable at rest, or unstable on average over the
    /// states (it feeds the vibration there); the others only flicker unstable.
    pub fn headline(&self, margin: f64) -> bool {
        self.unstable_at_rest(margin) || self.mean_damping_ratio < -margin
    }
}

#[derive(Debug, Clone)]
pub struct DynamicStability {
    /// The linearization times (stored states), and the braking torque there.
    pub times: Vec<f64>,
    pub torque: Vec<f64>,
    /// The modes unstable at the static state or at any time, in the nominal order.
    pub tracks: Vec<TrackedMode>,
    /// Tracks of nominal modes followed (all of them) and how many were lost on the way.
    pub followed: usize,
    pub lost: usize,
    pub seconds_per_point: f64,
}

/// What the linearizations need: the contact at the stored states, the nominal state and
/// its projection.
pub struct Linearization<'a, 'p> {
    pub at: ContactAt<'a, 'p>,
    pub nominal: &'a ContactState,
    pub stability: &'a ProjectedStability,
    pub margin: f64,
}

/// Linearizes at the stored states `indices` and tracks the nominal complex modes; `torque`:
/// the braking torque at those states.
///
/// # Collective
pub fn dynamic_stability(
    states: &StoredStates,
    indices: &[usize],
    torque: Vec<f64>,
    lin: &Linearization,
) -> Result<DynamicStability, StatesError> {
    let (petsc, contact) = (lin.at.petsc, lin.at.contact);
    let (kp, cp) = lin
        .stability
        .operators_at(petsc.world(), contact, lin.nominal);
    let size = lin.stability.projection.size;
    let nominal = projected_coordinates(size, &kp, &cp).map_err(LaError::from)?;
    let mut points = vec![nominal];
    let start = std::time::Instant::now();
    for &i in indices {
        let state = lin.at.state(states, i)?;
        let (kp, cp) = lin.stability.operators_at(petsc.world(), contact, &state);
        points.push(projected_coordinates(size, &kp, &cp).map_err(LaError::from)?);
    }
    let seconds_per_point = start.elapsed().as_secs_f64() / indices.len().max(1) as f64;
    let (tracks, followed, lost) = tracked_modes(&points, &torque, lin.margin);
    Ok(DynamicStability {
        times: indices.iter().map(|&i| states.times[i]).collect(),
        torque,
        tracks,
        followed,
        lost,
        seconds_per_point,
    })
}

/// The nominal modes (`points[0]`: the static state's projected complex modes) tracked by MAC
/// through the later points (the tangents along the run), those unstable at the static state
/// or at any point kept, with their statistics over the later points; and how many tracks
/// were followed and lost. `torque`: at the later points.
pub fn tracked_modes(
    points: &[Vec<DenseEigenpair>],
    torque: &[f64],
    margin: f64,
) -> (Vec<TrackedMode>, usize, usize) {
    let tracked = track(points);
    let followed = tracked.tracks.len();
    let lost = tracked
        .tracks
        .iter()
        .filter(|t| t.iter().any(Option::is_none))
        .count();
    let unstable = |s: (f64, f64)| damping_ratio(s) < -margin;
    let mut tracks = Vec::new();
    for (k, t) in tracked.tracks.iter().enumerate() {
        let nan = (f64::NAN, f64::NAN);
        let eigenvalue: Vec<(f64, f64)> = t.iter().map(|p| p.map_or(nan, |p| p.0)).collect();
        if !eigenvalue.iter().any(|&s| unstable(s)) {
            continue;
        }
        let along = &eigenvalue[1..];
        let zeta: Vec<f64> = along.iter().map(|&s| damping_ratio(s)).collect();
        let extremes = [true, false].map(|highest| {
            let i = extreme_point(&eigenvalue, highest);
            let y = points[i]
                .iter()
                .find(|(s, _)| *s == eigenvalue[i])
                .map_or_else(Vec::new, |(_, y)| y.clone());
            (i, y)
        });
        let dominant_real_mode = points[0]
            .iter()
            .find(|(s, _)| *s == eigenvalue[0])
            .and_then(|(_, y)| crate::eigen::complex_modes::dominant_real_mode(y));
        tracks.push(TrackedMode {
            name: format!("C{}", k + 1),
            mean_re_s: along.iter().map(|s| s.0).sum::<f64>() / along.len().max(1) as f64,
            dominant_real_mode,
            mac: t.iter().map(|p| p.map_or(f64::NAN, |p| p.1)).collect(),
            unstable_fraction: along.iter().filter(|&&s| unstable(s)).count() as f64
                / along.len().max(1) as f64,
            mean_damping_ratio: zeta.iter().sum::<f64>() / zeta.len().max(1) as f64,
            torque_correlation: correlation(&zeta, torque),
            extremes,
            eigenvalue,
        });
    }
    (tracks, followed, lost)
}

/// The point (after the static state, 0 when there is none) where the frequency is highest
/// (or lowest).
fn extreme_point(eigenvalue: &[(f64, f64)], highest: bool) -> usize {
    (1..eigenvalue.len())
        .filter(|&i| eigenvalue[i].1.is_finite())
        .max_by(|&a, &b| {
            let order = eigenvalue[a].1.total_cmp(&eigenvalue[b].1);
            if highest {
                order
            } else {
                order.reverse()
            }
        })
        .unwrap_or(0)
}

/// Pearson correlation of two series (NaN when either is constant or holds NaN).
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    let mean = |x: &[f64]| x.iter().take(n as usize).sum::<f64>() / n;
    let (ma, mb) = (mean(a), mean(b));
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += (x - ma) * (y - mb);
        aa += (x - ma) * (x - ma);
        bb += (y - mb) * (y - mb);
    }
    ab / (aa * bb).sqrt()
}

/// The stored states of the last `periods` periods (ending at the last cycle start found,
/// else at the last state), or those nearest to the explicit `times`.
pub fn choose_states(
    states: &StoredStates,
    settings: &DynamicStabilitySettings,
    cycle_starts: &[f64],
    period: f64,
) -> Vec<usize> {
    if let Some(times) = &settings.times {
        let mut chosen: Vec<usize> = times.iter().map(|&t| states.nearest(t)).collect();
        chosen.dedup();
        return chosen;
    }
    let end = states.window_end(cycle_starts);
    let from = end - settings.periods as f64 * period;
    // Half-open window [from, end): exactly `periods` periods, each phase once.
    states
        .between(from, end)
        .into_iter()
        .filter(|&i| states.times[i] < end - 1e-9 * period)
        .collect()
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn correlation_of_affine_series_is_one_and_nan_for_constants() {
        let a = [1.0, 2.0, 4.0, 3.0];
        let b: Vec<f64> = a.iter().map(|x| 3.0 - 2.0 * x).collect();
        assert!((correlation(&a, &b) + 1.0).abs() < 1e-14);
        assert!(correlation(&a, &[1.0; 4]).is_nan());
    }
}
