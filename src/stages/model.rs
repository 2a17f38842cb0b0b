//! Stage 1: the model. Generates the parametric brake or a structured test geometry, or
//! imports an Abaqus/Gmsh mesh; renumbers the nodes for the partition.

use crate::mesh::point::PointKind;
use std::path::Path;

use super::RunError;
use crate::mesh::partition;
use crate::mesh::structured::{annulus, block};
use crate::mesh::{Clamp, Interface, InterfaceKind, Mesh, PressureLoad};
use crate::scene::ModelSource;

/// A finite-element model ready for assembly: mesh, constraints, contact interfaces and
/// pressure loads (the last two from the brake generator or `*CONTACT PAIR`s).
#[derive(Debug, Clone)]
pub struct Model {
    pub mesh: Mesh,
    pub clamps: Vec<Clamp>,
    pub interfaces: Vec<Interface>,
    pub loads: Vec<PressureLoad>,
    /// Brake-line pressure (Pa) of the loads.
    pub pressure: f64,
    /// What the model builder substituted or assumed, for the log.
    pub notes: Vec<String>,
}

impl Model {
    /// The piston's force (N): brake pressure on the first load's hydraulic area.
    pub fn piston_force(&self) -> f64 {
        self.loads.first().map_or(0.0, |l| l.area * self.pressure)
    }

    pub fn plain(mesh: Mesh, clamps: Vec<Clamp>) -> Self {
        Model {
            mesh,
            clamps,
            interfaces: Vec::new(),
            loads: Vec::new(),
            pressure: 0.0,
            notes: Vec::new(),
        }
    }
}

/// Builds (generates or imports) the model; None for a matrices model. Relative file names
/// are resolved from `scene_dir`. Nodes are renumbered by recursive coordinate bisection
/// (`mesh::partition`), and every element passes the quality check.
pub fn build_model(model: &ModelSource, scene_dir: &Path) -> Result<Option<Model>, RunError> {
    let mut built = match model {
        ModelSource::Abaqus {
            file,
            constraint_penalty,
        } => abaqus_model(&scene_dir.join(file), *constraint_penalty)?,
        ModelSource::Gmsh {
            file,
            materials,
            clamp,
        } => {
            let msh = crate::mesh::gmsh_msh::read(&scene_dir.join(file), materials)?;
            Model::plain(msh.mesh, clamp.iter().map(|s| Clamp::all(s)).collect())
        }
        ModelSource::Block {
            element,
            size,
            cells,
            material,
            clamp,
        } => Model::plain(
            block(*size, *cells, *element, material.clone()),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        ),
        ModelSource::Annulus {
            element,
            inner_radius,
            outer_radius,
            thickness,
            cells,
            material,
            clamp,
        } => Model::plain(
            annulus(
                *inner_radius,
                *outer_radius,
                *thickness,
                *cells,
                *element,
                material.clone(),
            ),
            clamp.iter().map(|s| Clamp::all(s)).collect(),
        ),
        ModelSource::Brake(spec) => {
            let b = crate::mesh::brake::generate(spec).map_err(RunError::Brake)?;
            let mut notes = b.notes;
            notes.insert(
                0,
                format!(
                    "brake: {} nodes, {} elements, element size {:.2} mm",
                    b.mesh.node_count(),
                    b.mesh.element_count(),
                    b.element_size * 1e3
                ),
            );
            Model {
                mesh: b.mesh,
                clamps: b.clamps,
                interfaces: b.interfaces,
                loads: b.loads,
                pressure: b.pressure,
                notes,
            }
        }
        ModelSource::Matrices { .. } => return Ok(None),
    };
    let order = partition::bisection_order(&built.mesh.coords);
    partition::renumber(&mut built.mesh, &order);
    Ok(Some(built))
}

/// An Abaqus deck as a model: its ties resolved into constraints on the mesh, its clamps,
/// contact pairs as sliding interfaces, and the log's notes on what was read.
fn abaqus_model(path: &Path, constraint_penalty: f64) -> Result<Model, RunError> {
    let mut inp = crate::mesh::abaqus_inp::read(path)?;
    inp.mesh.constraints.penalty = constraint_penalty;
    let mut tie_notes = Vec::new();
    for tie in &inp.ties {
        let (constraints, report) =
            crate::contact::tie::constrain(&mut inp.mesh, tie).map_err(|message| {
                RunError::from(crate::mesh::abaqus_inp::InpError::Model {
                    file: path.to_path_buf(),
                    message,
                })
            })?;
        inp.mesh.constraints.equations.extend(constraints);
        tie_notes.push(report.describe(tie));
    }
    let clamps = inp
        .clamps
        .iter()
        .map(|(set, components)| Clamp {
            node_set: set.clone(),
            components: *components,
        })
        .collect();
    let mut notes = inp.skipped_notes();
    notes.extend(inp.notes.iter().cloned());
    for (block, abaqus, count) in &inp.element_types {
        notes.extend(block_note(&inp.mesh, block, abaqus, *count));
    }
    notes.extend(tie_notes);
    let constraints = inp.mesh.constraints.equations.len();
    if constraints > 0 {
        notes.push(format!(
            "{constraints} linear constraint(s) (*EQUATION, *TIE) by penalty: k_p = {constraint_penalty:e} x the largest diagonal entry of K, so each holds to about 1/{constraint_penalty:e} of the deformation it resists ([model] constraint_penalty)"
        ));
    }
    let mut m = Model::plain(inp.mesh, clamps);
    m.notes = notes;
    m.interfaces = inp
        .contact_pairs
        .iter()
        .map(|p| Interface {
            name: format!("{}-{}", p.slave, p.master),
            master: p.slave.clone(),
            slave: p.master.clone(),
            kind: InterfaceKind::Sliding,
        })
        .collect();
    Ok(m)
}

/// The log's line on a block read from a deck: a solid block's element and rule, or a point
/// block's value and where it acts.
fn block_note(mesh: &crate::mesh::Mesh, block: &str, abaqus: &str, count: usize) -> Option<String> {
    if let Some(kind) = mesh.blocks.iter().find(|b| b.name == block).map(|b| b.kind) {
        let modified = if abaqus == "C3D10M" {
            " (C3D10M read as C3D10: its own mass and contact treatment are not reproduced)"
        } else {
            ""
        };
        return Some(format!(
            "{block}: {count} {abaqus} as {}, {}{modified}",
            kind.name(),
            kind.rule_description()
        ));
    }
    let points = mesh.point_blocks.iter().find(|b| b.name == block)?;
    let mass = points.kind == PointKind::Mass;
    let dofs = match points.kind {
        PointKind::Grounded { dof } => format!(", DOF {} to ground", dof + 1),
        PointKind::Between { dofs: [i, j] } => format!(", DOF {} to DOF {}", i + 1, j + 1),
        PointKind::Axial => ", along the line of its nodes".into(),
        PointKind::Mass => String::new(),
    };
    let value = if (1e-3..1e4).contains(&points.value) {
        points.value.to_string()
    } else {
        format!("{:e}", points.value)
    };
    Some(format!(
        "{block}: {count} {abaqus} of {value} {}{dofs}, into {}",
        if mass { "kg" } else { "N/m" },
        if mass { "M" } else { "K" }
    ))
}
