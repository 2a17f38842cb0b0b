//! The operating points of a matrix, the slice of them a run computes, and the order it
//! computes them in (each point warm-started from the nearest finished one).

use super::{MatrixSettings, Sampling};

/// Every point's parameter values (in the order of `MatrixSettings::axis_list`).
pub fn points(settings: &MatrixSettings) -> Vec<Vec<f64>> {
    let axes: Vec<_> = settings.axes.values().collect();
    match settings.sampling {
        Sampling::Grid => {
            let values: Vec<Vec<f64>> = axes.iter().map(|a| a.values()).collect();
            let count: usize = values.iter().map(Vec::len).product();
            // The last axis fastest.
            (0..count)
                .map(|mut i| {
                    let mut p = vec![0.0; values.len()];
                    for (d, v) in values.iter().enumerate().rev() {
                        p[d] = v[i % v.len()];
                        i /= v.len();
                    }
                    p
                })
                .collect()
        }
        Sampling::Sobol => {
            let n = settings.points.unwrap_or(0);
            (0..n)
                .map(|i| {
                    axes.iter()
                        .enumerate()
                        .map(|(d, a)| {
                            let (lo, hi) = a.range();
                            let u = sobol_burley::sample(i as u32, d as u32, settings.seed);
                            lo + (hi - lo) * f64::from(u)
                        })
                        .collect()
                })
                .collect()
        }
    }
}

/// `K/N` of `squeal run --slice`: the K-th of N contiguous blocks of the points (K from 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slice {
    pub index: usize,
    pub count: usize,
}

impl Slice {
    pub const WHOLE: Slice = Slice { index: 1, count: 1 };

    /// The point indices of this slice among `total`.
    pub fn range(self, total: usize) -> std::ops::Range<usize> {
        let start = (self.index - 1) * total / self.count;
        let end = self.index * total / self.count;
        start..end
    }
}

impl Default for Slice {
    fn default() -> Self {
        Slice::WHOLE
    }
}

impl std::str::FromStr for Slice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("--slice {s:?}: expected K/N with 1 <= K <= N, e.g. 3/16");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Slice { index, count })
    }
}

