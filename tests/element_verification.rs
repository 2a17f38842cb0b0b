//! Element-level verification (DESIGN.md §6, rung 1), pure Rust (no MPI, no PETSc):
//!
//! - Irons' patch test (B. M. Irons, A. Razzaque, "Experience with the patch test for
//!   convergence of finite elements", 1972; the distorted-mesh form of MacNeal & Harder,
//!   "A proposed standard set of problems to test finite element accuracy", FEAD 1, 1985):
//!   a linear displacement field imposed on the boundary of a patch of distorted elements is
//!   reproduced exactly at the interior nodes, for every element type.
//! - Rigid-body modes: the free element stiffness has exactly six zero eigenvalues.
//! - Symmetry of element stiffness and mass; mass sums to rho x volume.

use squeal::dense::{cholesky, cholesky_solve, symmetric_eigenvalues};
use squeal::fem::assembly::{assemble, DenseSink};
use squeal::fem::dofmap::DofMap;
use squeal::fem::element::ElementKernel;
use squeal::measure::nan_max;
use squeal::mesh::element::{ElementKind, HEX_EDGES, TET_EDGES};
use squeal::mesh::material::Material;
use squeal::mesh::structured::block;
use squeal::mesh::Mesh;

#[path = "support/materials.rs"]
mod materials;
use materials::pad_lining;

const ALL: [ElementKind; 5] = [
    ElementKind::Hex8,
    ElementKind::Hex8I,
    ElementKind::Hex20,
    ElementKind::Tet10,
    ElementKind::Tet4,
];

fn steel() -> Material {
    Material::isotropic("steel", 2.1e11, 0.3, 7850.0)
}

/// Deterministic pseudo-random numbers in [-1, 1] (no dependency, reproducible).
fn noise(i: usize, salt: u64) -> f64 {
    let mut x = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt;
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    x ^= x >> 33;
    (x as f64 / u64::MAX as f64) * 2.0 - 1.0
}

/// A 3x3x3 patch of the unit cube with interior vertices moved randomly by up to 30% of a
/// cell; mid-edge nodes at the middle of their (straight) edges.
fn distorted_patch(kind: ElementKind, material: Material) -> Mesh {
    let n = 3;
    let mut mesh = block([1.0; 3], [n, n, n], kind, material);
    let h = 1.0 / n as f64;
    let on_grid = |v: f64| ((v / h).round() * h - v).abs() < 1e-12;
    let interior = |v: f64| v > 1e-12 && v < 1.0 - 1e-12;
    for (i, x) in mesh.coords.iter_mut().enumerate() {
        if x.iter().all(|&v| on_grid(v) && interior(v)) {
            for (d, v) in x.iter_mut().enumerate() {
                *v += 0.3 * h * noise(3 * i + d, 7);
            }
        }
    }
    let edges: &[[usize; 2]] = match kind {
        ElementKind::Hex20 => &HEX_EDGES,
        ElementKind::Tet10 => &TET_EDGES,
        _ => &[],
    };
    let corners = if matches!(kind, ElementKind::Tet10 | ElementKind::Tet4) {
        4
    } else {
        8
    };
    let conn = mesh.blocks[0].connectivity.clone();
    for el in conn.chunks(kind.nodes()) {
        for (k, [a, b]) in edges.iter().enumerate() {
            let (pa, pb) = (mesh.coords[el[*a]], mesh.coords[el[*b]]);
            mesh.coords[el[corners + k]] = [0, 1, 2].map(|d| 0.5 * (pa[d] + pb[d]));
        }
    }
    mesh
}

fn linear_field(x: [f64; 3]) -> [f64; 3] {
    [
        1e-3 * (1.0 + 2.0 * x[0] - 0.5 * x[1] + 0.7 * x[2]),
        1e-3 * (-0.3 + 0.4 * x[0] + 1.1 * x[1] - 0.9 * x[2]),
        1e-3 * (0.2 - 0.6 * x[0] + 0.3 * x[1] + 1.5 * x[2]),
    ]
}

