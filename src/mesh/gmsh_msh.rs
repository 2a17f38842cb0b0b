//! Gmsh meshes (`.msh`, format 4.1 ASCII). Physical volumes become element blocks
//! (components) named after the physical group; physical surfaces become element-face
//! surfaces (each surface element is matched to the face of the volume element it bounds) and
//! node sets of the same name; physical points and curves become node sets. Materials come
//! from the scene, by block name.
//!
//! Node orders differ from Abaqus for the quadratic elements: Gmsh numbers the mid-edge nodes
//! of a 20-node hexahedron and of a 10-node tetrahedron in its own edge order
//! (`GMSH_HEX_EDGES`, `GMSH_TET_EDGES`); they are permuted on reading.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use super::{ElementBlock, Mesh};
use crate::mesh::element::{ElementKind, HEX_EDGES, TET_EDGES};
use crate::mesh::material::Material;

/// Gmsh's edge order of the 20-node hexahedron (mid-edge nodes 8..19).
const GMSH_HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [0, 3],
    [0, 4],
    [1, 2],
    [1, 5],
    [2, 3],
    [2, 6],
    [3, 7],
    [4, 5],
    [4, 7],
    [5, 6],
    [6, 7],
];

/// Gmsh's edge order of the 10-node tetrahedron (mid-edge nodes 4..9).
const GMSH_TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MshError {
    #[error("{file}: {message}")]
    Io { file: PathBuf, message: String },
    #[error("{file}:{line}: {message}")]
    Syntax {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    Model { file: PathBuf, message: String },
}

/// Element types: (kind of volume element | number of corners of a face element, nodes).
fn element_type(t: u32) -> Option<(Option<ElementKind>, usize, usize)> {
    // (volume kind, face corners (0 when not a face), node count)
    Some(match t {
        5 => (Some(ElementKind::Hex8), 0, 8),
        17 => (Some(ElementKind::Hex20), 0, 20),
        4 => (Some(ElementKind::Tet4), 0, 4),
        11 => (Some(ElementKind::Tet10), 0, 10),
        2 => (None, 3, 3),
        9 => (None, 3, 6),
        3 => (None, 4, 4),
        16 => (None, 4, 8),
        10 => (None, 4, 9),
        15 => (None, 0, 1),
        1 => (None, 0, 2),
        8 => (None, 0, 3),
        _ => return None,
    })
}

/// Permutation `abaqus[i] = gmsh[perm[i]]` of a quadratic element's nodes.
fn permutation(kind: ElementKind) -> Vec<usize> {
    let (ours, theirs, first): (&[[usize; 2]], &[[usize; 2]], usize) = match kind {
        ElementKind::Hex20 | ElementKind::Hex20R => (&HEX_EDGES, &GMSH_HEX_EDGES, 8),
        ElementKind::Tet10 => (&TET_EDGES, &GMSH_TET_EDGES, 4),
        _ => return (0..kind.nodes()).collect(),
    };
    let mut perm: Vec<usize> = (0..first).collect();
    for &[a, b] in ours {
        let j = theirs
            .iter()
            .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
            .expect("same edges");
        perm.push(first + j);
    }
    perm
}

struct Reader<'a> {
    file: &'a Path,
    lines: Vec<&'a str>,
    pos: usize,
}

impl<'a> Reader<'a> {
    fn syntax(&self, message: impl Into<String>) -> MshError {
        MshError::Syntax {
            file: self.file.to_path_buf(),
            line: self.pos.min(self.lines.len()),
            message: message.into(),
        }
    }

    fn next(&mut self) -> Result<&'a str, MshError> {
        let line = *self
            .lines
            .get(self.pos)
            .ok_or_else(|| self.syntax("unexpected end of file"))?;
        self.pos += 1;
        Ok(line.trim())
    }

    fn numbers<T: std::str::FromStr>(&mut self) -> Result<Vec<T>, MshError> {
        let line = self.next()?;
        line.split_whitespace()
            .map(|w| {
                w.parse::<T>()
                    .map_err(|_| self.syntax(format!("'{w}' is not a number")))
            })
            .collect()
    }

    fn expect(&mut self, tag: &str) -> Result<(), MshError> {
        let line = self.next()?;
        if line != tag {
            return Err(self.syntax(format!("expected {tag}, found '{line}'")));
        }
        Ok(())
    }
}

/// A mesh read from a Gmsh file.
#[derive(Debug, Clone)]
pub struct MshModel {
    pub mesh: Mesh,
    /// Section names skipped (line, name).
    pub skipped: Vec<(usize, String)>,
}

