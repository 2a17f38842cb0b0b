//! The first pass over an input file: every keyword and data line into raw tables in file
//! order (Abaqus ids, names as written), with syntax errors naming the file and line. What the
//! tables mean together (ids to indices, sets to elements, materials to blocks) is decided in
//! `resolve.rs`.

use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

use super::elastic::{elasticity, ElasticForm};
use super::point::{point_nodes, refused_type, RawPointBlock, RawProperty};
use super::{abbreviates, element_kind, parse_keyword, InpError, Keyword, SAFE_TO_SKIP};
use crate::mesh::material::Elasticity;
use crate::mesh::ElementKind;

/// An *ELEMENT block as read: kind, its ELSET, connectivity by Abaqus node ids, element ids.
/// Every *ELEMENT keyword of one type and ELSET adds to the same block.
pub(super) struct RawBlock {
    /// The Abaqus element type as written (upper case).
    pub abaqus: String,
    pub kind: ElementKind,
    pub elset: Option<String>,
    pub connectivity: Vec<i64>,
    pub ids: Vec<i64>,
    /// Node ids beyond the element's on its lines (ignored), and the first line with some.
    pub extra_ids: usize,
    pub first_extra_line: usize,
}

/// A material as read: name, density, elasticity.
pub(super) struct RawMaterial {
    pub name: String,
    pub density: Option<f64>,
    pub elasticity: Option<Elasticity>,
}

/// A *SOLID SECTION: element set, material, orientation, line.
pub(super) struct RawSection {
    pub elset: String,
    pub material: String,
    pub orientation: Option<String>,
    pub line: usize,
}

/// An *ORIENTATION as read: name, cylindrical or rectangular, its numbers (a, b[, origin]),
/// the extra rotation's line (axis 1..3, degrees), and the keyword's line.
pub(super) struct RawOrientation {
    pub name: String,
    pub cylindrical: bool,
    pub points: Vec<f64>,
    pub rotation: Option<(usize, f64)>,
    pub line: usize,
}

/// A *BOUNDARY line: node set or id, first and last DOF (1-based), line.
pub(super) struct RawBoundary {
    pub target: String,
    pub first: usize,
    pub last: usize,
    pub line: usize,
}

/// One *SURFACE data line: element set or id, face label (S1..S6), line.
pub(super) struct RawFace {
    pub target: String,
    pub face: String,
    pub line: usize,
}

/// A *CONTACT PAIR: slave surface, master surface, interaction.
pub(super) struct RawPair {
    pub slave: String,
    pub master: String,
    pub interaction: String,
}

/// Every table of the file, in file order.
#[derive(Default)]
pub(super) struct RawInp {
    /// Node ids with their coordinates.
    pub nodes: Vec<(i64, [f64; 3])>,
    pub node_index: HashMap<i64, usize>,
    pub blocks: Vec<RawBlock>,
    /// Masses and springs, and the *MASS / *SPRING lines that give their values.
    pub point_blocks: Vec<RawPointBlock>,
    pub properties: Vec<RawProperty>,
    pub equations: Vec<super::equation::RawEquation>,
    /// Node-based surfaces: name -> (node ids or node sets, line).
    pub node_surfaces: BTreeMap<String, Vec<(String, usize)>>,
    pub ties: Vec<super::tie::RawTie>,
    pub elsets: BTreeMap<String, Vec<i64>>,
    pub nsets: BTreeMap<String, Vec<i64>>,
    pub materials: Vec<RawMaterial>,
    pub sections: Vec<RawSection>,
    pub orientations: Vec<RawOrientation>,
    pub boundaries: Vec<RawBoundary>,
    pub surfaces: BTreeMap<String, Vec<RawFace>>,
    /// Surface interactions with their friction coefficient.
    pub interactions: HashMap<String, Option<f64>>,
    pub pairs: Vec<RawPair>,
    /// Keywords skipped (line, keyword).
    pub skipped: Vec<(usize, String)>,
}

