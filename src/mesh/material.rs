//! Linear elastic materials: the 6x6 constitutive matrix in Voigt order
//! (xx, yy, zz, xy, yz, zx) with engineering shear strains.

use serde::{Deserialize, Serialize};

use crate::dense::invert_spd;

// A model holds a handful of materials: the 288-byte variant costs nothing worth boxing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "lowercase", deny_unknown_fields)]
pub enum Elasticity {
    /// Young's modulus `e` (Pa), Poisson's ratio `nu`.
    Isotropic { e: f64, nu: f64 },
    /// Orthotropic in the global axes x, y, z (moduli in Pa; `nu_ij` = -eps_j / eps_i under
    /// stress along i).
    Orthotropic {
        e1: f64,
        e2: f64,
        e3: f64,
        nu12: f64,
        nu13: f64,
        nu23: f64,
        g12: f64,
        g13: f64,
        g23: f64,
    },
    /// The constitutive matrix itself (Pa), in this module's Voigt order (xx, yy, zz, xy, yz,
    /// zx) with engineering shear strains: Abaqus' TYPE=ORTHOTROPIC and ANISOTROPIC.
    /// Symmetric positive definite.
    Anisotropic { d: [[f64; 6]; 6] },
}

/// Abaqus' Voigt position (11, 22, 33, 12, 13, 23) of each of this module's (xx, yy, zz, xy,
/// yz, zx) and back: the orders differ in the last two.
pub const FROM_ABAQUS_VOIGT: [usize; 6] = [0, 1, 2, 3, 5, 4];

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    /// kg/m^3
    pub density: f64,
    pub elasticity: Elasticity,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialError {
    #[error("material '{material}': {key} = {value} is not allowed: {rule}")]
    OutOfRange {
        material: String,
        key: &'static str,
        value: f64,
        rule: &'static str,
    },
    #[error("material '{material}': the elastic constants do not give a positive definite stiffness (check the Poisson ratios against the moduli, or the matrix' entries)")]
    NotPositiveDefinite { material: String },
}

impl Material {
    pub fn isotropic(name: &str, e: f64, nu: f64, density: f64) -> Self {
        Material {
            name: name.into(),
            density,
            elasticity: Elasticity::Isotropic { e, nu },
        }
    }

