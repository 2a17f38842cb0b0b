//! Pairing, done once: contact points at the Gauss points of the master faces, projected on
//! the slave surface by closest-point projection (bounding-box tree, Gauss-Newton in the
//! face's parametric coordinates, a sampling fallback). Points farther than the search
//! distance, or outside every slave face, miss and are dropped with a count.

use super::surface::{cross, dot, norm, normalize, scale, sub, Face};
use super::ContactError;
use super::ResolvedInterface;
use crate::mesh::Mesh;

/// A contact point: where it is, what it couples, and its local frame.
#[derive(Debug, Clone)]
pub struct ContactPoint {
    pub interface: usize,
    /// The master (pad) point.
    pub position: [f64; 3],
    /// Gauss weight x surface Jacobian (m^2).
    pub weight: f64,
    /// Slave outward normal (from the slave towards the master).
    pub normal: [f64; 3],
    /// Tangent of friction or first stick direction.
    pub tangent: [f64; 3],
    /// Second stick direction (zero where the interface slides freely along the axis).
    pub tangent2: [f64; 3],
    /// Distance from the disc axis (m).
    pub radius: f64,
    /// Gap in the undeformed configuration (m).
    pub initial_gap: f64,
    pub master_nodes: Vec<usize>,
    pub master_shape: Vec<f64>,
    pub slave_nodes: Vec<usize>,
    pub slave_shape: Vec<f64>,
    /// d(N)/d(theta) of the slave shape functions (rad^-1), for the convection term.
    pub slave_dtheta: Vec<f64>,
    /// The master face (element, face), the point's parametric position on it, and the slave face.
    pub master_face: (usize, u8),
    pub master_xi: [f64; 2],
    pub slave_face: (usize, u8),
}

/// The disc's rotation axis (unit) through `center`.
#[derive(Debug, Clone, Copy)]
pub struct Axis {
    pub direction: [f64; 3],
    pub center: [f64; 3],
}

impl Axis {
    /// (radius, e_theta) at x.
    pub fn polar(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        let d = sub(x, self.center);
        let radial = sub(d, scale(self.direction, dot(d, self.direction)));
        let r = norm(radial);
        if r < 1e-300 {
            return (0.0, [0.0; 3]);
        }
        (r, cross(self.direction, scale(radial, 1.0 / r)))
    }
}

/// Points of all interfaces, and how many master points missed per interface.
#[derive(Debug, Clone)]
pub struct Pairing {
    pub points: Vec<ContactPoint>,
    pub misses: Vec<usize>,
    pub candidates: Vec<usize>,
}

/// Pairs every interface. `gauss` is the points per direction of the master-face rule;
/// `search_distance` the largest |gap| accepted.
pub fn pair(
    mesh: &Mesh,
    interfaces: &[ResolvedInterface],
    axis: Axis,
    gauss: usize,
    search_distance: f64,
) -> Result<Pairing, ContactError> {
    let mut out = Pairing {
        points: Vec::new(),
        misses: vec![0; interfaces.len()],
        candidates: vec![0; interfaces.len()],
    };
    for (i, itf) in interfaces.iter().enumerate() {
        let surface = |side: &'static str, name: &str| {
            mesh.surface(name).map_err(|source| ContactError::Surface {
                interface: itf.name.clone(),
                side,
                source,
            })
        };
        let (master, slave) = (
            surface("master", &itf.master)?,
            surface("slave", &itf.slave)?,
        );
        if master.is_empty() || slave.is_empty() {
            let empty = if master.is_empty() {
                &itf.master
            } else {
                &itf.slave
            };
            return Err(ContactError::EmptySurface {
                interface: itf.name.clone(),
                surface: empty.clone(),
            });
        }
        let slave_faces: Vec<Face> = slave.iter().map(|&(e, f)| Face::new(mesh, e, f)).collect();
        let tree = BoxTree::new(&slave_faces, search_distance);
        let sliding = itf.friction.is_sliding();
        let mut candidates = Vec::new();
        for &(e, f) in master {
            let face = Face::new(mesh, e, f);
            for (xi, w) in face.shape.rule(gauss) {
                let p = face.at(xi);
                let (_, jac) = p.normal();
                out.candidates[i] += 1;
                tree.query(p.x, &mut candidates);
                let best = candidates
                    .iter()
                    .filter_map(|&s| project(&slave_faces[s], p.x).map(|r| (s, r)))
                    .filter(|(_, r)| r.distance <= search_distance)
                    .min_by(|a, b| a.1.distance.total_cmp(&b.1.distance).then(a.0.cmp(&b.0)));
                let Some((s, proj)) = best else {
                    out.misses[i] += 1;
                    continue;
                };
                let sface = &slave_faces[s];
                let sp = sface.at(proj.xi);
                let (n, _) = sp.normal();
                let (radius, e_theta) = axis.polar(sp.x);
                let along_axis = dot(n, axis.direction).abs() > 0.5;
                let project_tangent = |v: [f64; 3]| {
                    let t = sub(v, scale(n, dot(v, n)));
                    if norm(t) < 1e-12 {
                        [0.0; 3]
                    } else {
                        normalize(t)
                    }
                };
                let (tangent, tangent2) = if sliding || along_axis {
                    let t1 = project_tangent(e_theta);
                    let t2 = if sliding { [0.0; 3] } else { cross(n, t1) };
                    (t1, t2)
                } else {
                    // A joint whose normal is transverse to the axis (pad abutments) guides
                    // the pad: it holds the direction normal to the axis, not along it.
                    (project_tangent(cross(axis.direction, n)), [0.0; 3])
                };
                let v_theta = scale(e_theta, radius);
                let slave_dtheta = sface.directional_derivative(&sp, v_theta);
                out.points.push(ContactPoint {
                    interface: i,
                    position: p.x,
                    weight: w * jac,
                    normal: n,
                    tangent,
                    tangent2,
                    radius,
                    initial_gap: dot(sub(p.x, sp.x), n),
                    master_nodes: face.nodes.clone(),
                    master_shape: p.n.clone(),
                    slave_nodes: sface.nodes.clone(),
                    slave_shape: sp.n.clone(),
                    slave_dtheta,
                    master_face: (e, f),
                    master_xi: xi,
                    slave_face: (sface.element, sface.face),
                });
            }
        }
    }
    Ok(out)
}

