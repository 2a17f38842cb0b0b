//! Parameter sweeps of the complex modes: the scene's `[sweep]` (friction coefficient, brake
//! pressure, disc speed, exponential-law p0 or lambda), and mode tracking across the points
//! by MAC so every track is one physical mode (the coalescence picture).

use serde::{Deserialize, Serialize};

use super::complex_modes::{mac, Complex, DenseEigenpair};
use crate::contact::law::{FrictionLaw, NormalLaw};
use crate::contact::ResolvedInterface;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepParameter {
    /// Friction coefficient of the sliding interfaces.
    Mu,
    PressureBar,
    /// rad/s.
    DiscSpeed,
    /// p0 of the sliding interfaces' exponential law (Pa).
    P0,
    /// lambda of the sliding interfaces' exponential law (1/m).
    Lambda,
}

impl SweepParameter {
    pub fn name(self) -> &'static str {
        match self {
            SweepParameter::Mu => "mu",
            SweepParameter::PressureBar => "pressure_bar",
            SweepParameter::DiscSpeed => "disc_speed",
            SweepParameter::P0 => "p0",
            SweepParameter::Lambda => "lambda",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            SweepParameter::Mu => "friction coefficient mu",
            SweepParameter::PressureBar => "brake pressure (bar)",
            SweepParameter::DiscSpeed => "disc speed (rad/s)",
            SweepParameter::P0 => "p0 (Pa)",
            SweepParameter::Lambda => "lambda (1/m)",
        }
    }
}

/// The `[sweep]` table: a parameter and its values (a list, or `from`, `to`, `points`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSettings {
    pub parameter: SweepParameter,
    #[serde(default)]
    pub values: Vec<f64>,
    #[serde(default)]
    pub from: Option<f64>,
    #[serde(default)]
    pub to: Option<f64>,
    #[serde(default)]
    pub points: Option<usize>,
}

impl SweepSettings {
    pub fn validate(&self) -> Result<(), String> {
        let values = self.values();
        if values.is_empty() {
            return Err(
                "key 'sweep': give 'values = [...]' or 'from', 'to' and 'points' (at least 2)"
                    .into(),
            );
        }
        if !self.values.is_empty() && (self.from.is_some() || self.to.is_some()) {
            return Err(
                "key 'sweep': give either 'values' or 'from'/'to'/'points', not both".into(),
            );
        }
        for v in &values {
            let ok = v.is_finite()
                && match self.parameter {
                    SweepParameter::Mu => *v >= 0.0,
                    _ => *v > 0.0,
                };
            if !ok {
                return Err(format!(
                    "key 'sweep.values': {v} is not a valid {} (finite, {})",
                    self.parameter.name(),
                    if self.parameter == SweepParameter::Mu {
                        "non-negative"
                    } else {
                        "positive"
                    }
                ));
            }
        }
        Ok(())
    }