fn run_patch_test(kind: ElementKind, material: Material) -> f64 {
    let mesh = distorted_patch(kind, material);
    let nn = mesh.node_count();
    let dofs = DofMap::new(&vec![[false; 3]; nn], 1, 0);
    let n = 3 * nn;
    let (mut k, mut m) = (DenseSink::new(n), DenseSink::new(n));
    assemble(&mesh, &dofs, &mut k, &mut m).unwrap();
    let on_boundary = |x: [f64; 3]| {
        x.iter()
            .any(|&v| v.abs() < 1e-12 || (v - 1.0).abs() < 1e-12)
    };
    let boundary: Vec<bool> = mesh.coords.iter().map(|&x| on_boundary(x)).collect();
    let interior: Vec<usize> = (0..nn).filter(|&i| !boundary[i]).collect();
    assert!(!interior.is_empty());
    let ni = 3 * interior.len();
    let mut u = vec![0.0; n];
    for (i, x) in mesh.coords.iter().enumerate() {
        if boundary[i] {
            u[3 * i..3 * i + 3].copy_from_slice(&linear_field(*x));
        }
    }
    let idx: Vec<usize> = interior
        .iter()
        .flat_map(|&i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mut kii = vec![0.0; ni * ni];
    let mut rhs = vec![0.0; ni];
    for (r, &gr) in idx.iter().enumerate() {
        for (c, &gc) in idx.iter().enumerate() {
            kii[r * ni + c] = k.values[gr * n + gc];
        }
        rhs[r] = -(0..n).map(|gc| k.values[gr * n + gc] * u[gc]).sum::<f64>();
    }
    cholesky(&mut kii, ni).expect("interior stiffness is positive definite");
    cholesky_solve(&kii, ni, &mut rhs);
    let mut max_err: f64 = 0.0;
    for (r, &gr) in idx.iter().enumerate() {
        let node = gr / 3;
        let exact = linear_field(mesh.coords[node])[gr % 3];
        max_err = nan_max(max_err, (rhs[r] - exact).abs() / 1e-3);
    }
    max_err
}

#[test]
fn irons_patch_test_distorted_mesh_every_element_type() {
    for kind in ALL {
        for material in [steel(), pad_lining()] {
            let name = material.name.clone();
            let err = run_patch_test(kind, material);
            assert!(err < 1e-9, "{kind:?} ({name}): patch test error {err:e}");
        }
    }
}

/// One element of each type, sheared and stretched (non-affine for hexahedra).
fn distorted_element(kind: ElementKind) -> Vec<[f64; 3]> {
    let reference = kind.reference_nodes();
    let corners = if matches!(kind, ElementKind::Tet10 | ElementKind::Tet4) {
        4
    } else {
        8
    };
    let mut x: Vec<[f64; 3]> = reference
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let q = [
                0.9 * p[0] + 0.2 * p[1] + 0.1 * p[2],
                0.1 * p[0] + 1.3 * p[1] - 0.1 * p[2],
                0.05 * p[0] + 0.1 * p[1] + 0.7 * p[2],
            ];
            if i < corners {
                [0, 1, 2].map(|d| q[d] + 0.08 * noise(3 * i + d, 11))
            } else {
                q
            }
        })
        .collect();
    let edges: &[[usize; 2]] = match kind {
        ElementKind::Hex20 => &HEX_EDGES,
        ElementKind::Tet10 => &TET_EDGES,
        _ => &[],
    };
    for (k, [a, b]) in edges.iter().enumerate() {
        x[corners + k] = [0, 1, 2].map(|d| 0.5 * (x[*a][d] + x[*b][d]));
    }
    x
}

#[test]
fn six_rigid_body_modes_every_element_type() {
    for kind in ALL {
        let mut kernel = ElementKernel::new(kind, &steel());
        let n = kernel.order();
        let mut ke = vec![0.0; n * n];
        kernel
            .stiffness(0, &distorted_element(kind), &mut ke)
            .unwrap();
        let ev = symmetric_eigenvalues(&ke, n);
        let max = ev.last().unwrap().abs();
        let zeros = ev.iter().filter(|v| v.abs() < 1e-10 * max).count();
        assert_eq!(zeros, 6, "{kind:?}: {:?}", &ev[..8]);
        assert!(
            ev[6] > 1e-6 * max,
            "{kind:?}: 7th eigenvalue {} (spurious mode)",
            ev[6]
        );
        assert!(
            ev[0] > -1e-10 * max,
            "{kind:?}: negative eigenvalue {}",
            ev[0]
        );
    }
}

#[test]
fn element_matrices_symmetric_and_mass_sums_to_rho_volume() {
    for kind in ALL {
        let mat = pad_lining();
        let mut kernel = ElementKernel::new(kind, &mat);
        let n = kernel.order();
        let x = distorted_element(kind);
        let (mut ke, mut me) = (vec![0.0; n * n], vec![0.0; n * n]);
        kernel.stiffness(0, &x, &mut ke).unwrap();
        kernel.mass(0, &x, &mut me).unwrap();
        let kmax = ke.iter().fold(0.0f64, |a, v| nan_max(a, v.abs()));
        for i in 0..n {
            for j in 0..n {
                assert!(
                    (ke[i * n + j] - ke[j * n + i]).abs() <= 1e-13 * kmax,
                    "{kind:?} K"
                );
                assert_eq!(me[i * n + j], me[j * n + i], "{kind:?} M");
            }
        }
        let total: f64 = (0..n / 3)
            .flat_map(|a| (0..n / 3).map(move |b| (a, b)))
            .map(|(a, b)| me[3 * a * n + 3 * b])
            .sum();
        let expected = mat.density * kernel.volume(&x);
        assert!(
            (total - expected).abs() < 1e-12 * expected,
            "{kind:?}: {total} vs {expected}"
        );
    }
}

#[test]
fn inverted_element_is_reported_by_number() {
    let mut kernel = ElementKernel::new(ElementKind::Hex8, &steel());
    let mut x = ElementKind::Hex8.reference_nodes();
    x.swap(0, 6);
    let mut ke = vec![0.0; 24 * 24];
    let err = kernel.stiffness(41, &x, &mut ke).unwrap_err();
    assert_eq!(err.element, 41);
    assert!(err.to_string().contains("element 41"));
}