/// A closest-point projection on one face.
#[derive(Debug, Clone, Copy)]
pub struct Projection {
    pub xi: [f64; 2],
    pub distance: f64,
}

/// Closest point of a face to x, if it lies inside the face (else None: a neighbour face
/// owns it). Gauss-Newton from the centre; if that does not converge inside, a 9 x 9 sample
/// of the face seeds a clamped iteration.
pub fn project(face: &Face, x: [f64; 3]) -> Option<Projection> {
    let size = {
        let (lo, hi) = face.bounds();
        norm(sub(hi, lo))
    };
    let tol = 1e-6;
    let newton = |start: [f64; 2], clamped: bool| -> Option<[f64; 2]> {
        let mut xi = start;
        for _ in 0..30 {
            let p = face.at(xi);
            let r = sub(p.x, x);
            let g11 = dot(p.dxi, p.dxi);
            let g12 = dot(p.dxi, p.deta);
            let g22 = dot(p.deta, p.deta);
            let (b1, b2) = (-dot(p.dxi, r), -dot(p.deta, r));
            let det = g11 * g22 - g12 * g12;
            if det.abs() < 1e-300 {
                return None;
            }
            let d = [(g22 * b1 - g12 * b2) / det, (g11 * b2 - g12 * b1) / det];
            let mut next = [xi[0] + d[0], xi[1] + d[1]];
            if clamped {
                next = face.shape.clamp(next);
            } else if next[0].abs() > 4.0 || next[1].abs() > 4.0 {
                return None;
            }
            let step = ((next[0] - xi[0]).powi(2) + (next[1] - xi[1]).powi(2)).sqrt();
            xi = next;
            if step < 1e-13 {
                return Some(xi);
            }
        }
        // Converged to round-off if the step stagnated at a tiny size.
        let p = face.at(xi);
        let r = sub(p.x, x);
        let grad = [dot(p.dxi, r), dot(p.deta, r)];
        ((grad[0].abs() + grad[1].abs()) < 1e-10 * size * size).then_some(xi)
    };
    let accept = |xi: [f64; 2]| {
        face.shape.contains(xi, tol).then(|| {
            let xi = face.shape.clamp(xi);
            Projection {
                xi,
                distance: norm(sub(face.at(xi).x, x)),
            }
        })
    };
    if let Some(xi) = newton(face.shape.centre(), false) {
        return accept(xi);
    }
    // Fallback: best sample, then a clamped iteration; accepted only if it ends inside.
    let mut best = (f64::INFINITY, face.shape.centre());
    for j in 0..9 {
        for i in 0..9 {
            let xi = if face.shape.is_triangle() {
                let (a, b) = (i as f64 / 8.0, j as f64 / 8.0);
                if a + b > 1.0 {
                    continue;
                }
                [a, b]
            } else {
                [-1.0 + i as f64 / 4.0, -1.0 + j as f64 / 4.0]
            };
            let d = norm(sub(face.at(xi).x, x));
            if d < best.0 {
                best = (d, xi);
            }
        }
    }
    let xi = newton(best.1, true)?;
    let p = face.at(xi);
    let r = sub(p.x, x);
    // Inside the face (not stopped at its boundary): the residual is normal to the face.
    let (n, _) = p.normal();
    let tangential = norm(sub(r, scale(n, dot(r, n))));
    (tangential < 1e-8 * size).then(|| accept(xi)).flatten()
}

/// Axis-aligned bounding-box tree over faces (boxes inflated by the search distance).
struct BoxTree {
    nodes: Vec<BoxNode>,
    order: Vec<usize>,
}

struct BoxNode {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Children, or a leaf range in `order`.
    kind: NodeKind,
}

