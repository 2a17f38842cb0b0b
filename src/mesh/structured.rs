//! Structured meshes of a parameter box [0,1]^3 mapped to physical space: blocks, annular
//! plates and discs. Quadratic elements get their mid-edge nodes in parameter space, so curved
//! boundaries (an annulus) are followed exactly at the nodes.

use std::collections::HashMap;

use super::{ElementBlock, Mesh};
use crate::mesh::element::{ElementKind, HEX_EDGES, TET_EDGES, WEDGE_EDGES};
use crate::mesh::material::Material;

/// Six tetrahedra of a hexahedron around its diagonal 0-6; conforming between translated
/// hexahedra (each face is cut along the same diagonal from both sides).
/// A hexahedral cell as two wedges, its bottom and top quadrilaterals split along the
/// diagonal from corner 0 (both counter-clockwise seen from the top, as the cell's).
const HEX_TO_WEDGES: [[usize; 6]; 2] = [[0, 1, 2, 4, 5, 6], [0, 2, 3, 4, 6, 7]];

const HEX_TO_TETS: [[usize; 4]; 6] = [
    [0, 1, 2, 6],
    [0, 2, 3, 6],
    [0, 3, 7, 6],
    [0, 7, 4, 6],
    [0, 4, 5, 6],
    [0, 5, 1, 6],
];

/// A structured mesh of `n = [nu, nv, nw]` cells over the parameter box; `periodic_v` closes the
/// v direction (an annulus); `map` takes parameter coordinates to physical ones. Node sets
/// `u0, u1, v0, v1, w0, w1` hold the nodes on the six faces of the parameter box (v0/v1 absent
/// when periodic), and `all`.
pub fn structured(
    n: [usize; 3],
    periodic_v: bool,
    kind: ElementKind,
    material: Material,
    map: impl Fn([f64; 3]) -> [f64; 3],
) -> Mesh {
    let [nu, nv, nw] = n;
    assert!(
        nu > 0 && nv > 0 && nw > 0,
        "structured mesh needs at least one cell per direction"
    );
    let nv_nodes = if periodic_v { nv } else { nv + 1 };
    let id = |i: usize, j: usize, k: usize| -> usize {
        let j = if periodic_v { j % nv } else { j };
        (k * nv_nodes + j) * (nu + 1) + i
    };
    let mut params: Vec<[f64; 3]> = Vec::with_capacity((nu + 1) * nv_nodes * (nw + 1));
    for k in 0..=nw {
        for j in 0..nv_nodes {
            for i in 0..=nu {
                params.push([
                    i as f64 / nu as f64,
                    j as f64 / nv as f64,
                    k as f64 / nw as f64,
                ]);
            }
        }
    }
    // Linear cells with their element-local (unwrapped) parameter coordinates.
    let mut cells: Vec<([usize; 8], [[f64; 3]; 8])> = Vec::with_capacity(nu * nv * nw);
    for k in 0..nw {
        for j in 0..nv {
            for i in 0..nu {
                let c = [
                    (i, j, k),
                    (i + 1, j, k),
                    (i + 1, j + 1, k),
                    (i, j + 1, k),
                    (i, j, k + 1),
                    (i + 1, j, k + 1),
                    (i + 1, j + 1, k + 1),
                    (i, j + 1, k + 1),
                ];
                let nodes = c.map(|(i, j, k)| id(i, j, k));
                let local = c.map(|(i, j, k)| {
                    [
                        i as f64 / nu as f64,
                        j as f64 / nv as f64,
                        k as f64 / nw as f64,
                    ]
                });
                cells.push((nodes, local));
            }
        }
    }

    let mut connectivity = Vec::with_capacity(cells.len() * kind.nodes());
    let mut midside: HashMap<(usize, usize), usize> = HashMap::new();
    let mut add_mid =
        |a: usize, b: usize, pa: [f64; 3], pb: [f64; 3], params: &mut Vec<[f64; 3]>| {
            *midside.entry((a.min(b), a.max(b))).or_insert_with(|| {
                params.push([
                    0.5 * (pa[0] + pb[0]),
                    0.5 * (pa[1] + pb[1]),
                    0.5 * (pa[2] + pb[2]),
                ]);
                params.len() - 1
            })
        };
    for (nodes, local) in &cells {
        match kind {
            ElementKind::Hex8 | ElementKind::Hex8I => connectivity.extend_from_slice(nodes),
            ElementKind::Hex20 | ElementKind::Hex20R => {
                connectivity.extend_from_slice(nodes);
                for [a, b] in HEX_EDGES {
                    let m = add_mid(nodes[a], nodes[b], local[a], local[b], &mut params);
                    connectivity.push(m);
                }
            }
            ElementKind::Tet4 => {
                for t in HEX_TO_TETS {
                    connectivity.extend(t.map(|c| nodes[c]));
                }
            }
            ElementKind::Wedge6 | ElementKind::Wedge15 => {
                for w in HEX_TO_WEDGES {
                    let wn = w.map(|c| nodes[c]);
                    let wp = w.map(|c| local[c]);
                    connectivity.extend_from_slice(&wn);
                    if kind == ElementKind::Wedge15 {
                        for [a, b] in WEDGE_EDGES {
                            let m = add_mid(wn[a], wn[b], wp[a], wp[b], &mut params);
                            connectivity.push(m);
                        }
                    }
                }
            }
            ElementKind::Tet10 => {
                for t in HEX_TO_TETS {
                    let tn = t.map(|c| nodes[c]);
                    let tp = t.map(|c| local[c]);
                    connectivity.extend_from_slice(&tn);
                    for [a, b] in TET_EDGES {
                        let m = add_mid(tn[a], tn[b], tp[a], tp[b], &mut params);
                        connectivity.push(m);
                    }
                }
            }
        }
    }
    let coords: Vec<[f64; 3]> = params.iter().map(|p| map(*p)).collect();

    let mut mesh = Mesh {
        coords,
        blocks: vec![ElementBlock {
            name: "solid".into(),
            kind,
            material: 0,
            connectivity,
            orientation: None,
        }],
        materials: vec![material],
        node_sets: Default::default(),
        surfaces: Default::default(),
        orientations: Vec::new(),
        point_blocks: Vec::new(),
        constraints: Default::default(),
    };
    if matches!(kind, ElementKind::Tet10 | ElementKind::Tet4) {
        orient_tets_positively(&mut mesh);
    }
    add_face_sets(&mut mesh, &params, periodic_v);
    mesh
}

