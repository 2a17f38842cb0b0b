//! Pseudo complex-mode trajectories (DESIGN.md §2b; the paper's §3.3, figs. 12-14): from an
//! unstable complex mode alone, the amplitude at which it stops sustaining itself. Along
//! q = q_static + Re(alpha psi e^{i theta}), qdot = Re(i w alpha psi e^{i theta}) (w the
//! mode's nominal circular frequency, theta = w t over one period) the contact is linearized
//! at M phases and the mode followed by MAC; its damping ratio averaged over the phases turns
//! from negative (the mode grows) to positive at alpha_sat, the predicted saturation
//! amplitude; alpha_crit is the first amplitude at which it is stable over part of its period.
//! Both are bracketed on a log-spaced sweep and refined by bisection.
//!
//! psi is scaled so that the largest relative displacement at a contact point (gap and both
//! slips, the quantities the contact laws see) is 1: alpha is that displacement in metres.
//! The design said "the largest displacement of the contact zone"; the relative one is what
//! opens the contact, and a rigid motion of pad and disc together does not count.
//!
//! The model is reached through [`PseudoSystem`] (the brake's projected contact tangent, or a
//! closed-form model in the tests), so everything here is plain arithmetic on m x m matrices.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::eigen::complex_modes::{
    damping_ratio, frequency_hz, solve_dense, Complex, DenseEigenpair,
};
use crate::eigen::tracking::{
    nearest, pair_modes, pairs_from_all_eigenvalues, pairs_near_tracked, HINTS,
};

/// `[post.pseudo_trajectory]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PseudoTrajectorySettings {
    /// Nominal complex modes to follow ("C35", numbered by frequency as in the complex-modes
    /// stage's projected route); default: those unstable at the static state.
    #[serde(default)]
    pub modes: Option<Vec<String>>,
    /// Without `modes`: only this many of the unstable modes, the largest Re(s) first (a
    /// large model has many; each costs its own sweep).
    #[serde(default)]
    pub most_unstable: Option<usize>,
    /// Swept amplitudes alpha (m): [first, last]; default [1e-3, 10] x the static gap scale.
    #[serde(default)]
    pub alpha_range: Option<[f64; 2]>,
    /// Log-spaced amplitudes in the sweep.
    #[serde(default = "default_alphas")]
    pub alphas: usize,
    /// Phases per period.
    #[serde(default = "default_phases")]
    pub phases: usize,
    /// Relative tolerance of the bisections for alpha_crit and alpha_sat. 1 % by default:
    /// what the phase count leaves is larger (the brake's C35: alpha_sat 1.94e-5 m at 32
    /// phases, 2.03e-5 at 64, 1.52e-5 at 16), and each halving of it costs one period.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Amplitude (m) of the pseudo stability diagram; default alpha_sat (else the largest).
    #[serde(default)]
    pub diagram_alpha: Option<f64>,
}

fn default_alphas() -> usize {
    25
}
fn default_phases() -> usize {
    32
}
fn default_tolerance() -> f64 {
    1e-2
}

impl Default for PseudoTrajectorySettings {
    fn default() -> Self {
        toml::from_str("").expect("the defaults parse")
    }
}

