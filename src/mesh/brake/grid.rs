//! Masked structured grids: the meshing engine of the parametric brake.
//!
//! A component is described by three axes, each cut into coarse segments (the geometric
//! features: ring, hat wall, lining, backplate, ...), in a coordinate frame (cylindrical about
//! an axis parallel to z, or Cartesian). Every coarse cell either belongs to an element block or
//! is empty, and is filled with a graded tensor grid of hexahedra. Neighbouring cells share
//! their nodes, so a lining and its backplate are one conforming mesh. Curved edges of
//! quadratic elements get their mid-edge nodes in the parameter space of the frame, so arcs
//! are followed exactly at the nodes.

use crate::mesh::material::Material;
use crate::mesh::ElementKind;
use crate::mesh::{ElementBlock, Mesh};

/// How the cells of one segment are sized.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Grading {
    Uniform,
    /// Finer at both ends: the middle cells are `ratio` times the end cells.
    Ends(f64),
}

/// A coarse segment of an axis, from the previous break to `end`.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub end: f64,
    pub cells: usize,
    pub grading: Grading,
}

/// One direction of a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub start: f64,
    pub segments: Vec<Segment>,
    /// The last point is the first one again (a full circle in theta).
    pub periodic: bool,
}

impl Axis {
    /// An axis through `breaks` with the given cell counts per segment, uniform.
    pub fn new(breaks: &[f64], cells: &[usize]) -> Self {
        assert_eq!(breaks.len(), cells.len() + 1, "one cell count per segment");
        Axis {
            start: breaks[0],
            segments: breaks[1..]
                .iter()
                .zip(cells)
                .map(|(&end, &cells)| Segment {
                    end,
                    cells,
                    grading: Grading::Uniform,
                })
                .collect(),
            periodic: false,
        }
    }

    /// An axis through `breaks` whose segments get `cells(length, h, 1)` cells each; `scale`
    /// turns a parameter length into a physical one (a radius for angles, else 1).
    pub fn sized(breaks: &[f64], h: f64, scale: f64) -> Self {
        let cells: Vec<usize> = breaks
            .windows(2)
            .map(|w| super::cells(scale * (w[1] - w[0]), h, 1))
            .collect();
        Axis::new(breaks, &cells)
    }

    pub fn graded(mut self, segment: usize, grading: Grading) -> Self {
        self.segments[segment].grading = grading;
        self
    }

    pub fn periodic(mut self) -> Self {
        self.periodic = true;
        self
    }

    pub fn breaks(&self) -> Vec<f64> {
        std::iter::once(self.start)
            .chain(self.segments.iter().map(|s| s.end))
            .collect()
    }

    /// Fine cells in total.
    pub fn cells(&self) -> usize {
        self.segments.iter().map(|s| s.cells).sum()
    }

    /// Fine points (cells + 1) and the coarse segment of every fine cell.
    pub fn points(&self) -> (Vec<f64>, Vec<usize>) {
        let mut points = vec![self.start];
        let mut segment_of_cell = Vec::new();
        let mut a = self.start;
        for (s, seg) in self.segments.iter().enumerate() {
            assert!(seg.cells > 0, "a segment needs at least one cell");
            let sizes = cell_sizes(seg.cells, seg.grading);
            let total: f64 = sizes.iter().sum();
            let mut acc = 0.0;
            for (i, size) in sizes.iter().enumerate() {
                acc += size;
                // The last point is the break itself, without round-off.
                let x = if i + 1 == sizes.len() {
                    seg.end
                } else {
                    a + (seg.end - a) * acc / total
                };
                points.push(x);
                segment_of_cell.push(s);
            }
            a = seg.end;
        }
        (points, segment_of_cell)
    }
}

fn cell_sizes(n: usize, grading: Grading) -> Vec<f64> {
    match grading {
        Grading::Uniform => vec![1.0; n],
        Grading::Ends(ratio) => {
            // Geometric growth from both ends to the middle.
            let half = n.div_ceil(2);
            let q = if half > 1 {
                ratio.powf(1.0 / (half - 1) as f64)
            } else {
                1.0
            };
            (0..n).map(|i| q.powi(i.min(n - 1 - i) as i32)).collect()
        }
    }
}

/// The coordinate frame of a grid's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Frame {
    /// (x, y, z).
    Cartesian,
    /// (r, theta, z) about the axis through `center` parallel to z.
    Cylindrical { center: [f64; 2] },
}

impl Frame {
    pub fn map(self, p: [f64; 3]) -> [f64; 3] {
        match self {
            Frame::Cartesian => p,
            Frame::Cylindrical { center } => [
                center[0] + p[0] * p[1].cos(),
                center[1] + p[0] * p[1].sin(),
                p[2],
            ],
        }
    }
}

