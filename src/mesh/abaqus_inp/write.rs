//! The Abaqus writer: the same subset the reader takes, so a generated model opens in other
//! tools (and reads back).

use std::fmt::Write as _;
use std::path::Path;

use super::abaqus_type;
use crate::mesh::material::Elasticity;
use crate::mesh::Mesh;

/// Writes a mesh (with clamps and surfaces) as an Abaqus input file; ids are 1-based
/// positions.
pub fn write(path: &Path, mesh: &Mesh, clamps: &[(String, [bool; 3])]) -> std::io::Result<()> {
    let mut s = String::new();
    s += "*HEADING\nwritten by squeal\n*NODE, NSET=ALLNODES\n";
    for (i, x) in mesh.coords.iter().enumerate() {
        let _ = writeln!(s, "{}, {:.17e}, {:.17e}, {:.17e}", i + 1, x[0], x[1], x[2]);
    }
    let mut next = 1;
    for block in &mesh.blocks {
        let _ = writeln!(
            s,
            "*ELEMENT, TYPE={}, ELSET={}",
            abaqus_type(block.kind),
            block.name
        );
        for e in 0..block.len() {
            // At most 16 numbers per data line; a trailing comma continues the element.
            let numbers: Vec<String> = std::iter::once(next.to_string())
                .chain(block.element(e).iter().map(|n| (n + 1).to_string()))
                .collect();
            let lines: Vec<String> = numbers.chunks(16).map(|c| c.join(", ")).collect();
            s += &lines.join(",\n");
            s += "\n";
            next += 1;
        }
    }
    for (name, nodes) in &mesh.node_sets {
        let _ = writeln!(s, "*NSET, NSET={name}");
        for chunk in nodes.chunks(16) {
            let ids: Vec<String> = chunk.iter().map(|n| (n + 1).to_string()).collect();
            let _ = writeln!(s, "{}", ids.join(", "));
        }
    }
    for (name, faces) in &mesh.surfaces {
        let _ = writeln!(s, "*SURFACE, TYPE=ELEMENT, NAME={name}");
        for (e, f) in faces {
            let _ = writeln!(s, "{}, S{f}", e + 1);
        }
    }
    for m in &mesh.materials {
        let _ = writeln!(s, "*MATERIAL, NAME={}", m.name);
        match m.elasticity {
            Elasticity::Isotropic { e, nu } => {
                let _ = writeln!(s, "*ELASTIC\n{e:.17e}, {nu:.17e}");
            }
            Elasticity::Orthotropic {
                e1,
                e2,
                e3,
                nu12,
                nu13,
                nu23,
                g12,
                g13,
                g23,
            } => {
                let _ = writeln!(
                    s,
                    "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{e1:.17e}, {e2:.17e}, {e3:.17e}, {nu12:.17e}, {nu13:.17e}, {nu23:.17e}, {g12:.17e}, {g13:.17e}\n{g23:.17e}"
                );
            }
        }
        let _ = writeln!(s, "*DENSITY\n{:.17e}", m.density);
    }
    for block in &mesh.blocks {
        let _ = writeln!(
            s,
            "*SOLID SECTION, ELSET={}, MATERIAL={}",
            block.name, mesh.materials[block.material].name
        );
    }
    if !clamps.is_empty() {
        s += "*BOUNDARY\n";
        for (set, comps) in clamps {
            for (c, on) in comps.iter().enumerate() {
                if *on {
                    let _ = writeln!(s, "{set}, {}, {}", c + 1, c + 1);
                }
            }
        }
    }
    std::fs::write(path, s)
}