impl PseudoTrajectorySettings {
    pub fn validate(&self) -> Result<(), String> {
        let key = "key 'post.pseudo_trajectory";
        if self.alphas < 2 || self.phases < 4 {
            return Err(format!(
                "{key}': alphas = {} and phases = {}: need at least 2 and 4",
                self.alphas, self.phases
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return Err(format!(
                "{key}.tolerance' = {}: a relative tolerance in (0, 0.5)",
                self.tolerance
            ));
        }
        if let Some([a, b]) = self.alpha_range {
            if !(a > 0.0 && b > a && b.is_finite()) {
                return Err(format!(
                    "{key}.alpha_range' = [{a}, {b}]: give 0 < first < last (m)"
                ));
            }
        }
        if let Some(a) = self.diagram_alpha {
            if !(a > 0.0 && a.is_finite()) {
                return Err(format!("{key}.diagram_alpha' = {a}: an amplitude > 0 (m)"));
            }
        }
        match (&self.modes, self.most_unstable) {
            (Some(_), Some(_)) => {
                return Err(format!(
                    "{key}': give either 'modes' or 'most_unstable', not both"
                ))
            }
            (None, Some(0)) => {
                return Err(format!(
                    "{key}.most_unstable' = 0: at least one mode (or leave the key out for all)"
                ))
            }
            _ => {}
        }
        if let Some(modes) = &self.modes {
            if let Some(bad) = modes.iter().find(|m| parse_mode(m).is_none()) {
                return Err(format!(
                    "{key}.modes': '{bad}' is not a complex mode's name (C1, C2, ...)"
                ));
            }
        }
        Ok(())
    }
}

/// "C35" -> index 34.
pub fn parse_mode(name: &str) -> Option<usize> {
    name.strip_prefix('C')?
        .parse::<usize>()
        .ok()?
        .checked_sub(1)
}

/// The tangent at one point of a pseudo trajectory.
#[derive(Debug, Clone)]
pub struct Linearized {
    /// Projected stiffness and damping, m x m column-major (unit projected mass).
    pub kp: Vec<f64>,
    pub cp: Vec<f64>,
    /// Fractions of the contact points open, sticking, sliding (all interfaces).
    pub fractions: [f64; 3],
    /// The status (0 open, 1 stick, 2 slide) of the sample point: the one where psi is
    /// largest.
    pub sample: u8,
}

/// A model along which pseudo trajectories are linearized (collective calls where the model
/// is distributed: every rank calls with the same arguments).
pub trait PseudoSystem {
    /// The largest relative displacement at a contact point of the shape with coordinates y.
    fn contact_amplitude(&self, y: &[Complex]) -> Result<f64, String>;
    /// The tangent at q_static + Re(alpha psi e^{i theta}), qdot = Re(i omega alpha psi
    /// e^{i theta}), psi given by its coordinates.
    fn linearize(
        &self,
        psi: &[Complex],
        omega: f64,
        alpha: f64,
        theta: f64,
    ) -> Result<Linearized, String>;
    /// Contact-law scale of the static state (m): the pressure-weighted mean of p / k_c over
    /// the points in contact (1 / lambda for the exponential law).
    fn gap_scale(&self) -> f64;
}

/// The mode followed over one period at one amplitude.
#[derive(Debug, Clone)]
pub struct Period {
    pub alpha: f64,
    /// The mode's eigenvalue at each phase (NaN where it was lost).
    pub eigenvalue: Vec<Complex>,
    /// The smallest MAC between successive phases.
    pub min_mac: f64,
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
    /// Phases whose eigenpairs needed the full dense solve (see [`pairs_near_tracked`]).
    pub dense_solves: usize,
}

impl std::ops::AddAssign for Cost {
    fn add_assign(&mut self, other: Cost) {
        self.linearize_seconds += other.linearize_seconds;
        self.near_shift_seconds += other.near_shift_seconds;
        self.dense_seconds += other.dense_seconds;
        self.dense_solves += other.dense_solves;
    }
}

impl Period {
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| frequency_hz(s)).collect()
    }
    pub fn damping_ratios(&self) -> Vec<f64> {
        self.eigenvalue.iter().map(|&s| damping_ratio(s)).collect()
    }
    fn has_stable_phase(&self) -> bool {
        self.unstable_fraction < 1.0
    }
}

/// A bisection's result: the amplitude, and whether the sweep bracketed it (else it lies
/// outside the swept range, on the side `below`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Found {
    At { alpha: f64, evaluations: usize },
    BelowRange,
    AboveRange,
}

impl Found {
    pub fn alpha(&self) -> Option<f64> {
        match self {
            Found::At { alpha, .. } => Some(*alpha),
            _ => None,
        }
    }
}

