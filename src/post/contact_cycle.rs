//! The contact state over one period of the cycle (DESIGN.md §2b; the paper's figs. 7, 8):
//! contact pressure and stiffness of every point at evenly spaced phases of the last cycle
//! found, per pad the largest stiffness at each phase and its variation over the cycle (the
//! paper: 66 % under the piston), and the fractions of the pad's points open, sticking and
//! sliding over the phases.

use crate::invalid::InvalidSetting;
use crate::measure::nan_max;
use serde::{Deserialize, Serialize};

use super::states::{ContactAt, StatesError, StoredStates};

/// `[post.contact_cycle]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactCycleSettings {
    /// Phases of the period (evenly spaced; the nearest stored states).
    #[serde(default = "default_phases")]
    pub phases: usize,
}

fn default_phases() -> usize {
    8
}

impl Default for ContactCycleSettings {
    fn default() -> Self {
        toml::from_str("").expect("the defaults parse")
    }
}

impl ContactCycleSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.phases < 2 {
            return Err(InvalidSetting::new(
                "post.contact_cycle.phases",
                format!(" = {}: need at least 2", self.phases),
            ));
        }
        Ok(())
    }
}

/// One pad (a sliding interface) over the cycle.
#[derive(Debug, Clone)]
pub struct PadCycle {
    pub interface: usize,
    pub name: String,
    /// The largest contact stiffness of the pad's points at each phase (Pa/m).
    pub largest_stiffness: Vec<f64>,
    /// (max - min) / max of the largest stiffness over the phases.
    pub variation: f64,
    /// The phases at which the largest stiffness is highest and lowest.
    pub extreme_phases: (usize, usize),
    /// Fractions of (point, phase) pairs open, sticking, sliding.
    pub fractions: [f64; 3],
}

#[derive(Debug, Clone)]
pub struct ContactCycle {
    /// The phases' times (stored states) and the period they cover.
    pub times: Vec<f64>,
    pub period: f64,
    /// Per phase, every contact point (point-id order): pressure (Pa), contact stiffness
    /// (Pa/m), status (0 open, 1 stick, 2 slip).
    pub pressure: Vec<Vec<f64>>,
    pub stiffness: Vec<Vec<f64>>,
    pub status: Vec<Vec<f64>>,
    pub pads: Vec<PadCycle>,
}

impl ContactCycle {
    /// Per point: min, max over the phases and (max - min) / max (0 where max is 0).
    pub fn spread(field: &[Vec<f64>]) -> [Vec<f64>; 3] {
        let points = field.first().map_or(0, Vec::len);
        let mut out = [
            vec![f64::INFINITY; points],
            vec![0.0; points],
            vec![0.0; points],
        ];
        for phase in field {
            for (j, &v) in phase.iter().enumerate() {
                out[0][j] = out[0][j].min(v);
                out[1][j] = out[1][j].max(v);
            }
        }
        for j in 0..points {
            out[2][j] = if out[1][j] > 0.0 {
                (out[1][j] - out[0][j]) / out[1][j]
            } else {
                0.0
            };
        }
        out
    }
}

/// The stored states at `phases` evenly spaced times of one period: the last full cycle
/// found (between the last two cycle starts), else the last period of the run.
pub fn phase_states(
    states: &StoredStates,
    phases: usize,
    cycle_starts: &[f64],
    period: f64,
) -> (Vec<usize>, f64) {
    let last = states.times.last().copied().unwrap_or(0.0);
    let (t0, t1) = match cycle_starts {
        [.., a, b] if *b <= last => (*a, *b),
        _ => (last - period, last),
    };
    let mut chosen: Vec<usize> = (0..phases)
        .map(|k| states.nearest(t0 + (t1 - t0) * k as f64 / phases as f64))
        .collect();
    chosen.dedup();
    (chosen, t1 - t0)
}

/// The contact state at the phases' stored states; `pads`: the sliding interfaces (index,
/// name).
///
/// # Collective
pub fn contact_cycle(
    states: &StoredStates,
    at: &ContactAt,
    indices: &[usize],
    period: f64,
    pads: &[(usize, String)],
) -> Result<ContactCycle, StatesError> {
    let contact = at.contact;
    let (mut pressure, mut stiffness, mut status) = (Vec::new(), Vec::new(), Vec::new());
    for &i in indices {
        let state = at.state(states, i)?;
        let r = &state.response;
        let local = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..r.len()).map(f).collect() };
        pressure.push(contact.gather(at.petsc, &local(&|k| r[k].pressure))?);
        stiffness.push(contact.gather(at.petsc, &local(&|k| r[k].stiffness))?);
        status.push(contact.gather(at.petsc, &local(&|k| r[k].status as u8 as f64))?);
    }
    let pads = pads
        .iter()
        .map(|(index, name)| {
            let mine: Vec<usize> = (0..contact.points().len())
                .filter(|&j| contact.points()[j].interface == *index)
                .collect();
            let largest: Vec<f64> = stiffness
                .iter()
                .map(|phase| mine.iter().map(|&j| phase[j]).fold(0.0, nan_max))
                .collect();
            let arg = |better: fn(f64, f64) -> bool| {
                (0..largest.len())
                    .fold(0, |b, k| if better(largest[k], largest[b]) { k } else { b })
            };
            let (hi, lo) = (arg(|a, b| a > b), arg(|a, b| a < b));
            let mut fractions = [0.0; 3];
            for phase in &status {
                for &j in &mine {
                    fractions[(phase[j] as usize).min(2)] += 1.0;
                }
            }
            let pairs = (mine.len() * status.len()).max(1) as f64;
            PadCycle {
                interface: *index,
                name: name.clone(),
                variation: (largest[hi] - largest[lo]) / largest[hi],
                extreme_phases: (hi, lo),
                largest_stiffness: largest,
                fractions: fractions.map(|f| f / pairs),
            }
        })
        .collect();
    Ok(ContactCycle {
        times: indices.iter().map(|&i| states.times[i]).collect(),
        period,
        pressure,
        stiffness,
        status,
        pads,
    })
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn spread_is_min_max_and_relative_range() {
        let field = vec![vec![1.0, 0.0], vec![4.0, 0.0], vec![2.0, 0.0]];
        let [lo, hi, var] = ContactCycle::spread(&field);
        assert_eq!((lo[0], hi[0], var[0]), (1.0, 4.0, 0.75));
        assert_eq!((lo[1], hi[1], var[1]), (0.0, 0.0, 0.0));
    }
}
