//! Writer of the superelement reduction's figures.

use super::WriteError;
use crate::io::results::ResultsFile;
use crate::report::summary::ReductionSummary;
use crate::stages::reduce::Reduced;

/// Writes /reduced: sizes, checks, the real modes of the reduced vs the full model.
///
/// # Collective
pub fn write_reduction(
    file: &ResultsFile,
    r: &Reduced,
    summary: &ReductionSummary,
) -> Result<(), WriteError> {
    let red = &r.model.reduction;
    let g = "reduced";
    file.set_number(g, "full_dofs", summary.full_dofs as f64)?;
    file.set_number(g, "size", red.size() as f64)?;
    file.set_number(g, "kept_dofs", red.kept as f64)?;
    file.set_number(g, "modal_coordinates", red.modal as f64)?;
    file.set_number(g, "basis_offered", red.offered as f64)?;
    file.set_number(g, "basis_dropped", red.dropped as f64)?;
    file.set_number(g, "mass_orthonormality", red.orthonormality)?;
    file.set_number(g, "static_state_error", r.static_error)?;
    file.set_number(g, "stiffness_entries", summary.stiffness_entries)?;
    file.set_number(g, "seconds", red.seconds)?;
    let full: Vec<f64> = r.mode_check.iter().map(|m| m.0).collect();
    let reduced: Vec<f64> = r.mode_check.iter().map(|m| m.1).collect();
    file.write_table("reduced/check/full_frequency", &full, "Hz")?;
    file.write_table("reduced/check/reduced_frequency", &reduced, "Hz")?;
    Ok(())
}