/// One mode's pseudo-trajectory study.
#[derive(Debug, Clone)]
pub struct PseudoTrajectory {
    /// The mode's name, nominal eigenvalue and coordinates of psi (contact amplitude 1).
    pub name: String,
    pub nominal: Complex,
    pub psi: Vec<Complex>,
    /// psi = y / scale for the unit-norm coordinates y of the complex-mode solver.
    pub scale: f64,
    pub sweep: Vec<Period>,
    pub alpha_crit: Found,
    pub alpha_sat: Found,
    /// Where the mean damping stays non-negative up to the end of the sweep (the last
    /// crossing; the same as alpha_sat when it crosses once), and how often it changes sign
    /// on the sweep's grid. A mean damping that hovers near zero above alpha_sat (found on the
    /// brake: within 4e-4 over a decade) makes the first crossing sensitive to round-off
    /// (4.3e-6 and 2.1e-5 m for the same mode in two runs whose real modes differed in their
    /// last bits); the interval between the two is what can be said.
    pub alpha_stable: Found,
    pub sign_changes: usize,
    /// The periods the bisections for alpha_sat and alpha_stable evaluated, by amplitude:
    /// where the mean damping was found to cross zero (between two grid amplitudes it can
    /// jump, so the sweep's line does not show the crossing).
    pub refinement: Vec<Period>,
    /// The pseudo stability diagram: the period at the diagram's amplitude.
    pub diagram: Period,
    pub linearizations: usize,
    pub cost: Cost,
    pub seconds: f64,
}

/// Follows the mode and its coupling partner over one period at `alpha`, starting from
/// `start` (the pair at phase 0 of a nearby amplitude); `near`: the eigenpairs near the pair
/// by shift-invert where that provably gives the same pairing ([`pairs_near_tracked`]), else
/// (and always without `near`) the full dense solve. Where the pair splits (the contact state
/// decouples it) the two continuations have nearly the same shape and either may be "the mode": the pair's least stable member is taken, a continuous function of the state
/// whichever member the MAC pairing follows (so the mean over the period is continuous in
/// alpha and a bisection on it well posed). `until_stable`: stop at the first stable phase
/// (all the bisection for alpha_crit asks of a period that has one; the statistics then
/// cover the phases evaluated).
#[allow(clippy::too_many_arguments)] // the period's definition and how its modes are solved
fn period(
    system: &dyn PseudoSystem,
    psi: &[Complex],
    omega: f64,
    alpha: f64,
    phases: usize,
    start: &[DenseEigenpair],
    margin: f64,
    near: bool,
    until_stable: bool,
) -> Result<Period, String> {
    let m = psi.len();
    let mut current = start.to_vec();
    // The eigenpairs found near the pair at the previous phase: the next phase's start block.
    let mut hints: Vec<DenseEigenpair> = Vec::new();
    let mut out = Period {
        alpha,
        eigenvalue: Vec::with_capacity(phases),
        min_mac: 1.0,
        unstable_fraction: 0.0,
        mean_damping_ratio: 0.0,
        fractions: Vec::with_capacity(phases),
        sample: Vec::with_capacity(phases),
        start: start.to_vec(),
        cost: Cost::default(),
    };
    for k in 0..phases {
        let theta = 2.0 * std::f64::consts::PI * k as f64 / phases as f64;
        let clock = Instant::now();
        let lin = system.linearize(psi, omega, alpha, theta)?;
        out.cost.linearize_seconds += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let found = if near {
            pairs_near_tracked(m, &lin.kp, &lin.cp, &current, &hints)?
        } else {
            None
        };
        out.cost.near_shift_seconds += clock.elapsed().as_secs_f64();
        let pairs = match found {
            Some(pairs) => pairs,
            None => {
                let clock = Instant::now();
                let pairs = if near {
                    pairs_from_all_eigenvalues(m, &lin.kp, &lin.cp, &current)?
                } else {
                    solve_dense(m, &lin.kp, &lin.cp)?
                };
                out.cost.dense_seconds += clock.elapsed().as_secs_f64();
                out.cost.dense_solves += 1;
                pairs
            }
        };
        hints = nearest(&pairs, &current, HINTS);
        out.fractions.push(lin.fractions);
        out.sample.push(lin.sample);
        let next: Option<Vec<(usize, f64)>> = pair_modes(&current, &pairs).into_iter().collect();
        match next {
            Some(next) => {
                for &(_, mac) in &next {
                    out.min_mac = out.min_mac.min(mac);
                }
                current = next.iter().map(|&(j, _)| pairs[j].clone()).collect();
                let least_stable = current
                    .iter()
                    .map(|p| p.0)
                    .min_by(|a, b| damping_ratio(*a).total_cmp(&damping_ratio(*b)))
                    .unwrap_or((f64::NAN, f64::NAN));
                out.eigenvalue.push(least_stable);
                if until_stable && damping_ratio(least_stable) >= -margin {
                    break;
                }
            }
            None => {
                out.min_mac = f64::NAN;
                out.eigenvalue.push((f64::NAN, f64::NAN));
            }
        }
        if k == 0 {
            out.start = current.clone();
        }
    }
    let zeta = out.damping_ratios();
    let evaluated = zeta.len() as f64;
    // A lost phase counts as unstable and makes the mean NaN: nothing is concluded from it.
    out.unstable_fraction =
        zeta.iter().filter(|z| z.is_nan() || **z < -margin).count() as f64 / evaluated;
    out.mean_damping_ratio = zeta.iter().sum::<f64>() / evaluated;
    Ok(out)
}

