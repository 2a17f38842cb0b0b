//! Abaqus input files (`.inp`), the subset that describes a solid model: `*NODE`, `*ELEMENT`
//! (C3D8, C3D8I, C3D20, C3D20R, C3D10, C3D4), `*NSET`/`*ELSET` (with GENERATE), `*SURFACE`
//! (element-face based), `*MATERIAL` with `*ELASTIC` (isotropic or engineering constants) and
//! `*DENSITY`, `*SOLID SECTION`, `*BOUNDARY` (zero values), `*INCLUDE`, `*CONTACT PAIR` with
//! `*SURFACE INTERACTION` / `*FRICTION`. Keywords of analysis steps and output requests are
//! reported and skipped; anything else that could change the model is an error naming the
//! line. A writer produces the same subset, so a generated model opens in other tools.

mod write;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use super::{ElementBlock, Mesh};
use crate::fem::material::{Elasticity, Material};
use crate::fem::shape::ElementKind;
pub use write::write;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InpError {
    #[error("{file}: {message}")]
    Io { file: PathBuf, message: String },
    #[error("{file}:{line}: {message}")]
    Syntax {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{file}:{line}: keyword *{keyword} is not supported here and could change the model: {hint}")]
    UnsupportedKeyword {
        file: PathBuf,
        line: usize,
        keyword: String,
        hint: String,
    },
    #[error("{file}: {message}")]
    Model { file: PathBuf, message: String },
}

/// A contact pair of an imported model: surface names and the friction coefficient.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactPair {
    pub slave: String,
    pub master: String,
    pub interaction: String,
    pub friction: Option<f64>,
}

/// What an input file holds beyond the mesh.
#[derive(Debug, Clone, Default)]
pub struct InpModel {
    pub mesh: Mesh,
    /// Node sets clamped (components 0..3) by `*BOUNDARY`.
    pub clamps: Vec<(String, [bool; 3])>,
    pub contact_pairs: Vec<ContactPair>,
    /// Keywords skipped (line, keyword), for the log.
    pub skipped: Vec<(usize, String)>,
}

/// Keywords of steps, outputs and bookkeeping: skipping them cannot change K or M.
const SAFE_TO_SKIP: &[&str] = &[
    "HEADING",
    "PREPRINT",
    "STEP",
    "END STEP",
    "STATIC",
    "FREQUENCY",
    "OUTPUT",
    "NODE OUTPUT",
    "ELEMENT OUTPUT",
    "NODE PRINT",
    "EL PRINT",
    "NODE FILE",
    "EL FILE",
    "RESTART",
    "MONITOR",
    "CLOAD",
    "DLOAD",
    "DSLOAD",
    "AMPLITUDE",
    "CONTROLS",
    "CONTACT OUTPUT",
    "ENERGY OUTPUT",
    "PHYSICAL CONSTANTS",
    "FILE FORMAT",
    "PARAMETER",
];

fn element_kind(abaqus: &str) -> Option<ElementKind> {
    match abaqus {
        "C3D8" => Some(ElementKind::Hex8),
        "C3D8I" => Some(ElementKind::Hex8I),
        // Reduced integration is not reproduced: C3D20R is read as a fully integrated Hex20.
        "C3D20" | "C3D20R" => Some(ElementKind::Hex20),
        "C3D10" => Some(ElementKind::Tet10),
        "C3D4" => Some(ElementKind::Tet4),
        _ => None,
    }
}

fn abaqus_type(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 => "C3D8",
        ElementKind::Hex8I => "C3D8I",
        ElementKind::Hex20 => "C3D20",
        ElementKind::Tet10 => "C3D10",
        ElementKind::Tet4 => "C3D4",
    }
}

/// A keyword line: upper-case keyword and its parameters (keys upper-case, values as given).
struct Keyword {
    name: String,
    params: HashMap<String, String>,
}