/// What the data lines after a keyword are.
enum Mode {
    None,
    Node(Option<String>),
    Element {
        block: usize,
        pending: Vec<i64>,
    },
    /// A point-element block's element lines.
    Point(usize),
    /// A *MASS or *SPRING's data lines.
    Property(usize),
    /// *EQUATION, with the terms of the open equation still to come.
    Equation(usize),
    Set {
        elements: bool,
        name: String,
        generate: bool,
    },
    Surface(String),
    NodeSurface(String),
    Tie(usize),
    Elastic {
        material: usize,
        form: ElasticForm,
        values: Vec<f64>,
    },
    Density(usize),
    Section,
    /// The orientation's index and how many of its data lines were read.
    Orientation(usize, usize),
    Boundary,
    Friction(String),
    ContactPair(String),
    Skip,
}

/// Where a line is, for its errors.
#[derive(Clone, Copy)]
pub(super) struct At<'a> {
    file: &'a PathBuf,
    pub(super) line: usize,
}

impl At<'_> {
    pub(super) fn syntax(&self, message: String) -> InpError {
        InpError::Syntax {
            file: self.file.clone(),
            line: self.line,
            message,
        }
    }

    pub(super) fn int(&self, s: &str) -> Result<i64, InpError> {
        s.parse()
            .map_err(|_| self.syntax(format!("'{s}' is not an integer")))
    }

    pub(super) fn num(&self, s: &str) -> Result<f64, InpError> {
        let v: f64 = s
            .replace(['d', 'D'], "e")
            .parse()
            .map_err(|_| self.syntax(format!("'{s}' is not a number")))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.syntax(format!("'{s}' is not finite")))
        }
    }
}

/// The parser's state between lines: the tables and what the next data line is.
struct Parser {
    raw: RawInp,
    mode: Mode,
    current_material: Option<usize>,
    current_interaction: Option<String>,
}

impl RawInp {
    /// Reads the lines (`*INCLUDE` expanded: file, line number, text) into tables.
    pub fn parse(
        lines: &[(PathBuf, usize, String)],
        path: &std::path::Path,
    ) -> Result<Self, InpError> {
        let mut p = Parser {
            raw: RawInp::default(),
            mode: Mode::None,
            current_material: None,
            current_interaction: None,
        };
        for (file, line, text) in lines {
            let at = At { file, line: *line };
            let t = text.trim();
            if t.is_empty() || t.starts_with("**") {
                continue;
            }
            if t.starts_with('*') {
                if let Mode::Element { pending, .. } = &p.mode {
                    if !pending.is_empty() {
                        return Err(at.syntax("the previous element line is incomplete".into()));
                    }
                }
                p.mode = p.keyword(&parse_keyword(t), at)?;
            } else {
                p.data(t, at)?;
            }
        }
        if let Mode::Element { pending, .. } = &p.mode {
            if !pending.is_empty() {
                let (file, line) = lines
                    .last()
                    .map_or((path.to_path_buf(), 0), |(f, l, _)| (f.clone(), *l));
                return Err(InpError::Syntax {
                    file,
                    line,
                    message: format!(
                        "the last element line is incomplete (element {} ends with a comma)",
                        pending[0]
                    ),
                });
            }
        }
        Ok(p.raw)
    }
}

