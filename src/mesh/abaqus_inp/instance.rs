//! Parts and instances (`*PART` ... `*END PART`, `*ASSEMBLY` with `*INSTANCE` ...
//! `*END INSTANCE`), flattened into the lines of one model before the tables are read: each
//! instance's copy of its part gets its node and element ids offset (past every other
//! instance's), its node coordinates translated and then rotated as the `*INSTANCE` data lines
//! say (Abaqus' order), and its names scoped as Abaqus scopes them (`Instance.Set`).
//! Assembly-level `*NSET` / `*ELSET` with `INSTANCE=` take the instance's ids and names.
//! Materials stay model-level names. A file without `*PART` is returned as it is.

use std::collections::HashMap;
use std::path::PathBuf;

use super::{parse_keyword, InpError};

type Line = (PathBuf, usize, String);

/// A part: its name and lines, with the largest node and element ids it uses.
struct Part {
    lines: Vec<Line>,
    max_node: i64,
    max_element: i64,
}

/// An instance: name, the rigid motion of its data lines, and its id offsets.
struct Instance {
    name: String,
    translation: [f64; 3],
    /// Axis point a, point b, angle (degrees).
    rotation: Option<([f64; 3], [f64; 3], f64)>,
    node_offset: i64,
    element_offset: i64,
}

/// What a keyword's data lines hold, for the renaming of an instance's copy.
#[derive(Clone, Copy, PartialEq)]
enum Data {
    Node,
    Element,
    /// Set members: ids (nodes or elements) or set names; GENERATE: start, end, step.
    Set {
        elements: bool,
        generate: bool,
    },
    /// Surface lines: element (or node) ids or set names first.
    Surface {
        nodes: bool,
    },
    /// First field a node set or node id (*BOUNDARY).
    FirstNode,
    /// Triples whose first field is a node set or id (*EQUATION after its count lines).
    Equation,
    /// Two surface names (*TIE, *CONTACT PAIR).
    Surfaces,
    Other,
}

fn err(line: &Line, message: String) -> InpError {
    InpError::Syntax {
        file: line.0.clone(),
        line: line.1,
        message,
    }
}

