//! Contact and friction laws (DESIGN.md §2). Pressure is positive in compression, the gap
//! positive when open; tractions are per unit area, positive along the point's tangent on the
//! master (pad) side.

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

/// Normal law p(g) with its contact stiffness k_c = -dp/dg.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "lowercase", deny_unknown_fields)]
pub enum NormalLaw {
    /// p = p0 exp(-lambda g); below the gap `linear_below_gap` (a penetration, so negative;
    /// default where p = 1000 p0) it continues linearly with its slope there, so deep
    /// penetration never overflows.
    Exponential {
        p0: f64,
        lambda: f64,
        #[serde(default)]
        linear_below_gap: Option<f64>,
    },
    /// p = k max(0, -g).
    Linear { stiffness: f64 },
}

/// Pressure, contact stiffness -dp/dg and its derivative d(k_c)/dg at one gap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalState {
    pub pressure: f64,
    pub stiffness: f64,
    pub stiffness_slope: f64,
}

impl NormalLaw {
    /// The penetration where the exponential law turns linear.
    pub fn guard_gap(&self) -> Option<f64> {
        match *self {
            NormalLaw::Exponential {
                lambda,
                linear_below_gap,
                ..
            } => Some(linear_below_gap.unwrap_or(-(1000.0f64).ln() / lambda)),
            NormalLaw::Linear { .. } => None,
        }
    }

    pub fn eval(&self, g: f64) -> NormalState {
        match *self {
            NormalLaw::Exponential { p0, lambda, .. } => {
                let g_lin = self.guard_gap().unwrap();
                if g >= g_lin {
                    let p = p0 * (-lambda * g).exp();
                    NormalState {
                        pressure: p,
                        stiffness: lambda * p,
                        stiffness_slope: -lambda * lambda * p,
                    }
                } else {
                    let p_lin = p0 * (-lambda * g_lin).exp();
                    let k_lin = lambda * p_lin;
                    NormalState {
                        pressure: p_lin + k_lin * (g_lin - g),
                        stiffness: k_lin,
                        stiffness_slope: 0.0,
                    }
                }
            }
            NormalLaw::Linear { stiffness } => {
                if g < 0.0 {
                    NormalState {
                        pressure: -stiffness * g,
                        stiffness,
                        stiffness_slope: 0.0,
                    }
                } else {
                    NormalState {
                        pressure: 0.0,
                        stiffness: 0.0,
                        stiffness_slope: 0.0,
                    }
                }
            }
        }
    }

    /// Whether a point at gap g counts as open: no contact for the linear law, less than 1 %
    /// of p0 for the exponential one (its pressure never vanishes).
    pub fn is_open(&self, g: f64) -> bool {
        match *self {
            NormalLaw::Exponential { lambda, .. } => g > (100.0f64).ln() / lambda,
            NormalLaw::Linear { .. } => g >= 0.0,
        }
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        match *self {
            NormalLaw::Exponential {
                p0,
                lambda,
                linear_below_gap,
            } => {
                positive("p0", p0)?;
                positive("lambda", lambda)?;
                if let Some(g) = linear_below_gap {
                    if !(g.is_finite() && g < 0.0) {
                        let detail = format!(" = {g}: must be a negative gap (a penetration)");
                        return Err(InvalidSetting::new("linear_below_gap", detail));
                    }
                }
                Ok(())
            }
            NormalLaw::Linear { stiffness } => positive("stiffness", stiffness),
        }
    }
}

fn positive(key: &str, v: f64) -> Result<(), InvalidSetting> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        let detail = format!(" = {v}: must be positive and finite");
        Err(InvalidSetting::new(key, detail))
    }
}

fn non_negative(key: &str, v: f64) -> Result<(), InvalidSetting> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        let detail = format!(" = {v}: must be finite and not negative");
        Err(InvalidSetting::new(key, detail))
    }
}

