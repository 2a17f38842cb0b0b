//! One period of a pseudo trajectory ([`super::pseudo_trajectory`]): the mode and its
//! coupling partner followed by MAC through the phases, from the pair of a nearby amplitude,
//! and on to phase 0 again to check that the pair comes back to where it started. Where the
//! pairing between two phases is not resolved (a continuation's MAC below 0.9) the step may be
//! halved (`halvings`, 0 by default) and the pair followed through the points between; those
//! points only carry the tracking and do not enter the period's statistics.
//!
//! Why the check: a period's statistics are those of the modes followed, and those depended on
//! the phase where the period started (the brake's C35 at 250 modes and 4.6 um: mean damping
//! +3.3e-4 from one phase, -7.8e-3 from the opposite one, the same states). A pair that does
//! not come back to its start shows that dependence; the summary counts those amplitudes.

use super::pseudo_trajectory::PseudoError;
use std::time::Instant;

use super::pseudo_trajectory::{Linearized, PseudoSystem};
use crate::eigen::complex_modes::{
    damping_ratio, frequency_hz, solve_dense, Complex, DenseEigenpair,
};
use crate::eigen::tracking::{
    coupling_pair, nearest, pair_modes, pairs_from_all_eigenvalues, pairs_near_tracked, HINTS,
};

/// The mode followed over one period at one amplitude.
#[derive(Debug, Clone)]
pub struct Period {
    pub alpha: f64,
    /// The mode's eigenvalue at each phase (NaN where it was lost).
    pub eigenvalue: Vec<Complex>,
    /// The smallest MAC between successive points the pair was followed through (NaN where it
    /// was lost).
    pub min_mac: f64,
    /// Whether the pair followed over the whole period, and on to phase 0 again, comes back
    /// to the one it started from: else which modes were followed depends on the phase where
    /// the period starts, and so do the period's statistics.
    pub closed: bool,
    pub unstable_fraction: f64,
    pub mean_damping_ratio: f64,
    /// Open / stick / slide fractions of all contact points, per phase.
    pub fractions: Vec<[f64; 3]>,
    pub sample: Vec<u8>,
    /// The mode and its partner at phase 0: where the next amplitude's tracking starts.
    start: Vec<DenseEigenpair>,
    pub cost: Cost,
}

/// Where a study's time goes: the linearizations (contact laws and the projection of the
/// tangent on the modes) and the eigenpairs, near the tracked pair or by the full dense solve.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Cost {
    pub linearize_seconds: f64,
    pub near_shift_seconds: f64,
    pub dense_seconds: f64,
    /// Eigen-solves, and those that needed the full dense solve (see [`pairs_near_tracked`]).
    pub solves: usize,
    pub dense_solves: usize,
    /// Linearizations between phases, where the step was halved.
    pub between_phases: usize,
}

impl std::ops::AddAssign for Cost {
    fn add_assign(&mut self, other: Cost) {
        self.linearize_seconds += other.linearize_seconds;
        self.near_shift_seconds += other.near_shift_seconds;
        self.dense_seconds += other.dense_seconds;
        self.solves += other.solves;
        self.dense_solves += other.dense_solves;
        self.between_phases += other.between_phases;
    }
}

impl Period {
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| frequency_hz(s)).collect()
    }
    pub fn damping_ratios(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| damping_ratio(s)).collect()
    }
    pub fn has_stable_phase(&self) -> bool {
        self.unstable_fraction < 1.0
    }
    /// Where the next period's tracking starts from this one.
    pub fn start(&self) -> Start<'_> {
        Start {
            alpha: self.alpha,
            pair: &self.start,
        }
    }
    /// Linearizations made: one per phase evaluated and those between phases.
    pub fn linearizations(&self) -> usize {
        self.eigenvalue.len() + self.cost.between_phases
    }
}

/// Where a period's tracking starts: the pair at phase 0 of amplitude `alpha` (0: the nominal
/// modes).
#[derive(Debug, Clone, Copy)]
pub struct Start<'a> {
    pub alpha: f64,
    pub pair: &'a [DenseEigenpair],
}

/// A continuation's MAC below which the step to it is halved.
const RESOLVED: f64 = 0.9;

/// Where a period is evaluated: at `phases` phases, the pair followed between two of them
/// through up to 2^`halvings` - 1 points more where the step is not resolved.
#[derive(Debug, Clone, Copy)]
pub struct Sampling {
    pub phases: usize,
    pub halvings: usize,
}

