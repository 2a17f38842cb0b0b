//! `*ELASTIC`'s data: its forms (isotropic, engineering constants, Abaqus' ORTHOTROPIC and
//! ANISOTROPIC D constants) into a material's elasticity.

use super::raw::At;
use super::InpError;
use crate::mesh::material::Elasticity;

/// The forms of *ELASTIC and how many constants each takes (before a temperature).
#[derive(Clone, Copy)]
pub(super) enum ElasticForm {
    Isotropic,
    Engineering,
    Orthotropic,
    Anisotropic,
}

impl ElasticForm {
    pub(super) fn constants(self) -> usize {
        match self {
            ElasticForm::Isotropic => 2,
            ElasticForm::Engineering | ElasticForm::Orthotropic => 9,
            ElasticForm::Anisotropic => 21,
        }
    }
}

/// Abaqus' ORTHOTROPIC (D1111, D1122, D2222, D1133, D2233, D3333, D1212, D1313, D2323) and
/// ANISOTROPIC (the upper triangle column by column: D1111, D1122, D2222, D1133, D2233,
/// D3333, D1112, D2212, D3312, D1212, ...) constants as (row, column) in Abaqus' Voigt order.
fn abaqus_d_positions(form: ElasticForm) -> Vec<(usize, usize)> {
    match form {
        ElasticForm::Orthotropic => vec![
            (0, 0),
            (0, 1),
            (1, 1),
            (0, 2),
            (1, 2),
            (2, 2),
            (3, 3),
            (4, 4),
            (5, 5),
        ],
        _ => (0..6).flat_map(|j| (0..=j).map(move |i| (i, j))).collect(),
    }
}

/// The elasticity once its values are complete (the 9 and 21 constants take two and three
/// lines of 8), else None. A trailing temperature is ignored.
pub(super) fn elasticity(
    values: &[f64],
    form: ElasticForm,
    at: At<'_>,
) -> Result<Option<Elasticity>, InpError> {
    use crate::mesh::material::FROM_ABAQUS_VOIGT;
    let n = form.constants();
    if values.len() < n {
        return match form {
            ElasticForm::Isotropic => Err(at.syntax("expected 'E, nu'".into())),
            _ => Ok(None),
        };
    }
    let v = values;
    Ok(Some(match form {
        ElasticForm::Isotropic => Elasticity::Isotropic { e: v[0], nu: v[1] },
        ElasticForm::Engineering => Elasticity::Orthotropic {
            e1: v[0],
            e2: v[1],
            e3: v[2],
            nu12: v[3],
            nu13: v[4],
            nu23: v[5],
            g12: v[6],
            g13: v[7],
            g23: v[8],
        },
        ElasticForm::Orthotropic | ElasticForm::Anisotropic => {
            let mut d = [[0.0; 6]; 6];
            for (k, (i, j)) in abaqus_d_positions(form).into_iter().enumerate() {
                let (p, q) = (FROM_ABAQUS_VOIGT[i], FROM_ABAQUS_VOIGT[j]);
                d[p][q] = v[k];
                d[q][p] = v[k];
            }
            Elasticity::Anisotropic { d }
        }
    }))
}
