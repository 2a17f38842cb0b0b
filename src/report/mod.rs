//! The report wing (DESIGN.md §3): above the stages, it turns their typed outputs into what a
//! reader gets: one writer per stage output (HDF5 groups of results.h5, CSV, PNG, XDMF; §5),
//! the run's summary and answer lines, and report.html. Writers only write: what they show was
//! computed by the stages or by `post`. Storage and drawing backends live in `crate::io`.

pub mod answer;
pub mod contact_map;
pub mod html;
pub mod link;
pub mod loudness;
pub mod matrix;
pub mod matrix_saturation;
pub mod modes;
pub mod post;
pub mod pseudo;
pub mod reduction;
mod sections;
pub mod stability;
pub mod statics;
pub mod summary;
pub mod sweep;
pub mod text;
pub mod transient;
pub mod vibration;

use std::path::Path;

use crate::eigen::complex_modes::ComplexModes;
use crate::eigen::real_modes::RealModes;
use crate::fem::quality::BlockQuality;
use crate::io::results::ResultsFile;
use crate::io::xdmf::{self, NodalField};
pub use crate::io::WriteError;
use crate::report::summary::ReductionSummary;
use crate::stages::complex::route_name;
use crate::stages::model::Model;
use crate::stages::operators::LoadBalance;
use crate::stages::{Analyses, Timings};

/// The run's identity at the root of results.h5: the scene, the PETSc options, the version,
/// the ranks and the model size (for reproducibility).
///
/// # Collective
pub fn write_header(
    file: &ResultsFile,
    scene_text: &str,
    petsc_options: &[String],
    ranks: usize,
    dofs: usize,
) -> Result<(), WriteError> {
    file.set_text("/", "scene", scene_text)?;
    file.set_text("/", "petsc_options", &petsc_options.join(" "))?;
    file.set_text("/", "squeal_version", env!("CARGO_PKG_VERSION"))?;
    file.set_number("/", "ranks", ranks as f64)?;
    file.set_number("/", "dofs", dofs as f64)?;
    Ok(())
}

/// Everything the stages before the transient found: the header, /model, /static, /modes,
/// /sweep, /reduced, with their CSV files and plots (and model.inp when asked).
///
/// # Collective
pub fn write_analyses<'p>(
    petsc: &'p crate::la::Petsc,
    file: &ResultsFile,
    a: &Analyses<'p>,
    maps: Option<contact_map::MapContext>,
    (scene_text, petsc_options): (&str, &[String]),
    write_inp_file: bool,
    output: &Path,
) -> Result<(), WriteError> {
    let ranks = petsc.size() as usize;
    write_header(file, scene_text, petsc_options, ranks, a.ops.dofs())?;
    if let Some(model) = &a.model {
        write_model(file, model, &a.quality, a.ops.balance.as_ref())?;
        if write_inp_file && petsc.rank() == 0 {
            write_inp(output, model)?;
        }
    }
    if let (Some(p), Some(model), Some(maps), Some(dofs)) =
        (&a.preload, &a.model, maps, &a.ops.dofs)
    {
        statics::write_static(petsc, file, p, dofs, model, maps, output)?;
    }
    if let Some(modes) = &a.modes {
        file.write_real_modes(modes, a.ops.dofs.as_ref())?;
    }
    for c in &a.complex {
        let mesh = a.model.as_ref().map(|m| &m.mesh);
        modes::write_complex(petsc, file, c, a.ops.dofs.as_ref(), mesh, output)?;
    }
    if let Some(sw) = &a.sweep {
        sweep::write_sweep(petsc, file, sw, output)?;
    }
    if let Some(r) = &a.reduced {
        let summary = ReductionSummary::of(petsc, r, a.ops.dofs())?;
        reduction::write_reduction(file, r, &summary)?;
    }
    Ok(())
}

/// /model (mesh, interfaces, loads, quality) and /partition.
///
/// # Collective
pub fn write_model(
    file: &ResultsFile,
    model: &Model,
    quality: &[BlockQuality],
    balance: Option<&LoadBalance>,
) -> Result<(), WriteError> {
    file.write_mesh(&model.mesh)?;
    for i in &model.interfaces {
        let group = format!("model/interfaces/{}", i.name);
        file.set_text(&group, "master", &i.master)?;
        file.set_text(&group, "slave", &i.slave)?;
        file.set_text(&group, "kind", &format!("{:?}", i.kind).to_lowercase())?;
    }
    for l in &model.loads {
        let group = format!("model/loads/{}", l.surface);
        file.set_number(&group, "hydraulic_area_m2", l.area)?;
        file.set_number(&group, "pressure_pa", model.pressure)?;
    }
    for q in quality {
        let group = format!("model/quality/{}", q.block);
        file.set_number(&group, "elements", q.elements as f64)?;
        file.set_number(&group, "min_scaled_jacobian", q.min_scaled_jacobian)?;
        file.set_number(&group, "max_aspect_ratio", q.max_aspect_ratio)?;
        file.set_number(&group, "mean_aspect_ratio", q.mean_aspect_ratio)?;
        file.set_number(&group, "max_warping_deg", q.max_warping_deg)?;
    }
    if let Some(b) = balance {
        let rows: Vec<f64> = b.rows.iter().map(|&r| r as f64).collect();
        let elements: Vec<f64> = b.elements.iter().map(|&e| e as f64).collect();
        file.write_table("partition/rows_per_rank", &rows, "1")?;
        file.write_table("partition/elements_per_rank", &elements, "1")?;
    }
    Ok(())
}

