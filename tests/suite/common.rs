//! Helpers shared by the MPI suite.

use super::TestResult;
use squeal::eigen::real_modes::{real_modes, RealModeRequest, RealModes};
use squeal::fem::petsc::{assemble_system, AssembledSystem};
use squeal::la::Petsc;
use squeal::measure::{largest_abs, max_abs_difference};
use squeal::mesh::material::Material;
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
) -> TestResult<(AssembledSystem<'p>, RealModes<'p>)> {
    let system = assemble_system(petsc, mesh, clamps)?;
    let modes = real_modes(
        petsc,
        &system.stiffness,
        &system.mass,
        system.is_free_free(),
        request,
        "",
    )?;
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
    max_abs_difference(one, other) / largest_abs(one)
}

/// Ok when `value <= bound`; an error naming `what` otherwise, and when `value` is NaN.
pub fn check_le(what: &str, value: f64, bound: f64) -> TestResult {
    if value <= bound {
        Ok(())
    } else {
        Err(format!("{what}: {value:e} exceeds the bound {bound:e}").into())
    }
}

/// Where the 1-rank run of the suite leaves results for the 2-rank run to compare against.
pub fn suite_dir() -> std::path::PathBuf {
    std::env::var_os("SQUEAL_SUITE_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("squeal-mpi-suite"))
}

/// Values kept by the 1-rank run of the suite for the 2- and 4-rank runs to compare against:
/// on 1 rank writes `values` under `name` in the suite folder, marks the test skipped (there is
/// nothing to compare with yet) and returns None; on more ranks returns the 1-rank values (an
/// error if they are missing or of another length).
pub fn one_rank_values(
    petsc: &squeal::la::Petsc,
    name: &str,
    values: &[f64],
) -> TestResult<Option<Vec<f64>>> {
    let rows = one_rank_rows(petsc, name, &[values.to_vec()])?;
    Ok(rows.map(|mut r| r.remove(0)))
}

/// As `one_rank_values`, for several rows (one per line of the stored file); rows may differ
/// in length, and each is compared in length with the 1-rank row.
pub fn one_rank_rows(
    petsc: &squeal::la::Petsc,
    name: &str,
    rows: &[Vec<f64>],
) -> TestResult<Option<Vec<Vec<f64>>>> {
    let file = suite_dir().join(format!("{name}-1-rank.txt"));
    if petsc.size() == 1 {
        std::fs::create_dir_all(suite_dir())?;
        let text: Vec<String> = rows
            .iter()
            .map(|row| {
                row.iter()
                    .map(|x| format!("{x:e}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect();
        std::fs::write(&file, text.join("\n"))?;
        skip(&format!(
            "1 rank: stored the reference {} for the runs on more ranks",
            file.display()
        ));
        return Ok(None);
    }
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("{}: {e}: run the suite on 1 rank first", file.display()))?;
    let one: Vec<Vec<f64>> = text
        .lines()
        .map(|l| {
            l.split_whitespace()
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    if one.len() != rows.len() {
        return Err(format!("{name}: {} rows on 1 rank, {} here", one.len(), rows.len()).into());
    }
    for (i, (a, b)) in one.iter().zip(rows).enumerate() {
        if a.len() != b.len() {
            return Err(format!(
                "{name}: row {i} has {} values on 1 rank, {} here",
                a.len(),
                b.len()
            )
            .into());
        }
    }
    Ok(Some(one))
}

thread_local! {
    static SKIPPED: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Marks the running test as skipped with a reason: it returns Ok but checked nothing on this
/// rank count (the harness reports it as skipped, not passed).
pub fn skip(reason: &str) {
    SKIPPED.with(|s| *s.borrow_mut() = Some(reason.to_string()));
}

/// The reason the test that just ran was skipped, if it was (and clears it for the next test).
pub fn take_skip() -> Option<String> {
    SKIPPED.with(|s| s.borrow_mut().take())
}
