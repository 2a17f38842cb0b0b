//! What a noise matrix says: how many operating points squeal, in which 1/3-octave bands and
//! with which modes (the noise-dynamometer chart), which region of the operating range is
//! worst, and which parameter drives the squeal propensity (the largest Re(s) of a point) by
//! its first-order sensitivity index.

use super::point::PointResult;
use super::{Axis, Sampling};
use crate::measure::{greatest, smallest};
use crate::post::loudness::third_octave_bands;

/// Occurrences of unstable modes in one 1/3-octave band.
#[derive(Debug, Clone, PartialEq)]
pub struct BandCount {
    /// Nominal centre frequency (Hz).
    pub nominal: f64,
    pub lower: f64,
    pub upper: f64,
    /// Points with at least one unstable mode in the band.
    pub points: usize,
}

/// How often one nominal mode (or an unpaired one) is unstable.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeCount {
    pub name: String,
    pub points: usize,
    pub mean_frequency_hz: f64,
    pub largest_real_part: f64,
}

/// A cell of the operating range: one third of the range of each of (up to) two axes.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// (axis, lower, upper) per axis of the cell.
    pub bounds: Vec<(Axis, f64, f64)>,
    pub points: usize,
    pub squealing: usize,
}

/// The matrix' statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct MatrixAnalysis {
    pub points: usize,
    pub solved: usize,
    pub failed: usize,
    /// Solved points with at least one unstable mode.
    pub squealing: usize,
    /// Bands with at least one occurrence, by frequency.
    pub bands: Vec<BandCount>,
    /// Modes unstable somewhere, most frequent first.
    pub modes: Vec<ModeCount>,
    /// First-order sensitivity index of the largest Re(s) per axis (in axis order).
    pub sensitivity: Vec<(Axis, f64)>,
    pub worst_region: Option<Region>,
}

impl MatrixAnalysis {
    /// The band with the most squealing points.
    pub fn most_frequent_band(&self) -> Option<&BandCount> {
        self.bands.iter().max_by(|a, b| {
            a.points
                .cmp(&b.points)
                .then(b.nominal.total_cmp(&a.nominal))
        })
    }

