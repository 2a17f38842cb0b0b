//! Point elements of an input file: `*ELEMENT, TYPE=MASS | SPRING1 | SPRING2 | SPRINGA` with
//! the `*MASS` and `*SPRING` lines that give their ELSET its mass or stiffness (the first
//! data line of a SPRING1/SPRING2 `*SPRING` names the DOFs, the next the stiffness; SPRINGA's
//! has the stiffness only, after a blank line or not).

use std::collections::HashMap;
use std::path::Path;

use super::raw::{At, RawInp};
use super::{InpError, Keyword};
use crate::mesh::point::{PointBlock, PointKind};

/// Nodes per element of the point element types read; None for any other type.
pub(super) fn point_nodes(abaqus: &str) -> Option<usize> {
    match abaqus {
        "MASS" | "SPRING1" => Some(1),
        "SPRING2" | "SPRINGA" => Some(2),
        _ => None,
    }
}

/// Element types a brake deck may hold that are refused with their reason.
pub(super) fn refused_type(abaqus: &str) -> Option<&'static str> {
    match abaqus {
        "ROTARYI" => Some("rotary inertia needs rotational DOFs, which solid nodes do not have: leave it out or replace it by masses at the nodes it spans"),
        "DASHPOT1" | "DASHPOT2" | "DASHPOTA" => Some("dashpots are not read: give the damping as [damping] in the scene"),
        _ => None,
    }
}

/// A point-element block as read: type, ELSET, element ids and node ids (nodes per element
/// each), the keyword's line.
pub(super) struct RawPointBlock {
    pub abaqus: String,
    pub elset: Option<String>,
    pub ids: Vec<i64>,
    pub nodes: Vec<i64>,
    pub line: usize,
}

/// A *MASS or *SPRING: its ELSET, data lines (fields) and keyword line.
pub(super) struct RawProperty {
    pub keyword: &'static str,
    pub elset: String,
    pub lines: Vec<Vec<String>>,
    pub line: usize,
}

/// A *MASS or *SPRING keyword line (ELSET needed; nonlinear or oriented springs refused).
pub(super) fn property_keyword(kw: &Keyword, at: At) -> Result<RawProperty, InpError> {
    let keyword = if kw.name == "MASS" { "MASS" } else { "SPRING" };
    if let Some(p) = ["NONLINEAR", "ORIENTATION", "DEPENDENCIES"]
        .iter()
        .find(|p| kw.params.contains_key(**p))
    {
        return Err(at.syntax(format!(
            "*{keyword}, {p}: only linear springs in global directions are read"
        )));
    }
    Ok(RawProperty {
        keyword,
        elset: kw
            .params
            .get("ELSET")
            .cloned()
            .ok_or_else(|| at.syntax(format!("*{keyword} needs ELSET=")))?,
        lines: Vec::new(),
        line: at.line,
    })
}

/// What a property gives an element: its kind (with the DOFs) and value.
type Given = (PointKind, f64);

