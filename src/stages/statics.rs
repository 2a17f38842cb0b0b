//! Stage 3: the static preload. Pairs the contact surfaces once, solves the nonlinear static
//! equilibrium under the brake pressure with the disc sliding, and assembles the symmetric
//! tangent K0 + K_c + K_stick of that state (the real modes' stiffness).

use super::model::Model;
use super::operators::Operators;
use super::{RunError, Timings};
use crate::contact::kernel::Part;
use crate::contact::linearize::Base;
use crate::contact::{ContactModel, ContactSettings};
use crate::la::{Petsc, SparseMatrix, Vector};
use crate::statics::{StaticSettings, StaticState};

/// The preloaded state and what it was computed with.
pub struct Preloaded<'p> {
    pub contact: ContactModel<'p>,
    pub state: StaticState<'p>,
    /// The external load (brake pressure on the piston and fingers), N.
    pub load: Vector<'p>,
    /// K0 + K_c + K_stick at the static state (symmetric).
    pub tangent: SparseMatrix<'p>,
    pub contact_settings: ContactSettings,
}

/// Pairs, solves and linearizes; each part timed in `timings`. Newton progress lines go to
/// stdout on rank 0.
///
/// # Collective
pub fn preload<'p>(
    petsc: &'p Petsc,
    model: &Model,
    ops: &Operators<'p>,
    contact_settings: &ContactSettings,
    settings: &StaticSettings,
    timings: &mut Timings,
) -> Result<Preloaded<'p>, RunError> {
    let Some(dofs) = &ops.dofs else {
        return Err(RunError::scene(
            "statics",
            "the static preload needs a mesh model (not user matrices)",
        ));
    };
    if model.interfaces.is_empty() {
        return Err(RunError::scene(
            "statics",
            "the model has no contact interfaces (a brake model or an .inp with *CONTACT PAIR has them)",
        ));
    }
    let interfaces = contact_settings
        .resolve(&model.interfaces)
        .map_err(RunError::Setting)?;
    let contact = timings.stage("contact pairing", || {
        ContactModel::new(petsc, &model.mesh, dofs, interfaces, contact_settings)
    })?;
    let load =
        crate::statics::pressure_load(petsc, &model.mesh, dofs, &model.loads, model.pressure)?;
    // Every Newton iteration for a person watching; the summary has the totals.
    let verbose = petsc.rank() == 0 && crate::progress::interactive();
    let state = timings.stage("static preload", || {
        crate::statics::solve(petsc, &ops.k0, &contact, &load, settings, None, |r| {
            if verbose {
                println!(
                    "  static step {} (pressure {:>3.0} %, friction {:>3.0} %) iteration {:>2}: residual {:.3e} N (of {:.3e}){}",
                    r.load_step,
                    100.0 * r.pressure_fraction,
                    100.0 * r.friction_fraction,
                    r.iteration,
                    r.residual,
                    r.reference,
                    if r.step_length > 0.0 && r.step_length < 1.0 { format!(", step {:.3}", r.step_length) } else { String::new() }
                );
            }
        })
    })?;
    let tangent = timings.stage("tangent state", || -> Result<SparseMatrix<'p>, RunError> {
        let kt = contact.linearize(
            petsc,
            Base::Plus(&ops.k0),
            &state.contact,
            &[Part::Normal, Part::Stick],
        )?;
        kt.set_symmetric(true)?;
        Ok(kt)
    })?;
    Ok(Preloaded {
        contact,
        state,
        load,
        tangent,
        contact_settings: contact_settings.clone(),
    })
}
