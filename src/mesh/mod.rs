//! Meshes: nodes, element blocks (one element type and material each), point elements, node sets and
//! element-face surfaces.

pub mod abaqus_inp;
pub mod brake;
pub mod clamp;
pub mod constraint;
pub mod element;
pub mod gmsh_msh;
pub mod material;
pub mod orientation;
pub mod partition;
pub mod point;
pub mod structured;

pub use clamp::Clamp;
pub use element::ElementKind;

use std::collections::BTreeMap;

/// A name the mesh does not have, or a set that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("no surface '{name}' in the mesh (surfaces: {})", available.join(", "))]
    NoSurface {
        name: String,
        available: Vec<String>,
    },
    #[error("no node set '{name}' in the mesh (sets: {})", available.join(", "))]
    NoNodeSet {
        name: String,
        available: Vec<String>,
    },
    #[error("node set '{0}' is empty: nothing would be clamped")]
    EmptyClamp(String),
}

use serde::{Deserialize, Serialize};

use crate::mesh::material::Material;

/// Elements of one type and one material (a component, or part of one).
#[derive(Debug, Clone)]
pub struct ElementBlock {
    pub name: String,
    pub kind: ElementKind,
    /// Index into `Mesh::materials`.
    pub material: usize,
    /// Node indices, `kind.nodes()` per element.
    pub connectivity: Vec<usize>,
    /// Index into `Mesh::orientations`: the axes the material's constants refer to (None:
    /// the global axes).
    pub orientation: Option<usize>,
}

impl ElementBlock {
    pub fn len(&self) -> usize {
        self.connectivity.len() / self.kind.nodes()
    }

    pub fn is_empty(&self) -> bool {
        self.connectivity.is_empty()
    }

    pub fn element(&self, e: usize) -> &[usize] {
        let n = self.kind.nodes();
        &self.connectivity[e * n..(e + 1) * n]
    }
}

#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub coords: Vec<[f64; 3]>,
    pub blocks: Vec<ElementBlock>,
    pub materials: Vec<Material>,
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Element-face surfaces: (global element index, face 1..6 in Abaqus numbering; 1..4 for
    /// tetrahedra). Global element indices run over the blocks in order.
    pub surfaces: BTreeMap<String, Vec<(usize, u8)>>,
    /// Material orientations the blocks refer to.
    pub orientations: Vec<orientation::Orientation>,
    /// Lumped masses and springs (imported models): they join nodes of the blocks.
    pub point_blocks: Vec<point::PointBlock>,
    /// Linear multi-point constraints (imported models: *EQUATION, *TIE), by penalty.
    pub constraints: constraint::Constraints,
}

impl Mesh {
    pub fn node_count(&self) -> usize {
        self.coords.len()
    }

    pub fn element_count(&self) -> usize {
        self.blocks.iter().map(ElementBlock::len).sum()
    }

    /// Coordinates of the nodes of an element.
    pub fn element_coords(&self, nodes: &[usize], out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend(nodes.iter().map(|&n| self.coords[n]));
    }

    /// (block, element within the block) of a global element index.
    pub fn locate_element(&self, global: usize) -> (usize, usize) {
        let mut start = 0;
        for (b, block) in self.blocks.iter().enumerate() {
            if global < start + block.len() {
                return (b, global - start);
            }
            start += block.len();
        }
        panic!("element {global} out of range ({} elements)", start)
    }

    /// Nodes of face `face` (Abaqus numbering) of the global element `global`: corners first,
    /// then mid-edge nodes for quadratic elements.
    pub fn face_nodes(&self, global: usize, face: u8) -> Vec<usize> {
        let (b, e) = self.locate_element(global);
        let block = &self.blocks[b];
        let nodes = block.element(e);
        block
            .kind
            .face_local_nodes(face)
            .iter()
            .map(|&i| nodes[i])
            .collect()
    }