impl std::fmt::Display for Slice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Distance of two points with every axis scaled to its range (so pressure in bar and p0 in Pa
/// weigh alike).
pub fn scaled_distance(a: &[f64], b: &[f64], ranges: &[(f64, f64)]) -> f64 {
    a.iter()
        .zip(b)
        .zip(ranges)
        .map(|((x, y), (lo, hi))| {
            let w = (hi - lo).abs();
            let d = if w > 0.0 { (x - y) / w } else { 0.0 };
            d * d
        })
        .sum::<f64>()
        .sqrt()
}

/// The order to compute `todo` in, each with the point it starts from: greedily the nearest
/// unfinished point to any finished one (`start` is the nominal point, index None), so each
/// static solve starts close to its answer. O(n^2) distances: 1e8 for the largest sample, a
/// second, negligible against the solves.
pub fn warm_order(
    values: &[Vec<f64>],
    todo: &[usize],
    start: &[f64],
    ranges: &[(f64, f64)],
) -> Vec<(usize, Option<usize>)> {
    let mut left: Vec<usize> = todo.to_vec();
    // Per unfinished point: its nearest finished point and the distance.
    let mut nearest: Vec<(f64, Option<usize>)> = left
        .iter()
        .map(|&i| (scaled_distance(&values[i], start, ranges), None))
        .collect();
    let mut order = Vec::with_capacity(left.len());
    while !left.is_empty() {
        let k = (0..left.len())
            .min_by(|&a, &b| {
                nearest[a]
                    .0
                    .total_cmp(&nearest[b].0)
                    .then(left[a].cmp(&left[b]))
            })
            .expect("not empty");
        let (chosen, (_, from)) = (left.swap_remove(k), nearest.swap_remove(k));
        order.push((chosen, from));
        for (j, &i) in left.iter().enumerate() {
            let d = scaled_distance(&values[i], &values[chosen], ranges);
            if d < nearest[j].0 {
                nearest[j] = (d, Some(chosen));
            }
        }
    }
    order
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::super::{Axis, AxisRange, MatrixSettings};
    use super::*;

    fn sobol(points: usize, seed: u32) -> MatrixSettings {
        let mut axes = std::collections::BTreeMap::new();
        let range = |a, b| AxisRange {
            from: Some(a),
            to: Some(b),
            ..Default::default()
        };
        axes.insert(Axis::PressureBar, range(5.0, 40.0));
        axes.insert(Axis::Mu, range(0.3, 0.6));
        axes.insert(Axis::DiscSpeed, range(1.0, 20.0));
        MatrixSettings {
            statics: Default::default(),
            full_checks: None,
            lining_blocks: None,
            saturation_modes: 0,
            parameter_shapes: true,
            sampling: Sampling::Sobol,
            points: Some(points),
            seed,
            axes,
            temperature: None,
        }
    }

    /// Reproducible from the seed, another seed another sample, and every axis' range covered:
    /// 64 points put exactly one in each of 64 equal strata of every axis (the (0, m, s)-net
    /// property that Owen scrambling keeps, per axis).
    #[test]
    fn sobol_sample_is_reproducible_and_stratifies_every_axis() {
        let (a, b, c) = (
            points(&sobol(64, 7)),
            points(&sobol(64, 7)),
            points(&sobol(64, 8)),
        );
        assert_eq!(a, b);
        assert_ne!(a, c);
        let settings = sobol(64, 7);
        for (d, range) in settings.axes.values().enumerate() {
            let (lo, hi) = range.range();
            let mut strata = vec![0; 64];
            for p in &a {
                assert!(p[d] >= lo && p[d] < hi, "{} outside [{lo}, {hi})", p[d]);
                let s = ((p[d] - lo) / (hi - lo) * 64.0).floor() as usize;
                strata[s.min(63)] += 1;
            }
            assert!(strata.iter().all(|&n| n == 1), "axis {d}: {strata:?}");
        }
    }

    #[test]
    fn grid_is_the_full_product_and_slices_cover_it_once() {
        let mut axes = std::collections::BTreeMap::new();
        axes.insert(
            Axis::PressureBar,
            AxisRange {
                values: vec![5.0, 10.0, 20.0],
                ..Default::default()
            },
        );
        axes.insert(
            Axis::Mu,
            AxisRange {
                from: Some(0.3),
                to: Some(0.5),
                points: Some(3),
                ..Default::default()
            },
        );
        let settings = MatrixSettings {
            statics: Default::default(),
            full_checks: None,
            lining_blocks: None,
            saturation_modes: 0,
            parameter_shapes: true,
            sampling: Sampling::Grid,
            points: None,
            seed: 1,
            axes,
            temperature: None,
        };
        let p = points(&settings);
        assert_eq!(p.len(), 9);
        // Axis order is the enum's (pressure_bar before mu); the last axis fastest.
        assert_eq!(p[1], vec![5.0, 0.4]);
        assert_eq!(p[8], vec![20.0, 0.5]);
        for n in 1..=9 {
            let mut seen = vec![0; 9];
            for k in 1..=n {
                for i in (Slice { index: k, count: n }).range(9) {
                    seen[i] += 1;
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "{n} slices: {seen:?}");
        }
        assert_eq!(
            "2/5".parse::<Slice>().unwrap(),
            Slice { index: 2, count: 5 }
        );
        assert!("0/5".parse::<Slice>().is_err() && "6/5".parse::<Slice>().is_err());
    }

    #[test]
    fn warm_order_visits_every_point_once_starting_nearest_the_nominal() {
        let values: Vec<Vec<f64>> = (0..10).map(|i| vec![i as f64]).collect();
        let todo: Vec<usize> = (0..10).collect();
        let order = warm_order(&values, &todo, &[6.2], &[(0.0, 9.0)]);
        assert_eq!(order[0], (6, None));
        let mut seen: Vec<usize> = order.iter().map(|o| o.0).collect();
        seen.sort();
        assert_eq!(seen, todo);
        // Each starts from the nearest of the nominal point and the points before it.
        let at = |o: Option<usize>| o.map_or(6.2, |j| j as f64);
        for (k, &(i, from)) in order.iter().enumerate() {
            let d = (i as f64 - at(from)).abs();
            let before = order[..k].iter().map(|o| Some(o.0)).chain([None]);
            let best = before
                .map(|o| (i as f64 - at(o)).abs())
                .fold(f64::INFINITY, crate::measure::nan_min);
            assert_eq!(d, best, "{order:?}");
        }
    }
}
