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

use crate::invalid::InvalidSetting;
use std::time::Instant;

/// Why a pseudo trajectory cannot be followed.
#[derive(Debug, thiserror::Error)]
pub enum PseudoError {
    #[error(transparent)]
    Dense(#[from] crate::la::DenseError),
    #[error(transparent)]
    La(#[from] crate::la::LaError),
    #[error(
        "{mode} does not move the contact points (contact amplitude {amplitude:.3e}): no pseudo trajectory"
    )]
    NoContactMotion { mode: String, amplitude: f64 },
    #[error("the mode's contact motion has one phase only (a real shape): no orbit to fit")]
    RealShape,
    #[error("{0} has a NaN or infinite entry")]
    NotFinite(&'static str),
}

use serde::{Deserialize, Serialize};

use super::pseudo_period::period;
pub use super::pseudo_period::{Cost, Period, Sampling, Start};
use crate::eigen::complex_modes::{Complex, DenseEigenpair};

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
    /// How often the step between two phases may be halved where the mode is not followed
    /// with MAC >= 0.9 across it (the points between carry the tracking, not the
    /// statistics). 0 by default: on the small brake's C35 (250 modes) 3 halvings change
    /// nothing where the period closes and cost 4x; where it does not, they give another
    /// answer, as more phases do, which is what shows the answer there is not resolved.
    #[serde(default = "default_halvings")]
    pub halvings: usize,
    /// Relative tolerance of the bisections for alpha_crit and alpha_sat. 1 % by default:
    /// what the phase count leaves is larger (the default scene's C35: alpha_sat 463 um at 32
    /// phases, 21.5 um at 64 and 128), and each halving of it costs one period.
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
fn default_halvings() -> usize {
    0
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
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        let key = "post.pseudo_trajectory";
        if self.alphas < 2 || self.phases < 4 {
            return Err(InvalidSetting::new(
                key,
                format!(
                    ": alphas = {} and phases = {}: need at least 2 and 4",
                    self.alphas, self.phases
                ),
            ));
        }
        if self.halvings > 8 {
            return Err(InvalidSetting::new(
                format!("{key}.halvings"),
                format!(
                    " = {}: at most 8 (a step of 1/256 of the phase spacing); raise phases instead",
                    self.halvings
                ),
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return Err(InvalidSetting::new(
                format!("{key}.tolerance"),
                format!(" = {}: a relative tolerance in (0, 0.5)", self.tolerance),
            ));
        }
        if let Some([a, b]) = self.alpha_range {
            if !(a > 0.0 && b > a && b.is_finite()) {
                return Err(InvalidSetting::new(
                    format!("{key}.alpha_range"),
                    format!(" = [{a}, {b}]: give 0 < first < last (m)"),
                ));
            }
        }
        if let Some(a) = self.diagram_alpha {
            if !(a > 0.0 && a.is_finite()) {
                return Err(InvalidSetting::new(
                    format!("{key}.diagram_alpha"),
                    format!(" = {a}: an amplitude > 0 (m)"),
                ));
            }
        }
        match (&self.modes, self.most_unstable) {
            (Some(_), Some(_)) => {
                return Err(InvalidSetting::new(
                    key,
                    ": give either 'modes' or 'most_unstable', not both",
                ))
            }
            (None, Some(0)) => {
                return Err(InvalidSetting::new(
                    format!("{key}.most_unstable"),
                    " = 0: at least one mode (or leave the key out for all)",
                ))
            }
            _ => {}
        }
        if let Some(modes) = &self.modes {
            if let Some(bad) = modes.iter().find(|m| parse_mode(m).is_none()) {
                return Err(InvalidSetting::new(
                    format!("{key}.modes"),
                    format!(": '{bad}' is not a complex mode's name (C1, C2, ...)"),
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
    /// The factor c of psi = y / c for the shape with coordinates y: |c| is the largest
    /// relative displacement at a contact point, and its phase makes the largest of gap and
    /// slips at that point real and positive in psi. So phase 0 is the same instant of the
    /// motion whatever the phase of y, which the eigensolver leaves to the signs of the real
    /// modes (1 and 2 ranks chose opposite ones for the brake's C35 at 250 modes, and the
    /// pseudo trajectory's statistics can depend on the phase where a period starts).
    fn contact_normalization(&self, y: &[Complex]) -> Result<Complex, PseudoError>;
    /// The tangent at q_static + Re(alpha psi e^{i theta}), qdot = Re(i omega alpha psi
    /// e^{i theta}), psi given by its coordinates.
    fn linearize(
        &self,
        psi: &[Complex],
        omega: f64,
        alpha: f64,
        theta: f64,
    ) -> Result<Linearized, PseudoError>;
    /// Contact-law scale of the static state (m): the pressure-weighted mean of p / k_c over
    /// the points in contact (1 / lambda for the exponential law).
    fn gap_scale(&self) -> f64;
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
    /// psi = y / normalization for the unit-norm coordinates y of the complex-mode solver.
    pub normalization: Complex,
    pub sweep: Vec<Period>,
    pub alpha_crit: Found,
    pub alpha_sat: Found,
    /// Where the mean damping stays non-negative up to the end of the sweep (the last
    /// crossing; the same as alpha_sat when it crosses once), and how often it changes sign
    /// on the sweep's grid. A mean damping that hovers near zero above alpha_sat (found on the
    /// brake: within 4e-4 over a decade) makes the first crossing sensitive to the phase count
    /// (the default scene's C35: 463 um at 32 phases, 21.5 um at 64 and 128); the interval
    /// between the two is what can be said.
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

/// Log-spaced amplitudes over `[a, b]`.
pub fn log_space(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| a * (b / a).powf(k as f64 / (n - 1).max(1) as f64))
        .collect()
}

/// Bisection in log(alpha) for the first amplitude where `crosses` turns true, between
/// `lo` (false) and `hi` (true), to relative width `tolerance`; with the periods evaluated.
/// Bisection, not a secant method: the mean damping is rough in alpha (it can jump and cross
/// zero several times within one grid interval), and regula falsi (Illinois, tried) saved
/// little there (benches/decisions-results.md, "pseudo-bisection").
fn bisect(
    lo: &Period,
    hi: &Period,
    tolerance: f64,
    mut evaluate: impl FnMut(f64, Start<'_>) -> Result<Period, PseudoError>,
    crosses: impl Fn(&Period) -> bool,
) -> Result<(Found, Vec<Period>), PseudoError> {
    let (mut lo, mut hi_alpha) = (lo.clone(), hi.alpha);
    let mut evaluated = Vec::new();
    while hi_alpha / lo.alpha > 1.0 + tolerance {
        let mid = (lo.alpha * hi_alpha).sqrt();
        let p = evaluate(mid, lo.start())?;
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
    evaluate: impl FnMut(f64, Start<'_>) -> Result<Period, PseudoError>,
    crosses: impl Fn(&Period) -> bool,
) -> Result<(Found, Vec<Period>), PseudoError> {
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

/// psi = y / c, the shape of coordinates `y` at contact amplitude 1 with its phase fixed by
/// the system (`PseudoSystem::contact_normalization`), and c.
pub fn unit_contact_shape(
    system: &dyn PseudoSystem,
    name: &str,
    y: &[Complex],
) -> Result<(Vec<Complex>, Complex), PseudoError> {
    let normalization = system.contact_normalization(y)?;
    let scale = normalization.0.hypot(normalization.1);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(PseudoError::NoContactMotion {
            mode: name.to_string(),
            amplitude: scale,
        });
    }
    let (c, d) = (normalization.0 / scale, -normalization.1 / scale);
    let psi: Vec<Complex> = y
        .iter()
        .map(|&(r, i)| ((r * c - i * d) / scale, (r * d + i * c) / scale))
        .collect();
    Ok((psi, normalization))
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
) -> Result<PseudoTrajectory, PseudoError> {
    let clock = Instant::now();
    let (s, y) = &nominal[index];
    let pair: Vec<DenseEigenpair> = std::iter::once(index)
        .chain(partner(nominal, index))
        .map(|k| nominal[k].clone())
        .collect();
    let (psi, normalization) = unit_contact_shape(system, name, y)?;
    let omega = s.1;
    let [a, b] = settings.alpha_range.unwrap_or_else(|| {
        let g = system.gap_scale();
        [1e-3 * g, 10.0 * g]
    });
    let sampling = Sampling {
        phases: settings.phases,
        halvings: settings.halvings,
    };
    let (mut count, mut cost) = (0, Cost::default());
    let mut run = |alpha: f64, start: Start<'_>, until_stable: bool| {
        let p = period(
            system,
            &psi,
            omega,
            alpha,
            sampling,
            start,
            margin,
            true,
            until_stable,
        )?;
        count += p.linearizations();
        cost += p.cost;
        Ok::<Period, PseudoError>(p)
    };
    let mut sweep: Vec<Period> = Vec::with_capacity(settings.alphas);
    let nominal_start = Start {
        alpha: 0.0,
        pair: &pair,
    };
    for alpha in log_space(a, b, settings.alphas) {
        let p = run(
            alpha,
            sweep.last().map_or(nominal_start, Period::start),
            false,
        )?;
        sweep.push(p);
    }
    let tol = settings.tolerance;
    // alpha_crit's refinement asks of a period only whether it has a stable phase (its
    // periods are not kept): each stops at its first.
    let until_stable = |alpha: f64, start: Start<'_>| run(alpha, start, true);
    let (alpha_crit, _) = bracket_and_bisect(&sweep, tol, until_stable, Period::has_stable_phase)?;
    let mut evaluate = |alpha: f64, start: Start<'_>| run(alpha, start, false);
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
            evaluate(at, below.map_or(nominal_start, Period::start))?
        }
    };
    Ok(PseudoTrajectory {
        name: name.to_string(),
        nominal: *s,
        psi,
        normalization,
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
    pub fn new(psi: &[Complex], sum: impl Fn(&mut [f64])) -> Result<Self, PseudoError> {
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
            return Err(PseudoError::RealShape);
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
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
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
                (got.alpha - alpha).abs() < 1e-11 * crate::measure::nan_max(alpha, 1.0),
                "{got:?} vs {alpha}"
            );
            let norm2 = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
            let share = norm2(&motion) / norm2(&mixed);
            assert!((got.share - share).abs() < 1e-12, "{got:?} vs {share}");
        }
        assert!(OrbitFit::new(&[(1.0, 0.0), (2.0, 0.0)], |_| {}).is_err());
    }
}