    /// Every face of the elements of the blocks `chosen` accepts, keyed by its sorted corner
    /// nodes (the same key for the two elements that share it): (key, (element, face 1-based)),
    /// elements numbered globally in block order.
    pub fn face_keys(&self, chosen: impl Fn(usize) -> bool) -> Vec<(Vec<usize>, (usize, u8))> {
        let mut out = Vec::new();
        let mut first = 0;
        for (b, block) in self.blocks.iter().enumerate() {
            if chosen(b) {
                let corners = if block.kind.faces() == 6 { 4 } else { 3 };
                for e in 0..block.len() {
                    let nodes = block.element(e);
                    for f in 1..=block.kind.faces() {
                        let mut key: Vec<usize> = block.kind.face_local_nodes(f)[..corners]
                            .iter()
                            .map(|&i| nodes[i])
                            .collect();
                        key.sort_unstable();
                        out.push((key, (first + e, f)));
                    }
                }
            }
            first += block.len();
        }
        out
    }

    /// The surface `name`, or an error listing the surfaces that exist.
    pub fn surface(&self, name: &str) -> Result<&[(usize, u8)], MeshError> {
        self.surfaces
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| MeshError::NoSurface {
                name: name.to_string(),
                available: self.surfaces.keys().cloned().collect(),
            })
    }

    /// The nodes of a surface, sorted and unique.
    pub fn surface_nodes(&self, name: &str) -> Result<Vec<usize>, MeshError> {
        let mut nodes: Vec<usize> = self
            .surface(name)?
            .iter()
            .flat_map(|&(e, f)| self.face_nodes(e, f))
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        Ok(nodes)
    }

    /// Appends `other`: its nodes, blocks (materials merged by name), point elements, node sets
    /// and surfaces
    /// (names must not clash; they get no prefix).
    pub fn append(&mut self, other: Mesh) {
        let node_offset = self.coords.len();
        let element_offset = self.element_count();
        let orientation_offset = self.orientations.len();
        self.coords.extend(other.coords);
        self.orientations.extend(other.orientations);
        for block in other.blocks {
            let material = &other.materials[block.material];
            let index = match self.materials.iter().position(|m| m.name == material.name) {
                Some(i) => i,
                None => {
                    self.materials.push(material.clone());
                    self.materials.len() - 1
                }
            };
            self.blocks.push(ElementBlock {
                name: block.name,
                kind: block.kind,
                material: index,
                connectivity: block.connectivity.iter().map(|n| n + node_offset).collect(),
                orientation: block.orientation.map(|o| o + orientation_offset),
            });
        }
        for mut points in other.point_blocks {
            points
                .connectivity
                .iter_mut()
                .for_each(|n| *n += node_offset);
            self.point_blocks.push(points);
        }
        for mut c in other.constraints.equations {
            c.terms.iter_mut().for_each(|t| t.0 += node_offset);
            self.constraints.equations.push(c);
        }
        for (name, nodes) in other.node_sets {
            let shifted = nodes.iter().map(|n| n + node_offset).collect();
            assert!(
                self.node_sets.insert(name.clone(), shifted).is_none(),
                "node set '{name}' defined twice"
            );
        }
        for (name, faces) in other.surfaces {
            let shifted = faces
                .iter()
                .map(|&(e, f)| (e + element_offset, f))
                .collect();
            assert!(
                self.surfaces.insert(name.clone(), shifted).is_none(),
                "surface '{name}' defined twice"
            );
        }
    }

    /// The node set `name`, or an error listing the sets that exist.
    pub fn node_set(&self, name: &str) -> Result<&[usize], MeshError> {
        self.node_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| MeshError::NoNodeSet {
                name: name.to_string(),
                available: self.node_sets.keys().cloned().collect(),
            })
    }
}

/// How two surfaces interact (the contact stage builds its laws from this).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InterfaceKind {
    /// Lining on disc: normal contact law and friction with the disc sliding.
    Sliding,
    /// Component joints held by friction without sliding.
    Sticking,
}

/// A contact interface: contact points at the Gauss points of `master`, projected on `slave`.
#[derive(Debug, Clone, PartialEq)]
pub struct Interface {
    pub name: String,
    pub master: String,
    pub slave: String,
    pub kind: InterfaceKind,
}

/// The brake-line pressure acting on a surface: total force = pressure x `area` (the
/// hydraulic area), spread uniformly over the surface, pushing into it.
#[derive(Debug, Clone, PartialEq)]
pub struct PressureLoad {
    pub surface: String,
    pub area: f64,
}
