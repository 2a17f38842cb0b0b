//! `*EQUATION`: linear constraints sum_i a_i u(node_i, dof_i) = 0 (the number of terms on a
//! line, then the terms, four (node or node set, DOF, coefficient) triples a line). Node sets
//! give one equation per node, the sets' nodes paired in ascending label order (the order
//! Abaqus sorts a set in); every set of an equation has the same size.

use std::path::Path;

use super::raw::{At, RawInp};
use super::InpError;
use crate::mesh::constraint::LinearConstraint;

/// An equation as read: (node id or node set, DOF 1..3, coefficient) terms and its line.
pub(super) struct RawEquation {
    pub terms: Vec<(String, usize, f64)>,
    pub expected: usize,
    pub line: usize,
}

/// A data line of *EQUATION: the term count opens an equation, triples fill it. Returns the
/// terms still missing.
pub(super) fn data(
    raw: &mut RawInp,
    remaining: usize,
    fields: &[&str],
    at: At,
) -> Result<usize, InpError> {
    if remaining == 0 {
        let count = at.int(fields.first().copied().unwrap_or(""))?;
        if count < 1 || fields.len() != 1 {
            return Err(at.syntax(
                "an equation starts with its number of terms (>= 1) alone on a line".into(),
            ));
        }
        raw.equations.push(RawEquation {
            terms: Vec::new(),
            expected: count as usize,
            line: at.line,
        });
        return Ok(count as usize);
    }
    if !fields.len().is_multiple_of(3) || fields.len() / 3 > remaining {
        return Err(at.syntax(format!(
            "expected 'node, DOF, coefficient' triples ({remaining} term(s) to go)"
        )));
    }
    let equation = raw.equations.last_mut().expect("an equation is open");
    for t in fields.chunks(3) {
        let dof = at.int(t[1])?;
        if !(1..=3).contains(&dof) {
            return Err(at.syntax(format!(
                "DOF {dof}: solid nodes have DOFs 1 to 3 (no rotations)"
            )));
        }
        equation
            .terms
            .push((t[0].to_string(), dof as usize - 1, at.num(t[2])?));
    }
    Ok(remaining - fields.len() / 3)
}

/// The constraints of the file's equations.
pub(super) fn resolve(raw: &RawInp, path: &Path) -> Result<Vec<LinearConstraint>, InpError> {
    let error = |line: usize, message: String| InpError::Model {
        file: path.to_path_buf(),
        message: format!("line {line}: *EQUATION: {message}"),
    };
    let mut constraints = Vec::new();
    for eq in &raw.equations {
        if eq.terms.len() != eq.expected {
            return Err(error(
                eq.line,
                format!("{} terms announced, {} given", eq.expected, eq.terms.len()),
            ));
        }
        if eq.terms[0].2 == 0.0 {
            return Err(error(
                eq.line,
                "the first term's coefficient is 0 (its DOF is the one the equation fixes)".into(),
            ));
        }
        // Each term's nodes: one node id, or a set's nodes in ascending label order.
        let mut nodes: Vec<Vec<usize>> = Vec::new();
        for (target, _, _) in &eq.terms {
            let ids: Vec<i64> = match target.parse::<i64>() {
                Ok(id) => vec![id],
                Err(_) => {
                    let mut ids = raw
                        .nsets
                        .iter()
                        .find(|(name, _)| name.eq_ignore_ascii_case(target))
                        .map(|(_, ids)| ids.clone())
                        .ok_or_else(|| {
                            error(eq.line, format!("node set '{target}' is not defined"))
                        })?;
                    ids.sort_unstable();
                    ids.dedup();
                    ids
                }
            };
            let mut indices = Vec::with_capacity(ids.len());
            for id in ids {
                indices.push(
                    raw.node_index.get(&id).copied().ok_or_else(|| {
                        error(eq.line, format!("node {id} is used but not defined"))
                    })?,
                );
            }
            nodes.push(indices);
        }
        let count = nodes.iter().map(Vec::len).max().unwrap_or(1);
        if nodes.iter().any(|n| n.len() != 1 && n.len() != count) {
            let sizes: Vec<usize> = nodes.iter().map(Vec::len).collect();
            return Err(error(
                eq.line,
                format!("its node sets differ in size ({sizes:?}): each set needs as many nodes"),
            ));
        }
        for k in 0..count {
            let terms = eq
                .terms
                .iter()
                .zip(&nodes)
                .map(|((_, dof, c), n)| (n[if n.len() == 1 { 0 } else { k }], *dof, *c))
                .collect();
            constraints.push(LinearConstraint {
                terms,
                origin: format!("*EQUATION line {}", eq.line),
            });
        }
    }
    Ok(constraints)
}