/// Log-spaced amplitudes over `[a, b]`.
pub fn log_space(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| a * (b / a).powf(k as f64 / (n - 1).max(1) as f64))
        .collect()
}

/// Bisection in log(alpha) for the first amplitude where `crosses` turns true, between
/// `lo` (false) and `hi` (true), to relative width `tolerance`; with the periods evaluated.
/// Bisection, not a secant method: the mean damping is rough in alpha (on the brake's C35 it
/// jumps by 4.5e-4 within 0.05 % of alpha near 1.84e-5 m and crosses zero three times in one
/// grid interval), and regula falsi (Illinois, tried) saved 1 of 10 periods there.
fn bisect(
    lo: &Period,
    hi: &Period,
    tolerance: f64,
    mut evaluate: impl FnMut(f64, &[DenseEigenpair]) -> Result<Period, String>,
    crosses: impl Fn(&Period) -> bool,
) -> Result<(Found, Vec<Period>), String> {
    let (mut lo, mut hi_alpha) = (lo.clone(), hi.alpha);
    let mut evaluated = Vec::new();
    while hi_alpha / lo.alpha > 1.0 + tolerance {
        let mid = (lo.alpha * hi_alpha).sqrt();
        let p = evaluate(mid, &lo.start)?;
        if crosses(&p) {
            hi_alpha = mid;
        } else {
            lo = p.clone();
        }
        evaluated.push(p);
    }
    Ok((
        Found::At {
            alpha: (lo.alpha * hi_alpha).sqrt(),
            evaluations: evaluated.len(),
        },
        evaluated,
    ))
}

/// The first grid amplitude where `crosses` holds, bisected against the one before.
fn bracket_and_bisect(
    sweep: &[Period],
    tolerance: f64,
    evaluate: impl FnMut(f64, &[DenseEigenpair]) -> Result<Period, String>,
    crosses: impl Fn(&Period) -> bool,
) -> Result<(Found, Vec<Period>), String> {
    match sweep.iter().position(&crosses) {
        None => Ok((Found::AboveRange, Vec::new())),
        Some(0) => Ok((Found::BelowRange, Vec::new())),
        Some(k) => bisect(&sweep[k - 1], &sweep[k], tolerance, evaluate, crosses),
    }
}

/// The coupling partner of nominal mode `index`: the other mode nearest in frequency (the
/// two modes of a mode-coupling flutter share their frequency), if there is one.
pub fn partner(nominal: &[DenseEigenpair], index: usize) -> Option<usize> {
    let f = nominal[index].0 .1;
    (0..nominal.len()).filter(|&k| k != index).min_by(|&a, &b| {
        (nominal[a].0 .1 - f)
            .abs()
            .total_cmp(&(nominal[b].0 .1 - f).abs())
    })
}