/// The most entries reserved ahead from a count the file announces (a corrupt count must not
/// allocate gigabytes before the entries are read).
const CAPACITY_HINT: usize = 1 << 20;

/// An element block as read: dimension, entity, type, (tag, node tags) per element, line.
struct RawElementBlock {
    dim: u32,
    entity: i64,
    ty: u32,
    elements: Vec<(u64, Vec<u64>)>,
    line: usize,
}

/// The sections of a file as read, in the file's tags.
#[derive(Default)]
struct RawMsh {
    seen_format: bool,
    /// (dim, physical tag) -> name
    names: HashMap<(u32, i64), String>,
    /// (dim, entity tag) -> physical tags
    entity_groups: HashMap<(u32, i64), Vec<i64>>,
    node_index: HashMap<u64, usize>,
    coords: Vec<[f64; 3]>,
    blocks: Vec<RawElementBlock>,
    /// Sections skipped (line, name).
    skipped: Vec<(usize, String)>,
}

/// Reads a Gmsh 4.1 ASCII file. `materials` gives the material of each physical volume by
/// name; every volume group needs one. The sections are read in file order, one method each
/// ($MeshFormat, $PhysicalNames, $Entities, $Nodes, $Elements), then resolved: volume
/// elements into blocks per physical group and kind, lower-dimensional groups into node sets
/// and surfaces.
pub fn read(path: &Path, materials: &BTreeMap<String, Material>) -> Result<MshModel, MshError> {
    let text = std::fs::read(path).map_err(|e| MshError::Io {
        file: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let text = String::from_utf8(text).map_err(|_| MshError::Model {
        file: path.to_path_buf(),
        message: "not a text file: binary .msh is not supported; save it as ASCII 4.1 (gmsh option -format msh41 with Mesh.Binary = 0)".into(),
    })?;
    let mut r = Reader {
        file: path,
        lines: text.lines().collect(),
        pos: 0,
    };
    let mut raw = RawMsh::default();
    while r.pos < r.lines.len() {
        let line = r.next()?;
        match line {
            "" => {}
            "$MeshFormat" => raw.format(&mut r)?,
            "$PhysicalNames" => raw.physical_names(&mut r)?,
            "$Entities" => raw.entities(&mut r)?,
            "$Nodes" => raw.nodes(&mut r)?,
            "$Elements" => raw.elements(&mut r)?,
            section if section.starts_with('$') && !section.starts_with("$End") => {
                // Post-processing data, periodicity, ...: cannot change K or M.
                raw.skipped.push((r.pos, section[1..].to_string()));
                let end = format!("$End{}", &section[1..]);
                while r.next()? != end {}
            }
            other => return Err(r.syntax(format!("unexpected line '{other}'"))),
        }
    }
    raw.resolve(path, materials)
}

impl RawMsh {
    fn format(&mut self, r: &mut Reader) -> Result<(), MshError> {
        let header = r.next()?;
        let mut w = header.split_whitespace();
        let version = w.next().unwrap_or("");
        let file_type = w.next().unwrap_or("");
        if !version.starts_with("4.1") {
            return Err(r.syntax(format!(
                "MSH version {version}: only 4.1 is read (re-save with gmsh -format msh41)"
            )));
        }
        if file_type != "0" {
            return Err(r.syntax("binary MSH is not supported: save as ASCII (Mesh.Binary = 0)"));
        }
        self.seen_format = true;
        r.expect("$EndMeshFormat")
    }

    fn physical_names(&mut self, r: &mut Reader) -> Result<(), MshError> {
        let n: Vec<usize> = r.numbers()?;
        for _ in 0..*n.first().ok_or_else(|| r.syntax("missing count"))? {
            let l = r.next()?;
            let mut w = l.splitn(3, char::is_whitespace);
            let dim: u32 = w
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| r.syntax("bad physical name line"))?;
            let tag: i64 = w
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| r.syntax("bad physical name line"))?;
            let name = w.next().unwrap_or("").trim().trim_matches('"').to_string();
            self.names.insert((dim, tag), name);
        }
        r.expect("$EndPhysicalNames")
    }

    fn entities(&mut self, r: &mut Reader) -> Result<(), MshError> {
        let counts: Vec<usize> = r.numbers()?;
        if counts.len() != 4 {
            return Err(r.syntax("expected 4 entity counts"));
        }
        for (dim, &count) in counts.iter().enumerate() {
            for _ in 0..count {
                let v: Vec<f64> = r.numbers()?;
                // Points: tag x y z nphys tags...; others: tag 6 box values nphys tags...
                let at = if dim == 0 { 4 } else { 7 };
                let np = *v.get(at).ok_or_else(|| r.syntax("short entity line"))? as usize;
                let tags: Vec<i64> = v
                    .get(at + 1..at + 1 + np)
                    .ok_or_else(|| r.syntax("short entity line"))?
                    .iter()
                    .map(|&t| t as i64)
                    .collect();
                self.entity_groups.insert((dim as u32, v[0] as i64), tags);
            }
        }
        r.expect("$EndEntities")
    }

    fn nodes(&mut self, r: &mut Reader) -> Result<(), MshError> {
        let head: Vec<usize> = r.numbers()?;
        let blocks = *head.first().ok_or_else(|| r.syntax("missing count"))?;
        for _ in 0..blocks {
            let b: Vec<i64> = r.numbers()?;
            if b.len() != 4 {
                return Err(r.syntax("node block header needs 4 numbers"));
            }
            // Parametric coordinates (b[2] = 1) follow x y z on the same line.
            let n = usize::try_from(b[3])
                .map_err(|_| r.syntax(format!("negative node count {}", b[3])))?;
            // A count read from the file is a hint, not a size to allocate up front.
            let mut tags = Vec::with_capacity(n.min(CAPACITY_HINT));
            for _ in 0..n {
                let t: Vec<u64> = r.numbers()?;
                tags.push(*t.first().ok_or_else(|| r.syntax("missing node tag"))?);
            }
            for tag in tags {
                let x: Vec<f64> = r.numbers()?;
                if x.len() < 3 {
                    return Err(r.syntax("node needs x y z"));
                }
                if x[..3].iter().any(|v| !v.is_finite()) {
                    return Err(r.syntax(format!("node {tag}: coordinate is not finite")));
                }
                if self.node_index.insert(tag, self.coords.len()).is_some() {
                    return Err(r.syntax(format!("node {tag} defined twice")));
                }
                self.coords.push([x[0], x[1], x[2]]);
            }
        }
        r.expect("$EndNodes")
    }

    fn elements(&mut self, r: &mut Reader) -> Result<(), MshError> {
        let head: Vec<usize> = r.numbers()?;
        let blocks = *head.first().ok_or_else(|| r.syntax("missing count"))?;
        for _ in 0..blocks {
            let b: Vec<i64> = r.numbers()?;
            if b.len() != 4 {
                return Err(r.syntax("element block header needs 4 numbers"));
            }
            let line = r.pos;
            let ty = b[2] as u32;
            let (_, _, nodes) = element_type(ty).ok_or_else(|| {
                r.syntax(format!(
                    "element type {ty} is not supported (volumes: 4 tet4, 5 hex8, 11 tet10, 17 hex20; faces: 2, 3, 9, 10, 16)"
                ))
            })?;
            let count = usize::try_from(b[3])
                .map_err(|_| r.syntax(format!("negative element count {}", b[3])))?;
            let mut elements = Vec::with_capacity(count.min(CAPACITY_HINT));
            for _ in 0..count {
                let v: Vec<u64> = r.numbers()?;
                if v.len() != nodes + 1 {
                    return Err(r.syntax(format!(
                        "element of type {ty} needs a tag and {nodes} nodes, found {} numbers",
                        v.len()
                    )));
                }
                elements.push((v[0], v[1..].to_vec()));
            }
            self.blocks.push(RawElementBlock {
                dim: b[0] as u32,
                entity: b[1],
                ty,
                elements,
                line,
            });
        }
        r.expect("$EndElements")
    }

    fn group_name(&self, dim: u32, tag: i64) -> String {
        self.names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical_{dim}_{tag}"))
    }

    fn node(&self, path: &Path, tag: u64, line: usize) -> Result<usize, MshError> {
        self.node_index
            .get(&tag)
            .copied()
            .ok_or_else(|| MshError::Syntax {
                file: path.to_path_buf(),
                line,
                message: format!("node {tag} is not defined"),
            })
    }

    /// The mesh these sections describe.
    fn resolve(
        self,
        path: &Path,
        materials: &BTreeMap<String, Material>,
    ) -> Result<MshModel, MshError> {
        let model_err = |message: String| MshError::Model {
            file: path.to_path_buf(),
            message,
        };
        if !self.seen_format {
            return Err(model_err("no $MeshFormat section: not a Gmsh file".into()));
        }
        let mut mesh = Mesh {
            coords: self.coords.clone(),
            ..Default::default()
        };
        self.volume_blocks(path, materials, &mut mesh)?;
        self.lower_groups(path, &mut mesh)?;
        Ok(MshModel {
            mesh,
            skipped: self.skipped,
        })
    }

    /// Volume elements, one block per (physical group, element kind), each with the
    /// material the scene gives its group; global element order = block order.
    fn volume_blocks(
        &self,
        path: &Path,
        materials: &BTreeMap<String, Material>,
        mesh: &mut Mesh,
    ) -> Result<(), MshError> {
        let model_err = |message: String| MshError::Model {
            file: path.to_path_buf(),
            message,
        };
        let mut block_of: HashMap<(String, ElementKind), usize> = HashMap::new();
        let mut pending: Vec<(usize, Vec<usize>, u64)> = Vec::new();
        for raw in &self.blocks {
            let (Some(kind), _, _) = element_type(raw.ty).unwrap() else {
                continue;
            };
            if raw.dim != 3 {
                continue;
            }
            let groups = self
                .entity_groups
                .get(&(3, raw.entity))
                .cloned()
                .unwrap_or_default();
            let name = match groups.first() {
                Some(&g) => self.group_name(3, g),
                None => format!("volume_{}", raw.entity),
            };
            let next = block_of.len();
            let b = *block_of.entry((name, kind)).or_insert(next);
            let perm = permutation(kind);
            for (tag, nodes) in &raw.elements {
                let ours: Vec<usize> = perm
                    .iter()
                    .map(|&p| self.node(path, nodes[p], raw.line))
                    .collect::<Result<_, _>>()?;
                pending.push((b, ours, *tag));
            }
        }
        if block_of.is_empty() {
            return Err(model_err(
                "no volume elements (types 4, 5, 11, 17): mesh the volumes, and put them in physical groups".into(),
            ));
        }
        let mut blocks = vec![(String::new(), ElementKind::Hex8); block_of.len()];
        for ((name, kind), &b) in &block_of {
            blocks[b] = (name.clone(), *kind);
        }
        for (name, kind) in &blocks {
            let material = materials.get(name).ok_or_else(|| {
                model_err(format!(
                    "physical volume '{name}' has no material: add [model.materials.{name}] to the scene (materials given: {})",
                    materials.keys().cloned().collect::<Vec<_>>().join(", ")
                ))
            })?;
            let index = match mesh.materials.iter().position(|m| m.name == material.name) {
                Some(i) => i,
                None => {
                    mesh.materials.push(material.clone());
                    mesh.materials.len() - 1
                }
            };
            mesh.blocks.push(ElementBlock {
                name: name.clone(),
                kind: *kind,
                material: index,
                connectivity: Vec::new(),
                orientation: None,
            });
        }
        for (b, nodes, _) in pending {
            mesh.blocks[b].connectivity.extend(nodes);
        }
        Ok(())
    }

    /// Lower-dimensional physical groups: node sets, and surfaces (faces of the volume
    /// elements) for dimension 2.
    fn lower_groups(&self, path: &Path, mesh: &mut Mesh) -> Result<(), MshError> {
        let faces = face_index(mesh);
        for raw in self.blocks.iter().filter(|b| b.dim != 3) {
            let groups = self
                .entity_groups
                .get(&(raw.dim, raw.entity))
                .cloned()
                .unwrap_or_default();
            let (_, corners, _) = element_type(raw.ty).unwrap();
            for group in groups {
                let name = self.group_name(raw.dim, group);
                let mut set: Vec<usize> = Vec::new();
                for (tag, nodes) in &raw.elements {
                    let ids: Vec<usize> = nodes
                        .iter()
                        .map(|&n| self.node(path, n, raw.line))
                        .collect::<Result<_, _>>()?;
                    set.extend(&ids);
                    if raw.dim == 2 && corners > 0 {
                        let mut key = ids[..corners].to_vec();
                        key.sort_unstable();
                        let face = faces.get(&key).ok_or_else(|| MshError::Syntax {
                            file: path.to_path_buf(),
                            line: raw.line,
                            message: format!(
                                "surface element {tag} of physical surface '{name}' is not a face of any volume element"
                            ),
                        })?;
                        mesh.surfaces.entry(name.clone()).or_default().push(*face);
                    }
                }
                let entry = mesh.node_sets.entry(name).or_default();
                entry.extend(set);
                entry.sort_unstable();
                entry.dedup();
            }
        }
        Ok(())
    }
}

/// The faces of the volume elements by their sorted corner nodes: (element, face 1-based).
fn face_index(mesh: &Mesh) -> HashMap<Vec<usize>, (usize, u8)> {
    mesh.face_keys(|_| true).into_iter().collect()
}