impl Parser {
    /// A keyword line: what its data lines will be.
    fn keyword(&mut self, kw: &Keyword, at: At) -> Result<Mode, InpError> {
        let param = |k: &str| kw.params.get(k).cloned();
        let need = |k: &str| param(k).ok_or_else(|| at.syntax(format!("*{} needs {k}=", kw.name)));
        Ok(match kw.name.as_str() {
            "NODE" => Mode::Node(param("NSET")),
            "ELEMENT" => self.element_keyword(&need("TYPE")?, param("ELSET"), at)?,
            "NSET" | "ELSET" => {
                let elements = kw.name == "ELSET";
                Mode::Set {
                    elements,
                    name: need(if elements { "ELSET" } else { "NSET" })?,
                    generate: kw.params.contains_key("GENERATE"),
                }
            }
            "SURFACE" => {
                let ty = param("TYPE").unwrap_or_else(|| "ELEMENT".into());
                match abbreviates(&ty, &["ELEMENT", "NODE"]) {
                    Some("ELEMENT") => Mode::Surface(need("NAME")?),
                    Some(_) => Mode::NodeSurface(need("NAME")?),
                    None => {
                        return Err(at.syntax(format!(
                            "*SURFACE TYPE={ty} is not supported: use TYPE=ELEMENT (element faces) or TYPE=NODE"
                        )))
                    }
                }
            }
            "MATERIAL" => {
                self.raw.materials.push(RawMaterial {
                    name: need("NAME")?,
                    density: None,
                    elasticity: None,
                });
                self.current_material = Some(self.raw.materials.len() - 1);
                Mode::None
            }
            "ELASTIC" | "DENSITY" => self.material_keyword(kw, at)?,
            "MASS" | "SPRING" => {
                let property = super::point::property_keyword(kw, at)?;
                self.raw.properties.push(property);
                Mode::Property(self.raw.properties.len() - 1)
            }
            "SOLID SECTION" => {
                self.raw.sections.push(RawSection {
                    elset: need("ELSET")?,
                    material: need("MATERIAL")?,
                    orientation: param("ORIENTATION"),
                    line: at.line,
                });
                Mode::Section
            }
            "ORIENTATION" => self.orientation_keyword(kw, need("NAME")?, at)?,
            "BOUNDARY" => Mode::Boundary,
            "EQUATION" => Mode::Equation(0),
            "TIE" => {
                let tie = super::tie::keyword(kw, at)?;
                self.raw.ties.push(tie);
                Mode::Tie(self.raw.ties.len() - 1)
            }
            "SURFACE INTERACTION" => {
                let name = need("NAME")?;
                self.raw.interactions.insert(name.clone(), None);
                self.current_interaction = Some(name);
                Mode::None
            }
            "FRICTION" => Mode::Friction(
                self.current_interaction
                    .clone()
                    .ok_or_else(|| at.syntax("*FRICTION outside a *SURFACE INTERACTION".into()))?,
            ),
            "CONTACT PAIR" => Mode::ContactPair(need("INTERACTION")?),
            // Initial temperatures are safe to skip; initial stresses would change K.
            "INITIAL CONDITIONS"
                if param("TYPE")
                    .and_then(|t| abbreviates(&t, &["TEMPERATURE"]))
                    .is_some() =>
            {
                self.raw.skipped.push((at.line, kw.name.clone()));
                Mode::Skip
            }
            name if SAFE_TO_SKIP.contains(&name) => {
                self.raw.skipped.push((at.line, name.to_string()));
                Mode::Skip
            }
            other => {
                return Err(InpError::UnsupportedKeyword {
                    file: at.file.clone(),
                    line: at.line,
                    keyword: other.to_string(),
                    hint: "remove it or replace it (couplings, MPCs, shells and beams are \
                           not read)"
                        .into(),
                })
            }
        })
    }

    fn element_keyword(
        &mut self,
        ty: &str,
        elset: Option<String>,
        at: At,
    ) -> Result<Mode, InpError> {
        let ty = ty.to_uppercase();
        if let Some(why) = refused_type(&ty) {
            return Err(at.syntax(format!("element type {ty}: {why}")));
        }
        if point_nodes(&ty).is_some() {
            self.raw.point_blocks.push(RawPointBlock {
                abaqus: ty,
                elset,
                ids: Vec::new(),
                nodes: Vec::new(),
                line: at.line,
            });
            return Ok(Mode::Point(self.raw.point_blocks.len() - 1));
        }
        let kind = element_kind(&ty).ok_or_else(|| {
            at.syntax(format!(
                "element type {ty} is not supported (use C3D8, C3D8I, C3D20, C3D20R, C3D10, C3D10M, C3D4, C3D6 or C3D15; MASS, SPRING1, SPRING2 or SPRINGA)"
            ))
        })?;
        // Pre-processors often write one *ELEMENT keyword per few hundred elements of the same
        // set: they are one block.
        let same = |b: &RawBlock| b.abaqus == ty && b.elset == elset;
        let block = match self.raw.blocks.iter().position(same) {
            Some(b) => b,
            None => {
                self.raw.blocks.push(RawBlock {
                    abaqus: ty,
                    kind,
                    elset,
                    connectivity: Vec::new(),
                    ids: Vec::new(),
                    extra_ids: 0,
                    first_extra_line: 0,
                });
                self.raw.blocks.len() - 1
            }
        };
        Ok(Mode::Element {
            block,
            pending: Vec::new(),
        })
    }