fn parse_keyword(line: &str) -> Keyword {
    let mut parts = line[1..].split(',');
    let name = parts.next().unwrap_or("").trim().to_uppercase();
    let mut params = HashMap::new();
    for p in parts {
        let p = p.trim();
        if p.is_empty() {
            continue;
        }
        match p.split_once('=') {
            Some((k, v)) => params.insert(k.trim().to_uppercase(), v.trim().to_string()),
            None => params.insert(p.to_uppercase(), String::new()),
        };
    }
    Keyword { name, params }
}

/// Lines of a file with `*INCLUDE` expanded: (file, line number, text).
fn read_lines(
    path: &Path,
    depth: usize,
    out: &mut Vec<(PathBuf, usize, String)>,
) -> Result<(), InpError> {
    if depth > 10 {
        return Err(InpError::Model {
            file: path.to_path_buf(),
            message: "*INCLUDE nested more than 10 deep (a cycle?)".into(),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|e| InpError::Io {
        file: path.to_path_buf(),
        message: e.to_string(),
    })?;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('*') && !t.starts_with("**") {
            let kw = parse_keyword(t);
            if kw.name == "INCLUDE" {
                let input = kw.params.get("INPUT").ok_or_else(|| InpError::Syntax {
                    file: path.to_path_buf(),
                    line: i + 1,
                    message: "*INCLUDE needs INPUT=<file>".into(),
                })?;
                let base = path.parent().unwrap_or(Path::new("."));
                read_lines(&base.join(input.trim_matches('"')), depth + 1, out)?;
                continue;
            }
        }
        out.push((path.to_path_buf(), i + 1, line.to_string()));
    }
    Ok(())
}

/// An *ELEMENT block as read: kind, its ELSET, connectivity by Abaqus node ids, element ids.
type RawBlock = (ElementKind, Option<String>, Vec<i64>, Vec<i64>);

/// Reads an Abaqus input file.
///
/// Long by design (about 530 lines): one pass over the keyword lines as a state machine whose
/// keyword arms and data arms share the raw tables declared at the top (sets, sections,
/// surfaces, interactions), then one resolution of those tables into the mesh; each arm is
/// short and reads top to bottom in file order. Splitting it would pass a dozen tables around.
pub fn read(path: &Path) -> Result<InpModel, InpError> {
    let mut lines = Vec::new();
    read_lines(path, 0, &mut lines)?;
    let mut model = InpModel::default();
    let mut node_index: HashMap<i64, usize> = HashMap::new();
    let mut elem_index: HashMap<i64, usize> = HashMap::new();
    let mut raw_blocks: Vec<RawBlock> = Vec::new();
    let mut elsets: BTreeMap<String, Vec<i64>> = BTreeMap::new();
    let mut nsets: BTreeMap<String, Vec<i64>> = BTreeMap::new();
    let mut materials: Vec<(String, Option<f64>, Option<Elasticity>)> = Vec::new();
    let mut sections: Vec<(String, String, usize)> = Vec::new(); // elset, material, line
    let mut boundaries: Vec<(String, usize, usize, usize)> = Vec::new(); // target, first, last, line
    let mut surfaces_raw: BTreeMap<String, Vec<(String, String, usize)>> = BTreeMap::new();
    let mut interactions: HashMap<String, Option<f64>> = HashMap::new();
    let mut pairs_raw: Vec<(String, String, String)> = Vec::new();

    enum Mode {
        None,
        Node(Option<String>),
        Element {
            block: usize,
            pending: Vec<i64>,
        },
        Set {
            elements: bool,
            name: String,
            generate: bool,
        },
        Surface(String),
        Elastic {
            material: usize,
            engineering: bool,
            values: Vec<f64>,
        },
        Density(usize),
        Section,
        Boundary,
        Friction(String),
        ContactPair(String),
        Skip,
    }
    let mut mode = Mode::None;
    let mut current_material: Option<usize> = None;
    let mut current_interaction: Option<String> = None;

    for (file, lineno, raw) in &lines {
        let syntax = |message: String| InpError::Syntax {
            file: file.clone(),
            line: *lineno,
            message,
        };
        let t = raw.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            if let Mode::Element { pending, .. } = &mode {
                if !pending.is_empty() {
                    return Err(syntax("the previous element line is incomplete".into()));
                }
            }
            let kw = parse_keyword(t);
            let param = |k: &str| kw.params.get(k).cloned();
            let need = |k: &str| param(k).ok_or_else(|| syntax(format!("*{} needs {k}=", kw.name)));
            mode = match kw.name.as_str() {
                "NODE" => Mode::Node(param("NSET")),
                "ELEMENT" => {
                    let ty = need("TYPE")?.to_uppercase();
                    let kind = element_kind(&ty).ok_or_else(|| {
                        syntax(format!(
                            "element type {ty} is not supported (use C3D8, C3D8I, C3D20, C3D20R, C3D10 or C3D4)"
                        ))
                    })?;
                    raw_blocks.push((kind, param("ELSET"), Vec::new(), Vec::new()));
                    Mode::Element {
                        block: raw_blocks.len() - 1,
                        pending: Vec::new(),
                    }
                }
                "NSET" | "ELSET" => {
                    let elements = kw.name == "ELSET";
                    let name = need(if elements { "ELSET" } else { "NSET" })?;
                    Mode::Set {
                        elements,
                        name,
                        generate: kw.params.contains_key("GENERATE"),
                    }
                }
                "SURFACE" => {
                    let ty = param("TYPE")
                        .unwrap_or_else(|| "ELEMENT".into())
                        .to_uppercase();
                    if ty != "ELEMENT" {
                        return Err(syntax(format!(
                            "*SURFACE TYPE={ty} is not supported: use element-face surfaces (TYPE=ELEMENT)"
                        )));
                    }
                    Mode::Surface(need("NAME")?)
                }
                "MATERIAL" => {
                    materials.push((need("NAME")?, None, None));
                    current_material = Some(materials.len() - 1);
                    Mode::None
                }
                "ELASTIC" | "DENSITY" => {
                    let m = current_material
                        .ok_or_else(|| syntax(format!("*{} outside a *MATERIAL", kw.name)))?;
                    if kw.name == "DENSITY" {
                        Mode::Density(m)
                    } else {
                        let ty = param("TYPE")
                            .unwrap_or_else(|| "ISOTROPIC".into())
                            .to_uppercase();
                        match ty.as_str() {
                            "ISOTROPIC" => Mode::Elastic { material: m, engineering: false, values: Vec::new() },
                            "ENGINEERING CONSTANTS" => Mode::Elastic { material: m, engineering: true, values: Vec::new() },
                            other => {
                                return Err(syntax(format!(
                                    "*ELASTIC TYPE={other} is not supported (ISOTROPIC or ENGINEERING CONSTANTS)"
                                )))
                            }
                        }
                    }
                }
                "SOLID SECTION" => {
                    if kw.params.contains_key("ORIENTATION") {
                        return Err(syntax(
                            "*SOLID SECTION with ORIENTATION is not supported: orthotropic axes are the global axes".into(),
                        ));
                    }
                    sections.push((need("ELSET")?, need("MATERIAL")?, *lineno));
                    Mode::Section
                }
                "BOUNDARY" => Mode::Boundary,
                "SURFACE INTERACTION" => {
                    let name = need("NAME")?;
                    interactions.insert(name.clone(), None);
                    current_interaction = Some(name);
                    Mode::None
                }
                "FRICTION" => Mode::Friction(
                    current_interaction
                        .clone()
                        .ok_or_else(|| syntax("*FRICTION outside a *SURFACE INTERACTION".into()))?,
                ),
                "CONTACT PAIR" => Mode::ContactPair(need("INTERACTION")?),
                name if SAFE_TO_SKIP.contains(&name) => {
                    model.skipped.push((*lineno, name.to_string()));
                    Mode::Skip
                }
                other => {
                    return Err(InpError::UnsupportedKeyword {
                        file: file.clone(),
                        line: *lineno,
                        keyword: other.to_string(),
                        hint: "remove it or flatten the model (parts/instances, orientations, \
                               shells and beams are not read)"
                            .into(),
                    })
                }
            };
            continue;
        }
        let fields: Vec<&str> = t
            .split(',')
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        let int = |s: &str| -> Result<i64, InpError> {
            s.parse()
                .map_err(|_| syntax(format!("'{s}' is not an integer")))
        };
        let num = |s: &str| -> Result<f64, InpError> {
            let v: f64 = s
                .replace(['d', 'D'], "e")
                .parse()
                .map_err(|_| syntax(format!("'{s}' is not a number")))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(syntax(format!("'{s}' is not finite")))
            }
        };
        match &mut mode {
            Mode::None => return Err(syntax("data line outside a keyword".into())),
            Mode::Skip => {}
            Mode::Node(nset) => {
                if fields.len() < 4 {
                    return Err(syntax("expected 'id, x, y, z'".into()));
                }
                let id = int(fields[0])?;
                let x = [num(fields[1])?, num(fields[2])?, num(fields[3])?];
                if node_index.insert(id, model.mesh.coords.len()).is_some() {
                    return Err(syntax(format!("node {id} defined twice")));
                }
                model.mesh.coords.push(x);
                if let Some(s) = nset {
                    nsets.entry(s.clone()).or_default().push(id);
                }
            }
            Mode::Element { block, pending } => {
                for f in &fields {
                    pending.push(int(f)?);
                }
                let kind = raw_blocks[*block].0;
                let need = kind.nodes() + 1;
                // Long elements continue on the next line after a trailing comma.
                if pending.len() < need && t.ends_with(',') {
                    continue;
                }
                if pending.len() != need {
                    return Err(syntax(format!(
                        "expected an element id and {} node ids, found {} numbers",
                        kind.nodes(),
                        pending.len()
                    )));
                }
                let b = &mut raw_blocks[*block];
                b.3.push(pending[0]);
                b.2.extend_from_slice(&pending[1..]);
                pending.clear();
            }
            Mode::Set {
                elements,
                name,
                generate,
            } => {
                let target = if *elements { &mut elsets } else { &mut nsets };
                let mut ids = Vec::new();
                if *generate {
                    if fields.len() < 2 {
                        return Err(syntax("GENERATE expects 'first, last[, step]'".into()));
                    }
                    let (a, b) = (int(fields[0])?, int(fields[1])?);
                    let step = if fields.len() > 2 { int(fields[2])? } else { 1 };
                    if step <= 0 || b < a {
                        return Err(syntax(format!("GENERATE range {a}, {b}, {step} is empty")));
                    }
                    ids.extend((a..=b).step_by(step as usize));
                } else {
                    for f in &fields {
                        match f.parse::<i64>() {
                            Ok(id) => ids.push(id),
                            // A set of sets: the named set must be defined above.
                            Err(_) => ids.extend(target.get(*f).cloned().ok_or_else(|| {
                                syntax(format!("'{f}' is neither an id nor a set defined above"))
                            })?),
                        }
                    }
                }
                target.entry(name.clone()).or_default().extend(ids);
            }
            Mode::Surface(name) => {
                if fields.len() != 2 {
                    return Err(syntax("expected 'element set or id, S1..S6'".into()));
                }
                surfaces_raw.entry(name.clone()).or_default().push((
                    fields[0].to_string(),
                    fields[1].to_uppercase(),
                    *lineno,
                ));
            }
            Mode::Elastic {
                material,
                engineering,
                values,
            } => {
                // Engineering constants take two lines (8 values, then G23).
                for f in &fields {
                    values.push(num(f)?);
                }
                let e = if *engineering {
                    if values.len() < 9 {
                        continue;
                    }
                    Elasticity::Orthotropic {
                        e1: values[0],
                        e2: values[1],
                        e3: values[2],
                        nu12: values[3],
                        nu13: values[4],
                        nu23: values[5],
                        g12: values[6],
                        g13: values[7],
                        g23: values[8],
                    }
                } else {
                    if values.len() < 2 {
                        return Err(syntax("expected 'E, nu'".into()));
                    }
                    Elasticity::Isotropic {
                        e: values[0],
                        nu: values[1],
                    }
                };
                materials[*material].2 = Some(e);
                values.clear();
            }
            Mode::Density(m) => materials[*m].1 = Some(num(fields.first().copied().unwrap_or(""))?),
            Mode::Section => {}
            Mode::Boundary => {
                if fields.len() < 2 {
                    return Err(syntax(
                        "expected 'node or set, first dof[, last dof[, value]]'".into(),
                    ));
                }
                let first = int(fields[1])? as usize;
                let last = if fields.len() > 2 {
                    int(fields[2])? as usize
                } else {
                    first
                };
                if fields.len() > 3 && num(fields[3])? != 0.0 {
                    return Err(syntax("prescribed non-zero displacements are not supported (constraints are eliminated)".into()));
                }
                if !(1..=6).contains(&first) || last < first || last > 6 {
                    return Err(syntax(format!("dof range {first}..{last}: use 1..6")));
                }
                boundaries.push((fields[0].to_string(), first, last, *lineno));
            }
            Mode::Friction(name) => {
                interactions.insert(
                    name.clone(),
                    Some(num(fields.first().copied().unwrap_or(""))?),
                );
            }
            Mode::ContactPair(interaction) => {
                if fields.len() != 2 {
                    return Err(syntax("expected 'slave surface, master surface'".into()));
                }
                pairs_raw.push((
                    fields[0].to_string(),
                    fields[1].to_string(),
                    interaction.clone(),
                ));
            }
        }
    }
    if let Mode::Element { pending, .. } = &mode {
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
    let model_err = |message: String| InpError::Model {
        file: path.to_path_buf(),
        message,
    };
    // ELSET= on an *ELEMENT line defines that element set too.
    for (_, elset, _, ids) in &raw_blocks {
        if let Some(name) = elset {
            elsets.entry(name.clone()).or_default().extend(ids);
        }
    }

    // Materials.
    let mut material_ids: HashMap<String, usize> = HashMap::new();
    for (name, density, elasticity) in materials {
        let m = Material {
            name: name.clone(),
            density: density.ok_or_else(|| {
                model_err(format!(
                    "material '{name}' has no *DENSITY (modes need mass)"
                ))
            })?,
            elasticity: elasticity
                .ok_or_else(|| model_err(format!("material '{name}' has no *ELASTIC")))?,
        };
        m.validate().map_err(|e| model_err(e.to_string()))?;
        material_ids.insert(name.to_uppercase(), model.mesh.materials.len());
        model.mesh.materials.push(m);
    }

    // Elements -> blocks, one per (*ELEMENT block, section); element numbering follows the file.
    let mut element_material: HashMap<i64, usize> = HashMap::new();
    for (elset, material, line) in &sections {
        let m = *material_ids.get(&material.to_uppercase()).ok_or_else(|| {
            model_err(format!(
                "line {line}: *SOLID SECTION names material '{material}', which is not defined"
            ))
        })?;
        let ids = elsets
            .get(elset)
            .cloned()
            .or_else(|| {
                raw_blocks
                    .iter()
                    .find(|b| b.1.as_deref() == Some(elset.as_str()))
                    .map(|b| b.3.clone())
            })
            .ok_or_else(|| {
                model_err(format!(
                    "line {line}: *SOLID SECTION names element set '{elset}', which is not defined"
                ))
            })?;
        for id in ids {
            element_material.insert(id, m);
        }
    }
    let map_node = |id: i64| -> Result<usize, InpError> {
        node_index
            .get(&id)
            .copied()
            .ok_or_else(|| model_err(format!("node {id} is used but not defined")))
    };
    for (kind, elset, conn, ids) in &raw_blocks {
        let nn = kind.nodes();
        // Split the block by material, keeping the file order within each.
        let mut by_material: BTreeMap<usize, (Vec<usize>, Vec<i64>)> = BTreeMap::new();
        for (e, id) in ids.iter().enumerate() {
            let m = *element_material.get(id).ok_or_else(|| {
                model_err(format!("element {id} has no *SOLID SECTION (no material)"))
            })?;
            let entry = by_material.entry(m).or_default();
            for &n in &conn[e * nn..(e + 1) * nn] {
                let node = node_index.get(&n).copied().ok_or_else(|| {
                    model_err(format!(
                        "element {id} uses node {n}, which no *NODE line defines"
                    ))
                })?;
                entry.0.push(node);
            }
            entry.1.push(*id);
        }
        for (m, (connectivity, eids)) in by_material {
            let name = match &elset {
                Some(s) if by_material_len_is_one(ids, &element_material) => s.clone(),
                Some(s) => format!("{s}-{}", model.mesh.materials[m].name),
                None => format!(
                    "block{}-{}",
                    model.mesh.blocks.len(),
                    model.mesh.materials[m].name
                ),
            };
            for id in eids {
                elem_index.insert(id, elem_index.len());
            }
            model.mesh.blocks.push(ElementBlock {
                name,
                kind: *kind,
                material: m,
                connectivity,
            });
        }
    }
    for (name, ids) in &nsets {
        let mut v = ids
            .iter()
            .map(|&id| map_node(id))
            .collect::<Result<Vec<_>, _>>()?;
        v.sort_unstable();
        v.dedup();
        model.mesh.node_sets.insert(name.clone(), v);
    }
    // Boundaries: translational dofs 1..3 become clamps; rotations (4..6) do not exist on solids.
    for (target, first, last, line) in boundaries {
        let mut comps = [false; 3];
        for d in first..=last.min(3) {
            comps[d - 1] = true;
        }
        if !comps.iter().any(|&c| c) {
            continue;
        }
        let set = if model.mesh.node_sets.contains_key(&target) {
            target
        } else {
            let id: i64 = target.parse().map_err(|_| {
                model_err(format!(
                    "line {line}: *BOUNDARY names '{target}', neither a node set nor a node id"
                ))
            })?;
            let name = format!("node{id}");
            model
                .mesh
                .node_sets
                .insert(name.clone(), vec![map_node(id)?]);
            name
        };
        // One clamp per node set, the union of its *BOUNDARY lines.
        match model.clamps.iter_mut().find(|(s, _)| *s == set) {
            Some((_, c)) => (0..3).for_each(|i| c[i] |= comps[i]),
            None => model.clamps.push((set, comps)),
        }
    }
    for (name, items) in surfaces_raw {
        let mut faces = Vec::new();
        for (target, face, line) in items {
            let f: u8 = face
                .strip_prefix('S')
                .and_then(|s| s.parse().ok())
                .filter(|f| (1..=6).contains(f))
                .ok_or_else(|| model_err(format!("line {line}: face '{face}' is not S1..S6")))?;
            let ids = match elsets.get(&target) {
                Some(ids) => ids.clone(),
                None => vec![target.parse().map_err(|_| {
                    model_err(format!(
                        "line {line}: '{target}' is neither an element set nor an element id"
                    ))
                })?],
            };
            for id in ids {
                let e = *elem_index.get(&id).ok_or_else(|| {
                    model_err(format!("line {line}: element {id} is not defined"))
                })?;
                faces.push((e, f));
            }
        }
        model.mesh.surfaces.insert(name, faces);
    }
    for (slave, master, interaction) in pairs_raw {
        for s in [&slave, &master] {
            if !model.mesh.surfaces.contains_key(s) {
                return Err(model_err(format!(
                    "*CONTACT PAIR names surface '{s}', which is not defined"
                )));
            }
        }
        let friction = *interactions.get(&interaction).ok_or_else(|| {
            model_err(format!(
                "*CONTACT PAIR names interaction '{interaction}', which is not defined"
            ))
        })?;
        model.contact_pairs.push(ContactPair {
            slave,
            master,
            interaction,
            friction,
        });
    }
    if model.mesh.blocks.is_empty() {
        return Err(model_err("no elements".into()));
    }
    Ok(model)
}

fn by_material_len_is_one(ids: &[i64], element_material: &HashMap<i64, usize>) -> bool {
    let mut it = ids.iter().filter_map(|id| element_material.get(id));
    match it.next() {
        Some(first) => it.all(|m| m == first),
        None => true,
    }
}
