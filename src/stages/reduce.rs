//! Stage 6: the hybrid superelement reduction. Every element touching a contact point is kept
//! (all interfaces: their forces act on kept DOFs only); the rest is reduced on the real modes
//! of the preloaded tangent and the static shape. The reduced model's real modes are checked
//! against the full ones.

use super::model::Model;
use super::operators::Operators;
use super::statics::Preloaded;
use crate::contact::kernel::Part;
use crate::contact::linearize::Base;
use crate::contact::{ContactError, ContactModel, ContactState};
use crate::eigen::real_modes::{real_modes, RealModeRequest, RealModes};
use crate::la::{LaError, Petsc, Vector};
use crate::measure::nan_max;
use crate::reduce::{ReducedModel, ReductionSettings};

/// Why the reduction could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ReductionError {
    #[error("key 'reduction': the reduction needs a mesh model (not user matrices)")]
    NoMesh,
    #[error("key 'reduction': the kept zone: {0}")]
    KeptZone(crate::mesh::MeshError),
    #[error("reduction: the contact model on the reduced unknowns: {0}")]
    Contact(#[from] ContactError),
    #[error(transparent)]
    La(#[from] LaError),
}

/// The reduced model with everything the time response needs in its unknowns.
pub struct Reduced<'p> {
    pub model: ReducedModel<'p>,
    pub contact: ContactModel<'p>,
    pub f_ext: Vector<'p>,
    pub q_static: Vector<'p>,
    pub static_state: ContactState,
    /// Representation error of the static state, ||q0 - T x0|| / ||q0||.
    pub static_error: f64,
    /// Real modes of the reduced tangent vs the full ones in the basis: (full Hz, reduced Hz).
    pub mode_check: Vec<(f64, f64)>,
    /// Below this frequency (Hz) a mode is rigid (the real modes' `rigid_below_hz`).
    pub rigid_below_hz: f64,
}

impl Reduced<'_> {
    /// The largest gap between a reduced and a full real mode, relative to the full mode's
    /// frequency or, for a rigid-body mode, to the rigid-body limit: a rigid mode's few mHz
    /// are round-off of a zero, so they agree when both stay well below the limit (NaN if any
    /// is NaN).
    pub fn mode_error(&self) -> f64 {
        self.mode_check
            .iter()
            .map(|(f, g)| (g - f).abs() / f.abs().max(self.rigid_below_hz))
            .fold(0.0, nan_max)
    }
}

/// # Collective
pub fn reduce<'p>(
    petsc: &'p Petsc,
    settings: &ReductionSettings,
    model: &Model,
    ops: &Operators<'p>,
    preload: &Preloaded<'p>,
    modes: &RealModes<'p>,
    extra_shapes: &[Vector<'p>],
) -> Result<Reduced<'p>, ReductionError> {
    let dofs = ops.dofs.as_ref().ok_or(ReductionError::NoMesh)?;
    let (contact, state) = (&preload.contact, &preload.state);
    let surfaces: Vec<&str> = contact
        .interfaces()
        .iter()
        .flat_map(|i| [i.master.as_str(), i.slave.as_str()])
        .collect();
    // The DOFs some contact point couples (every point is known on every rank).
    let mut coupled = vec![false; dofs.global_dofs()];
    for &d in contact.point_columns().iter().flatten() {
        if d >= 0 {
            coupled[d as usize] = true;
        }
    }
    let kept = crate::reduce::kept_dofs(&model.mesh, dofs, &surfaces, Some(&coupled))
        .map_err(ReductionError::KeptZone)?;
    let mut static_shapes: Vec<&Vector<'p>> = extra_shapes.iter().collect();
    if settings.static_shape {
        static_shapes.insert(0, &state.displacement);
    }
    let reduced = crate::reduce::reduce(
        petsc,
        &ops.k0,
        &ops.m,
        &kept,
        &modes.shapes,
        &static_shapes,
        settings,
    )?;
    let r = &reduced.reduction;
    let reduced_contact = contact.restricted(petsc, &r.map, r.columns.clone())?;
    let f_ext = r.project_force(petsc, &preload.load)?;
    let q_static = r.restrict(petsc, &state.displacement)?;
    let mut recovered = state.displacement.duplicate()?;
    r.recover(petsc, &q_static, &mut recovered)?;
    recovered.axpy(-1.0, &state.displacement)?;
    let static_error = recovered.norm2()? / state.displacement.norm2()?.max(f64::MIN_POSITIVE);
    let static_state = reduced_contact.evaluate(&q_static, None, state.contact.friction_scale)?;
    // The reduced tangent's real modes: those of the full model in the basis, exactly.
    let kt = reduced_contact.linearize(
        petsc,
        Base::Plus(&reduced.stiffness),
        &static_state,
        &[Part::Normal, Part::Stick],
    )?;
    kt.set_symmetric(true)?;
    let request = RealModeRequest {
        count: modes.shapes.len(),
        tolerance: 1e-10,
        ..Default::default()
    };
    let check = real_modes(petsc, &kt, &reduced.mass, false, &request, "reduced_")?;
    let mode_check = modes
        .frequencies_hz
        .iter()
        .copied()
        .zip(check.frequencies_hz.iter().copied())
        .collect();
    Ok(Reduced {
        model: reduced,
        contact: reduced_contact,
        f_ext,
        q_static,
        static_state,
        static_error,
        mode_check,
        rigid_below_hz: modes.rigid_below_hz,
    })
}