/// Exact volume of the coarse cells (r, theta, z) a selector keeps, revolved about z:
/// (theta1 - theta0) / 2 (r1^2 - r0^2) (z1 - z0) each.
pub fn revolved_volume(
    r: &[f64],
    theta: &[f64],
    z: &[f64],
    select: &dyn Fn([usize; 3]) -> Option<usize>,
) -> f64 {
    let mut v = 0.0;
    for ri in 0..r.len() - 1 {
        for ti in 0..theta.len() - 1 {
            for zi in 0..z.len() - 1 {
                if select([ri, ti, zi]).is_some() {
                    v += 0.5
                        * (theta[ti + 1] - theta[ti])
                        * (r[ri + 1].powi(2) - r[ri].powi(2))
                        * (z[zi + 1] - z[zi]);
                }
            }
        }
    }
    v
}

/// A face of a grid cell: the direction of its outward normal in parameter space.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellFace {
    pub axis: usize,
    pub positive: bool,
}

impl CellFace {
    /// Abaqus face number of a hexahedron whose corners follow the grid axes.
    pub fn abaqus(self) -> u8 {
        match (self.axis, self.positive) {
            (0, false) => 6,
            (0, true) => 4,
            (1, false) => 3,
            (1, true) => 5,
            (2, false) => 1,
            _ => 2,
        }
    }

    pub const ALL: [CellFace; 6] = [
        CellFace {
            axis: 0,
            positive: false,
        },
        CellFace {
            axis: 0,
            positive: true,
        },
        CellFace {
            axis: 1,
            positive: false,
        },
        CellFace {
            axis: 1,
            positive: true,
        },
        CellFace {
            axis: 2,
            positive: false,
        },
        CellFace {
            axis: 2,
            positive: true,
        },
    ];
}

/// A structured grid in a frame.
#[derive(Debug, Clone)]
pub struct Grid {
    pub axes: [Axis; 3],
    pub frame: Frame,
}

/// A meshed grid: the mesh, and for every element its fine and coarse cell.
pub struct GridMesh {
    pub mesh: Mesh,
    pub fine_cell: Vec<[usize; 3]>,
    pub coarse_cell: Vec<[usize; 3]>,
    /// Block of every fine cell (None: empty), indexed like `Grid::cell_index`.
    active: Vec<Option<usize>>,
    cells: [usize; 3],
    periodic: [bool; 3],
}

struct Lattice {
    /// Lattice points per axis (before wrapping: the point count of a periodic axis is its
    /// cell count times the order).
    dims: [usize; 3],
    periodic: [bool; 3],
}

impl Lattice {
    fn wrap(&self, mut p: [usize; 3]) -> [usize; 3] {
        for d in 0..3 {
            if self.periodic[d] {
                p[d] %= self.dims[d];
            }
        }
        p
    }

    /// Linear index with axis 2 fastest, then 0, then 1 (theta slowest): contiguous node
    /// ranges are then angular sectors of a disc, with small interfaces between ranks.
    fn index(&self, p: [usize; 3]) -> usize {
        let p = self.wrap(p);
        (p[1] * self.dims[0] + p[0]) * self.dims[2] + p[2]
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }
}

impl Grid {
    pub fn cells(&self) -> [usize; 3] {
        [
            self.axes[0].cells(),
            self.axes[1].cells(),
            self.axes[2].cells(),
        ]
    }

    fn lattice(&self, order: usize) -> Lattice {
        let cells = self.cells();
        let mut dims = [0; 3];
        let mut periodic = [false; 3];
        for d in 0..3 {
            periodic[d] = self.axes[d].periodic;
            dims[d] = cells[d] * order + usize::from(!periodic[d]);
        }
        Lattice { dims, periodic }
    }