/// Tangential law: friction along the sliding direction, or elastic stick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "lowercase", deny_unknown_fields)]
pub enum FrictionLaw {
    /// Regularized Coulomb: t = mu p tanh(w / slip_speed): DESIGN's min(k_t |w|, mu p) with
    /// k_t = mu p / slip_speed, its corner rounded (the same slope at w = 0 and the same
    /// limit, within 0.1 % of it from |w| = 3.8 slip_speed). The clamp is only C0: a Newton
    /// iterate whose sliding speed sits at the corner sees a tangent that jumps between
    /// k_t and 0, and the transient's iterations stalled there at every band crossing.
    Coulomb { mu: f64, slip_speed: f64 },
    /// t = mu p (2/pi) atan(w / slip_speed).
    Arctan { mu: f64, slip_speed: f64 },
    /// Velocity-dependent friction (Stribeck-like decay, a negative slope):
    /// mu(w) = mu_kinetic + (mu_static - mu_kinetic) exp(-|w| / decay_speed), regularized by
    /// (2/pi) atan(w / slip_speed).
    Stribeck {
        mu_static: f64,
        mu_kinetic: f64,
        decay_speed: f64,
        slip_speed: f64,
    },
    /// The joints between components: elastic stick in the tangent plane with stiffness
    /// mu k_c(g), smoothly limited by Coulomb's mu p(g): t = mu p tanh(|s|) s / |s| with
    /// s = (k_c / p) delta ([`FrictionLaw::stick_traction`]).
    Stick { mu: f64 },
    /// Frictionless.
    None,
}

/// Traction and its derivatives with respect to pressure and sliding speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Traction {
    pub traction: f64,
    pub d_pressure: f64,
    pub d_speed: f64,
}

/// The joints' traction and its derivatives ([`FrictionLaw::stick_traction`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StickTraction {
    pub traction: [f64; 2],
    /// dt_i / d delta_j and dt_i / dg.
    pub d_slip: [[f64; 2]; 2],
    pub d_gap: [f64; 2],
    /// |t| / (mu p), in [0, 1).
    pub saturation: f64,
}

impl FrictionLaw {
    /// Whether the law makes points slide (the disc interfaces) rather than stick elastically.
    pub fn is_sliding(&self) -> bool {
        !matches!(self, FrictionLaw::Stick { .. } | FrictionLaw::None)
    }

    /// The friction coefficient at high sliding speed (for torque checks and reports).
    pub fn mu(&self) -> f64 {
        match *self {
            FrictionLaw::Coulomb { mu, .. }
            | FrictionLaw::Arctan { mu, .. }
            | FrictionLaw::Stick { mu } => mu,
            FrictionLaw::Stribeck { mu_kinetic, .. } => mu_kinetic,
            FrictionLaw::None => 0.0,
        }
    }

    /// The speed below which a point counts as sticking.
    pub fn slip_speed(&self) -> f64 {
        match *self {
            FrictionLaw::Coulomb { slip_speed, .. }
            | FrictionLaw::Arctan { slip_speed, .. }
            | FrictionLaw::Stribeck { slip_speed, .. } => slip_speed,
            _ => 0.0,
        }
    }

    /// Friction traction at pressure p and sliding speed w (sliding laws only; `Stick` and
    /// `None` give zero here, see [`FrictionLaw::stick_stiffness`]).
    pub fn traction(&self, p: f64, w: f64) -> Traction {
        let two_over_pi = 2.0 / std::f64::consts::PI;
        match *self {
            FrictionLaw::Coulomb { mu, slip_speed } => {
                let th = (w / slip_speed).tanh();
                Traction {
                    traction: mu * p * th,
                    d_pressure: mu * th,
                    d_speed: mu * p * (1.0 - th * th) / slip_speed,
                }
            }
            FrictionLaw::Arctan { mu, slip_speed } => {
                let s = w / slip_speed;
                let a = two_over_pi * s.atan();
                Traction {
                    traction: mu * p * a,
                    d_pressure: mu * a,
                    d_speed: mu * p * two_over_pi / (slip_speed * (1.0 + s * s)),
                }
            }
            FrictionLaw::Stribeck {
                mu_static,
                mu_kinetic,
                decay_speed,
                slip_speed,
            } => {
                let s = w / slip_speed;
                let a = two_over_pi * s.atan();
                let da = two_over_pi / (slip_speed * (1.0 + s * s));
                let e = (-w.abs() / decay_speed).exp();
                let mu = mu_kinetic + (mu_static - mu_kinetic) * e;
                let dmu = -(mu_static - mu_kinetic) * e / decay_speed * w.signum();
                Traction {
                    traction: mu * p * a,
                    d_pressure: mu * a,
                    d_speed: p * (dmu * a + mu * da),
                }
            }
            FrictionLaw::Stick { .. } | FrictionLaw::None => Traction {
                traction: 0.0,
                d_pressure: 0.0,
                d_speed: 0.0,
            },
        }
    }

    /// Tangential stiffness factor of elastic stick at small slip: traction = factor x k_c x
    /// delta.
    pub fn stick_stiffness(&self) -> f64 {
        match *self {
            FrictionLaw::Stick { mu } => mu,
            _ => 0.0,
        }
    }

