//! Tied surfaces (Abaqus `*TIE`): every slave node within the position tolerance of the
//! master surface gets three linear constraints, u_s = sum_a N_a(xi) u_a at its closest
//! point xi on the nearest master face (imposed by penalty: `mesh::constraint`). With
//! ADJUST the slave node is first moved onto that point, as Abaqus and CalculiX do.

use super::pairing::project;
use super::surface::{norm, sub, Face};
use crate::mesh::abaqus_inp::Tie;
use crate::mesh::constraint::LinearConstraint;
use crate::mesh::Mesh;

/// What a tie did, for the log.
#[derive(Debug, Clone, PartialEq)]
pub struct TieReport {
    pub tied: usize,
    /// Slave nodes that are nodes of the master surface too (already joined).
    pub shared: usize,
    /// Slave nodes beyond the tolerance (not tied).
    pub beyond: usize,
    pub tolerance: f64,
    /// The largest distance of a tied slave node from the master surface (m).
    pub largest_gap: f64,
}

impl TieReport {
    pub fn describe(&self, tie: &Tie) -> String {
        format!(
            "*TIE {} (line {}): {} slave nodes of '{}' tied to '{}'{}{}, the largest gap {:.2e} m{} (position tolerance {:.2e} m)",
            tie.name,
            tie.line,
            self.tied,
            tie.slave,
            tie.master,
            if self.shared > 0 { format!(", {} shared with it", self.shared) } else { String::new() },
            if self.beyond > 0 { format!(", {} beyond the tolerance left free", self.beyond) } else { String::new() },
            self.largest_gap,
            if tie.adjust { ", moved onto it (ADJUST)" } else { "" },
            self.tolerance
        )
    }
}

/// The constraints of `tie` on `mesh` (its slave nodes moved when the tie adjusts). Err: no
/// slave node is within the tolerance (the surfaces do not face each other).
pub fn constrain(mesh: &mut Mesh, tie: &Tie) -> Result<(Vec<LinearConstraint>, TieReport), String> {
    let faces: Vec<Face> = mesh
        .surface(&tie.master)
        .map_err(|e| e.to_string())?
        .iter()
        .map(|&(e, f)| Face::new(mesh, e, f))
        .collect();
    let boxes: Vec<([f64; 3], [f64; 3])> = faces.iter().map(Face::bounds).collect();
    let tolerance = tie.tolerance.unwrap_or_else(|| {
        let mut diagonals: Vec<f64> = boxes.iter().map(|(lo, hi)| norm(sub(*hi, *lo))).collect();
        diagonals.sort_by(f64::total_cmp);
        0.05 * diagonals.get(diagonals.len() / 2).copied().unwrap_or(0.0)
    });
    let master_nodes: std::collections::BTreeSet<usize> =
        faces.iter().flat_map(|f| f.nodes.iter().copied()).collect();
    let mut report = TieReport {
        tied: 0,
        shared: 0,
        beyond: 0,
        tolerance,
        largest_gap: 0.0,
    };
    let mut constraints = Vec::new();
    for &s in &tie.slave_nodes {
        if master_nodes.contains(&s) {
            report.shared += 1;
            continue;
        }
        let x = mesh.coords[s];
        let near = |(lo, hi): &([f64; 3], [f64; 3])| {
            (0..3).all(|d| x[d] >= lo[d] - tolerance && x[d] <= hi[d] + tolerance)
        };
        let best = faces
            .iter()
            .zip(&boxes)
            .filter(|(_, b)| near(b))
            .filter_map(|(f, _)| project(f, x).map(|p| (f, p)))
            .min_by(|a, b| a.1.distance.total_cmp(&b.1.distance));
        let Some((face, p)) = best.filter(|(_, p)| p.distance <= tolerance) else {
            report.beyond += 1;
            continue;
        };
        let point = face.at(p.xi);
        report.tied += 1;
        report.largest_gap = report.largest_gap.max(p.distance);
        if tie.adjust {
            mesh.coords[s] = point.x;
        }
        for d in 0..3 {
            let mut terms = vec![(s, d, 1.0)];
            terms.extend(
                face.nodes
                    .iter()
                    .zip(&point.n)
                    .filter(|(_, n)| n.abs() > 1e-14)
                    .map(|(&a, &n)| (a, d, -n)),
            );
            constraints.push(LinearConstraint {
                terms,
                origin: format!("*TIE {} line {}", tie.name, tie.line),
            });
        }
    }
    if report.tied == 0 && report.beyond > 0 {
        return Err(format!(
            "*TIE {} (line {}): none of the {} slave nodes of '{}' is within {:.2e} m of '{}': check that the surfaces face each other, or give POSITION TOLERANCE",
            tie.name,
            tie.line,
            report.beyond,
            tie.slave,
            tolerance,
            tie.master
        ));
    }
    Ok((constraints, report))
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml)
mod tests {
    use super::*;
    use crate::mesh::material::Material;
    use crate::mesh::structured::block;
    use crate::mesh::ElementKind;

    /// A unit cube's top face as the master, and the four corners of a second cube 0.5 above
    /// it as the slave nodes.
    fn two_cubes() -> (Mesh, Tie) {
        let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
        let mut mesh = block([1.0; 3], [1, 1, 1], ElementKind::Hex8, steel.clone());
        let top: Vec<(usize, u8)> = (1..=6u8)
            .filter(|&f| {
                mesh.face_nodes(0, f)
                    .iter()
                    .all(|&n| mesh.coords[n][2] == 1.0)
            })
            .map(|f| (0, f))
            .collect();
        mesh.surfaces.insert("top".into(), top);
        let mut upper = block([1.0; 3], [1, 1, 1], ElementKind::Hex8, steel);
        upper.coords.iter_mut().for_each(|x| x[2] += 1.5);
        upper.node_sets.clear();
        upper.blocks[0].name = "upper".into();
        let first = mesh.node_count();
        mesh.append(upper);
        let slave_nodes: Vec<usize> = (first..mesh.node_count())
            .filter(|&n| mesh.coords[n][2] == 1.5)
            .collect();
        let tie = Tie {
            name: "T".into(),
            slave: "S".into(),
            slave_nodes,
            master: "top".into(),
            tolerance: None,
            adjust: true,
            line: 1,
        };
        (mesh, tie)
    }

    #[test]
    fn slave_nodes_beyond_the_tolerance_are_refused_and_within_it_tied_and_moved() {
        let (mut mesh, mut tie) = two_cubes();
        // The default tolerance, 5 % of the face's diagonal (0.071), does not reach 0.5.
        let e = constrain(&mut mesh, &tie).unwrap_err();
        assert!(
            e.contains("none of the 4 slave nodes") && e.contains("POSITION TOLERANCE"),
            "{e}"
        );
        tie.tolerance = Some(0.6);
        let (constraints, report) = constrain(&mut mesh, &tie).unwrap();
        assert_eq!((report.tied, report.beyond, constraints.len()), (4, 0, 12));
        assert!(
            (report.largest_gap - 0.5).abs() < 1e-12,
            "{}",
            report.largest_gap
        );
        // Adjusted onto the master face; each constraint ties one DOF to one master corner.
        for &s in &tie.slave_nodes {
            assert!((mesh.coords[s][2] - 1.0).abs() < 1e-12);
        }
        for c in &constraints {
            assert_eq!(c.terms.len(), 2, "{:?}", c.terms);
            assert!((c.terms[1].2 + 1.0).abs() < 1e-12);
        }
    }
}