/// A point (amplitude, phase) of the pseudo trajectory.
#[derive(Debug, Clone, Copy)]
struct Point {
    alpha: f64,
    theta: f64,
}

impl Point {
    /// Halfway to `other`: in log(alpha) (the sweep's spacing) and in phase.
    fn midpoint(self, other: Point) -> Point {
        let alpha = if self.alpha > 0.0 {
            (self.alpha * other.alpha).sqrt()
        } else {
            0.5 * other.alpha
        };
        Point {
            alpha,
            theta: 0.5 * (self.theta + other.theta),
        }
    }
}

/// The pair while it is followed, and what following it cost.
struct Follower<'a> {
    system: &'a dyn PseudoSystem,
    psi: &'a [Complex],
    omega: f64,
    near: bool,
    current: Vec<DenseEigenpair>,
    /// The eigenpairs found near the pair at the previous point: the next one's start block.
    hints: Vec<DenseEigenpair>,
    min_mac: f64,
    cost: Cost,
}

impl Follower<'_> {
    fn linearize(&mut self, at: Point) -> Result<Linearized, PseudoError> {
        let clock = Instant::now();
        let lin = self
            .system
            .linearize(self.psi, self.omega, at.alpha, at.theta)?;
        self.cost.linearize_seconds += clock.elapsed().as_secs_f64();
        Ok(lin)
    }

    /// The eigenpairs of the tangent `lin` that the pairing of the current pair needs: near
    /// the pair by shift-invert where that provably gives the full pairing, else from all
    /// eigenvalues (`near`), or the full dense solve.
    fn eigenpairs(&mut self, lin: &Linearized) -> Result<Vec<DenseEigenpair>, PseudoError> {
        let m = self.psi.len();
        self.cost.solves += 1;
        if self.near {
            let clock = Instant::now();
            let found = pairs_near_tracked(m, &lin.kp, &lin.cp, &self.current, &self.hints)?;
            self.cost.near_shift_seconds += clock.elapsed().as_secs_f64();
            if let Some(pairs) = found {
                return Ok(pairs);
            }
        }
        let clock = Instant::now();
        let pairs = if self.near {
            pairs_from_all_eigenvalues(m, &lin.kp, &lin.cp, &self.current)?
        } else {
            solve_dense(m, &lin.kp, &lin.cp)?
        };
        self.cost.dense_seconds += clock.elapsed().as_secs_f64();
        self.cost.dense_solves += 1;
        Ok(pairs)
    }

    /// Moves the pair from `from` to `to`, where the tangent is `lin`; where a continuation's
    /// MAC is below [`RESOLVED`] the step is halved (at most `halvings` times more) and the
    /// pair followed through the midpoint. False where a member has no continuation (the pair
    /// is lost there; it stays where it was).
    fn advance(
        &mut self,
        from: Point,
        to: Point,
        lin: &Linearized,
        halvings: usize,
    ) -> Result<bool, PseudoError> {
        let pairs = self.eigenpairs(lin)?;
        let next: Option<Vec<(usize, f64)>> =
            pair_modes(&self.current, &pairs).into_iter().collect();
        let Some(next) = next else {
            return Ok(false);
        };
        if halvings > 0 && next.iter().any(|&(_, mac)| mac < RESOLVED) {
            let mid = from.midpoint(to);
            let at_mid = self.linearize(mid)?;
            self.cost.between_phases += 1;
            return Ok(self.advance(from, mid, &at_mid, halvings - 1)?
                && self.advance(mid, to, lin, halvings - 1)?);
        }
        for &(_, mac) in &next {
            self.min_mac = self.min_mac.min(mac);
        }
        self.hints = nearest(&pairs, &self.current, HINTS);
        let chosen: Vec<usize> = next.iter().map(|&(j, _)| j).collect();
        let members = coupling_pair(&self.current, &pairs, &chosen);
        self.current = members.iter().map(|&j| pairs[j].clone()).collect();
        Ok(true)
    }

    /// The pair's least stable member. Where the pair splits (the contact state decouples
    /// it) the two continuations have nearly the same shape and either may be "the mode":
    /// the least stable member is a continuous function of the state whichever member the
    /// pairing follows (so the mean over the period is continuous in alpha and a bisection on
    /// it well posed).
    fn least_stable(&self) -> Complex {
        self.current
            .iter()
            .map(|p| p.0)
            .min_by(|a, b| damping_ratio(*a).total_cmp(&damping_ratio(*b)))
            .unwrap_or((f64::NAN, f64::NAN))
    }
}