    /// Checks physical admissibility; names the offending key.
    pub fn validate(&self) -> Result<(), MaterialError> {
        let bad = |key, value, rule| MaterialError::OutOfRange {
            material: self.name.clone(),
            key,
            value,
            rule,
        };
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(bad(
                "density",
                self.density,
                "a positive finite number (kg/m^3)",
            ));
        }
        match self.elasticity {
            Elasticity::Isotropic { e, nu } => {
                if !(e.is_finite() && e > 0.0) {
                    return Err(bad("e", e, "a positive finite Young's modulus (Pa)"));
                }
                if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                    return Err(bad("nu", nu, "-1 < nu < 0.5"));
                }
            }
            Elasticity::Orthotropic {
                e1,
                e2,
                e3,
                g12,
                g13,
                g23,
                nu12,
                nu13,
                nu23,
            } => {
                for (k, v) in [
                    ("e1", e1),
                    ("e2", e2),
                    ("e3", e3),
                    ("g12", g12),
                    ("g13", g13),
                    ("g23", g23),
                ] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(bad(k, v, "a positive finite modulus (Pa)"));
                    }
                }
                for (k, v) in [("nu12", nu12), ("nu13", nu13), ("nu23", nu23)] {
                    if !v.is_finite() {
                        return Err(bad(k, v, "a finite Poisson ratio"));
                    }
                }
                if invert_spd(&self.compliance()).is_none() {
                    return Err(MaterialError::NotPositiveDefinite {
                        material: self.name.clone(),
                    });
                }
            }
            Elasticity::Anisotropic { d } => {
                for (i, row) in d.iter().enumerate() {
                    for (j, &v) in row.iter().enumerate() {
                        if !v.is_finite() {
                            return Err(bad("d", v, "finite constants (Pa)"));
                        }
                        if (v - d[j][i]).abs() > 1e-12 * (v.abs() + d[j][i].abs()) {
                            return Err(bad("d", v, "a symmetric constitutive matrix"));
                        }
                    }
                }
                if invert_spd(&d).is_none() {
                    return Err(MaterialError::NotPositiveDefinite {
                        material: self.name.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    fn compliance(&self) -> [[f64; 6]; 6] {
        let mut s = [[0.0; 6]; 6];
        let (e1, e2, e3, n12, n13, n23, g12, g13, g23) = match self.elasticity {
            Elasticity::Isotropic { e, nu } => {
                let g = e / (2.0 * (1.0 + nu));
                (e, e, e, nu, nu, nu, g, g, g)
            }
            Elasticity::Orthotropic {
                e1,
                e2,
                e3,
                nu12,
                nu13,
                nu23,
                g12,
                g13,
                g23,
            } => (e1, e2, e3, nu12, nu13, nu23, g12, g13, g23),
            Elasticity::Anisotropic { d } => {
                return invert_spd(&d).expect("validated anisotropic material");
            }
        };
        s[0][0] = 1.0 / e1;
        s[1][1] = 1.0 / e2;
        s[2][2] = 1.0 / e3;
        s[0][1] = -n12 / e1;
        s[1][0] = s[0][1];
        s[0][2] = -n13 / e1;
        s[2][0] = s[0][2];
        s[1][2] = -n23 / e2;
        s[2][1] = s[1][2];
        s[3][3] = 1.0 / g12;
        s[4][4] = 1.0 / g23;
        s[5][5] = 1.0 / g13;
        s
    }

    /// The constitutive matrix D (sigma = D eps). Call `validate` first.
    pub fn stiffness_matrix(&self) -> [[f64; 6]; 6] {
        match self.elasticity {
            Elasticity::Isotropic { e, nu } => {
                let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
                let mu = e / (2.0 * (1.0 + nu));
                let mut d = [[0.0; 6]; 6];
                for (i, row) in d.iter_mut().enumerate().take(3) {
                    for (j, v) in row.iter_mut().enumerate().take(3) {
                        *v = if i == j { lambda + 2.0 * mu } else { lambda };
                    }
                }
                d[3][3] = mu;
                d[4][4] = mu;
                d[5][5] = mu;
                d
            }
            Elasticity::Orthotropic { .. } => {
                invert_spd(&self.compliance()).expect("validated orthotropic material")
            }
            Elasticity::Anisotropic { d } => d,
        }
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn orthotropic_with_isotropic_constants_equals_isotropic() {
        let (e, nu) = (2.1e11, 0.3);
        let g = e / (2.0 * (1.0 + nu));
        let iso = Material::isotropic("steel", e, nu, 7850.0);
        let ortho = Material {
            name: "steel".into(),
            density: 7850.0,
            elasticity: Elasticity::Orthotropic {
                e1: e,
                e2: e,
                e3: e,
                nu12: nu,
                nu13: nu,
                nu23: nu,
                g12: g,
                g13: g,
                g23: g,
            },
        };
        ortho.validate().unwrap();
        let (a, b) = (iso.stiffness_matrix(), ortho.stiffness_matrix());
        for i in 0..6 {
            for j in 0..6 {
                assert!((a[i][j] - b[i][j]).abs() < 1e-6 * e, "D[{i}][{j}]");
            }
        }
    }

    #[test]
    fn inadmissible_constants_name_the_key() {
        let m = Material::isotropic("pad", 1e9, 0.5, 2500.0);
        let err = m.validate().unwrap_err().to_string();
        assert!(err.contains("'pad'") && err.contains("nu"), "{err}");
        let m = Material::isotropic("pad", 1e9, 0.3, -1.0);
        assert!(m.validate().unwrap_err().to_string().contains("density"));
        let m = Material::isotropic("pad", f64::NAN, 0.3, 1.0);
        assert!(m.validate().unwrap_err().to_string().contains("e = NaN"));
    }
}