    pub fn values(&self) -> Vec<f64> {
        if !self.values.is_empty() {
            return self.values.clone();
        }
        match (self.from, self.to, self.points) {
            (Some(a), Some(b), Some(n)) if n >= 2 => (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// Sets a law parameter on the sliding interfaces (mu, p0, lambda); other parameters are not
/// laws and are left to the caller. Errors name an interface whose law has no such parameter.
pub fn apply_to_laws(
    parameter: SweepParameter,
    value: f64,
    interfaces: &mut [ResolvedInterface],
) -> Result<(), String> {
    for i in interfaces.iter_mut().filter(|i| i.friction.is_sliding()) {
        match parameter {
            SweepParameter::Mu => {
                i.friction = match i.friction {
                    FrictionLaw::Coulomb { slip_speed, .. } => FrictionLaw::Coulomb {
                        mu: value,
                        slip_speed,
                    },
                    FrictionLaw::Arctan { slip_speed, .. } => FrictionLaw::Arctan {
                        mu: value,
                        slip_speed,
                    },
                    other => {
                        return Err(format!(
                            "sweep over mu: interface '{}' has friction law {other:?}; a mu sweep needs coulomb or arctan",
                            i.name
                        ))
                    }
                }
            }
            SweepParameter::P0 | SweepParameter::Lambda => {
                let NormalLaw::Exponential {
                    p0,
                    lambda,
                    linear_below_gap,
                } = i.normal
                else {
                    return Err(format!(
                        "sweep over {}: interface '{}' does not use the exponential law",
                        parameter.name(),
                        i.name
                    ));
                };
                i.normal = if parameter == SweepParameter::P0 {
                    NormalLaw::Exponential {
                        p0: value,
                        lambda,
                        linear_below_gap,
                    }
                } else {
                    NormalLaw::Exponential {
                        p0,
                        lambda: value,
                        linear_below_gap,
                    }
                };
            }
            SweepParameter::PressureBar | SweepParameter::DiscSpeed => {}
        }
    }
    Ok(())
}

/// Mode tracks over the sweep points: `tracks[t][i]` is track t's eigenvalue at point i and
/// its MAC with the track's mode at the previous point (1 at the first point).
#[derive(Debug, Clone, Default)]
pub struct Tracks {
    pub tracks: Vec<Vec<Option<(Complex, f64)>>>,
}

/// Relative eigenvalue spacing below which modes form a cluster (a doublet of the disc).
const CLUSTER: f64 = 2e-3;

/// Pairs the modes of one point with those of the next: for each previous mode, the index of
/// its continuation and the MAC (or None). Greedy on the cost (1 - MAC) + |s_i - s_j| / |s_i|,
/// where for a mode inside a cluster (a doublet: eigenvalues within 2e-3) the MAC is taken
/// with the cluster's whole plane. So the shape decides at crossings (frequencies meet,
/// shapes differ), and inside a doublet, whose two shapes may rotate freely within their plane
/// from one point to the next, the eigenvalue decides: its tracks keep their order, no swaps.
pub fn pair_modes(
    previous: &[DenseEigenpair],
    next: &[DenseEigenpair],
) -> Vec<Option<(usize, f64)>> {
    let close = |a: Complex, b: Complex| {
        (a.0 - b.0).hypot(a.1 - b.1) <= CLUSTER * a.0.hypot(a.1).max(b.0.hypot(b.1))
    };
    let mut candidates = Vec::with_capacity(previous.len() * next.len());
    for (i, (si, _)) in previous.iter().enumerate() {
        let scale = si.0.hypot(si.1).max(1e-300);
        let cluster: Vec<usize> = (0..previous.len())
            .filter(|&k| close(previous[k].0, *si))
            .collect();
        for (j, (sj, yj)) in next.iter().enumerate() {
            let m = cluster
                .iter()
                .map(|&k| mac(&previous[k].1, yj))
                .sum::<f64>()
                .min(1.0);
            let ds = (si.0 - sj.0).hypot(si.1 - sj.1) / scale;
            candidates.push(((1.0 - m) + ds, i, j, m));
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = vec![None; previous.len()];
    let mut taken = vec![false; next.len()];
    for (_, i, j, m) in candidates {
        if out[i].is_none() && !taken[j] {
            out[i] = Some((j, m));
            taken[j] = true;
        }
    }
    out
}

/// Tracks modes through the points (each point's modes with their modal coordinates in one
/// fixed basis). Tracks start at the first point; a mode of a later point that continues no
/// track is dropped (its track would start mid-sweep).
pub fn track(points: &[Vec<DenseEigenpair>]) -> Tracks {
    let Some(first) = points.first() else {
        return Tracks::default();
    };
    let mut tracks: Vec<Vec<Option<(Complex, f64)>>> =
        first.iter().map(|(s, _)| vec![Some((*s, 1.0))]).collect();
    // The current mode of each track (index into the latest point), None once lost.
    let mut current: Vec<Option<usize>> = (0..first.len()).map(Some).collect();
    for w in points.windows(2) {
        let (prev, next) = (&w[0], &w[1]);
        let alive: Vec<usize> = current.iter().filter_map(|c| *c).collect();
        let subset: Vec<DenseEigenpair> = alive.iter().map(|&i| prev[i].clone()).collect();
        let pairs = pair_modes(&subset, next);
        let by_prev: std::collections::HashMap<usize, Option<(usize, f64)>> =
            alive.iter().copied().zip(pairs).collect();
        for (t, c) in current.iter_mut().enumerate() {
            match c.and_then(|i| by_prev.get(&i).copied().flatten()) {
                Some((j, m)) => {
                    tracks[t].push(Some((next[j].0, m)));
                    *c = Some(j);
                }
                None => {
                    tracks[t].push(None);
                    *c = None;
                }
            }
        }
    }
    Tracks { tracks }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(k: usize, n: usize) -> Vec<Complex> {
        (0..n).map(|i| (f64::from(u8::from(i == k)), 0.0)).collect()
    }

    /// Two distinct modes whose frequencies cross (shapes e0 and e1 stay), and a doublet (e2,
    /// e3 plane) whose members rotate by 60 degrees per point while splitting slightly: the
    /// crossing is followed by shape, the doublet keeps its frequency order, no swaps.
    #[test]
    fn crossings_follow_shapes_and_doublets_do_not_swap() {
        let n = 4;
        let mut points = Vec::new();
        for p in 0..5 {
            let x = p as f64;
            let angle = (60.0 * x).to_radians();
            let (c, s) = (angle.cos(), angle.sin());
            let rotated = |a: f64, b: f64| -> Vec<Complex> {
                vec![(0.0, 0.0), (0.0, 0.0), (a, 0.0), (b, 0.0)]
            };
            let split = 1e-4 * (1.0 + x);
            points.push(vec![
                ((0.0, 100.0 + 10.0 * x), unit(0, n)), // rising
                ((0.0, 140.0 - 10.0 * x), unit(1, n)), // falling: crosses the first at x = 2
                ((0.0, 500.0 * (1.0 - split)), rotated(c, s)),
                ((0.0, 500.0 * (1.0 + split)), rotated(-s, c)),
            ]);
        }
        let t = track(&points);
        assert_eq!(t.tracks.len(), 4);
        for (k, track) in t.tracks.iter().enumerate() {
            let freqs: Vec<f64> = track.iter().map(|p| p.unwrap().0 .1).collect();
            match k {
                0 => assert!(freqs.windows(2).all(|w| w[1] > w[0]), "rising: {freqs:?}"),
                1 => assert!(freqs.windows(2).all(|w| w[1] < w[0]), "falling: {freqs:?}"),
                2 => assert!(
                    freqs.iter().all(|&f| f < 500.0),
                    "lower doublet member: {freqs:?}"
                ),
                _ => assert!(
                    freqs.iter().all(|&f| f > 500.0),
                    "upper doublet member: {freqs:?}"
                ),
            }
        }
    }

    #[test]
    fn values_from_range_and_validation_names_the_key() {
        let s = SweepSettings {
            parameter: SweepParameter::Mu,
            values: Vec::new(),
            from: Some(0.0),
            to: Some(0.5),
            points: Some(6),
        };
        assert_eq!(s.values().len(), 6);
        assert!((s.values()[5] - 0.5).abs() < 1e-15);
        s.validate().unwrap();
        let bad = SweepSettings {
            values: vec![0.1, f64::NAN],
            from: None,
            to: None,
            points: None,
            ..s
        };
        assert!(bad.validate().unwrap_err().contains("sweep.values"));
    }
}