    /// *ORIENTATION: SYSTEM=RECTANGULAR (default) or CYLINDRICAL, DEFINITION=COORDINATES.
    fn orientation_keyword(
        &mut self,
        kw: &Keyword,
        name: String,
        at: At,
    ) -> Result<Mode, InpError> {
        let system = kw
            .params
            .get("SYSTEM")
            .cloned()
            .unwrap_or_else(|| "RECTANGULAR".into());
        let cylindrical = match abbreviates(&system, &["RECTANGULAR", "CYLINDRICAL", "SPHERICAL"]) {
            Some("RECTANGULAR") => false,
            Some("CYLINDRICAL") => true,
            _ => {
                return Err(at.syntax(format!(
                    "*ORIENTATION SYSTEM={system} is not supported (RECTANGULAR or CYLINDRICAL)"
                )))
            }
        };
        if let Some(d) = kw.params.get("DEFINITION") {
            if abbreviates(d, &["COORDINATES", "NODES", "OFFSET TO NODES"]) != Some("COORDINATES") {
                return Err(at.syntax(format!(
                    "*ORIENTATION DEFINITION={d} is not supported: give the points' coordinates (DEFINITION=COORDINATES)"
                )));
            }
        }
        self.raw.orientations.push(RawOrientation {
            name,
            cylindrical,
            points: Vec::new(),
            rotation: None,
            line: at.line,
        });
        Ok(Mode::Orientation(self.raw.orientations.len() - 1, 0))
    }

    /// *ELASTIC or *DENSITY of the current material.
    fn material_keyword(&mut self, kw: &Keyword, at: At) -> Result<Mode, InpError> {
        let m = self
            .current_material
            .ok_or_else(|| at.syntax(format!("*{} outside a *MATERIAL", kw.name)))?;
        if kw.name == "DENSITY" {
            return Ok(Mode::Density(m));
        }
        let ty = kw
            .params
            .get("TYPE")
            .cloned()
            .unwrap_or_else(|| "ISOTROPIC".into());
        let forms = [
            "ISOTROPIC",
            "ENGINEERING CONSTANTS",
            "ORTHOTROPIC",
            "ANISOTROPIC",
        ];
        let form = match abbreviates(&ty, &forms) {
            Some("ISOTROPIC") => ElasticForm::Isotropic,
            Some("ENGINEERING CONSTANTS") => ElasticForm::Engineering,
            Some("ORTHOTROPIC") => ElasticForm::Orthotropic,
            Some(_) => ElasticForm::Anisotropic,
            None => {
                return Err(at.syntax(format!(
                    "*ELASTIC TYPE={ty} is not supported (ISOTROPIC, ENGINEERING CONSTANTS, ORTHOTROPIC or ANISOTROPIC)"
                )))
            }
        };
        Ok(Mode::Elastic {
            material: m,
            form,
            values: Vec::new(),
        })
    }