/// The lines of the model with parts and instances flattened.
pub(super) fn flatten(lines: Vec<Line>) -> Result<Vec<Line>, InpError> {
    let has_parts = lines
        .iter()
        .any(|l| keyword_name(&l.2).as_deref() == Some("PART"));
    if !has_parts {
        return Ok(lines);
    }
    let mut parts: HashMap<String, Part> = HashMap::new();
    let mut out = Vec::new();
    let mut i = 0;
    let mut next_node = 0i64;
    let mut next_element = 0i64;
    let mut instances: HashMap<String, Instance> = HashMap::new();
    while i < lines.len() {
        let line = &lines[i];
        match keyword_name(&line.2).as_deref() {
            Some("PART") => {
                let name =
                    param(&line.2, "NAME").ok_or_else(|| err(line, "*PART needs NAME=".into()))?;
                let start = i + 1;
                let end = (start..lines.len())
                    .find(|&j| keyword_name(&lines[j].2).as_deref() == Some("END PART"))
                    .ok_or_else(|| err(line, format!("*PART {name} has no *END PART")))?;
                let body = lines[start..end].to_vec();
                let (max_node, max_element) = largest_ids(&body);
                parts.insert(
                    name.to_uppercase(),
                    Part {
                        lines: body,
                        max_node,
                        max_element,
                    },
                );
                i = end + 1;
            }
            Some("ASSEMBLY") | Some("END ASSEMBLY") => i += 1,
            Some("INSTANCE") => {
                let name = param(&line.2, "NAME")
                    .ok_or_else(|| err(line, "*INSTANCE needs NAME=".into()))?;
                let part_name = param(&line.2, "PART").ok_or_else(|| {
                    err(
                        line,
                        format!(
                            "*INSTANCE {name} needs PART= (instances of instances are not read)"
                        ),
                    )
                })?;
                let part = parts.get(&part_name.to_uppercase()).ok_or_else(|| {
                    err(
                        line,
                        format!("*INSTANCE {name}: part '{part_name}' is not defined before it"),
                    )
                })?;
                let mut instance = Instance {
                    name: name.clone(),
                    translation: [0.0; 3],
                    rotation: None,
                    node_offset: next_node,
                    element_offset: next_element,
                };
                next_node += part.max_node;
                next_element += part.max_element;
                let mut j = i + 1;
                let mut data = 0;
                while j < lines.len()
                    && keyword_name(&lines[j].2).as_deref() != Some("END INSTANCE")
                {
                    let t = lines[j].2.trim();
                    if t.is_empty() || t.starts_with("**") {
                        j += 1;
                        continue;
                    }
                    if t.starts_with('*') {
                        return Err(err(&lines[j], format!("*INSTANCE {name}: keywords inside an instance are not read (only its translation and rotation lines)")));
                    }
                    let numbers = numbers(&lines[j])?;
                    match (data, numbers.len()) {
                        (0, 3) => instance.translation = [numbers[0], numbers[1], numbers[2]],
                        (1, 7) => {
                            instance.rotation = Some((
                                [numbers[0], numbers[1], numbers[2]],
                                [numbers[3], numbers[4], numbers[5]],
                                numbers[6],
                            ))
                        }
                        _ => return Err(err(&lines[j], "an *INSTANCE takes a translation line (x, y, z) and a rotation line (a1, a2, a3, b1, b2, b3, degrees)".into())),
                    }
                    data += 1;
                    j += 1;
                }
                if j == lines.len() {
                    return Err(err(line, format!("*INSTANCE {name} has no *END INSTANCE")));
                }
                copy_part(part, &instance, &mut out)?;
                instances.insert(name.to_uppercase(), instance);
                i = j + 1;
            }
            Some("NSET") | Some("ELSET") if param(&line.2, "INSTANCE").is_some() => {
                let inst_name = param(&line.2, "INSTANCE").unwrap_or_default();
                let instance = instances.get(&inst_name.to_uppercase()).ok_or_else(|| {
                    err(
                        line,
                        format!("INSTANCE={inst_name}: no such instance before this line"),
                    )
                })?;
                let kw = parse_keyword(line.2.trim());
                let elements = kw.name == "ELSET";
                let generate = kw.params.contains_key("GENERATE");
                out.push((line.0.clone(), line.1, without_param(&line.2, "INSTANCE")));
                let mut j = i + 1;
                while j < lines.len() && !lines[j].2.trim_start().starts_with('*') {
                    let data = Data::Set { elements, generate };
                    out.push(rename_data(&lines[j], data, instance)?);
                    j += 1;
                }
                i = j;
            }
            _ => {
                out.push(line.clone());
                i += 1;
            }
        }
    }
    Ok(out)
}

/// The upper-case keyword of a keyword line (None: a data or comment line).
fn keyword_name(text: &str) -> Option<String> {
    let t = text.trim();
    (t.starts_with('*') && !t.starts_with("**")).then(|| parse_keyword(t).name)
}

fn param(text: &str, key: &str) -> Option<String> {
    parse_keyword(text.trim()).params.get(key).cloned()
}

fn without_param(text: &str, key: &str) -> String {
    text.split(',')
        .filter(|p| {
            p.split_once('=')
                .is_none_or(|(k, _)| !k.trim().eq_ignore_ascii_case(key))
        })
        .collect::<Vec<_>>()
        .join(",")
}

fn numbers(line: &Line) -> Result<Vec<f64>, InpError> {
    line.2
        .split(',')
        .map(str::trim)
        .filter(|f| !f.is_empty())
        .map(|f| {
            f.replace(['d', 'D'], "e")
                .parse::<f64>()
                .map_err(|_| err(line, format!("'{f}' is not a number")))
        })
        .collect()
}