/// The point blocks of the file, one per *ELEMENT block and property; each as (name, Abaqus
/// type, element count) for the log.
pub(super) fn resolve(
    raw: &RawInp,
    path: &Path,
    blocks: &mut Vec<PointBlock>,
) -> Result<Vec<(String, String, usize)>, InpError> {
    let error = |message: String| InpError::Model {
        file: path.to_path_buf(),
        message,
    };
    let mut given: HashMap<i64, (usize, Given)> = HashMap::new();
    for (p, property) in raw.properties.iter().enumerate() {
        let ids = raw
            .elsets
            .iter()
            .find(|(name, _)| name.eq_ignore_ascii_case(&property.elset))
            .map(|(_, ids)| ids)
            .ok_or_else(|| {
                error(format!(
                    "line {}: *{} names element set '{}', which is not defined",
                    property.line, property.keyword, property.elset
                ))
            })?;
        for &id in ids {
            let Some(block) = raw.point_blocks.iter().find(|b| b.ids.contains(&id)) else {
                return Err(error(format!(
                    "line {}: *{} ELSET={} holds element {id}, which is not a MASS or SPRING element",
                    property.line, property.keyword, property.elset
                )));
            };
            let kind = property_of(property, &block.abaqus).map_err(|m| {
                error(format!(
                    "line {}: *{}: {m}",
                    property.line, property.keyword
                ))
            })?;
            given.insert(id, (p, kind));
        }
    }
    let mut log = Vec::new();
    for block in &raw.point_blocks {
        let n = point_nodes(&block.abaqus).expect("only point types are read into point blocks");
        let mut by_property: Vec<(usize, Given, Vec<usize>)> = Vec::new();
        for (e, id) in block.ids.iter().enumerate() {
            let &(p, kind) = given.get(id).ok_or_else(|| {
                error(format!(
                    "{} element {id} (line {}) has no *{} for its ELSET",
                    block.abaqus,
                    block.line,
                    if block.abaqus == "MASS" {
                        "MASS"
                    } else {
                        "SPRING"
                    }
                ))
            })?;
            let mut nodes = Vec::with_capacity(n);
            for node in &block.nodes[e * n..(e + 1) * n] {
                nodes.push(raw.node_index.get(node).copied().ok_or_else(|| {
                    error(format!(
                        "element {id} uses node {node}, which no *NODE line defines"
                    ))
                })?);
            }
            if kind.0 == PointKind::Axial && raw.nodes[nodes[0]].1 == raw.nodes[nodes[1]].1 {
                return Err(error(format!(
                    "SPRINGA element {id} of '{}': its two nodes are at the same place (no axis to act along)",
                    block.elset.as_deref().unwrap_or("(no ELSET)")
                )));
            }
            match by_property.iter_mut().find(|(q, _, _)| *q == p) {
                Some((_, _, c)) => c.extend(nodes),
                None => by_property.push((p, kind, nodes)),
            }
        }
        let several = by_property.len() > 1;
        for (p, (kind, value), connectivity) in by_property {
            let base = block
                .elset
                .clone()
                .unwrap_or_else(|| block.abaqus.to_lowercase());
            let name = if several {
                format!("{base}-{}", raw.properties[p].elset)
            } else {
                base
            };
            log.push((name.clone(), block.abaqus.clone(), connectivity.len() / n));
            blocks.push(PointBlock {
                name,
                kind,
                value,
                connectivity,
            });
        }
    }
    Ok(log)
}

/// The kind and value a property gives elements of type `abaqus`.
fn property_of(property: &RawProperty, abaqus: &str) -> Result<Given, String> {
    let number = |line: &[String]| -> Result<f64, String> {
        let f = line.first().ok_or("a data line without a value")?;
        let v: f64 = f
            .replace(['d', 'D'], "e")
            .parse()
            .map_err(|_| format!("'{f}' is not a number"))?;
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(format!("{v}: must be a finite value >= 0"))
        }
    };
    let dof = |f: Option<&String>| -> Result<usize, String> {
        let f = f.ok_or("the first data line names the DOF(s): '1' .. '3'")?;
        match f.parse::<usize>() {
            Ok(d @ 1..=3) => Ok(d - 1),
            _ => Err(format!(
                "DOF '{f}': solid nodes have DOFs 1 to 3 (no rotations)"
            )),
        }
    };
    let lines = &property.lines;
    match (property.keyword, abaqus) {
        ("MASS", "MASS") => Ok((
            PointKind::Mass,
            number(lines.first().ok_or("no mass line")?)?,
        )),
        ("SPRING", "SPRINGA") => {
            let line = lines.last().ok_or("no stiffness line")?;
            if lines.len() > 1 {
                return Err("a SPRINGA spring takes one data line, its stiffness".into());
            }
            Ok((PointKind::Axial, number(line)?))
        }
        ("SPRING", "SPRING1" | "SPRING2") => {
            let [dofs, stiffness] = lines.as_slice() else {
                return Err(format!(
                    "a {abaqus} spring takes two data lines: its DOF(s), then its stiffness"
                ));
            };
            let kind = if abaqus == "SPRING1" {
                PointKind::Grounded {
                    dof: dof(dofs.first())?,
                }
            } else {
                PointKind::Between {
                    dofs: [dof(dofs.first())?, dof(dofs.get(1))?],
                }
            };
            Ok((kind, number(stiffness)?))
        }
        (keyword, ty) => Err(format!("*{keyword} does not apply to {ty} elements")),
    }
}
