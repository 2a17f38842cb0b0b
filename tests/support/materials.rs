//! Materials shared by the pure-Rust test binaries.

use squeal::mesh::material::{Elasticity, Material};

/// A brake-pad lining: transversely isotropic, soft through the thickness (z).
pub fn pad_lining() -> Material {
    Material {
        name: "lining".into(),
        density: 2500.0,
        elasticity: Elasticity::Orthotropic {
            e1: 6e9,
            e2: 6e9,
            e3: 2e9,
            nu12: 0.25,
            nu13: 0.1,
            nu23: 0.1,
            g12: 2.4e9,
            g13: 1.0e9,
            g23: 1.0e9,
        },
    }
}
