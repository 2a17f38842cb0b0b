//! Stage 5a: complex modes of the tangent state, by the projected route (dense, on the real
//! modes, contact re-projected through the observation rows) and/or the full route (SLEPc PEP).

use super::modes::symmetric_stiffness;
use super::operators::Operators;
use super::statics::Preloaded;
use super::{RunError, Timings};
use crate::contact::kernel::Part;
use crate::contact::linearize::Base;
use crate::eigen::complex_modes::{
    project_operators, ComplexMode, ComplexModeSettings, ComplexModes, DampingSettings, Route,
};
use crate::eigen::real_modes::RealModes;
use crate::eigen::stability::ProjectedStability;
use crate::la::{LaError, Petsc, SparseMatrix};
use crate::measure::nan_max;

/// Why the complex modes could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum ComplexModesError {
    #[error("key 'complex_modes': no tangent state (add [statics]) and no user matrices")]
    NoTangent,
    #[error("key 'complex_modes': the projected route needs [real_modes]")]
    NoRealModes,
    #[error(
        "projected complex modes: the real modes are not M-orthonormal (|Phi^T M Phi - I| = {deviation:.1e})"
    )]
    NotOrthonormal { deviation: f64 },
    #[error(transparent)]
    La(#[from] LaError),
}

pub fn route_name(route: Route) -> &'static str {
    match route {
        Route::Projected => "projected",
        Route::Full => "full",
        Route::Both => "both",
    }
}

/// The complex modes of every route the settings ask for (projected first).
///
/// # Collective
pub fn complex_modes<'p>(
    petsc: &'p Petsc,
    settings: &ComplexModeSettings,
    damping: &DampingSettings,
    ops: &Operators<'p>,
    preload: Option<&Preloaded<'p>>,
    modes: Option<&RealModes<'p>>,
    timings: &mut Timings,
) -> Result<Vec<ComplexModes<'p>>, RunError> {
    let (kf, cf) = timings.stage("complex operators", || -> Result<_, RunError> {
        Ok(quadratic_operators(petsc, damping, ops, preload)?)
    })?;
    let quadratic = crate::eigen::complex_modes::Operators::new(&kf, &cf, &ops.m)?;
    let mut out = Vec::new();
    if settings.method != Route::Full {
        let modes = modes.ok_or(ComplexModesError::NoRealModes)?;
        let (kp, cp) = timings.time(
            "complex modes projection",
            || -> Result<(Vec<f64>, Vec<f64>), ComplexModesError> {
                match preload {
                    Some(p) => {
                        let world = petsc.world();
                        let stability = ProjectedStability::new(
                            world,
                            &p.contact,
                            modes,
                            &p.state.contact,
                            *damping,
                        )?;
                        Ok(stability.operators_at(world, &p.contact, &p.state.contact))
                    }
                    None => {
                        let (kp, cp, mp) = project_operators(&quadratic, &modes.shapes)?;
                        let n = modes.shapes.len();
                        let deviation = (0..n * n)
                            .map(|i| (mp[i] - f64::from(u8::from(i % (n + 1) == 0))).abs())
                            .fold(0.0f64, nan_max);
                        // NaN-aware: a NaN deviation is no orthonormality.
                        if deviation.is_nan() || deviation > 1e-8 {
                            return Err(ComplexModesError::NotOrthonormal { deviation });
                        }
                        Ok((kp, cp))
                    }
                }
            },
        )?;
        let projected = timings.stage("complex modes (projected)", || -> Result<_, RunError> {
            let quadratic = Some(&quadratic);
            let (shapes, kp, cp) = (&modes.shapes, &kp, &cp);
            Ok(crate::eigen::complex_modes::projected(
                shapes, kp, cp, quadratic, settings,
            )?)
        })?;
        out.push(projected);
    }
    if settings.method != Route::Projected {
        let default_count = modes.map_or(20, |m| m.shapes.len());
        let full = timings.stage("complex modes (full)", || -> Result<_, RunError> {
            let count = default_count;
            Ok(crate::eigen::complex_modes::full(
                petsc, &quadratic, settings, count,
            )?)
        })?;
        out.push(full);
    }
    for route in &out {
        let finite = |m: &&ComplexMode| m.eigenvalue.0.is_finite() && m.eigenvalue.1.is_finite();
        if let Some(bad) = route.modes.iter().find(|m| !finite(m)) {
            return Err(RunError::ComplexNotFinite {
                route: format!("{:?}", route.route),
                mode: bad.name.clone(),
                eigenvalue: bad.eigenvalue,
            });
        }
    }
    Ok(out)
}

/// The full quadratic operators K = K0 + K_c + K_stick + K_f and C = alpha M + beta K0 + C_f
/// at the static state, or the user's (full stiffness, damping).
///
/// # Collective
pub fn quadratic_operators<'p>(
    petsc: &'p Petsc,
    damping: &DampingSettings,
    ops: &Operators<'p>,
    preload: Option<&Preloaded<'p>>,
) -> Result<(SparseMatrix<'p>, SparseMatrix<'p>), ComplexModesError> {
    match (preload, &ops.user_complex) {
        (Some(p), _) => {
            let (contact, state) = (&p.contact, &p.state.contact);
            let kf = contact.linearize(
                petsc,
                Base::Plus(&ops.k0),
                state,
                &[
                    Part::Normal,
                    Part::Stick,
                    Part::Friction,
                    Part::StickCoupling,
                ],
            )?;
            let mut rayleigh = contact.joined_matrix(petsc, &ops.k0)?;
            rayleigh.scale(damping.rayleigh_beta)?;
            if damping.rayleigh_alpha != 0.0 {
                rayleigh.axpy(damping.rayleigh_alpha, &ops.m)?;
            }
            let cf = contact.linearize(petsc, Base::Plus(&rayleigh), state, &[Part::Damping])?;
            Ok((kf, cf))
        }
        (None, Some((k_full, c))) => {
            let kf = k_full.try_clone()?;
            let mut cf = match c {
                Some(c) => c.try_clone()?,
                None => {
                    let mut z = ops.m.try_clone()?;
                    z.zero_entries()?;
                    z
                }
            };
            if damping.rayleigh_beta != 0.0 {
                cf.axpy(damping.rayleigh_beta, symmetric_stiffness(ops, preload))?;
            }
            if damping.rayleigh_alpha != 0.0 {
                cf.axpy(damping.rayleigh_alpha, &ops.m)?;
            }
            Ok((kf, cf))
        }
        (None, None) => Err(ComplexModesError::NoTangent),
    }
}
