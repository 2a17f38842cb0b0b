//! Stage 4: the real modes of the symmetric stiffness: the preloaded tangent
//! K0 + K_c + K_stick when there is a static state, else K0 (free-free parts shifted).

use super::operators::Operators;
use super::statics::Preloaded;
use super::RunError;
use crate::eigen::real_modes::{RealModeRequest, RealModes};
use crate::la::{Petsc, SparseMatrix};

/// The stiffness whose modes are the real modes: the static tangent, or K0 without one.
pub fn symmetric_stiffness<'a, 'p>(
    ops: &'a Operators<'p>,
    preload: Option<&'a Preloaded<'p>>,
) -> &'a SparseMatrix<'p> {
    preload.map_or(&ops.k0, |p| &p.tangent)
}

/// # Collective
pub fn real_modes<'p>(
    petsc: &'p Petsc,
    ops: &Operators<'p>,
    preload: Option<&Preloaded<'p>>,
    request: &RealModeRequest,
) -> Result<RealModes<'p>, RunError> {
    let k = symmetric_stiffness(ops, preload);
    Ok(crate::eigen::real_modes::real_modes(
        petsc,
        k,
        &ops.m,
        ops.free_free,
        request,
        "",
    )?)
}
