//! The Abaqus writer: the same subset the reader takes, so a generated model opens in other
//! tools (and reads back).

use std::fmt::Write as _;
use std::path::Path;

use super::abaqus_type;
use crate::mesh::material::Elasticity;
use crate::mesh::orientation::System;
use crate::mesh::point::PointKind;
use crate::mesh::Mesh;

/// A number in at most 20 characters, the longest field CalculiX reads: the shorter of its
/// decimal and exponent forms that read back exactly (Rust's shortest round-trip digits) when
/// one fits, else the most digits that fit: at least 12 decimals (a relative change below
/// 5e-13; 15 decimals, 5e-16, for the coordinates of a model in metres).
fn field(x: f64) -> String {
    let (decimal, exponent) = (format!("{x}"), format!("{x:e}"));
    let exact = if decimal.len() <= exponent.len() {
        decimal
    } else {
        exponent
    };
    if exact.len() <= 20 {
        return exact;
    }
    (1..17)
        .rev()
        .map(|digits| format!("{x:.digits$e}"))
        .find(|s| s.len() <= 20)
        .unwrap_or(exact)
}

/// [`field`] with a decimal point: CalculiX tells a *SPRING's stiffness line from its DOF
/// line by one ("1e6" would read as DOFs).
fn field_with_point(x: f64) -> String {
    let f = field(x);
    if f.contains('.') {
        return f;
    }
    match f.find('e') {
        Some(at) => format!("{}.0{}", &f[..at], &f[at..]),
        None => format!("{f}.0"),
    }
}

/// Writes a mesh (with clamps and surfaces) as an Abaqus input file; ids are 1-based
/// positions; numbers in fields CalculiX reads too (`field`).
pub fn write(path: &Path, mesh: &Mesh, clamps: &[(String, [bool; 3])]) -> std::io::Result<()> {
    let mut s = String::new();
    s += "*HEADING\nwritten by squeal\n*NODE, NSET=ALLNODES\n";
    for (i, x) in mesh.coords.iter().enumerate() {
        let _ = writeln!(
            s,
            "{}, {}, {}, {}",
            i + 1,
            field(x[0]),
            field(x[1]),
            field(x[2])
        );
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
    for points in &mesh.point_blocks {
        let _ = writeln!(
            s,
            "*ELEMENT, TYPE={}, ELSET={}",
            points.kind.abaqus(),
            points.name
        );
        for e in 0..points.len() {
            let nodes: Vec<String> = points
                .element(e)
                .iter()
                .map(|n| (n + 1).to_string())
                .collect();
            let _ = writeln!(s, "{next}, {}", nodes.join(", "));
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
    write_materials(&mut s, mesh);
    for o in &mesh.orientations {
        let (system, points) = match o.system {
            System::Rectangular { a, b, origin } => ("RECTANGULAR", vec![a, b, origin]),
            System::Cylindrical { a, b } => ("CYLINDRICAL", vec![a, b]),
        };
        let numbers: Vec<String> = points.iter().flatten().map(|&v| field(v)).collect();
        let _ = writeln!(
            s,
            "*ORIENTATION, NAME={}, SYSTEM={system}\n{}",
            o.name,
            numbers.join(", ")
        );
        if let Some((axis, degrees)) = o.extra_rotation {
            let _ = writeln!(s, "{}, {}", axis + 1, field(degrees));
        }
    }
    for block in &mesh.blocks {
        let orientation = block.orientation.map_or(String::new(), |o| {
            format!(", ORIENTATION={}", mesh.orientations[o].name)
        });
        let _ = writeln!(
            s,
            "*SOLID SECTION, ELSET={}, MATERIAL={}{orientation}",
            block.name, mesh.materials[block.material].name
        );
    }
    write_properties_and_constraints(&mut s, mesh);
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

/// The materials: *MATERIAL with *ELASTIC in its form and *DENSITY.
fn write_materials(s: &mut String, mesh: &Mesh) {
    for m in &mesh.materials {
        let _ = writeln!(s, "*MATERIAL, NAME={}", m.name);
        match m.elasticity {
            Elasticity::Isotropic { e, nu } => {
                let _ = writeln!(s, "*ELASTIC\n{}, {}", field(e), field(nu));
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
                let first: Vec<String> = [e1, e2, e3, nu12, nu13, nu23, g12, g13]
                    .into_iter()
                    .map(field)
                    .collect();
                let _ = writeln!(
                    s,
                    "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{}\n{}",
                    first.join(", "),
                    field(g23)
                );
            }
            Elasticity::Anisotropic { d } => {
                // The upper triangle column by column, in Abaqus' Voigt order, 8 per line.
                use crate::mesh::material::FROM_ABAQUS_VOIGT as V;
                let values: Vec<String> = (0..6)
                    .flat_map(|j| (0..=j).map(move |i| (i, j)))
                    .map(|(i, j)| field(d[V[i]][V[j]]))
                    .collect();
                let lines: Vec<String> = values.chunks(8).map(|c| c.join(", ")).collect();
                let _ = writeln!(s, "*ELASTIC, TYPE=ANISOTROPIC\n{}", lines.join("\n"));
            }
        }
        let _ = writeln!(s, "*DENSITY\n{}", field(m.density));
    }
}

/// The point elements' *MASS / *SPRING values, then the constraints as *EQUATION.
fn write_properties_and_constraints(s: &mut String, mesh: &Mesh) {
    for points in &mesh.point_blocks {
        let (keyword, dofs) = match points.kind {
            PointKind::Mass => ("MASS", String::new()),
            PointKind::Axial => ("SPRING", String::new()),
            PointKind::Grounded { dof } => ("SPRING", format!("{}\n", dof + 1)),
            PointKind::Between { dofs: [i, j] } => ("SPRING", format!("{}, {}\n", i + 1, j + 1)),
        };
        let _ = writeln!(
            s,
            "*{keyword}, ELSET={}\n{dofs}{}",
            points.name,
            field_with_point(points.value)
        );
    }
    for c in &mesh.constraints.equations {
        let terms: Vec<String> = c
            .terms
            .iter()
            .map(|&(n, d, a)| format!("{}, {}, {}", n + 1, d + 1, field(a)))
            .collect();
        let lines: Vec<String> = terms.chunks(4).map(|t| t.join(", ")).collect();
        let _ = writeln!(s, "*EQUATION\n{}\n{}", c.terms.len(), lines.join("\n"));
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml)
mod tests {
    use super::field;

    #[test]
    fn fields_fit_20_characters_and_read_back_exactly_when_they_can() {
        for x in [
            0.0,
            2.1e11,
            0.3,
            7850.0,
            0.12345678901234568,
            -0.12345678901234568,
            1e-300,
        ] {
            let f = field(x);
            assert!(f.len() <= 20, "{f}");
            assert_eq!(f.parse::<f64>().unwrap(), x, "{f}");
            let p = super::field_with_point(x);
            assert!(p.contains('.') && p.parse::<f64>().unwrap() == x, "{p}");
        }
        // 17 digits do not fit: as many decimals as fit, within half a unit of the last.
        for (x, decimals) in [(-1.2345678901234567e-10, 13), (0.0012345678901234567, 15)] {
            let f = field(x);
            assert!(f.len() <= 20, "{f}");
            let bound = 0.5 * 10f64.powi(-decimals);
            assert!(
                (f.parse::<f64>().unwrap() - x).abs() <= bound * x.abs(),
                "{f}"
            );
        }
    }
}