    /// Lattice points (in units of half cells for quadratic elements) of a cell's nodes, in
    /// the element's node order.
    fn cell_nodes(cell: [usize; 3], order: usize, quadratic: bool) -> Vec<[usize; 3]> {
        let [i, j, k] = cell.map(|c| c * order);
        let o = order;
        let corners = [
            [i, j, k],
            [i + o, j, k],
            [i + o, j + o, k],
            [i, j + o, k],
            [i, j, k + o],
            [i + o, j, k + o],
            [i + o, j + o, k + o],
            [i, j + o, k + o],
        ];
        let mut nodes = corners.to_vec();
        if quadratic {
            for [a, b] in crate::mesh::element::HEX_EDGES {
                let (p, q) = (corners[a], corners[b]);
                nodes.push([(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2]);
            }
        }
        nodes
    }

    fn select_cells(&self, select: &dyn Fn([usize; 3]) -> Option<usize>) -> Vec<Option<usize>> {
        let cells = self.cells();
        let segs: Vec<Vec<usize>> = self.axes.iter().map(|a| a.points().1).collect();
        let mut active = vec![None; cells.iter().product()];
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                for k in 0..cells[2] {
                    active[(j * cells[0] + i) * cells[2] + k] =
                        select([segs[0][i], segs[1][j], segs[2][k]]);
                }
            }
        }
        active
    }

    /// Number of nodes the grid would have, without building it.
    pub fn count_nodes(
        &self,
        kind: ElementKind,
        select: &dyn Fn([usize; 3]) -> Option<usize>,
    ) -> usize {
        let quadratic = matches!(kind, ElementKind::Hex20 | ElementKind::Hex20R);
        let order = if quadratic { 2 } else { 1 };
        let lattice = self.lattice(order);
        let cells = self.cells();
        let active = self.select_cells(select);
        let mut used = vec![false; lattice.len()];
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                for k in 0..cells[2] {
                    if active[(j * cells[0] + i) * cells[2] + k].is_some() {
                        for p in Self::cell_nodes([i, j, k], order, quadratic) {
                            used[lattice.index(p)] = true;
                        }
                    }
                }
            }
        }
        used.iter().filter(|&&u| u).count()
    }

    /// Meshes the cells `select` assigns to a block (an index into `blocks`: name, material).
    pub fn mesh(
        &self,
        kind: ElementKind,
        blocks: &[(&str, Material)],
        select: &dyn Fn([usize; 3]) -> Option<usize>,
    ) -> GridMesh {
        assert!(
            matches!(
                kind,
                ElementKind::Hex8 | ElementKind::Hex8I | ElementKind::Hex20 | ElementKind::Hex20R
            ),
            "the brake generator makes hexahedra"
        );
        let quadratic = matches!(kind, ElementKind::Hex20 | ElementKind::Hex20R);
        let order = if quadratic { 2 } else { 1 };
        let lattice = self.lattice(order);
        let cells = self.cells();
        let active = self.select_cells(select);
        let (points, segments): (Vec<Vec<f64>>, Vec<Vec<usize>>) =
            self.axes.iter().map(Axis::points).unzip();
        // Parameter value at a lattice index (midpoints at odd indices when quadratic).
        let value = |d: usize, l: usize| -> f64 {
            let p = &points[d];
            if l.is_multiple_of(order) {
                p[l / order]
            } else {
                0.5 * (p[l / order] + p[l / order + 1])
            }
        };

        let mut node_of = vec![usize::MAX; lattice.len()];
        let mut per_block: Vec<Vec<([usize; 3], Vec<usize>)>> = vec![Vec::new(); blocks.len()];
        let mut lattice_points: Vec<[usize; 3]> = Vec::new();
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                for k in 0..cells[2] {
                    let Some(b) = active[(j * cells[0] + i) * cells[2] + k] else {
                        continue;
                    };
                    let mut conn = Vec::with_capacity(kind.nodes());
                    for p in Self::cell_nodes([i, j, k], order, quadratic) {
                        let li = lattice.index(p);
                        if node_of[li] == usize::MAX {
                            node_of[li] = lattice_points.len();
                            lattice_points.push(lattice.wrap(p));
                        }
                        conn.push(node_of[li]);
                    }
                    per_block[b].push(([i, j, k], conn));
                }
            }
        }
        let coords = lattice_points
            .iter()
            .map(|p| {
                self.frame
                    .map([value(0, p[0]), value(1, p[1]), value(2, p[2])])
            })
            .collect();
        let mut mesh = Mesh {
            coords,
            ..Default::default()
        };
        let mut fine_cell = Vec::new();
        for (b, (name, material)) in blocks.iter().enumerate() {
            let elements = std::mem::take(&mut per_block[b]);
            if elements.is_empty() {
                continue;
            }
            mesh.materials.push(material.clone());
            let mut connectivity = Vec::with_capacity(elements.len() * kind.nodes());
            for (cell, conn) in elements {
                fine_cell.push(cell);
                connectivity.extend(conn);
            }
            mesh.blocks.push(ElementBlock {
                name: name.to_string(),
                kind,
                material: mesh.materials.len() - 1,
                connectivity,
                orientation: None,
            });
        }
        let coarse_cell = fine_cell
            .iter()
            .map(|c| [segments[0][c[0]], segments[1][c[1]], segments[2][c[2]]])
            .collect();
        GridMesh {
            mesh,
            fine_cell,
            coarse_cell,
            active,
            cells,
            periodic: [
                self.axes[0].periodic,
                self.axes[1].periodic,
                self.axes[2].periodic,
            ],
        }
    }
}

impl GridMesh {
    fn neighbour_active(&self, cell: [usize; 3], face: CellFace) -> bool {
        let d = face.axis;
        let n = self.cells[d];
        let c = cell[d];
        let next = if face.positive {
            if c + 1 < n {
                Some(c + 1)
            } else if self.periodic[d] {
                Some(0)
            } else {
                None
            }
        } else if c > 0 {
            Some(c - 1)
        } else if self.periodic[d] {
            Some(n - 1)
        } else {
            None
        };
        match next {
            None => false,
            Some(m) => {
                let mut q = cell;
                q[d] = m;
                self.active[(q[1] * self.cells[0] + q[0]) * self.cells[2] + q[2]].is_some()
            }
        }
    }