    /// A data line of the current keyword.
    fn data(&mut self, t: &str, at: At) -> Result<(), InpError> {
        let fields: Vec<&str> = t
            .split(',')
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        let raw = &mut self.raw;
        match &mut self.mode {
            Mode::None => return Err(at.syntax("data line outside a keyword".into())),
            Mode::Skip | Mode::Section => {}
            Mode::Orientation(o, read) => {
                let orientation = &mut raw.orientations[*o];
                match *read {
                    0 => {
                        if !(fields.len() == 6 || fields.len() == 9) {
                            return Err(at.syntax(
                                "expected 'a1, a2, a3, b1, b2, b3[, c1, c2, c3]' (the points a, b and the origin)".into(),
                            ));
                        }
                        for f in &fields {
                            orientation.points.push(at.num(f)?);
                        }
                    }
                    1 => {
                        let axis = at.int(fields.first().copied().unwrap_or(""))?;
                        let angle = match fields.get(1) {
                            Some(f) => at.num(f)?,
                            None => 0.0,
                        };
                        if !(1..=3).contains(&axis) {
                            return Err(at.syntax(format!(
                                "the extra rotation's axis is {axis}: use 1, 2 or 3"
                            )));
                        }
                        orientation.rotation = Some((axis as usize - 1, angle));
                    }
                    _ => return Err(at.syntax("*ORIENTATION takes two data lines".into())),
                }
                *read += 1;
            }
            Mode::Node(nset) => node(raw, nset.as_deref(), &fields, at)?,
            Mode::Point(b) => {
                let block = &mut raw.point_blocks[*b];
                let n = point_nodes(&block.abaqus).unwrap_or(1);
                if fields.len() != n + 1 {
                    return Err(at.syntax(format!(
                        "a {} element line is 'id, {}'",
                        block.abaqus,
                        if n == 1 { "node" } else { "node, node" }
                    )));
                }
                block.ids.push(at.int(fields[0])?);
                for f in &fields[1..] {
                    block.nodes.push(at.int(f)?);
                }
            }
            Mode::Equation(remaining) => {
                *remaining = super::equation::data(raw, *remaining, &fields, at)?
            }
            Mode::Property(p) => raw.properties[*p]
                .lines
                .push(fields.iter().map(|f| f.to_string()).collect()),
            Mode::Element { block, pending } => element(
                &mut raw.blocks[*block],
                pending,
                &fields,
                t.ends_with(','),
                at,
            )?,
            Mode::Set {
                elements,
                name,
                generate,
            } => {
                let target = if *elements {
                    &mut raw.elsets
                } else {
                    &mut raw.nsets
                };
                set(target, name, *generate, &fields, at)?
            }
            Mode::Surface(name) => {
                if fields.len() != 2 {
                    return Err(at.syntax("expected 'element set or id, S1..S6'".into()));
                }
                raw.surfaces.entry(name.clone()).or_default().push(RawFace {
                    target: fields[0].to_string(),
                    face: fields[1].to_uppercase(),
                    line: at.line,
                });
            }
            Mode::NodeSurface(name) => super::tie::node_surface_line(raw, name, &fields, at)?,
            Mode::Tie(t) => super::tie::surfaces_line(&mut raw.ties[*t], &fields, at)?,
            Mode::Elastic {
                material,
                form,
                values,
            } => {
                for f in &fields {
                    values.push(at.num(f)?);
                }
                if let Some(e) = elasticity(values, *form, at)? {
                    raw.materials[*material].elasticity = Some(e);
                    values.clear();
                }
            }
            Mode::Density(m) => {
                raw.materials[*m].density = Some(at.num(fields.first().copied().unwrap_or(""))?)
            }
            Mode::Boundary => raw.boundaries.push(boundary(&fields, at)?),
            Mode::Friction(name) => {
                let mu = at.num(fields.first().copied().unwrap_or(""))?;
                raw.interactions.insert(name.clone(), Some(mu));
            }
            Mode::ContactPair(interaction) => {
                if fields.len() != 2 {
                    return Err(at.syntax("expected 'slave surface, master surface'".into()));
                }
                raw.pairs.push(RawPair {
                    slave: fields[0].to_string(),
                    master: fields[1].to_string(),
                    interaction: interaction.clone(),
                });
            }
        }
        Ok(())
    }
}