/// Whether two sets of eigenpairs hold the same eigenvalues (to the solvers' agreement).
fn same_modes(a: &[DenseEigenpair], b: &[DenseEigenpair]) -> bool {
    let close = |s: Complex, t: Complex| (s.0 - t.0).hypot(s.1 - t.1) <= 1e-8 * s.0.hypot(s.1);
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| close(p.0, q.0)))
}

/// Follows the mode and its coupling partner over one period at `alpha` from `start`;
/// `near`: the eigenpairs near the pair by shift-invert where that provably gives the same
/// pairing ([`pairs_near_tracked`]), else (and always without `near`) the full dense solve.
/// The mode's eigenvalue at a phase is the pair's least stable member. `until_stable`: stop
/// at the first stable phase (all the bisection for alpha_crit asks of a period that has
/// one; the statistics then cover the phases evaluated).
#[allow(clippy::too_many_arguments)] // the period's definition and how its modes are solved
pub fn period(
    system: &dyn PseudoSystem,
    psi: &[Complex],
    omega: f64,
    alpha: f64,
    sampling: Sampling,
    start: Start<'_>,
    margin: f64,
    near: bool,
    until_stable: bool,
) -> Result<Period, PseudoError> {
    let phases = sampling.phases;
    let mut follower = Follower {
        system,
        psi,
        omega,
        near,
        current: start.pair.to_vec(),
        hints: Vec::new(),
        min_mac: 1.0,
        cost: Cost::default(),
    };
    let mut out = Period {
        alpha,
        eigenvalue: Vec::with_capacity(phases),
        min_mac: 1.0,
        closed: false,
        unstable_fraction: 0.0,
        mean_damping_ratio: 0.0,
        fractions: Vec::with_capacity(phases),
        sample: Vec::with_capacity(phases),
        start: start.pair.to_vec(),
        cost: Cost::default(),
    };
    let phase = |k: usize| 2.0 * std::f64::consts::PI * k as f64 / phases as f64;
    let mut from = Point {
        alpha: start.alpha,
        theta: 0.0,
    };
    let (mut lost, mut phase_zero) = (false, None);
    for k in 0..phases {
        let to = Point {
            alpha,
            theta: phase(k),
        };
        let lin = follower.linearize(to)?;
        let followed = follower.advance(from, to, &lin, sampling.halvings)?;
        out.fractions.push(lin.fractions);
        out.sample.push(lin.sample);
        if k == 0 {
            out.start = follower.current.clone();
            phase_zero = Some(lin);
        }
        from = to;
        if !followed {
            lost = true;
            out.eigenvalue.push((f64::NAN, f64::NAN));
            continue;
        }
        let least_stable = follower.least_stable();
        out.eigenvalue.push(least_stable);
        if until_stable && damping_ratio(least_stable) >= -margin {
            break;
        }
    }
    // On to phase 0 again (the same tangent): the pair must come back to where it started.
    if let (false, Some(lin)) = (lost || out.eigenvalue.len() < phases, phase_zero) {
        let end = Point {
            alpha,
            theta: phase(phases),
        };
        out.closed = follower.advance(from, end, &lin, sampling.halvings)?
            && same_modes(&follower.current, &out.start);
    }
    out.min_mac = if lost { f64::NAN } else { follower.min_mac };
    out.cost = follower.cost;
    let zeta = out.damping_ratios();
    let evaluated = zeta.len() as f64;
    // A lost phase counts as unstable and makes the mean NaN: nothing is concluded from it.
    out.unstable_fraction =
        zeta.iter().filter(|z| z.is_nan() || **z < -margin).count() as f64 / evaluated;
    out.mean_damping_ratio = zeta.iter().sum::<f64>() / evaluated;
    Ok(out)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::post::pseudo_trajectory::partner;

    /// A 40-mode chain whose neighbours couple through an antisymmetric (friction-like)
    /// stiffness, and whose stiffness changes along the pseudo trajectory by
    /// alpha (cos theta S + sin theta A), S symmetric, A antisymmetric: eigenvalues move by
    /// several per cent over a period at alpha = 1, through close modes.
    struct Chain {
        m: usize,
        k0: Vec<f64>,
        c: Vec<f64>,
    }

    impl Chain {
        fn new(m: usize) -> Self {
            let mut k0 = vec![0.0; m * m];
            let mut c = vec![0.0; m * m];
            for i in 0..m {
                // Pairs of close modes (1, 1.01, 2, 2.01, ...) x 1000 rad/s.
                let w = 1e3 * ((i / 2 + 1) as f64 + 0.01 * (i % 2) as f64);
                k0[i * m + i] = w * w;
                c[i * m + i] = 2.0 * 0.005 * w;
                if i + 1 < m {
                    k0[(i + 1) * m + i] = 0.2 * w * w;
                    k0[i * m + i + 1] = -0.2 * w * w;
                }
            }
            Chain { m, k0, c }
        }
    }

    impl PseudoSystem for Chain {
        fn contact_normalization(&self, _: &[Complex]) -> Result<Complex, PseudoError> {
            Ok((1.0, 0.0))
        }
        fn linearize(
            &self,
            _: &[Complex],
            _: f64,
            alpha: f64,
            theta: f64,
        ) -> Result<Linearized, PseudoError> {
            let m = self.m;
            let mut kp = self.k0.clone();
            for j in 0..m {
                for i in 0..m {
                    let scale = (self.k0[i * m + i] * self.k0[j * m + j]).sqrt();
                    let sym = 0.03 * ((1 + i + j) as f64).sin();
                    let anti = 0.02 * ((i as f64 - j as f64) * 0.7).sin();
                    kp[j * m + i] += alpha * scale * (theta.cos() * sym + theta.sin() * anti);
                }
            }
            Ok(Linearized {
                kp,
                cp: self.c.clone(),
                fractions: [0.0, 0.0, 1.0],
                sample: 2,
            })
        }
        fn gap_scale(&self) -> f64 {
            1.0
        }
    }

    /// The pair followed through a period by shift-invert near it is the pair the full dense
    /// solve follows: at every phase the same eigenvalue to 1e-9 (both converge to round-off;
    /// the iteration stops at a residual of 1e-13 ||A||), and the shift-invert does the work
    /// at most phases (else the test would compare the full solve with itself).
    #[test]
    fn pair_tracked_near_its_shift_is_the_full_dense_solves_pair() {
        let chain = Chain::new(48);
        let m = chain.m;
        let nominal = solve_dense(m, &chain.k0, &chain.c).unwrap();
        let index = nominal
            .iter()
            .enumerate()
            .min_by(|a, b| damping_ratio(a.1 .0).total_cmp(&damping_ratio(b.1 .0)))
            .map(|(k, _)| k)
            .unwrap();
        let pair: Vec<DenseEigenpair> = std::iter::once(index)
            .chain(partner(&nominal, index))
            .map(|k| nominal[k].clone())
            .collect();
        let omega = nominal[index].0 .1;
        let (mut near_used, mut solves) = (0, 0);
        for alpha in [1e-6, 0.1, 0.5, 1.0] {
            let run = |near| {
                let start = Start {
                    alpha: 0.0,
                    pair: &pair,
                };
                let sampling = Sampling {
                    phases: 32,
                    halvings: 3,
                };
                period(
                    &chain, &pair[0].1, omega, alpha, sampling, start, 0.0, near, false,
                )
            };
            let (fast, full) = (run(true).unwrap(), run(false).unwrap());
            assert_eq!(full.cost.dense_solves, full.cost.solves);
            near_used += fast.cost.solves - fast.cost.dense_solves;
            solves += fast.cost.solves;
            for (k, (a, b)) in fast.eigenvalue.iter().zip(&full.eigenvalue).enumerate() {
                let d = (a.0 - b.0).hypot(a.1 - b.1) / b.0.hypot(b.1);
                assert!(
                    d <= 1e-9,
                    "alpha {alpha}, phase {k}: {a:?} vs {b:?} ({d:.1e})"
                );
            }
            let (zf, zd) = (fast.mean_damping_ratio, full.mean_damping_ratio);
            assert!(
                (zf - zd).abs() <= 1e-9 * crate::measure::nan_max(zd.abs(), 1e-3),
                "{zf} vs {zd}"
            );
        }
        assert!(
            2 * near_used >= solves,
            "shift-invert used at {near_used} of {solves} solves"
        );
    }
}
