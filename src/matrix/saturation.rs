//! A noise-matrix point's most unstable modes followed along their pseudo trajectories
//! (DESIGN.md §2b) to the saturation amplitude alpha_sat, and their A-weighted sound power
//! level there (§2c): how loud the point would squeal, not only whether it does.

use std::time::Instant;

use crate::eigen::complex_modes::{damping_ratio, DenseEigenpair};
use crate::la::LaError;
use crate::la::{Petsc, Vector};
use crate::post::loudness::LoudnessSettings;
use crate::post::pseudo_contact::ContactPseudoSystem;
use crate::post::pseudo_trajectory::{pseudo_trajectory, PseudoTrajectorySettings};
use crate::post::radiator::{mode_loudness, Radiator};

use super::point::{ModeSaturation, PointMode};

/// What the studies need besides the point.
pub struct SaturationInputs<'a, 'p> {
    /// The most unstable modes per point to follow (`matrix.saturation_modes`).
    pub modes: usize,
    pub trajectory: PseudoTrajectorySettings,
    /// The radiating surfaces and the air, with [post.loudness].
    pub loudness: Option<(&'a Radiator<'p>, &'a LoudnessSettings)>,
}

/// The point's modes that are followed: unstable beyond `margin`, the largest Re(s) first,
/// at most `count`. `modes` pairs each reported mode with its index in the point's pairs.
pub fn chosen(modes: &[(usize, PointMode)], margin: f64, count: usize) -> Vec<usize> {
    let mut unstable: Vec<usize> = (0..modes.len())
        .filter(|&k| damping_ratio(modes[k].1.s()) < -margin)
        .collect();
    unstable.sort_by(|&a, &b| modes[b].1.re.total_cmp(&modes[a].1.re));
    unstable.truncate(count);
    unstable
}

/// The studies of the chosen modes on `system` (the point's contact model and state on the
/// nominal basis), `pairs` the point's complex modes with coordinates. A study that fails is
/// recorded with its reason; the point stays solved.
///
/// # Collective
pub fn study<'p>(
    petsc: &'p Petsc,
    inputs: &SaturationInputs<'_, 'p>,
    system: &ContactPseudoSystem,
    shapes: &[Vector<'p>],
    (pairs, modes): (&[DenseEigenpair], &[(usize, PointMode)]),
    margin: f64,
) -> Result<Vec<ModeSaturation>, LaError> {
    let mut out = Vec::new();
    for k in chosen(modes, margin, inputs.modes) {
        let (index, mode) = &modes[k];
        let clock = Instant::now();
        let name = match mode.label {
            Some(l) => format!("C{l}"),
            None => format!("the unpaired mode at {:.1} Hz", mode.frequency_hz()),
        };
        let mut result = ModeSaturation {
            label: mode.label,
            frequency_hz: mode.frequency_hz(),
            re: mode.re,
            alpha_crit: None,
            alpha_sat: None,
            level_db_a: None,
            seconds: 0.0,
            failure: None,
        };
        match pseudo_trajectory(system, &name, pairs, *index, &inputs.trajectory, margin) {
            Ok(t) => {
                result.alpha_crit = t.alpha_crit.alpha();
                result.alpha_sat = t.alpha_sat.alpha();
                if let (Some((radiator, air)), Some(_)) = (inputs.loudness, result.alpha_sat) {
                    let shape = (&name[..], pairs[*index].0, &t.psi[..]);
                    let level =
                        mode_loudness(petsc, radiator, air, shapes, shape, result.alpha_sat)?;
                    result.level_db_a = Some(level.level_a());
                }
            }
            Err(e) => result.failure = Some(format!("pseudo trajectory of {name}: {e}")),
        }
        result.seconds = clock.elapsed().as_secs_f64();
        out.push(result);
    }
    Ok(out)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn mode(re: f64, hz: f64) -> PointMode {
        PointMode {
            label: None,
            re,
            im: 2.0 * std::f64::consts::PI * hz,
            mac: 0.0,
        }
    }

    /// Unstable beyond the margin only, the largest Re(s) first, at most `count`.
    #[test]
    fn the_chosen_modes_are_the_most_unstable() {
        let modes: Vec<(usize, PointMode)> = [
            mode(-5.0, 1000.0),
            mode(40.0, 2000.0),
            mode(1e-9, 3000.0),
            mode(90.0, 4000.0),
            mode(10.0, 5000.0),
        ]
        .into_iter()
        .enumerate()
        .collect();
        assert_eq!(chosen(&modes, 1e-6, 2), vec![3, 1]);
        assert_eq!(chosen(&modes, 1e-6, 10), vec![3, 1, 4]);
        assert!(chosen(&modes, 1e-6, 0).is_empty());
    }
}
