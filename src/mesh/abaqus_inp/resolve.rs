//! The second pass: the raw tables of a file resolved into a model (Abaqus ids to indices,
//! sections to materials and element blocks, sets to nodes, boundaries to clamps, surfaces to
//! element faces, contact pairs to their interactions), with errors naming the file (and the
//! line where one is known).

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::raw::{RawBlock, RawInp};
use super::{ContactPair, InpError, InpModel};
use crate::mesh::material::Material;
use crate::mesh::orientation::{Orientation, System};
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
        for b in &self.point_blocks {
            if let Some(name) = &b.elset {
                self.elsets.entry(name.clone()).or_default().extend(&b.ids);
            }
        }
        let material_ids = r.materials(&self)?;
        let orientation_ids = r.orientations(&self)?;
        let element_material = r.sections(&self, &material_ids, &orientation_ids)?;
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
        let points = super::point::resolve(&self, path, &mut r.model.mesh.point_blocks)?;
        r.model.element_types.extend(points);
        r.model.mesh.constraints.equations = super::equation::resolve(&self, path)?;
        r.check_orientations()?;
        r.node_sets(&self)?;
        r.boundaries(&self)?;
        r.surfaces(&self)?;
        r.contact_pairs(&self)?;
        r.model.ties = super::tie::resolve(&self, path, &r.model.mesh)?;
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

    /// The orientations, their axes checked; their indices by upper-case name.
    fn orientations(&mut self, raw: &RawInp) -> Result<HashMap<String, usize>, InpError> {
        let mut ids = HashMap::new();
        for o in &raw.orientations {
            let p = &o.points;
            let point = |k: usize| [p[3 * k], p[3 * k + 1], p[3 * k + 2]];
            let system = if o.cylindrical {
                System::Cylindrical {
                    a: point(0),
                    b: point(1),
                }
            } else {
                let origin = if p.len() == 9 { point(2) } else { [0.0; 3] };
                System::Rectangular {
                    a: point(0),
                    b: point(1),
                    origin,
                }
            };
            let orientation = Orientation {
                name: o.name.clone(),
                system,
                extra_rotation: o.rotation,
            };
            let defined = match orientation.system {
                System::Rectangular { .. } => orientation.axes_at([0.0; 3]).is_some(),
                System::Cylindrical { a, b } => a != b && p.len() == 6,
            };
            if p.is_empty() || !defined {
                return Err(self.error(format!(
                    "line {}: *ORIENTATION {}: its points do not define axes (a rectangular system needs a away from the origin and b off that line; a cylindrical one two distinct points a, b on its axis and no origin)",
                    o.line, o.name
                )));
            }
            ids.insert(o.name.to_uppercase(), self.model.mesh.orientations.len());
            self.model.mesh.orientations.push(orientation);
        }
        Ok(ids)
    }

    /// Every element of a block on a cylindrical orientation has its centroid off the axis,
    /// where the local axes are defined (`ElementKernel` falls back to it at points on it).
    fn check_orientations(&self) -> Result<(), InpError> {
        let mesh = &self.model.mesh;
        let mut x = Vec::new();
        for block in &mesh.blocks {
            let Some(o) = block.orientation.map(|o| &mesh.orientations[o]) else {
                continue;
            };
            for e in 0..block.len() {
                mesh.element_coords(block.element(e), &mut x);
                let n = x.len() as f64;
                let c = [0, 1, 2].map(|i| x.iter().map(|p| p[i]).sum::<f64>() / n);
                if o.axes_at(c).is_none() {
                    return Err(self.error(format!(
                        "block {}: element {} has its centroid on the axis of the cylindrical *ORIENTATION {}, where no radial direction exists",
                        block.name,
                        e + 1,
                        o.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Each element's material and orientation, from the *SOLID SECTION lines.
    fn sections(
        &self,
        raw: &RawInp,
        material_ids: &HashMap<String, usize>,
        orientation_ids: &HashMap<String, usize>,
    ) -> Result<HashMap<i64, (usize, Option<usize>)>, InpError> {
        let mut element_material = HashMap::new();
        for s in &raw.sections {
            let (elset, material, line) = (&s.elset, &s.material, s.line);
            let m = *material_ids.get(&material.to_uppercase()).ok_or_else(|| {
                self.error(format!(
                    "line {line}: *SOLID SECTION names material '{material}', which is not defined"
                ))
            })?;
            let o = match &s.orientation {
                Some(name) => Some(*orientation_ids.get(&name.to_uppercase()).ok_or_else(|| {
                    self.error(format!(
                        "line {line}: *SOLID SECTION names orientation '{name}', which no *ORIENTATION defines"
                    ))
                })?),
                None => None,
            };
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
                element_material.insert(id, (m, o));
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
        element_material: &HashMap<i64, (usize, Option<usize>)>,
    ) -> Result<(), InpError> {
        let nn = block.kind.nodes();
        type Section = (usize, Option<usize>);
        let mut by_material: BTreeMap<Section, (Vec<usize>, Vec<i64>)> = BTreeMap::new();
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
        for ((m, o), (connectivity, eids)) in by_material {
            let mesh = &self.model.mesh;
            let mut name = match &block.elset {
                Some(s) if one_material => s.clone(),
                Some(s) => format!("{s}-{}", mesh.materials[m].name),
                None => format!("block{}-{}", mesh.blocks.len(), mesh.materials[m].name),
            };
            // One ELSET with several element types or orientations: blocks named apart.
            if mesh.blocks.iter().any(|b| b.name == name) {
                name = format!("{name}-{}", block.abaqus.to_lowercase());
            }
            let base = name.clone();
            let mut k = 2;
            while mesh.blocks.iter().any(|b| b.name == name) {
                name = format!("{base}-{k}");
                k += 1;
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
                orientation: o,
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
