//! Helpers shared by the MPI suite.

use squeal::eigen::real_modes::{real_modes, RealModeRequest, RealModes};
use squeal::fem::material::Material;
use squeal::la::fem_assembly::{assemble_system, AssembledSystem};
use squeal::la::Petsc;
use squeal::mesh::Clamp;
use squeal::mesh::Mesh;

pub fn steel() -> Material {
    Material::isotropic("steel", 2.1e11, 0.3, 7850.0)
}

pub fn solve_modes<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    clamps: &[Clamp],
    request: &RealModeRequest,
) -> Result<(AssembledSystem<'p>, RealModes<'p>), String> {
    let system = assemble_system(petsc, mesh, clamps).map_err(|e| e.to_string())?;
    let modes = real_modes(
        petsc,
        &system.stiffness,
        &system.mass,
        system.is_free_free(),
        request,
        "",
    )
    .map_err(|e| e.to_string())?;
    Ok((system, modes))
}

/// Prints on rank 0 only.
pub fn say(petsc: &Petsc, text: &str) {
    if petsc.rank() == 0 {
        println!("    {text}");
    }
}

pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The largest |a - b| over the pairs, relative to the largest |a| (NaN if any is NaN or
/// the lengths differ): how far a series from another rank count is from the 1-rank one.
pub fn max_scaled_difference(one: &[f64], other: &[f64]) -> f64 {
    if one.len() != other.len() {
        return f64::NAN;
    }
    let scale = one.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    one.iter()
        .zip(other)
        .map(|(a, b)| (a - b).abs() / scale)
        .fold(0.0f64, |m, d| if d.is_nan() { d } else { m.max(d) })
}

/// Where the 1-rank run of the suite leaves results for the 2-rank run to compare against.
pub fn suite_dir() -> std::path::PathBuf {
    std::env::var_os("SQUEAL_SUITE_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("squeal-mpi-suite"))
}

/// Values kept by the 1-rank run of the suite for the 2-rank run to compare against: on 1
/// rank writes `values` under `name` in the suite folder and returns None; on more ranks
/// returns the 1-rank values (an error if they are missing or of another length).
pub fn one_rank_values(
    petsc: &squeal::la::Petsc,
    name: &str,
    values: &[f64],
) -> Result<Option<Vec<f64>>, String> {
    let file = suite_dir().join(format!("{name}-1-rank.txt"));
    if petsc.size() == 1 {
        if petsc.rank() == 0 {
            let text: Vec<String> = values.iter().map(|x| format!("{x:e}")).collect();
            std::fs::write(&file, text.join("\n")).map_err(|e| e.to_string())?;
        }
        return Ok(None);
    }
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("{}: {e}: run the suite on 1 rank first", file.display()))?;
    let one: Vec<f64> = text
        .lines()
        .map(|l| l.parse().unwrap_or(f64::NAN))
        .collect();
    if one.len() != values.len() {
        return Err(format!(
            "{name}: {} values on 1 rank, {} here",
            one.len(),
            values.len()
        ));
    }
    Ok(Some(one))
}
