//! Element kinds and their topology: nodes, faces and edges in the Abaqus node order (C3D8,
//! C3D20, C3D10, C3D4, C3D6, C3D15; the hexahedra's and tetrahedra's also VTK's/XDMF's), and the nodes' reference coordinates. The shape
//! functions and quadrature rules on them are the finite elements' (`fem::shape`).

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    /// Trilinear hexahedron (fully integrated; locks in bending, kept for reference).
    Hex8,
    /// Trilinear hexahedron with Wilson-Taylor incompatible modes, statically condensed:
    /// accurate in bending at linear cost (Abaqus C3D8I).
    #[serde(rename = "hex8i")]
    Hex8I,
    /// Serendipity quadratic hexahedron.
    Hex20,
    /// Serendipity quadratic hexahedron with reduced (2x2x2) integration (Abaqus C3D20R):
    /// softer than Hex20, free of locking, with hourglass modes that a single element shows
    /// and a mesh of several suppresses.
    #[serde(rename = "hex20r")]
    Hex20R,
    /// Quadratic tetrahedron.
    Tet10,
    /// Linear tetrahedron (constant strain; stiff in bending: for imported meshes, C3D4).
    Tet4,
    /// Linear wedge (triangular prism, Abaqus C3D6; for imported meshes).
    Wedge6,
    /// Quadratic wedge (Abaqus C3D15; for imported meshes).
    Wedge15,
}

/// Corner positions of the reference cube, in C3D8 order.
pub const HEX_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Edges of a hexahedron as corner pairs, in the order of the C3D20 mid-edge nodes 8..19.
pub const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Edges of a tetrahedron as corner pairs, in the order of the C3D10 mid-edge nodes 4..9.
pub const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];

/// Corner positions of the reference wedge (triangle in xi, eta; zeta in [-1, 1]).
pub const WEDGE_CORNERS: [[f64; 3]; 6] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];

/// Edges of a wedge as corner pairs, in the order of the C3D15 mid-edge nodes 6..14: the
/// bottom triangle, the top triangle, the three vertical edges.
pub const WEDGE_EDGES: [[usize; 2]; 9] = [
    [0, 1],
    [1, 2],
    [2, 0],
    [3, 4],
    [4, 5],
    [5, 3],
    [0, 3],
    [1, 4],
    [2, 5],
];

/// Corners of the five faces of a wedge (Abaqus faces S1..S5: the triangles 1-2-3 and 4-5-6,
/// then the quadrilaterals 1-2-5-4, 2-3-6-5, 3-1-4-6), counter-clockwise seen from outside.
pub const WEDGE_FACES: [&[usize]; 5] = [
    &[0, 2, 1],
    &[3, 4, 5],
    &[0, 1, 4, 3],
    &[1, 2, 5, 4],
    &[2, 0, 3, 5],
];

/// Corners of the six faces of a hexahedron (Abaqus faces S1..S6), counter-clockwise seen
/// from outside.
pub const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// Corners of the four faces of a tetrahedron (Abaqus faces S1..S4), counter-clockwise seen
/// from outside.
pub const TET_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];

impl ElementKind {
    /// Element-local nodes of face `face` (1-based, Abaqus numbering): corners in
    /// counter-clockwise order seen from outside, then the mid-edge nodes of quadratic
    /// elements in the order of the face's edges.
    pub fn face_local_nodes(self, face: u8) -> Vec<usize> {
        let f = face as usize - 1;
        let (corners, edges): (Vec<usize>, &[[usize; 2]]) = match self {
            ElementKind::Hex8 | ElementKind::Hex8I => (HEX_FACES[f].to_vec(), &[]),
            ElementKind::Hex20 | ElementKind::Hex20R => (HEX_FACES[f].to_vec(), &HEX_EDGES),
            ElementKind::Tet4 => (TET_FACES[f].to_vec(), &[]),
            ElementKind::Tet10 => (TET_FACES[f].to_vec(), &TET_EDGES),
            ElementKind::Wedge6 => (WEDGE_FACES[f].to_vec(), &[]),
            ElementKind::Wedge15 => (WEDGE_FACES[f].to_vec(), &WEDGE_EDGES),
        };
        let mut out = corners.clone();
        if !edges.is_empty() {
            let first_mid = match self {
                ElementKind::Hex20 | ElementKind::Hex20R => 8,
                ElementKind::Wedge15 => 6,
                _ => 4,
            };
            for i in 0..corners.len() {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                let e = edges
                    .iter()
                    .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
                    .expect("face edges are element edges");
                out.push(first_mid + e);
            }
        }
        out
    }

    /// Number of faces (6 for hexahedra, 5 for wedges, 4 for tetrahedra).
    pub fn faces(self) -> u8 {
        match self {
            ElementKind::Tet4 | ElementKind::Tet10 => 4,
            ElementKind::Wedge6 | ElementKind::Wedge15 => 5,
            _ => 6,
        }
    }

    pub fn nodes(self) -> usize {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => 8,
            ElementKind::Hex20 | ElementKind::Hex20R => 20,
            ElementKind::Tet10 => 10,
            ElementKind::Tet4 => 4,
            ElementKind::Wedge6 => 6,
            ElementKind::Wedge15 => 15,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Hex8 => "hex8",
            ElementKind::Hex8I => "hex8i",
            ElementKind::Hex20 => "hex20",
            ElementKind::Hex20R => "hex20r",
            ElementKind::Tet10 => "tet10",
            ElementKind::Tet4 => "tet4",
            ElementKind::Wedge6 => "wedge6",
            ElementKind::Wedge15 => "wedge15",
        }
    }

    /// Reference coordinates of the nodes.
    pub fn reference_nodes(self) -> Vec<[f64; 3]> {
        match self {
            ElementKind::Hex8 | ElementKind::Hex8I => HEX_CORNERS.to_vec(),
            ElementKind::Hex20 | ElementKind::Hex20R => {
                let mut v = HEX_CORNERS.to_vec();
                for [a, b] in HEX_EDGES {
                    let (p, q) = (HEX_CORNERS[a], HEX_CORNERS[b]);
                    v.push([
                        0.5 * (p[0] + q[0]),
                        0.5 * (p[1] + q[1]),
                        0.5 * (p[2] + q[2]),
                    ]);
                }
                v
            }
            ElementKind::Tet4 => vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            ElementKind::Tet10 => {
                let c = [
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                ];
                let mut v = c.to_vec();
                for [a, b] in TET_EDGES {
                    v.push([
                        0.5 * (c[a][0] + c[b][0]),
                        0.5 * (c[a][1] + c[b][1]),
                        0.5 * (c[a][2] + c[b][2]),
                    ]);
                }
                v
            }
            ElementKind::Wedge6 => WEDGE_CORNERS.to_vec(),
            ElementKind::Wedge15 => {
                let c = WEDGE_CORNERS;
                let mut v = c.to_vec();
                for [a, b] in WEDGE_EDGES {
                    v.push([
                        0.5 * (c[a][0] + c[b][0]),
                        0.5 * (c[a][1] + c[b][1]),
                        0.5 * (c[a][2] + c[b][2]),
                    ]);
                }
                v
            }
        }
    }
}