enum NodeKind {
    Inner(usize, usize),
    Leaf(usize, usize),
}

impl BoxTree {
    fn new(faces: &[Face], inflate: f64) -> BoxTree {
        let boxes: Vec<([f64; 3], [f64; 3])> = faces
            .iter()
            .map(|f| {
                let (mut lo, mut hi) = f.bounds();
                for d in 0..3 {
                    lo[d] -= inflate;
                    hi[d] += inflate;
                }
                (lo, hi)
            })
            .collect();
        let mut tree = BoxTree {
            nodes: Vec::new(),
            order: (0..faces.len()).collect(),
        };
        tree.build(&boxes, 0, faces.len());
        tree
    }

    fn build(&mut self, boxes: &[([f64; 3], [f64; 3])], start: usize, end: usize) -> usize {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &i in &self.order[start..end] {
            for d in 0..3 {
                lo[d] = lo[d].min(boxes[i].0[d]);
                hi[d] = hi[d].max(boxes[i].1[d]);
            }
        }
        let id = self.nodes.len();
        self.nodes.push(BoxNode {
            lo,
            hi,
            kind: NodeKind::Leaf(start, end),
        });
        if end - start > 4 {
            let axis = (0..3)
                .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
                .unwrap();
            let centre = |i: usize| boxes[i].0[axis] + boxes[i].1[axis];
            self.order[start..end]
                .sort_by(|&a, &b| centre(a).total_cmp(&centre(b)).then(a.cmp(&b)));
            let mid = (start + end) / 2;
            let left = self.build(boxes, start, mid);
            let right = self.build(boxes, mid, end);
            self.nodes[id].kind = NodeKind::Inner(left, right);
        }
        id
    }

    /// Faces whose box contains x.
    fn query(&self, x: [f64; 3], out: &mut Vec<usize>) {
        out.clear();
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if (0..3).any(|d| x[d] < node.lo[d] || x[d] > node.hi[d]) {
                continue;
            }
            match node.kind {
                NodeKind::Inner(a, b) => {
                    stack.push(a);
                    stack.push(b);
                }
                NodeKind::Leaf(s, e) => out.extend_from_slice(&self.order[s..e]),
            }
        }
        out.sort_unstable();
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;
    use crate::contact::law::{FrictionLaw, NormalLaw};
    use crate::mesh::material::Material;
    use crate::mesh::structured::block;
    use crate::mesh::ElementKind;

    fn faces_at(mesh: &Mesh, elements: std::ops::Range<usize>, z0: f64) -> Vec<(usize, u8)> {
        elements
            .flat_map(|e| (1..=6u8).map(move |f| (e, f)))
            .filter(|&(e, f)| {
                mesh.face_nodes(e, f)
                    .iter()
                    .all(|&n| (mesh.coords[n][2] - z0).abs() < 1e-12)
            })
            .collect()
    }

    /// A master surface overhanging its slave: points beyond the slave's edge miss and are
    /// counted; the others project exactly (gap = the offset, weights sum to the paired area).
    #[test]
    fn overhanging_points_miss_and_the_rest_project_exactly() {
        let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let mut mesh = block([1.0, 1.0, 0.5], [3, 3, 1], kind, steel.clone());
            let n_lower = mesh.element_count();
            // Upper block 1.5 wide in x, lifted by a 1e-4 gap: x in (1, 1.5] overhangs.
            let mut upper = block([1.5, 1.0, 0.5], [6, 4, 1], kind, steel.clone());
            for c in &mut upper.coords {
                c[2] += 0.5 + 1e-4;
            }
            upper.node_sets.clear();
            mesh.append(upper);
            let all = mesh.element_count();
            mesh.surfaces
                .insert("slave".into(), faces_at(&mesh, 0..n_lower, 0.5));
            mesh.surfaces
                .insert("master".into(), faces_at(&mesh, n_lower..all, 0.5 + 1e-4));
            let itf = ResolvedInterface {
                name: "test".into(),
                master: "master".into(),
                slave: "slave".into(),
                normal: NormalLaw::Linear { stiffness: 1.0 },
                friction: FrictionLaw::None,
            };
            let axis = Axis {
                direction: [0.0, 0.0, 1.0],
                center: [0.0; 3],
            };
            let p = pair(&mesh, &[itf], axis, 2, 1e-3).unwrap();
            // 6 x 4 master faces x 4 points; the 2 columns of faces beyond x = 1 miss.
            assert_eq!(p.candidates[0], 96, "{kind:?}");
            assert_eq!(p.misses[0], 32, "{kind:?}");
            let area: f64 = p.points.iter().map(|q| q.weight).sum();
            assert!((area - 1.0).abs() < 1e-12, "{kind:?}: paired area {area}");
            for q in &p.points {
                assert!((q.initial_gap - 1e-4).abs() < 1e-12, "{kind:?}");
                assert!((q.normal[2] - 1.0).abs() < 1e-12);
                let s: f64 = q.slave_shape.iter().sum();
                assert!((s - 1.0).abs() < 1e-12);
            }
        }
    }
}