    /// The axis with the largest first-order index.
    pub fn driver(&self) -> Option<(Axis, f64)> {
        self.sensitivity
            .iter()
            .copied()
            .filter(|(_, s)| s.is_finite())
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// The statistics of `points` (any order; failed ones counted apart). `margin`: the damping
/// ratio below -margin that counts as unstable.
pub fn analyse(
    points: &[PointResult],
    axes: &[Axis],
    sampling: Sampling,
    margin: f64,
) -> MatrixAnalysis {
    let solved: Vec<&PointResult> = points.iter().filter(|p| p.solved().is_some()).collect();
    let squeals = |p: &PointResult| p.unstable(margin).next().is_some();
    let mut bands: Vec<BandCount> = third_octave_bands()
        .into_iter()
        .map(|b| BandCount {
            nominal: b.nominal,
            lower: b.lower,
            upper: b.upper,
            points: 0,
        })
        .collect();
    let mut modes: Vec<(String, usize, f64, f64)> = Vec::new();
    for p in &solved {
        let mut hit = vec![false; bands.len()];
        for m in p.unstable(margin) {
            let f = m.frequency_hz();
            if let Some(b) = bands.iter().position(|b| b.lower <= f && f < b.upper) {
                hit[b] = true;
            }
            let name = m.name();
            match modes.iter_mut().find(|e| e.0 == name) {
                Some(e) => {
                    e.1 += 1;
                    e.2 += f;
                    e.3 = e.3.max(m.re);
                }
                None => modes.push((name, 1, f, m.re)),
            }
        }
        for (b, h) in bands.iter_mut().zip(hit) {
            b.points += usize::from(h);
        }
    }
    bands.retain(|b| b.points > 0);
    let mut modes: Vec<ModeCount> = modes
        .into_iter()
        .map(|(name, n, f, re)| ModeCount {
            name,
            points: n,
            mean_frequency_hz: f / n as f64,
            largest_real_part: re,
        })
        .collect();
    modes.sort_by(|a, b| {
        b.points
            .cmp(&a.points)
            .then(a.mean_frequency_hz.total_cmp(&b.mean_frequency_hz))
    });
    let y: Vec<f64> = solved.iter().map(|p| p.largest_real_part()).collect();
    let sensitivity: Vec<(Axis, f64)> = axes
        .iter()
        .enumerate()
        .map(|(d, &a)| {
            let x: Vec<f64> = solved.iter().map(|p| p.values[d]).collect();
            (a, first_order_index(&x, &y, sampling))
        })
        .collect();
    let flags: Vec<bool> = solved.iter().map(|p| squeals(p)).collect();
    let values: Vec<&[f64]> = solved.iter().map(|p| p.values.as_slice()).collect();
    let worst_region = worst_region(&values, &flags, axes, &sensitivity);
    MatrixAnalysis {
        points: points.len(),
        solved: solved.len(),
        failed: points.len() - solved.len(),
        squealing: flags.iter().filter(|&&f| f).count(),
        bands,
        modes,
        sensitivity,
        worst_region,
    }
}

/// Var(E[Y | X]) / Var(Y), estimated from the means of Y over groups of X: a grid's levels
/// (exact for a full factorial: every level sees the same combinations of the other axes),
/// or for a sample sqrt(n) groups of equal count by X, less the variance the finite groups
/// add by chance ((groups - 1) / n x the mean within-group variance). NaN when Y does not
/// vary or there are fewer than 4 points.
pub fn first_order_index(x: &[f64], y: &[f64], sampling: Sampling) -> f64 {
    let n = x.len();
    if n < 4 || y.iter().any(|v| !v.is_finite()) {
        return f64::NAN;
    }
    let mean = y.iter().sum::<f64>() / n as f64;
    let total = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
    if total.is_nan() || total <= 0.0 {
        return f64::NAN;
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let groups: Vec<Vec<usize>> = match sampling {
        Sampling::Grid => {
            let mut g: Vec<Vec<usize>> = Vec::new();
            for &i in &order {
                match g.last_mut() {
                    Some(last) if x[last[0]] == x[i] => last.push(i),
                    _ => g.push(vec![i]),
                }
            }
            g
        }
        Sampling::Sobol => {
            let count = ((n as f64).sqrt().floor() as usize).max(2);
            (0..count)
                .map(|k| order[k * n / count..(k + 1) * n / count].to_vec())
                .collect()
        }
    };
    let (mut between, mut within) = (0.0, 0.0);
    for g in &groups {
        let m = g.iter().map(|&i| y[i]).sum::<f64>() / g.len() as f64;
        between += g.len() as f64 * (m - mean).powi(2);
        within += g.iter().map(|&i| (y[i] - m).powi(2)).sum::<f64>();
    }
    let (between, within) = (between / n as f64, within / n as f64);
    // E[between] = Var(E[Y|X]) + (groups - 1) / n x sigma_within^2 for random groups.
    let chance = match sampling {
        Sampling::Grid => 0.0,
        Sampling::Sobol => {
            let sigma2_within = within * n as f64 / (n - groups.len()) as f64;
            (groups.len() - 1) as f64 / n as f64 * sigma2_within
        }
    };
    ((between - chance) / total).clamp(0.0, 1.0)
}

/// The cell (thirds of the range of the two most influential axes, or of the only one) where
/// the largest share of points squeals (ties: more points).
fn worst_region(
    values: &[&[f64]],
    squeals: &[bool],
    axes: &[Axis],
    sensitivity: &[(Axis, f64)],
) -> Option<Region> {
    if values.is_empty() || !squeals.iter().any(|&s| s) {
        return None;
    }
    let mut ranked: Vec<usize> = (0..axes.len()).collect();
    let key = |d: usize| {
        if sensitivity[d].1.is_finite() {
            sensitivity[d].1
        } else {
            -1.0
        }
    };
    ranked.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
    ranked.truncate(2);
    let ranges: Vec<(f64, f64)> = ranked
        .iter()
        .map(|&d| {
            let v = values.iter().map(|p| p[d]);
            (smallest(v.clone()), greatest(v))
        })
        .collect();
    let third = |v: f64, (lo, hi): (f64, f64)| {
        if hi > lo {
            (((v - lo) / (hi - lo) * 3.0).floor() as usize).min(2)
        } else {
            0
        }
    };
    let mut cells = [(0usize, 0usize); 9];
    for (p, &s) in values.iter().zip(squeals) {
        let c = ranked
            .iter()
            .zip(&ranges)
            .fold(0, |c, (&d, &r)| 3 * c + third(p[d], r));
        cells[c].0 += 1;
        cells[c].1 += usize::from(s);
    }
    let share = |c: &(usize, usize)| c.1 as f64 / c.0.max(1) as f64;
    // A cell with fewer than half the mean count per occupied cell says little (one point
    // that squeals is 100 %): such cells compete only when no cell is better filled.
    let occupied = cells.iter().filter(|c| c.0 > 0).count().max(1);
    let enough = (values.len() / (2 * occupied)).max(1);
    let filled = if cells.iter().any(|c| c.0 >= enough && c.1 > 0) {
        enough
    } else {
        1
    };
    let best = (0..cells.len())
        .filter(|&c| cells[c].0 >= filled)
        .max_by(|&a, &b| {
            share(&cells[a])
                .total_cmp(&share(&cells[b]))
                .then(cells[a].0.cmp(&cells[b].0))
        })?;
    // Cell index: 3 t0 + t1 for two axes (the most influential major), t0 for one.
    let thirds = if ranked.len() == 2 {
        vec![best / 3, best % 3]
    } else {
        vec![best]
    };
    let bounds = ranked
        .iter()
        .zip(&ranges)
        .zip(thirds)
        .map(|((&d, &(lo, hi)), t)| {
            let w = (hi - lo) / 3.0;
            (axes[d], lo + t as f64 * w, lo + (t + 1) as f64 * w)
        })
        .collect();
    Some(Region {
        bounds,
        points: cells[best].0,
        squealing: cells[best].1,
    })
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::super::point::{Outcome, PointMode, SolvedPoint};
    use super::*;

    fn point(index: usize, values: Vec<f64>, modes: Vec<(f64, f64)>) -> PointResult {
        PointResult {
            index,
            values,
            outcome: Outcome::Solved(SolvedPoint {
                modes: modes
                    .into_iter()
                    .enumerate()
                    .map(|(k, (re, f))| PointMode {
                        label: Some(k + 1),
                        re,
                        im: 2.0 * std::f64::consts::PI * f,
                        mac: 1.0,
                    })
                    .collect(),
                braking_torque: 1.0,
                normal_force: 1.0,
                newton_iterations: 1,
                factorizations: 1,
                cold_restart: false,
                seconds_statics: 0.0,
                seconds_factorizing: 0.0,
                full_check: None,
                saturation: Vec::new(),
                factor_solves: 0,
                seconds_solving: 0.0,
                seconds_modes: 0.0,
            }),
        }
    }

    /// Y = a(x1) + b(x2) on a full 2-axis grid: the first-order indices are Var(a) / Var(Y)
    /// and Var(b) / Var(Y) exactly (the closed form of an additive function).
    #[test]
    fn additive_function_on_a_grid_has_its_closed_form_indices() {
        let (xs, zs) = ([0.0, 1.0, 2.0], [0.0, 1.0]);
        let mut points = Vec::new();
        for &x in &xs {
            for &z in &zs {
                // a = 10 x (variance 200/3 over the levels), b = 5 z (variance 25/4).
                let y = 10.0 * x + 5.0 * z - 12.0;
                points.push(point(
                    points.len(),
                    vec![x, z],
                    vec![(y, 1000.0 + 100.0 * x)],
                ));
            }
        }
        let a = analyse(&points, &[Axis::PressureBar, Axis::Mu], Sampling::Grid, 0.0);
        let (va, vb) = (200.0 / 3.0, 25.0 / 4.0);
        assert!(
            (a.sensitivity[0].1 - va / (va + vb)).abs() < 1e-12,
            "{:?}",
            a.sensitivity
        );
        assert!((a.sensitivity[1].1 - vb / (va + vb)).abs() < 1e-12);
        assert_eq!(a.driver().unwrap().0, Axis::PressureBar);
        // Squealing (y > 0): x = 2 (both z: y = 8, 13) and x = 1, z = 1 (y = 3).
        assert_eq!((a.solved, a.squealing), (6, 3));
        // Their frequencies: 1,100 Hz (band 1,000 Hz: 891-1,122) and 1,200 Hz (1,250 Hz).
        let bands: Vec<(f64, usize)> = a.bands.iter().map(|b| (b.nominal, b.points)).collect();
        assert_eq!(bands, vec![(1000.0, 1), (1250.0, 2)]);
        // Three cells squeal at every point (one point each); the tie goes to the last, the
        // top third of both ranges.
        let worst = a.worst_region.unwrap();
        assert_eq!((worst.points, worst.squealing), (1, 1));
        assert_eq!(
            (worst.bounds[0].0, worst.bounds[1].0),
            (Axis::PressureBar, Axis::Mu)
        );
        assert!((worst.bounds[0].1 - 4.0 / 3.0).abs() < 1e-12);
        assert!((worst.bounds[1].1 - 2.0 / 3.0).abs() < 1e-12);
    }

    /// A Sobol sample of Y = x1 (x2 without effect): the index of x1 near 1 and of x2 near 0,
    /// within the estimator's error for 256 points (bins of 16: O(1/16)).
    #[test]
    fn sample_estimate_separates_a_driver_from_a_bystander() {
        let settings = super::super::MatrixSettings {
            statics: Default::default(),
            full_checks: None,
            lining_blocks: None,
            saturation_modes: 0,
            parameter_shapes: true,
            sampling: Sampling::Sobol,
            points: Some(256),
            seed: 3,
            axes: [Axis::PressureBar, Axis::Mu]
                .into_iter()
                .map(|a| {
                    let r = super::super::AxisRange {
                        from: Some(0.1),
                        to: Some(1.0),
                        ..Default::default()
                    };
                    (a, r)
                })
                .collect(),
            temperature: None,
        };
        let values = super::super::sample::points(&settings);
        let x1: Vec<f64> = values.iter().map(|p| p[0]).collect();
        let x2: Vec<f64> = values.iter().map(|p| p[1]).collect();
        let y: Vec<f64> = x1.iter().map(|x| x - 0.5).collect();
        assert!(first_order_index(&x1, &y, Sampling::Sobol) > 0.95);
        assert!(first_order_index(&x2, &y, Sampling::Sobol) < 0.05);
        assert!(first_order_index(&x2, &[f64::NAN; 256], Sampling::Sobol).is_nan());
    }
}