/// The largest node id (in *NODE lines) and element id (first field of *ELEMENT lines) a
/// part uses.
fn largest_ids(lines: &[Line]) -> (i64, i64) {
    let (mut node, mut element) = (0i64, 0i64);
    let mut mode = Data::Other;
    let mut continued = false;
    for (_, _, text) in lines {
        let t = text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if let Some(name) = keyword_name(t) {
            mode = match name.as_str() {
                "NODE" => Data::Node,
                "ELEMENT" => Data::Element,
                _ => Data::Other,
            };
            continued = false;
            continue;
        }
        let first = t
            .split(',')
            .next()
            .and_then(|f| f.trim().parse::<i64>().ok());
        match (mode, first) {
            (Data::Node, Some(id)) => node = node.max(id),
            (Data::Element, Some(id)) if !continued => element = element.max(id),
            _ => {}
        }
        continued = mode == Data::Element && t.ends_with(',');
    }
    (node, element)
}

/// The instance's copy of its part: keyword parameters and data lines renamed and offset.
fn copy_part(part: &Part, instance: &Instance, out: &mut Vec<Line>) -> Result<(), InpError> {
    let mut data = Data::Other;
    let mut continued = false;
    let mut equation_count_next = true;
    for line in &part.lines {
        let t = line.2.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            let kw = parse_keyword(t);
            data = match kw.name.as_str() {
                "NODE" => Data::Node,
                "ELEMENT" => Data::Element,
                "NSET" | "ELSET" => Data::Set {
                    elements: kw.name == "ELSET",
                    generate: kw.params.contains_key("GENERATE"),
                },
                "SURFACE" => Data::Surface {
                    nodes: kw
                        .params
                        .get("TYPE")
                        .is_some_and(|t| t.to_uppercase().starts_with('N')),
                },
                "BOUNDARY" => Data::FirstNode,
                "EQUATION" => Data::Equation,
                "TIE" | "CONTACT PAIR" => Data::Surfaces,
                _ => Data::Other,
            };
            continued = false;
            equation_count_next = true;
            out.push((line.0.clone(), line.1, scoped_keyword(t, &instance.name)));
            continue;
        }
        let renamed = match data {
            Data::Node => node_line(line, instance)?,
            Data::Element => {
                let l = element_line(line, instance, continued)?;
                continued = t.ends_with(',');
                l
            }
            Data::Equation => {
                // Count lines (one integer) alternate with the term lines.
                let fields: Vec<&str> = t
                    .split(',')
                    .map(str::trim)
                    .filter(|f| !f.is_empty())
                    .collect();
                if equation_count_next && fields.len() == 1 {
                    equation_count_next = false;
                    line.clone()
                } else {
                    rename_data(line, Data::Equation, instance)?
                }
            }
            d => rename_data(line, d, instance)?,
        };
        out.push(renamed);
    }
    Ok(())
}

/// A keyword line of a part, its set, surface and orientation names scoped to the instance.
fn scoped_keyword(text: &str, instance: &str) -> String {
    let mut parts = text.split(',');
    let head = parts.next().unwrap_or("").to_string();
    // NAME= names a surface or an orientation of the part (materials are model-level).
    let keyword = head.trim().trim_start_matches('*').trim().to_uppercase();
    let named = keyword == "SURFACE" || keyword == "ORIENTATION";
    let mut out = vec![head];
    for p in parts {
        match p.split_once('=') {
            Some((k, v)) => {
                let key = k.trim().to_uppercase();
                let scoped = ["NSET", "ELSET", "ORIENTATION"].contains(&key.as_str())
                    || (named && key == "NAME");
                if scoped {
                    out.push(format!("{}={instance}.{}", k, v.trim()));
                } else {
                    out.push(p.to_string());
                }
            }
            None => out.push(p.to_string()),
        }
    }
    out.join(",")
}

/// A name or id field of the instance: an integer id offset, a name scoped.
fn scoped_field(field: &str, offset: i64, instance: &str) -> String {
    match field.parse::<i64>() {
        Ok(id) => (id + offset).to_string(),
        Err(_) => format!("{instance}.{field}"),
    }
}

