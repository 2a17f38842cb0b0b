//! The second pass: the raw tables of a file resolved into a model (Abaqus ids to indices,
//! sections to materials and element blocks, sets to nodes, boundaries to clamps, surfaces to
//! element faces, contact pairs to their interactions), with errors naming the file (and the
//! line where one is known).

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::raw::{RawBlock, RawInp};
use super::{ContactPair, InpError, InpModel};
use crate::mesh::material::Material;
use crate::mesh::ElementBlock;

/// The resolution's state: the model so far and the maps from Abaqus ids.
struct Resolver<'a> {
    path: &'a Path,
    model: InpModel,
    elem_index: HashMap<i64, usize>,
}

impl RawInp {
    /// The model these tables describe.
    pub fn resolve(mut self, path: &Path) -> Result<InpModel, InpError> {
        let mut r = Resolver {
            path,
            model: InpModel::default(),
            elem_index: HashMap::new(),
        };
        r.model.mesh.coords = self.nodes.iter().map(|&(_, x)| x).collect();
        r.model.skipped = std::mem::take(&mut self.skipped);
        // ELSET= on an *ELEMENT line defines that element set too.
        for b in &self.blocks {
            if let Some(name) = &b.elset {
                self.elsets.entry(name.clone()).or_default().extend(&b.ids);
            }
        }
        let material_ids = r.materials(&self)?;
        let element_material = r.sections(&self, &material_ids)?;
        for block in &self.blocks {
            r.block(&self, block, &element_material)?;
            if block.extra_ids > 0 {
                r.model.notes.push(format!(
                    "{} {}: element lines carry {} node ids more than the element has (from line {}); each element takes its first {}",
                    block.abaqus,
                    block.elset.as_deref().unwrap_or("(no ELSET)"),
                    block.extra_ids,
                    block.first_extra_line,
                    block.kind.nodes()
                ));
            }
        }
        r.node_sets(&self)?;
        r.boundaries(&self)?;
        r.surfaces(&self)?;
        r.contact_pairs(&self)?;
        if r.model.mesh.blocks.is_empty() {
            return Err(r.error("no elements".into()));
        }
        Ok(r.model)
    }
}

