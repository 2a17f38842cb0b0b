//! Gmsh 4.1 import: physical groups to components, surfaces and node sets; node orders of
//! quadratic elements (Gmsh's edge order, from its reference element definitions
//! `edges_hexa` and `edges_tetra`: hex20 mid-edge nodes on edges 01 03 04 12 15 23 26 37 45
//! 47 56 67; tet10 on 01 12 20 30 32 31); malformed files give errors with line numbers.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;

use squeal::fem::element::ElementKernel;
use squeal::fem::quality;
use squeal::mesh::gmsh_msh::read;
use squeal::mesh::material::Material;
use squeal::mesh::structured::block;
use squeal::mesh::ElementKind;
use squeal::mesh::Mesh;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-msh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn steel() -> Material {
    Material::isotropic("steel", 210e9, 0.3, 7850.0)
}

fn materials(names: &[&str]) -> BTreeMap<String, Material> {
    names.iter().map(|n| (n.to_string(), steel())).collect()
}

/// Two unit cubes along x (physical volumes "disc" and "pad"), the x = 2 face as physical
/// surface "end" (a quad), the x = 0 face nodes as physical surface "hub".
const TWO_CUBES: &str = include_str!("data/seeds/two_cubes.msh");

#[test]
fn physical_groups_become_components_surfaces_and_node_sets() {
    let path = scratch("two.msh");
    std::fs::write(&path, TWO_CUBES).unwrap();
    let m = read(&path, &materials(&["disc", "pad"])).unwrap().mesh;
    let names: Vec<&str> = m.blocks.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["disc", "pad"]);
    // x = 2 is face S4 (+x) of the second element; x = 0 is S6 (-x) of the first.
    assert_eq!(m.surfaces["end"], vec![(1, 4)]);
    assert_eq!(m.surfaces["hub"], vec![(0, 6)]);
    assert_eq!(m.node_sets["hub"], vec![0, 3, 6, 9]);
    let stats = quality::check(&m).unwrap();
    assert!((stats[0].min_scaled_jacobian - 1.0).abs() < 1e-12);
}

/// Writes a mesh of one block in Gmsh 4.1 with Gmsh's node order.
fn write_msh(
    mesh: &Mesh,
    gmsh_type: u32,
    gmsh_edges: &[[usize; 2]],
    our_edges: &[[usize; 2]],
) -> String {
    let block = &mesh.blocks[0];
    let nn = block.kind.nodes();
    let first = nn - our_edges.len();
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"solid\"\n$EndPhysicalNames\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n$EndEntities\n");
    let n = mesh.node_count();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n3 1 0 {n}");
    for i in 0..n {
        let _ = writeln!(s, "{}", i + 1);
    }
    for x in &mesh.coords {
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", x[0], x[1], x[2]);
    }
    let ne = block.len();
    let _ = writeln!(
        s,
        "$EndNodes\n$Elements\n1 {ne} 1 {ne}\n3 1 {gmsh_type} {ne}"
    );
    for e in 0..ne {
        let ours = block.element(e);
        let mut theirs: Vec<usize> = ours[..first].to_vec();
        for &[a, b] in gmsh_edges {
            let j = our_edges
                .iter()
                .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
                .unwrap();
            theirs.push(ours[first + j]);
        }
        let ids: Vec<String> = theirs.iter().map(|n| (n + 1).to_string()).collect();
        let _ = writeln!(s, "{} {}", e + 1, ids.join(" "));
    }
    s + "$EndElements\n"
}

#[test]
fn quadratic_node_orders_are_converted() {
    use squeal::mesh::element::{HEX_EDGES, TET_EDGES};
    let gmsh_hex: [[usize; 2]; 12] = [
        [0, 1],
        [0, 3],
        [0, 4],
        [1, 2],
        [1, 5],
        [2, 3],
        [2, 6],
        [3, 7],
        [4, 5],
        [4, 7],
        [5, 6],
        [6, 7],
    ];
    let gmsh_tet: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];
    for (kind, ty, gmsh_edges, ours) in [
        (ElementKind::Hex20, 17, &gmsh_hex[..], &HEX_EDGES[..]),
        (ElementKind::Tet10, 11, &gmsh_tet[..], &TET_EDGES[..]),
    ] {
        let original = block([2.0, 1.0, 0.5], [2, 2, 1], kind, steel());
        let path = scratch(&format!("{kind:?}.msh"));
        std::fs::write(&path, write_msh(&original, ty, gmsh_edges, ours)).unwrap();
        let read_back = read(&path, &materials(&["solid"])).unwrap().mesh;
        assert_eq!(
            read_back.blocks[0].connectivity, original.blocks[0].connectivity,
            "{kind:?}"
        );
        let kernel = ElementKernel::new(kind, &steel());
        let mut x = Vec::new();
        let volume: f64 = (0..read_back.blocks[0].len())
            .map(|e| {
                read_back.element_coords(read_back.blocks[0].element(e), &mut x);
                kernel.volume(&x)
            })
            .sum();
        assert!((volume - 1.0).abs() < 1e-13, "{kind:?}: {volume}");
    }
}

fn expect_error(name: &str, text: &str, materials_given: &[&str], needles: &[&str]) {
    let path = scratch(name);
    std::fs::write(&path, text).unwrap();
    let e = read(&path, &materials(materials_given))
        .unwrap_err()
        .to_string();
    for n in needles {
        assert!(e.contains(n), "{name}: '{n}' not in: {e}");
    }
}

#[test]
fn malformed_files_give_the_documented_errors() {
    expect_error(
        "nomat.msh",
        TWO_CUBES,
        &["disc"],
        &[
            "nomat.msh",
            "physical volume 'pad' has no material",
            "[model.materials.pad]",
        ],
    );
    expect_error(
        "v2.msh",
        &TWO_CUBES.replace("4.1 0 8", "2.2 0 8"),
        &["disc", "pad"],
        &["v2.msh:2", "only 4.1"],
    );
    expect_error(
        "binary.msh",
        &TWO_CUBES.replace("4.1 0 8", "4.1 1 8"),
        &["disc", "pad"],
        &["binary MSH is not supported"],
    );
    expect_error(
        "node.msh",
        &TWO_CUBES.replace("1 1 2 5 4 7 8 11 10", "1 1 2 5 4 7 8 11 99"),
        &["disc", "pad"],
        &["node.msh:", "node 99 is not defined"],
    );
    expect_error(
        "type.msh",
        &TWO_CUBES.replace("3 1 5 1\n", "3 1 6 1\n"),
        &["disc", "pad"],
        &["element type 6 is not supported"],
    );
    expect_error(
        "face.msh",
        &TWO_CUBES.replace("3 3 6 12 9", "3 3 6 12 11"),
        &["disc", "pad"],
        &["surface element 3 of physical surface 'end' is not a face"],
    );
    expect_error(
        "short.msh",
        &TWO_CUBES.replace("1 1 2 5 4 7 8 11 10", "1 1 2 5 4 7 8 11"),
        &["disc", "pad"],
        &["needs a tag and 8 nodes"],
    );
}