fn node_line(line: &Line, instance: &Instance) -> Result<Line, InpError> {
    let fields: Vec<&str> = line.2.split(',').map(str::trim).collect();
    let id: i64 = fields[0]
        .parse()
        .map_err(|_| err(line, format!("'{}' is not a node id", fields[0])))?;
    let mut x = [0.0; 3];
    for (d, f) in fields.iter().skip(1).take(3).enumerate() {
        x[d] = f
            .replace(['d', 'D'], "e")
            .parse()
            .map_err(|_| err(line, format!("'{f}' is not a number")))?;
    }
    let x = moved(x, instance);
    Ok((
        line.0.clone(),
        line.1,
        format!(
            "{}, {:e}, {:e}, {:e}",
            id + instance.node_offset,
            x[0],
            x[1],
            x[2]
        ),
    ))
}

/// Translation first, then the rotation about the axis a-b by the angle (right hand).
fn moved(x: [f64; 3], instance: &Instance) -> [f64; 3] {
    let t = instance.translation;
    let x = [x[0] + t[0], x[1] + t[1], x[2] + t[2]];
    let Some((a, b, degrees)) = instance.rotation else {
        return x;
    };
    let axis = crate::dense::normalize(crate::dense::sub(b, a));
    let r = crate::dense::sub(x, a);
    let (s, c) = degrees.to_radians().sin_cos();
    let k = axis;
    let kxr = crate::dense::cross(k, r);
    let kr = crate::dense::dot(k, r);
    // Rodrigues: r c + (k x r) s + k (k . r)(1 - c).
    [0, 1, 2].map(|d| a[d] + r[d] * c + kxr[d] * s + k[d] * kr * (1.0 - c))
}

fn element_line(line: &Line, instance: &Instance, continued: bool) -> Result<Line, InpError> {
    let mut fields = Vec::new();
    for (k, f) in line.2.split(',').map(str::trim).enumerate() {
        if f.is_empty() {
            fields.push(String::new());
            continue;
        }
        let id: i64 = f
            .parse()
            .map_err(|_| err(line, format!("'{f}' is not an integer")))?;
        let offset = if k == 0 && !continued {
            instance.element_offset
        } else {
            instance.node_offset
        };
        fields.push((id + offset).to_string());
    }
    Ok((line.0.clone(), line.1, fields.join(", ")))
}

/// A data line of sets, surfaces, boundaries, equations or ties, for the instance.
fn rename_data(line: &Line, data: Data, instance: &Instance) -> Result<Line, InpError> {
    let fields: Vec<&str> = line.2.split(',').map(str::trim).collect();
    let (n, e) = (instance.node_offset, instance.element_offset);
    let name = &instance.name;
    let renamed: Vec<String> = match data {
        Data::Set { elements, generate } => {
            let offset = if elements { e } else { n };
            fields
                .iter()
                .enumerate()
                .map(|(k, f)| match (generate, k) {
                    (_, _) if f.is_empty() => String::new(),
                    (true, 2) => f.to_string(),
                    _ => scoped_field(f, offset, name),
                })
                .collect()
        }
        Data::Surface { nodes } => fields
            .iter()
            .enumerate()
            .map(|(k, f)| {
                if k == 0 && !f.is_empty() {
                    scoped_field(f, if nodes { n } else { e }, name)
                } else {
                    f.to_string()
                }
            })
            .collect(),
        Data::FirstNode => fields
            .iter()
            .enumerate()
            .map(|(k, f)| {
                if k == 0 {
                    scoped_field(f, n, name)
                } else {
                    f.to_string()
                }
            })
            .collect(),
        Data::Equation => fields
            .iter()
            .enumerate()
            .map(|(k, f)| {
                if k % 3 == 0 && !f.is_empty() {
                    scoped_field(f, n, name)
                } else {
                    f.to_string()
                }
            })
            .collect(),
        Data::Surfaces => fields
            .iter()
            .map(|f| {
                if f.is_empty() {
                    String::new()
                } else {
                    format!("{name}.{f}")
                }
            })
            .collect(),
        Data::Node | Data::Element | Data::Other => return Ok(line.clone()),
    };
    Ok((line.0.clone(), line.1, renamed.join(", ")))
}
