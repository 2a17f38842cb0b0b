//! `*TIE` with node-based (`*SURFACE, TYPE=NODE`) or element-face slave surfaces: each tie's
//! slave nodes and master surface, for the model stage to constrain
//! (`contact::tie`: the slave node's displacement equals the master surface's at its
//! projection).

use std::path::Path;

use super::raw::{At, RawInp};
use super::{InpError, Keyword};
use crate::mesh::Mesh;

/// A *TIE as read: name, position tolerance, adjust, its (slave, master) surfaces and line.
pub(super) struct RawTie {
    pub name: String,
    pub tolerance: Option<f64>,
    pub adjust: bool,
    pub surfaces: Option<(String, String)>,
    pub line: usize,
}

/// The *TIE keyword line: NAME, POSITION TOLERANCE, ADJUST (YES by default).
pub(super) fn keyword(kw: &Keyword, at: At) -> Result<RawTie, InpError> {
    let param = |k: &str| kw.params.get(k).cloned();
    let tolerance = match param("POSITION TOLERANCE") {
        Some(t) => Some(at.num(&t)?),
        None => None,
    };
    let adjust = match param("ADJUST").map(|a| a.to_uppercase()) {
        None => true,
        Some(a) if a == "YES" => true,
        Some(a) if a == "NO" => false,
        Some(a) => return Err(at.syntax(format!("*TIE, ADJUST={a}: use YES or NO"))),
    };
    if let Some(p) = ["TYPE", "ROTATION", "CONSTRAINT RATIO"]
        .iter()
        .find(|p| kw.params.contains_key(**p))
    {
        return Err(at.syntax(format!(
            "*TIE, {p}: only the default surface-to-surface tie of translations is read"
        )));
    }
    Ok(RawTie {
        name: param("NAME").ok_or_else(|| at.syntax("*TIE needs NAME=".into()))?,
        tolerance,
        adjust,
        surfaces: None,
        line: at.line,
    })
}

/// The *TIE's data line: slave surface, master surface.
pub(super) fn surfaces_line(tie: &mut RawTie, fields: &[&str], at: At) -> Result<(), InpError> {
    if fields.len() != 2 || tie.surfaces.is_some() {
        return Err(at.syntax("*TIE takes one data line: 'slave surface, master surface'".into()));
    }
    tie.surfaces = Some((fields[0].to_string(), fields[1].to_string()));
    Ok(())
}

/// A data line of *SURFACE, TYPE=NODE: a node set or id (a weight after it is not used).
pub(super) fn node_surface_line(
    raw: &mut RawInp,
    name: &str,
    fields: &[&str],
    at: At,
) -> Result<(), InpError> {
    if fields.is_empty() || fields.len() > 2 {
        return Err(at.syntax("expected 'node set or id[, weight]'".into()));
    }
    raw.node_surfaces
        .entry(name.to_string())
        .or_default()
        .push((fields[0].to_string(), at.line));
    Ok(())
}

/// A tie of an imported model.
#[derive(Debug, Clone, PartialEq)]
pub struct Tie {
    pub name: String,
    /// The slave surface's name and nodes (sorted, unique).
    pub slave: String,
    pub slave_nodes: Vec<usize>,
    /// The master element-face surface.
    pub master: String,
    /// POSITION TOLERANCE (m); None: the default, 5 % of the master faces' median diagonal.
    pub tolerance: Option<f64>,
    /// ADJUST=YES (the default): slave nodes moved onto the master surface.
    pub adjust: bool,
    pub line: usize,
}

/// The file's ties, their surfaces resolved on `mesh` (its element-face surfaces read).
pub(super) fn resolve(raw: &RawInp, path: &Path, mesh: &Mesh) -> Result<Vec<Tie>, InpError> {
    let error = |line: usize, message: String| InpError::Model {
        file: path.to_path_buf(),
        message: format!("line {line}: *TIE: {message}"),
    };
    let mut ties = Vec::new();
    for t in &raw.ties {
        let (slave, master) = t
            .surfaces
            .clone()
            .ok_or_else(|| error(t.line, "no 'slave surface, master surface' line".into()))?;
        let find = |name: &str| {
            mesh.surfaces
                .keys()
                .find(|k| k.eq_ignore_ascii_case(name))
                .cloned()
        };
        let master_name = find(&master).ok_or_else(|| {
            let node_based = raw.node_surfaces.keys().any(|k| k.eq_ignore_ascii_case(&master));
            error(
                t.line,
                if node_based {
                    format!("master surface '{master}' is node-based: a master needs element faces (*SURFACE, TYPE=ELEMENT)")
                } else {
                    format!("master surface '{master}' is not defined")
                },
            )
        })?;
        let slave_nodes = match raw
            .node_surfaces
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(&slave))
        {
            Some((_, targets)) => {
                let mut nodes = Vec::new();
                for (target, line) in targets {
                    let ids: Vec<i64> = match target.parse::<i64>() {
                        Ok(id) => vec![id],
                        Err(_) => raw
                            .nsets
                            .iter()
                            .find(|(k, _)| k.eq_ignore_ascii_case(target))
                            .map(|(_, ids)| ids.clone())
                            .ok_or_else(|| {
                                error(
                                    *line,
                                    format!(
                                        "node set '{target}' of surface '{slave}' is not defined"
                                    ),
                                )
                            })?,
                    };
                    for id in ids {
                        nodes.push(raw.node_index.get(&id).copied().ok_or_else(|| {
                            error(*line, format!("node {id} is used but not defined"))
                        })?);
                    }
                }
                nodes.sort_unstable();
                nodes.dedup();
                nodes
            }
            None => {
                let name = find(&slave).ok_or_else(|| {
                    error(t.line, format!("slave surface '{slave}' is not defined"))
                })?;
                mesh.surface_nodes(&name)
                    .expect("a surface of the mesh has nodes")
            }
        };
        if let Some(tol) = t.tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(error(
                    t.line,
                    format!("POSITION TOLERANCE={tol}: must be > 0"),
                ));
            }
        }
        ties.push(Tie {
            name: t.name.clone(),
            slave,
            slave_nodes,
            master: master_name,
            tolerance: t.tolerance,
            adjust: t.adjust,
            line: t.line,
        });
    }
    Ok(ties)
}