/// The pseudo-trajectory study of nominal mode `index` of the static state's modes
/// `nominal` (eigenvalues with coordinates), named `name`.
pub fn pseudo_trajectory(
    system: &dyn PseudoSystem,
    name: &str,
    nominal: &[DenseEigenpair],
    index: usize,
    settings: &PseudoTrajectorySettings,
    margin: f64,
) -> Result<PseudoTrajectory, String> {
    let clock = Instant::now();
    let (s, y) = &nominal[index];
    let pair: Vec<DenseEigenpair> = std::iter::once(index)
        .chain(partner(nominal, index))
        .map(|k| nominal[k].clone())
        .collect();
    let scale = system.contact_amplitude(y)?;
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(format!(
            "{name} does not move the contact points (contact amplitude {scale:.3e}): no pseudo trajectory"
        ));
    }
    let psi: Vec<Complex> = y.iter().map(|&(r, i)| (r / scale, i / scale)).collect();
    let omega = s.1;
    let [a, b] = settings.alpha_range.unwrap_or_else(|| {
        let g = system.gap_scale();
        [1e-3 * g, 10.0 * g]
    });
    let phases = settings.phases;
    let (mut count, mut cost) = (0, Cost::default());
    let mut run = |alpha: f64, start: &[DenseEigenpair], until_stable: bool| {
        let p = period(
            system,
            &psi,
            omega,
            alpha,
            phases,
            start,
            margin,
            true,
            until_stable,
        )?;
        count += p.eigenvalue.len();
        cost += p.cost;
        Ok::<Period, String>(p)
    };
    let mut sweep: Vec<Period> = Vec::with_capacity(settings.alphas);
    for alpha in log_space(a, b, settings.alphas) {
        let start = sweep.last().map_or(&pair, |p| &p.start).clone();
        sweep.push(run(alpha, &start, false)?);
    }
    let tol = settings.tolerance;
    // alpha_crit's refinement asks of a period only whether it has a stable phase (its
    // periods are not kept): each stops at its first.
    let until_stable = |alpha: f64, start: &[DenseEigenpair]| run(alpha, start, true);
    let (alpha_crit, _) = bracket_and_bisect(&sweep, tol, until_stable, Period::has_stable_phase)?;
    let mut evaluate = |alpha: f64, start: &[DenseEigenpair]| run(alpha, start, false);
    let crosses = |p: &Period| p.mean_damping_ratio >= 0.0;
    let (alpha_sat, mut near_sat) = bracket_and_bisect(&sweep, tol, &mut evaluate, crosses)?;
    let sign_changes = sweep
        .windows(2)
        .filter(|w| (w[0].mean_damping_ratio < 0.0) != (w[1].mean_damping_ratio < 0.0))
        .count();
    let first_crossing = sweep.iter().position(crosses);
    let mut refinement = Vec::new();
    let alpha_stable = match sweep
        .iter()
        .rposition(|p| p.mean_damping_ratio.is_nan() || p.mean_damping_ratio < 0.0)
    {
        None => Found::BelowRange,
        Some(j) if j + 1 == sweep.len() => Found::AboveRange,
        // The last crossing is the first: its bracket was refined above.
        Some(j) if Some(j + 1) == first_crossing => alpha_sat,
        Some(j) => {
            let (lo, hi) = (&sweep[j], &sweep[j + 1]);
            let (found, periods) = bisect(lo, hi, tol, &mut evaluate, crosses)?;
            refinement.extend(periods);
            found
        }
    };
    refinement.extend(near_sat.iter().cloned());
    refinement.sort_by(|a, b| a.alpha.total_cmp(&b.alpha));
    // The diagram at alpha_sat: the period the refinement evaluated within the tolerance of
    // it, when there is one (one period fewer), else a new one.
    let at = settings.diagram_alpha.or(alpha_sat.alpha()).unwrap_or(b);
    let close = |p: &Period| (p.alpha / at).ln().abs() <= 0.5 * (1.0 + tol).ln();
    let reuse = match settings.diagram_alpha {
        None => near_sat
            .iter()
            .position(close)
            .map(|k| near_sat.swap_remove(k)),
        Some(_) => None,
    };
    let diagram = match reuse {
        Some(p) => p,
        None => {
            let below = sweep.iter().rev().find(|p| p.alpha <= at);
            let start = below.map_or(&pair, |p| &p.start).clone();
            evaluate(at, &start)?
        }
    };
    Ok(PseudoTrajectory {
        name: name.to_string(),
        nominal: *s,
        psi,
        scale,
        sweep,
        alpha_crit,
        alpha_sat,
        alpha_stable,
        sign_changes,
        refinement,
        diagram,
        linearizations: count,
        cost,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The amplitude of a complex mode in recorded motion, in the pseudo trajectory's units: the
/// relative displacement at the contact points (gap and slips, each rank's points), about the
/// orbit's centre, fitted by Re(a C psi) in least squares; alpha = |a|. For motion in the mode
/// alone it is exact, at every instant. The contact observation is exact on a reduced model
/// (every contact DOF is kept) and does not depend on the real-mode basis, which a restart
/// recomputes (rotated within the disc's doublets: modal coordinates stored by the first run
/// would not match the new basis' psi). Two other definitions were tried and dropped: the
/// decomposition on all first-order modes with left eigenvectors is ill-conditioned near a
/// coalescence (a flutter pair's two coordinates grow and cancel; it gave C5 2.5 mm on the
/// brake's cycle), and the projection of the modal state depends on the basis.
pub struct OrbitFit {
    /// Re(C psi) and -Im(C psi): the motion of a = 1 and a = i.
    basis: [Vec<f64>; 2],
    gram: [f64; 3],
    inverse: [[f64; 2]; 2],
}

/// The fit at one instant: the mode's amplitude, and the share of the motion's squared norm
/// the fitted mode motion holds (1: the motion is the mode's; small: the mode is a small part
/// of it, and its amplitude says little about the motion).
#[derive(Debug, Clone, Copy)]
pub struct Fitted {
    pub alpha: f64,
    pub share: f64,
}

impl OrbitFit {
    /// `psi`: the observed shape at this rank's points; `sum`: adds numbers over the ranks.
    pub fn new(psi: &[Complex], sum: impl Fn(&mut [f64])) -> Result<Self, String> {
        let basis = [
            psi.iter().map(|p| p.0).collect::<Vec<f64>>(),
            psi.iter().map(|p| -p.1).collect::<Vec<f64>>(),
        ];
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let mut g = [
            dot(&basis[0], &basis[0]),
            dot(&basis[0], &basis[1]),
            dot(&basis[1], &basis[1]),
        ];
        sum(&mut g);
        let det = g[0] * g[2] - g[1] * g[1];
        if det.is_nan() || det <= 1e-12 * g[0] * g[2] {
            return Err(
                "the mode's contact motion has one phase only (a real shape): no orbit to fit"
                    .into(),
            );
        }
        Ok(OrbitFit {
            basis,
            gram: g,
            inverse: [[g[2] / det, -g[1] / det], [-g[1] / det, g[0] / det]],
        })
    }

    /// The mode in the observed motion x (this rank's part, centred).
    pub fn fit(&self, x: &[f64], sum: impl Fn(&mut [f64])) -> Fitted {
        let [u, w] = &self.basis;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        let mut rhs = [dot(u, x), dot(w, x), dot(x, x)];
        sum(&mut rhs);
        let a_r = self.inverse[0][0] * rhs[0] + self.inverse[0][1] * rhs[1];
        let a_i = self.inverse[1][0] * rhs[0] + self.inverse[1][1] * rhs[1];
        let g = &self.gram;
        let fitted = a_r * a_r * g[0] + 2.0 * a_r * a_i * g[1] + a_i * a_i * g[2];
        Fitted {
            alpha: a_r.hypot(a_i),
            share: if rhs[2] > 0.0 {
                fitted / rhs[2]
            } else {
                f64::NAN
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_names_parse_and_log_space_spans_the_range() {
        assert_eq!(parse_mode("C35"), Some(34));
        assert_eq!(parse_mode("C0"), None);
        assert_eq!(parse_mode("R3"), None);
        let a = log_space(1e-3, 10.0, 5);
        assert!((a[0] - 1e-3).abs() < 1e-18 && (a[4] - 10.0).abs() < 1e-12);
        assert!((a[2] - 0.1).abs() < 1e-14);
    }

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
        fn contact_amplitude(&self, _: &[Complex]) -> Result<f64, String> {
            Ok(1.0)
        }
        fn linearize(
            &self,
            _: &[Complex],
            _: f64,
            alpha: f64,
            theta: f64,
        ) -> Result<Linearized, String> {
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
        let mut near_used = 0;
        for alpha in [1e-6, 0.1, 0.5, 1.0] {
            let run = |near| {
                period(
                    &chain, &pair[0].1, omega, alpha, 32, &pair, 0.0, near, false,
                )
            };
            let (fast, full) = (run(true).unwrap(), run(false).unwrap());
            assert_eq!(full.cost.dense_solves, 32);
            near_used += 32 - fast.cost.dense_solves;
            for (k, (a, b)) in fast.eigenvalue.iter().zip(&full.eigenvalue).enumerate() {
                let d = (a.0 - b.0).hypot(a.1 - b.1) / b.0.hypot(b.1);
                assert!(
                    d <= 1e-9,
                    "alpha {alpha}, phase {k}: {a:?} vs {b:?} ({d:.1e})"
                );
            }
            let (zf, zd) = (fast.mean_damping_ratio, full.mean_damping_ratio);
            assert!((zf - zd).abs() <= 1e-9 * zd.abs().max(1e-3), "{zf} vs {zd}");
        }
        assert!(
            near_used >= 64,
            "shift-invert used at {near_used} of 128 phases"
        );
    }

    fn cmul(a: Complex, b: Complex) -> Complex {
        (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
    }

    /// Motion in one mode: the amplitude fitted at any instant is the one put in, and
    /// adding motion orthogonal to the mode's two phases changes nothing.
    #[test]
    fn orbit_fit_recovers_the_amplitude_of_motion_in_the_mode() {
        let psi = [(0.3, -0.2), (1.0, 0.0), (-0.4, 0.7), (0.1, 0.05)];
        let fit = OrbitFit::new(&psi, |_| {}).unwrap();
        let other = [0.5, -0.1, 0.2, 1.0];
        // Make `other` orthogonal to Re(psi) and Im(psi) (Gram-Schmidt).
        let [u, w] = &fit.basis;
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let (uu, uw, ww) = (dot(u, u), dot(u, w), dot(w, w));
        let (eu, ew) = (dot(&other, u), dot(&other, w));
        let det = uu * ww - uw * uw;
        let (x, z) = ((eu * ww - ew * uw) / det, (ew * uu - eu * uw) / det);
        let orthogonal: Vec<f64> = (0..4).map(|k| other[k] - x * u[k] - z * w[k]).collect();
        for (alpha, phase) in [(1e-6, 0.3), (2.5, 2.0), (0.7, -1.2)] {
            let c = (alpha * f64::cos(phase), alpha * f64::sin(phase));
            let motion: Vec<f64> = psi.iter().map(|&p| cmul(c, p).0).collect();
            let got = fit.fit(&motion, |_| {}).alpha;
            assert!((got - alpha).abs() < 1e-12 * alpha, "{got} vs {alpha}");
            assert!((fit.fit(&motion, |_| {}).share - 1.0).abs() < 1e-12);
            let mixed: Vec<f64> = (0..4).map(|k| motion[k] + 3.0 * orthogonal[k]).collect();
            let got = fit.fit(&mixed, |_| {});
            assert!(
                (got.alpha - alpha).abs() < 1e-11 * alpha.max(1.0),
                "{got:?} vs {alpha}"
            );
            let norm2 = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
            let share = norm2(&motion) / norm2(&mixed);
            assert!((got.share - share).abs() < 1e-12, "{got:?} vs {share}");
        }
        assert!(OrbitFit::new(&[(1.0, 0.0), (2.0, 0.0)], |_| {}).is_err());
    }
}
