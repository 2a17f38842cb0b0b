//! Abaqus input files (`.inp`), the subset that describes a solid model: `*NODE`, `*ELEMENT`
//! (C3D8, C3D8I, C3D20, C3D20R, C3D10 and C3D10M, C3D4, C3D6, C3D15, each integrated as
//! CalculiX does:
//! `fem::shape`), `*NSET`/`*ELSET` (with GENERATE), `*SURFACE` (element-face based),
//! `*MATERIAL` with `*ELASTIC` (isotropic, engineering constants, orthotropic, anisotropic)
//! and `*DENSITY`, `*SOLID SECTION` with `*ORIENTATION`, `*BOUNDARY` (zero values), point
//! masses and linear springs (MASS, SPRING1, SPRING2, SPRINGA with `*MASS` / `*SPRING`),
//! `*EQUATION` and `*TIE` (node or element-face slave surfaces; by penalty:
//! `mesh::constraint`),
//! `*INCLUDE`, `*CONTACT PAIR` with `*SURFACE INTERACTION` / `*FRICTION`; `*PART`s instanced
//! in an `*ASSEMBLY` are flattened first (`instance.rs`). Keywords of analysis
//! steps and output requests are reported and skipped; anything else that could change the
//! model is an error naming the line. A writer produces the same subset, so a generated model
//! opens in other tools (CalculiX reads it: tests/ccx_reference.rs).

mod elastic;
mod equation;
mod instance;
mod point;
mod raw;
mod resolve;
mod tie;
mod write;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::Mesh;
use crate::mesh::ElementKind;
pub use tie::Tie;
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
    /// *TIE constraints, for the model stage to resolve on the geometry.
    pub ties: Vec<Tie>,
    /// Keywords skipped (line, keyword), for the log.
    pub skipped: Vec<(usize, String)>,
    /// Per mesh block: its name, the Abaqus element type read into it and its element count.
    pub element_types: Vec<(String, String, usize)>,
    /// What the log should say of the reading (padded element lines).
    pub notes: Vec<String>,
}

impl InpModel {
    /// The log's lines on the skipped keywords: one per keyword, with its lines.
    pub fn skipped_notes(&self) -> Vec<String> {
        let mut by_keyword: Vec<(String, Vec<usize>)> = Vec::new();
        for (line, keyword) in &self.skipped {
            match by_keyword.iter_mut().find(|(k, _)| k == keyword) {
                Some((_, lines)) => lines.push(*line),
                None => by_keyword.push((keyword.clone(), vec![*line])),
            }
        }
        by_keyword
            .into_iter()
            .map(|(keyword, lines)| {
                let shown: Vec<String> = lines.iter().take(5).map(usize::to_string).collect();
                let more = if lines.len() > 5 {
                    format!(" and {} more", lines.len() - 5)
                } else {
                    String::new()
                };
                let why = match keyword.as_str() {
                    "CLOAD" | "DLOAD" | "DSLOAD" => "loads of the deck's steps are not read: the scene's pressure is the preload",
                    "TEMPERATURE" | "INITIAL CONDITIONS" => "temperatures do not change K or M (no thermal expansion)",
                    _ => "steps, procedures and outputs do not change K, M or the contact",
                };
                format!("*{keyword} skipped (line {}{more}): {why}", shown.join(", "))
            })
            .collect()
    }
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
    // Procedures of other analyses: their steps do not change the model data.
    "STEADY STATE DYNAMICS",
    "MODAL DYNAMIC",
    "MODAL DAMPING",
    "COMPLEX FREQUENCY",
    "SELECT EIGENMODES",
    "DYNAMIC",
    "BUCKLE",
    "DESIGN RESPONSE",
    "SENSITIVITY",
    "OBJECTIVE",
    // Temperatures: squeal's materials have no thermal expansion.
    "TEMPERATURE",
];

/// The one of `options` that `value` (any case) abbreviates, as Abaqus matches parameter
/// values by their start (TYPE=ISO is TYPE=ISOTROPIC); None when none or several do.
pub(super) fn abbreviates<'o>(value: &str, options: &[&'o str]) -> Option<&'o str> {
    let v = value.trim().to_uppercase();
    if let Some(exact) = options.iter().find(|o| **o == v) {
        return Some(exact);
    }
    let mut found = options
        .iter()
        .filter(|o| !v.is_empty() && o.starts_with(&v));
    match (found.next(), found.next()) {
        (Some(o), None) => Some(o),
        _ => None,
    }
}

fn element_kind(abaqus: &str) -> Option<ElementKind> {
    match abaqus {
        "C3D8" => Some(ElementKind::Hex8),
        "C3D8I" => Some(ElementKind::Hex8I),
        "C3D20" => Some(ElementKind::Hex20),
        "C3D20R" => Some(ElementKind::Hex20R),
        // C3D10M (modified, for contact) is read as C3D10, which the log says.
        "C3D10" | "C3D10M" => Some(ElementKind::Tet10),
        "C3D4" => Some(ElementKind::Tet4),
        "C3D6" => Some(ElementKind::Wedge6),
        "C3D15" => Some(ElementKind::Wedge15),
        _ => None,
    }
}

fn abaqus_type(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 => "C3D8",
        ElementKind::Hex8I => "C3D8I",
        ElementKind::Hex20 => "C3D20",
        ElementKind::Hex20R => "C3D20R",
        ElementKind::Tet10 => "C3D10",
        ElementKind::Tet4 => "C3D4",
        ElementKind::Wedge6 => "C3D6",
        ElementKind::Wedge15 => "C3D15",
    }
}

/// A keyword line: upper-case keyword and its parameters (keys upper-case, values as given).
pub(super) struct Keyword {
    pub name: String,
    pub params: HashMap<String, String>,
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

/// Reads an Abaqus input file: its lines with `*INCLUDE` expanded and parts and instances
/// flattened (`instance.rs`), their tables in file order
/// (`raw.rs`, one method per keyword), then the model those tables describe (`resolve.rs`).
pub fn read(path: &Path) -> Result<InpModel, InpError> {
    let mut lines = Vec::new();
    read_lines(path, 0, &mut lines)?;
    let lines = instance::flatten(lines)?;
    raw::RawInp::parse(&lines, path)?.resolve(path)
}
