//! Meshes: nodes, element blocks (one element type and material each) and node sets.

pub mod abaqus_inp;
pub mod structured;

use std::collections::BTreeMap;

use crate::fem::material::Material;
use crate::fem::shape::ElementKind;

/// Elements of one type and one material (a component, or part of one).
#[derive(Debug, Clone)]
pub struct ElementBlock {
    pub name: String,
    pub kind: ElementKind,
    /// Index into `Mesh::materials`.
    pub material: usize,
    /// Node indices, `kind.nodes()` per element.
    pub connectivity: Vec<usize>,
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

    /// The node set `name`, or an error listing the sets that exist.
    pub fn node_set(&self, name: &str) -> Result<&[usize], String> {
        self.node_sets.get(name).map(Vec::as_slice).ok_or_else(|| {
            format!(
                "no node set '{name}' in the mesh (sets: {})",
                self.node_sets
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }
}