    /// The joints' traction at the normal state `n` and tangential slip `delta`:
    /// t = mu p tanh(rho) s / rho with s = r delta, r = k_c / p, rho = |s|. At small slip it
    /// is the elastic stick mu k_c delta (the stiffness the modal stages use); it never
    /// exceeds Coulomb's mu p, so a joint cannot pass more tangential force than its pressure
    /// allows (an unlimited elastic stick lets a self-excited vibration grow without bound).
    /// Memoryless: the joint returns to its reference position when unloaded.
    ///
    /// Derivatives (with sech^2 = d tanh / d rho, psi = (phi' / rho), phi = tanh(rho) / rho):
    /// dt/d delta = mu k_c (phi I + psi s s^T); dt/dg = mu (p r' sech^2(rho) - k_c r phi) delta,
    /// r' = dr/dg = (k_c' p + k_c^2) / p^2 (0 for the exponential law, where r = lambda).
    pub fn stick_traction(&self, n: &NormalState, delta: [f64; 2]) -> StickTraction {
        let mu = self.stick_stiffness();
        let (p, k) = (n.pressure, n.stiffness);
        if mu == 0.0 || p <= 0.0 || k <= 0.0 {
            return StickTraction::default();
        }
        let r = k / p;
        // d(k/p)/dg = k'/p + (k/p)^2, not (k' p + k^2)/p^2: a joint open by ~2 mm has an
        // exponential pressure whose square underflows, and 0/0 put NaN into the 600k
        // superelement's projected operators at high pressure (2026-11-27).
        let dr = n.stiffness_slope / p + r * r;
        let s = [r * delta[0], r * delta[1]];
        let rho = s[0].hypot(s[1]);
        // phi = tanh(rho) / rho and psi = phi'(rho) / rho, by their series near 0.
        let (phi, psi, sech2) = if rho < 1e-3 {
            let r2 = rho * rho;
            (1.0 - r2 / 3.0, -2.0 / 3.0 + 8.0 * r2 / 15.0, 1.0 - r2)
        } else {
            let th = rho.tanh();
            let sech2 = 1.0 - th * th;
            (th / rho, (rho * sech2 - th) / (rho * rho * rho), sech2)
        };
        let d_slip = [
            [
                mu * k * (phi + psi * s[0] * s[0]),
                mu * k * psi * s[0] * s[1],
            ],
            [
                mu * k * psi * s[1] * s[0],
                mu * k * (phi + psi * s[1] * s[1]),
            ],
        ];
        let gap_factor = mu * (p * dr * sech2 - k * r * phi);
        StickTraction {
            traction: [mu * p * phi * s[0], mu * p * phi * s[1]],
            d_slip,
            d_gap: [gap_factor * delta[0], gap_factor * delta[1]],
            saturation: rho.tanh(),
        }
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        match *self {
            FrictionLaw::Coulomb { mu, slip_speed } | FrictionLaw::Arctan { mu, slip_speed } => {
                non_negative("mu", mu)?;
                positive("slip_speed", slip_speed)
            }
            FrictionLaw::Stribeck {
                mu_static,
                mu_kinetic,
                decay_speed,
                slip_speed,
            } => {
                non_negative("mu_static", mu_static)?;
                non_negative("mu_kinetic", mu_kinetic)?;
                positive("decay_speed", decay_speed)?;
                positive("slip_speed", slip_speed)
            }
            FrictionLaw::Stick { mu } => non_negative("mu", mu),
            FrictionLaw::None => Ok(()),
        }
    }
}