/// `id, x, y, z`
fn node(raw: &mut RawInp, nset: Option<&str>, fields: &[&str], at: At) -> Result<(), InpError> {
    if fields.len() < 4 {
        return Err(at.syntax("expected 'id, x, y, z'".into()));
    }
    let id = at.int(fields[0])?;
    let x = [at.num(fields[1])?, at.num(fields[2])?, at.num(fields[3])?];
    if raw.node_index.insert(id, raw.nodes.len()).is_some() {
        return Err(at.syntax(format!("node {id} defined twice")));
    }
    raw.nodes.push((id, x));
    if let Some(s) = nset {
        raw.nsets.entry(s.to_string()).or_default().push(id);
    }
    Ok(())
}

/// `id, n1, n2, ...`; long elements continue on the next line after a trailing comma.
fn element(
    block: &mut RawBlock,
    pending: &mut Vec<i64>,
    fields: &[&str],
    continued: bool,
    at: At,
) -> Result<(), InpError> {
    for f in fields {
        pending.push(at.int(f)?);
    }
    let need = block.kind.nodes() + 1;
    if pending.len() < need && continued {
        return Ok(());
    }
    if pending.len() < need {
        return Err(at.syntax(format!(
            "expected an element id and {} node ids, found {} numbers",
            block.kind.nodes(),
            pending.len()
        )));
    }
    // Ids beyond the element's (some pre-processors pad the line): the first ones are the
    // element's nodes, as other readers take them; the count goes to the log.
    if pending.len() > need {
        if block.extra_ids == 0 {
            block.first_extra_line = at.line;
        }
        block.extra_ids += pending.len() - need;
    }
    block.ids.push(pending[0]);
    block.connectivity.extend_from_slice(&pending[1..need]);
    pending.clear();
    Ok(())
}

/// Ids, names of sets defined above, or with GENERATE `first, last[, step]`.
fn set(
    target: &mut BTreeMap<String, Vec<i64>>,
    name: &str,
    generate: bool,
    fields: &[&str],
    at: At,
) -> Result<(), InpError> {
    let mut ids = Vec::new();
    if generate {
        if fields.len() < 2 {
            return Err(at.syntax("GENERATE expects 'first, last[, step]'".into()));
        }
        let (a, b) = (at.int(fields[0])?, at.int(fields[1])?);
        let step = if fields.len() > 2 {
            at.int(fields[2])?
        } else {
            1
        };
        if step <= 0 || b < a {
            return Err(at.syntax(format!("GENERATE range {a}, {b}, {step} is empty")));
        }
        ids.extend((a..=b).step_by(step as usize));
    } else {
        for f in fields {
            match f.parse::<i64>() {
                Ok(id) => ids.push(id),
                // A set of sets: the named set must be defined above.
                Err(_) => ids.extend(target.get(*f).cloned().ok_or_else(|| {
                    at.syntax(format!("'{f}' is neither an id nor a set defined above"))
                })?),
            }
        }
    }
    target.entry(name.to_string()).or_default().extend(ids);
    Ok(())
}

/// `node or set, first dof[, last dof[, value]]` with a zero value.
fn boundary(fields: &[&str], at: At) -> Result<RawBoundary, InpError> {
    if fields.len() < 2 {
        return Err(at.syntax("expected 'node or set, first dof[, last dof[, value]]'".into()));
    }
    let first = at.int(fields[1])? as usize;
    let last = if fields.len() > 2 {
        at.int(fields[2])? as usize
    } else {
        first
    };
    if fields.len() > 3 && at.num(fields[3])? != 0.0 {
        return Err(at.syntax(
            "prescribed non-zero displacements are not supported (constraints are eliminated)"
                .into(),
        ));
    }
    if !(1..=6).contains(&first) || last < first || last > 6 {
        return Err(at.syntax(format!("dof range {first}..{last}: use 1..6")));
    }
    Ok(RawBoundary {
        target: fields[0].to_string(),
        first,
        last,
        line: at.line,
    })
}