    /// Boundary faces (no active cell beyond them) of the elements whose coarse cell and face
    /// direction satisfy `keep`: (element, Abaqus face number).
    pub fn boundary_faces(&self, keep: impl Fn([usize; 3], CellFace) -> bool) -> Vec<(usize, u8)> {
        let mut out = Vec::new();
        for (e, (fine, coarse)) in self.fine_cell.iter().zip(&self.coarse_cell).enumerate() {
            for face in CellFace::ALL {
                if keep(*coarse, face) && !self.neighbour_active(*fine, face) {
                    out.push((e, face.abaqus()));
                }
            }
        }
        out
    }

    /// Adds a surface of boundary faces; panics when it is empty (a generator bug).
    pub fn add_surface(&mut self, name: &str, keep: impl Fn([usize; 3], CellFace) -> bool) {
        let faces = self.boundary_faces(keep);
        assert!(
            !faces.is_empty(),
            "surface '{name}' of the generator is empty"
        );
        self.mesh.surfaces.insert(name.into(), faces);
    }

    /// Adds a node set made of the nodes of a surface already added.
    pub fn add_node_set_of_surface(&mut self, set: &str, surface: &str) {
        let nodes = self
            .mesh
            .surface_nodes(surface)
            .expect("surface added before its node set");
        self.mesh.node_sets.insert(set.into(), nodes);
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn steel() -> Material {
        Material::isotropic("steel", 210e9, 0.3, 7850.0)
    }

    #[test]
    fn graded_points_end_on_the_breaks_and_grow_by_the_ratio() {
        let axis = Axis::new(&[0.0, 1.0, 3.0], &[2, 6]).graded(1, Grading::Ends(4.0));
        let (p, seg) = axis.points();
        assert_eq!(p.len(), 9);
        assert_eq!(p[2], 1.0);
        assert_eq!(p[8], 3.0);
        assert_eq!(seg, vec![0, 0, 1, 1, 1, 1, 1, 1]);
        let sizes: Vec<f64> = p.windows(2).map(|w| w[1] - w[0]).collect();
        assert!((sizes[4] / sizes[2] - 4.0).abs() < 1e-12, "{sizes:?}");
        assert!((sizes[2] - sizes[7]).abs() < 1e-12);
    }

    #[test]
    fn masked_cells_share_nodes_and_count_matches() {
        // An L of three unit cubes: 3 x 8 corners minus 2 x 4 shared = 16 nodes.
        let grid = Grid {
            axes: [
                Axis::new(&[0.0, 1.0, 2.0], &[1, 1]),
                Axis::new(&[0.0, 1.0, 2.0], &[1, 1]),
                Axis::new(&[0.0, 1.0], &[1]),
            ],
            frame: Frame::Cartesian,
        };
        let select = |c: [usize; 3]| (c[0] == 0 || c[1] == 0).then_some(0);
        for (kind, nodes) in [(ElementKind::Hex8, 16), (ElementKind::Hex20, 16 + 28)] {
            let g = grid.mesh(kind, &[("l", steel())], &select);
            assert_eq!(g.mesh.node_count(), nodes, "{kind:?}");
            assert_eq!(grid.count_nodes(kind, &select), nodes);
            assert_eq!(g.mesh.element_count(), 3);
        }
        let mut g = grid.mesh(ElementKind::Hex8, &[("l", steel())], &select);
        // The x = 2 boundary is one face; the inner corner faces (x = 1, y in [1, 2]) another.
        g.add_surface("xmax", |_, f| {
            f == CellFace {
                axis: 0,
                positive: true,
            }
        });
        assert_eq!(g.mesh.surfaces["xmax"].len(), 2);
        let nodes = g.mesh.surface_nodes("xmax").unwrap();
        assert_eq!(nodes.len(), 8);
    }

    #[test]
    fn a_periodic_axis_closes_the_ring() {
        let grid = Grid {
            axes: [
                Axis::new(&[1.0, 2.0], &[1]),
                Axis::new(&[0.0, std::f64::consts::TAU], &[8]).periodic(),
                Axis::new(&[0.0, 0.1], &[1]),
            ],
            frame: Frame::Cylindrical { center: [0.0, 0.0] },
        };
        let g = grid.mesh(ElementKind::Hex8, &[("ring", steel())], &|_| Some(0));
        assert_eq!(g.mesh.node_count(), 2 * 8 * 2);
        // No boundary faces across the seam.
        assert!(g.boundary_faces(|_, f| f.axis == 1).is_empty());
    }
}
