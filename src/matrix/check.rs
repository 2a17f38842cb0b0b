//! The reduced statics' error: at the points a matrix also solved on the full model
//! (`full_checks`), the superelement's static state and complex modes against the full ones.

use super::point::{PointMode, PointResult};
use crate::measure::nan_max;

/// The differences at the checked points (largest over them).
#[derive(Debug, Clone, PartialEq)]
pub struct ReducedError {
    /// Points checked, and of them those whose full solve failed.
    pub checked: usize,
    pub failed: usize,
    /// |T q_r - q| / |q| of the static displacement.
    pub displacement: f64,
    /// Relative difference of the braking torque and of the normal force.
    pub torque: f64,
    pub normal_force: f64,
    /// |largest Re(s) reduced - full| (1/s), and the largest |Re(s)| of the full points as
    /// its scale.
    pub largest_real_part: f64,
    pub real_part_scale: f64,
    /// Relative frequency difference of each mode unstable in either state to the nearest
    /// eigenvalue of the other.
    pub frequency: f64,
    /// Checked points whose unstable modes (by label) are the same in both states.
    pub same_unstable: usize,
}

/// The reduced route's error over `points` (None when none was checked). `margin`: the damping
/// ratio below -margin that counts as unstable.
pub fn reduced_error(points: &[PointResult], margin: f64) -> Option<ReducedError> {
    let checks: Vec<_> = points
        .iter()
        .filter_map(|p| p.solved())
        .filter_map(|s| s.full_check.as_ref().map(|c| (s, c)))
        .collect();
    if checks.is_empty() {
        return None;
    }
    let relative = |a: f64, b: f64| (a - b).abs() / b.abs().max(f64::MIN_POSITIVE);
    let unstable = |modes: &[PointMode]| -> Vec<Option<usize>> {
        let mut labels: Vec<_> = modes
            .iter()
            .filter(|m| m.damping_ratio() < -margin)
            .map(|m| m.label)
            .collect();
        labels.sort();
        labels
    };
    let mut e = ReducedError {
        checked: checks.len(),
        failed: 0,
        displacement: 0.0,
        torque: 0.0,
        normal_force: 0.0,
        largest_real_part: 0.0,
        real_part_scale: 0.0,
        frequency: 0.0,
        same_unstable: 0,
    };
    for (reduced, full) in checks {
        if full.failure.is_some() {
            e.failed += 1;
            continue;
        }
        e.displacement = nan_max(e.displacement, full.displacement_error);
        e.torque = nan_max(
            e.torque,
            relative(reduced.braking_torque, full.braking_torque),
        );
        e.normal_force = nan_max(
            e.normal_force,
            relative(reduced.normal_force, full.normal_force),
        );
        let re_full = full.largest_real_part();
        let re_reduced = crate::measure::greatest(reduced.modes.iter().map(|m| m.re));
        e.largest_real_part = nan_max(e.largest_real_part, (re_reduced - re_full).abs());
        e.real_part_scale = nan_max(e.real_part_scale, re_full.abs());
        if unstable(&reduced.modes) == unstable(&full.modes) {
            e.same_unstable += 1;
        }
        // Each mode unstable in one state against the nearest eigenvalue of the other: the
        // nominal labels of two close modes with low MACs may swap between the states.
        for (modes, other) in [(&reduced.modes, &full.modes), (&full.modes, &reduced.modes)] {
            for m in modes.iter().filter(|m| m.damping_ratio() < -margin) {
                let distance = |n: &PointMode| (n.re - m.re).hypot(n.im - m.im);
                let nearest = other
                    .iter()
                    .min_by(|a, b| distance(a).total_cmp(&distance(b)));
                e.frequency = nan_max(
                    e.frequency,
                    nearest.map_or(f64::INFINITY, |n| {
                        relative(n.frequency_hz(), m.frequency_hz())
                    }),
                );
            }
        }
    }
    Some(e)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::matrix::point::{FullCheck, Outcome, SolvedPoint};

    fn mode(label: usize, re: f64, hz: f64) -> PointMode {
        PointMode {
            label: Some(label),
            re,
            im: 2.0 * std::f64::consts::PI * hz,
            mac: 1.0,
        }
    }

    fn point(modes: Vec<PointMode>, torque: f64, check: Option<FullCheck>) -> PointResult {
        PointResult {
            index: 0,
            values: vec![1.0],
            outcome: Outcome::Solved(SolvedPoint {
                modes,
                braking_torque: torque,
                normal_force: 1000.0,
                newton_iterations: 1,
                factorizations: 0,
                cold_restart: false,
                seconds_statics: 0.0,
                seconds_factorizing: 0.0,
                seconds_modes: 0.0,
                full_check: check,
                saturation: Vec::new(),
                factor_solves: 0,
                seconds_solving: 0.0,
            }),
        }
    }

    fn check(modes: Vec<PointMode>, torque: f64, displacement_error: f64) -> FullCheck {
        FullCheck {
            displacement_error,
            braking_torque: torque,
            normal_force: 1000.0,
            modes,
            seconds: 0.0,
            failure: None,
        }
    }

    #[test]
    fn differences_are_the_largest_over_the_checked_points() {
        let points = vec![
            point(
                vec![mode(1, -5.0, 500.0), mode(2, 100.0, 2000.0)],
                101.0,
                Some(check(
                    vec![mode(1, -5.0, 500.0), mode(2, 90.0, 2010.0)],
                    100.0,
                    1e-3,
                )),
            ),
            point(vec![mode(2, 50.0, 2000.0)], 50.0, None),
            point(
                vec![mode(1, 3.0, 500.0), mode(2, 40.0, 2000.0)],
                200.0,
                Some(check(
                    vec![mode(1, -1.0, 505.0), mode(2, 40.0, 2000.0)],
                    200.0,
                    2e-3,
                )),
            ),
        ];
        let e = reduced_error(&points, 1e-6).unwrap();
        assert_eq!((e.checked, e.failed, e.same_unstable), (2, 0, 1));
        assert_eq!(e.displacement, 2e-3);
        assert!((e.torque - 0.01).abs() < 1e-12);
        assert!((e.largest_real_part - 10.0).abs() < 1e-12);
        assert!((e.real_part_scale - 90.0).abs() < 1e-12);
        // C1 is unstable in the reduced state of the second check: its 500 Hz against the
        // full state's nearest eigenvalue, C1 at 505 Hz.
        assert!((e.frequency - 5.0 / 500.0).abs() < 1e-12);
        assert!(reduced_error(&points[1..2], 1e-6).is_none());
    }

    #[test]
    fn a_nan_displacement_error_is_not_hidden() {
        let p = point(
            vec![mode(1, 1.0, 500.0)],
            1.0,
            Some(check(vec![mode(1, 1.0, 500.0)], 1.0, f64::NAN)),
        );
        assert!(reduced_error(&[p], 1e-6).unwrap().displacement.is_nan());
    }
}