impl Resolver<'_> {
    fn error(&self, message: String) -> InpError {
        InpError::Model {
            file: self.path.to_path_buf(),
            message,
        }
    }

    fn node(&self, raw: &RawInp, id: i64) -> Result<usize, InpError> {
        raw.node_index
            .get(&id)
            .copied()
            .ok_or_else(|| self.error(format!("node {id} is used but not defined")))
    }

    /// The materials, validated; their indices by upper-case name.
    fn materials(&mut self, raw: &RawInp) -> Result<HashMap<String, usize>, InpError> {
        let mut ids = HashMap::new();
        for m in &raw.materials {
            let name = &m.name;
            let material = Material {
                name: name.clone(),
                density: m.density.ok_or_else(|| {
                    self.error(format!(
                        "material '{name}' has no *DENSITY (modes need mass)"
                    ))
                })?,
                elasticity: m
                    .elasticity
                    .clone()
                    .ok_or_else(|| self.error(format!("material '{name}' has no *ELASTIC")))?,
            };
            material.validate().map_err(|e| self.error(e.to_string()))?;
            ids.insert(name.to_uppercase(), self.model.mesh.materials.len());
            self.model.mesh.materials.push(material);
        }
        Ok(ids)
    }

    /// Each element's material, from the *SOLID SECTION lines.
    fn sections(
        &self,
        raw: &RawInp,
        material_ids: &HashMap<String, usize>,
    ) -> Result<HashMap<i64, usize>, InpError> {
        let mut element_material = HashMap::new();
        for s in &raw.sections {
            let (elset, material, line) = (&s.elset, &s.material, s.line);
            let m = *material_ids.get(&material.to_uppercase()).ok_or_else(|| {
                self.error(format!(
                    "line {line}: *SOLID SECTION names material '{material}', which is not defined"
                ))
            })?;
            let ids = raw
                .elsets
                .get(elset)
                .cloned()
                .or_else(|| {
                    raw.blocks
                        .iter()
                        .find(|b| b.elset.as_deref() == Some(elset.as_str()))
                        .map(|b| b.ids.clone())
                })
                .ok_or_else(|| {
                    self.error(format!(
                        "line {line}: *SOLID SECTION names element set '{elset}', which is not defined"
                    ))
                })?;
            for id in ids {
                element_material.insert(id, m);
            }
        }
        Ok(element_material)
    }

    /// An *ELEMENT block as mesh blocks, one per material, keeping the file order within
    /// each (element numbering follows the file).
    fn block(
        &mut self,
        raw: &RawInp,
        block: &RawBlock,
        element_material: &HashMap<i64, usize>,
    ) -> Result<(), InpError> {
        let nn = block.kind.nodes();
        let mut by_material: BTreeMap<usize, (Vec<usize>, Vec<i64>)> = BTreeMap::new();
        for (e, id) in block.ids.iter().enumerate() {
            let m = *element_material.get(id).ok_or_else(|| {
                self.error(format!("element {id} has no *SOLID SECTION (no material)"))
            })?;
            let entry = by_material.entry(m).or_default();
            for &n in &block.connectivity[e * nn..(e + 1) * nn] {
                let node = raw.node_index.get(&n).copied().ok_or_else(|| {
                    self.error(format!(
                        "element {id} uses node {n}, which no *NODE line defines"
                    ))
                })?;
                entry.0.push(node);
            }
            entry.1.push(*id);
        }
        let one_material = by_material.len() <= 1;
        for (m, (connectivity, eids)) in by_material {
            let mesh = &self.model.mesh;
            let mut name = match &block.elset {
                Some(s) if one_material => s.clone(),
                Some(s) => format!("{s}-{}", mesh.materials[m].name),
                None => format!("block{}-{}", mesh.blocks.len(), mesh.materials[m].name),
            };
            // One ELSET with several element types: a block per type, named apart.
            if mesh.blocks.iter().any(|b| b.name == name) {
                name = format!("{name}-{}", block.abaqus.to_lowercase());
            }
            self.model
                .element_types
                .push((name.clone(), block.abaqus.clone(), eids.len()));
            for id in eids {
                self.elem_index.insert(id, self.elem_index.len());
            }
            self.model.mesh.blocks.push(ElementBlock {
                name,
                kind: block.kind,
                material: m,
                connectivity,
            });
        }
        Ok(())
    }

    fn node_sets(&mut self, raw: &RawInp) -> Result<(), InpError> {
        for (name, ids) in &raw.nsets {
            let mut v = ids
                .iter()
                .map(|&id| self.node(raw, id))
                .collect::<Result<Vec<_>, _>>()?;
            v.sort_unstable();
            v.dedup();
            self.model.mesh.node_sets.insert(name.clone(), v);
        }
        Ok(())
    }

    /// Translational DOFs 1..3 become clamps, one per node set (the union of its *BOUNDARY
    /// lines); rotations (4..6) do not exist on solids.
    fn boundaries(&mut self, raw: &RawInp) -> Result<(), InpError> {
        for b in &raw.boundaries {
            let mut comps = [false; 3];
            for d in b.first..=b.last.min(3) {
                comps[d - 1] = true;
            }
            if !comps.iter().any(|&c| c) {
                continue;
            }
            let target = &b.target;
            let set = if self.model.mesh.node_sets.contains_key(target) {
                target.clone()
            } else {
                let id: i64 = target.parse().map_err(|_| {
                    self.error(format!(
                        "line {}: *BOUNDARY names '{target}', neither a node set nor a node id",
                        b.line
                    ))
                })?;
                let name = format!("node{id}");
                let node = self.node(raw, id)?;
                self.model.mesh.node_sets.insert(name.clone(), vec![node]);
                name
            };
            match self.model.clamps.iter_mut().find(|(s, _)| *s == set) {
                Some((_, c)) => (0..3).for_each(|i| c[i] |= comps[i]),
                None => self.model.clamps.push((set, comps)),
            }
        }
        Ok(())
    }

    fn surfaces(&mut self, raw: &RawInp) -> Result<(), InpError> {
        for (name, items) in &raw.surfaces {
            let mut faces = Vec::new();
            for item in items {
                let (face, line, target) = (&item.face, item.line, &item.target);
                let f: u8 = face
                    .strip_prefix('S')
                    .and_then(|s| s.parse().ok())
                    .filter(|f| (1..=6).contains(f))
                    .ok_or_else(|| {
                        self.error(format!("line {line}: face '{face}' is not S1..S6"))
                    })?;
                let ids = match raw.elsets.get(target) {
                    Some(ids) => ids.clone(),
                    None => vec![target.parse().map_err(|_| {
                        self.error(format!(
                            "line {line}: '{target}' is neither an element set nor an element id"
                        ))
                    })?],
                };
                for id in ids {
                    let e = *self.elem_index.get(&id).ok_or_else(|| {
                        self.error(format!("line {line}: element {id} is not defined"))
                    })?;
                    faces.push((e, f));
                }
            }
            self.model.mesh.surfaces.insert(name.clone(), faces);
        }
        Ok(())
    }

    fn contact_pairs(&mut self, raw: &RawInp) -> Result<(), InpError> {
        for p in &raw.pairs {
            for s in [&p.slave, &p.master] {
                if !self.model.mesh.surfaces.contains_key(s) {
                    return Err(self.error(format!(
                        "*CONTACT PAIR names surface '{s}', which is not defined"
                    )));
                }
            }
            let interaction = &p.interaction;
            let friction = *raw.interactions.get(interaction).ok_or_else(|| {
                self.error(format!(
                    "*CONTACT PAIR names interaction '{interaction}', which is not defined"
                ))
            })?;
            self.model.contact_pairs.push(ContactPair {
                slave: p.slave.clone(),
                master: p.master.clone(),
                interaction: interaction.clone(),
                friction,
            });
        }
        Ok(())
    }
}