/// model.inp: the model as an Abaqus input (rank 0 only).
pub fn write_inp(output: &Path, model: &Model) -> Result<(), WriteError> {
    let path = output.join("model.inp");
    let named: Vec<(String, [bool; 3])> = model
        .clamps
        .iter()
        .map(|c| (c.node_set.clone(), c.components))
        .collect();
    crate::mesh::abaqus_inp::write(&path, &model.mesh, &named)
        .map_err(|source| WriteError::Io { path, source })
}

/// What the ParaView files show besides the mesh.
pub struct Views<'a, 'p> {
    pub modes: Option<&'a RealModes<'p>>,
    /// The first route's complex shapes go in, as real and imaginary parts.
    pub complex: &'a [ComplexModes<'p>],
    /// More nodal vectors (the shapes the dynamic stability tracked).
    pub more: Vec<NodalField>,
    /// The static state was solved: its displacement and contact pressure go in.
    pub with_contact: bool,
    pub frames: Option<&'a crate::report::vibration::Frames>,
}

/// results.xdmf (the brake with the static state and the mode shapes), surfaces.xdmf (the
/// named surfaces), vibration.xdmf (the transient's frames, when written) and model.png
/// (rank 0 only).
pub fn write_views_and_preview(
    output: &Path,
    model: &Model,
    views: Views,
) -> Result<(), WriteError> {
    let mut fields = Vec::new();
    if views.with_contact {
        fields.push(NodalField::vector(
            "static displacement (m)",
            "/static/displacement",
        ));
        fields.push(NodalField::scalar(
            "static contact pressure (Pa)",
            "/static/contact_pressure_at_nodes",
        ));
    }
    if let Some(modes) = views.modes {
        for (i, f) in modes.frequencies_hz.iter().enumerate() {
            fields.push(NodalField::vector(
                &format!("mode {:03} ({f:.1} Hz)", i + 1),
                &format!("/modes/real/shapes/mode_{:04}", i + 1),
            ));
        }
    }
    for c in views.complex.iter().take(1) {
        for (i, mode) in c.modes.iter().take(c.shapes.len()).enumerate() {
            let state = if mode.unstable { ", unstable" } else { "" };
            for part in ["re", "im"] {
                fields.push(NodalField::vector(
                    &format!(
                        "{} {part} ({:.1} Hz, zeta {:.2e}{state})",
                        mode.name, mode.frequency_hz, mode.damping_ratio
                    ),
                    &format!(
                        "/modes/complex/{}/shapes/mode_{:04}_{part}",
                        route_name(c.route),
                        i + 1
                    ),
                ));
            }
        }
    }
    fields.extend(views.more);
    let h5 = "results.h5";
    let mesh = &model.mesh;
    let io = |path: std::path::PathBuf, written: std::io::Result<()>| {
        written.map_err(|source| WriteError::Io { path, source })
    };
    let path = output.join("results.xdmf");
    io(path.clone(), xdmf::write_brake(&path, h5, mesh, &fields))?;
    let path = output.join("surfaces.xdmf");
    let pressure = views.with_contact;
    io(
        path.clone(),
        xdmf::write_surfaces(&path, h5, mesh, pressure),
    )?;
    if let Some(frames) = views.frames {
        let path = output.join("vibration.xdmf");
        io(
            path.clone(),
            xdmf::write_frames(&path, h5, mesh, &frames.times),
        )?;
    }
    let path = output.join("model.png");
    io(
        path.clone(),
        crate::io::preview::write_png(&path, mesh, 1200, 900),
    )
}

/// K.<format> and M.<format> (`mtx`: Matrix Market, else PETSc binary) of the stiffness the
/// real modes use and the mass.
///
/// # Collective
pub fn export_matrices(
    petsc: &crate::la::Petsc,
    format: &str,
    k: &crate::la::SparseMatrix,
    m: &crate::la::SparseMatrix,
    output: &Path,
) -> Result<(), WriteError> {
    export_named(petsc, format, &[("K", k), ("M", m)], output)
}

/// <name>.<format> for each named matrix (`mtx`: Matrix Market, else PETSc binary).
///
/// # Collective
pub fn export_named(
    petsc: &crate::la::Petsc,
    format: &str,
    matrices: &[(&str, &crate::la::SparseMatrix)],
    output: &Path,
) -> Result<(), WriteError> {
    for &(name, a) in matrices {
        if format == "mtx" {
            crate::io::matrix_market::write(petsc.world(), a, &output.join(format!("{name}.mtx")))?;
        } else {
            a.save_binary(petsc, &output.join(format!("{name}.petsc")))?;
        }
    }
    Ok(())
}

/// /timings: seconds per stage.
///
/// # Collective
pub fn write_timings(file: &ResultsFile, timings: &Timings) -> Result<(), WriteError> {
    for (name, secs) in &timings.stages {
        file.set_number("timings", &name.replace(' ', "_"), *secs)?;
    }
    Ok(())
}