/// The node sets of the parameter box's faces (u0 .. w1, v0/v1 absent when periodic) from the
/// nodes' parameter coordinates, and `all`.
fn add_face_sets(mesh: &mut Mesh, params: &[[f64; 3]], periodic_v: bool) {
    let on = |d: usize, v: f64| -> Vec<usize> {
        params
            .iter()
            .enumerate()
            .filter(|(_, p)| (p[d] - v).abs() < 1e-12)
            .map(|(i, _)| i)
            .collect()
    };
    for (name, d, v) in [
        ("u0", 0, 0.0),
        ("u1", 0, 1.0),
        ("v0", 1, 0.0),
        ("v1", 1, 1.0),
        ("w0", 2, 0.0),
        ("w1", 2, 1.0),
    ] {
        if periodic_v && d == 1 {
            continue;
        }
        mesh.node_sets.insert(name.into(), on(d, v));
    }
    mesh.node_sets
        .insert("all".into(), (0..mesh.node_count()).collect());
}

/// Swaps nodes 1 and 2 (and the matching mid-edge nodes) of every negatively oriented tet.
fn orient_tets_positively(mesh: &mut Mesh) {
    let coords = &mesh.coords;
    for block in &mut mesh.blocks {
        let quadratic = block.kind == ElementKind::Tet10;
        for t in block.connectivity.chunks_mut(block.kind.nodes()) {
            let p = |i: usize| coords[t[i]];
            let (a, b, c, d) = (p(0), p(1), p(2), p(3));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
            let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                + u[2] * (v[0] * w[1] - v[1] * w[0]);
            if det < 0.0 {
                // Corners 1<->2; edges (0,1)<->(0,2)=4<->6, (1,3)<->(2,3)=8<->9, (1,2) stays.
                t.swap(1, 2);
                if quadratic {
                    t.swap(4, 6);
                    t.swap(8, 9);
                }
            }
        }
    }
}

/// A box [0,lx] x [0,ly] x [0,lz] with n cells per direction.
pub fn block(size: [f64; 3], n: [usize; 3], kind: ElementKind, material: Material) -> Mesh {
    structured(n, false, kind, material, |p| {
        [p[0] * size[0], p[1] * size[1], p[2] * size[2]]
    })
}

/// An annular plate of inner radius `r_in`, outer radius `r_out` and thickness `t`, its axis
/// along z: `nr` cells radially, `ntheta` around, `nz` through the thickness. Node sets:
/// `inner` (r = r_in), `outer` (r = r_out), `bottom` (z = 0), `top` (z = t).
pub fn annulus(
    r_in: f64,
    r_out: f64,
    thickness: f64,
    n: [usize; 3],
    kind: ElementKind,
    material: Material,
) -> Mesh {
    let mut mesh = structured(n, true, kind, material, |p| {
        let r = r_in + p[0] * (r_out - r_in);
        let theta = 2.0 * std::f64::consts::PI * p[1];
        [r * theta.cos(), r * theta.sin(), p[2] * thickness]
    });
    for (from, to) in [
        ("u0", "inner"),
        ("u1", "outer"),
        ("w0", "bottom"),
        ("w1", "top"),
    ] {
        let set = mesh.node_sets.remove(from).unwrap_or_default();
        mesh.node_sets.insert(to.into(), set);
    }
    mesh
}