/// The sliding laws the tests exercise: Coulomb, arctan and Stribeck at typical values.
#[cfg(test)]
pub(crate) fn sample_sliding_laws(decay_speed: f64) -> [FrictionLaw; 3] {
    [
        FrictionLaw::Coulomb {
            mu: 0.4,
            slip_speed: 1e-3,
        },
        FrictionLaw::Arctan {
            mu: 0.4,
            slip_speed: 1e-3,
        },
        FrictionLaw::Stribeck {
            mu_static: 0.5,
            mu_kinetic: 0.35,
            decay_speed,
            slip_speed: 1e-3,
        },
    ]
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / crate::measure::nan_max(b.abs(), 1e-300)
    }

    /// Every derivative against a central difference (relative error below 1e-6), also at the
    /// exponential law's guard and beyond it, and for speeds crossing zero.
    #[test]
    fn law_tangents_match_central_differences() {
        let exp = NormalLaw::Exponential {
            p0: 1e6,
            lambda: 2e5,
            linear_below_gap: None,
        };
        let g_lin = exp.guard_gap().unwrap();
        for g in [
            3e-5,
            1e-6,
            0.0,
            -1e-5,
            0.5 * g_lin,
            1.001 * g_lin,
            0.999 * g_lin,
            -1.0,
        ] {
            let s = exp.eval(g);
            let h = 1e-9;
            let (sp, sm) = (exp.eval(g + h), exp.eval(g - h));
            let fd = -(sp.pressure - sm.pressure) / (2.0 * h);
            assert!(
                rel(fd, s.stiffness) < 1e-6,
                "g = {g}: {fd} vs {}",
                s.stiffness
            );
            let fd = (sp.stiffness - sm.stiffness) / (2.0 * h);
            if s.stiffness_slope != 0.0 {
                assert!(rel(fd, s.stiffness_slope) < 1e-6, "g = {g}");
            } else {
                assert!(fd.abs() < 1e-6 * s.stiffness / h, "g = {g}");
            }
            assert!(s.pressure.is_finite() && s.stiffness.is_finite());
        }
        // Deep penetration: finite, linear, continuous at the guard.
        let deep = exp.eval(-1.0);
        assert!(deep.pressure.is_finite() && deep.pressure > 0.0);
        let (a, b) = (
            exp.eval(g_lin * (1.0 + 1e-12)),
            exp.eval(g_lin * (1.0 - 1e-12)),
        );
        assert!(rel(a.pressure, b.pressure) < 1e-9 && rel(a.stiffness, b.stiffness) < 1e-9);

        let p = 8e5;
        for law in sample_sliding_laws(0.5) {
            for w in [-2.0, -3e-4, -1e-7, 0.0, 1e-7, 4e-4, 1.3] {
                let t = law.traction(p, w);
                let h = 1e-5 * crate::measure::nan_max(w.abs(), 1e-3);
                let fd_w =
                    (law.traction(p, w + h).traction - law.traction(p, w - h).traction) / (2.0 * h);
                let scale = crate::measure::nan_max(t.d_speed.abs(), 1e-3 * law.mu() * p);
                assert!(
                    (fd_w - t.d_speed).abs() < 1e-6 * scale,
                    "{law:?} w = {w}: {fd_w} vs {}",
                    t.d_speed
                );
                let hp = 1.0;
                let fd_p = (law.traction(p + hp, w).traction - law.traction(p - hp, w).traction)
                    / (2.0 * hp);
                assert!(
                    (fd_p - t.d_pressure).abs()
                        < 1e-6 * crate::measure::nan_max(t.d_pressure.abs(), 1e-6),
                    "{law:?} w = {w}"
                );
                // Friction opposes the relative motion and never exceeds mu_static p.
                assert!(t.traction * w >= 0.0 && t.traction.abs() <= 0.5 * p * (1.0 + 1e-12));
            }
        }
    }

    /// A joint point far open (the exponential pressure ~1e-255 Pa at 3 mm, whose square
    /// underflows) has a finite, vanishing traction and finite derivatives; nearer, the gap
    /// derivative matches a central difference.
    #[test]
    fn stick_traction_is_finite_far_open_and_its_gap_derivative_matches_differences() {
        let exp = NormalLaw::Exponential {
            p0: 1e6,
            lambda: 2e5,
            linear_below_gap: None,
        };
        let stick = FrictionLaw::Stick { mu: 0.2 };
        let delta = [3e-6, -1e-6];
        for g in [3e-3, 2.5e-3, 1.95e-3, 1e-3] {
            let t = stick.stick_traction(&exp.eval(g), delta);
            let all = [t.traction, t.d_gap, t.d_slip[0], t.d_slip[1]];
            assert!(
                all.iter().flatten().all(|x| x.is_finite()),
                "g = {g}: {t:?}"
            );
        }
        for g in [2e-5, 0.0, -2e-6] {
            let h = 1e-10;
            let t = stick.stick_traction(&exp.eval(g), delta);
            let (tp, tm) = (
                stick.stick_traction(&exp.eval(g + h), delta),
                stick.stick_traction(&exp.eval(g - h), delta),
            );
            for i in 0..2 {
                let fd = (tp.traction[i] - tm.traction[i]) / (2.0 * h);
                assert!(
                    rel(fd, t.d_gap[i]) < 1e-6,
                    "g = {g}: {fd} vs {}",
                    t.d_gap[i]
                );
            }
        }
    }
}
