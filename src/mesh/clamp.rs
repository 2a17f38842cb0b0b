//! Dirichlet constraints named by node set.

/// A component-wise Dirichlet constraint u_c = 0 on a node set.
#[derive(Debug, Clone)]
pub struct Clamp {
    pub node_set: String,
    pub components: [bool; 3],
}

impl Clamp {
    pub fn all(node_set: &str) -> Self {
        Clamp {
            node_set: node_set.into(),
            components: [true; 3],
        }
    }
}
