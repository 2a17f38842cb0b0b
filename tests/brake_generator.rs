//! The parametric brake against its analytic geometry.
//!
//! References: the volume of every component follows in closed form from its dimensions
//! (revolved rectangles: V = (theta1 - theta0)/2 (r1^2 - r0^2) dz per coarse cell). Hex20
//! elements put their mid-edge nodes on the arcs, so their volume error is O(dtheta^4); Hex8
//! elements have straight edges, so each cell of angle dtheta holds exactly sin(dtheta)/dtheta
//! of the exact sector: the relative volume deficit is at most dtheta_max^2 / 6.

use squeal::fem::element::ElementKernel;
use squeal::fem::quality;
use squeal::measure::nan_max;
use squeal::mesh::brake::{
    anchor, caliper, disc, element_size_for, generate, generate_with_size, pad, piston, BrakeSpec,
    Component, Side,
};
use squeal::mesh::ElementKind;
use squeal::mesh::Mesh;

fn block_volume(mesh: &Mesh, name: &str) -> f64 {
    let b = mesh
        .blocks
        .iter()
        .find(|b| b.name == name)
        .unwrap_or_else(|| panic!("no block {name}"));
    let kernel = ElementKernel::new(b.kind, &mesh.materials[b.material]);
    let mut x = Vec::new();
    (0..b.len())
        .map(|e| {
            mesh.element_coords(b.element(e), &mut x);
            kernel.volume(&x)
        })
        .sum()
}

fn exact_volumes(spec: &BrakeSpec) -> Vec<(&'static str, f64)> {
    let g = &spec.geometry;
    let (lining, backplate) = pad::volumes(g);
    vec![
        ("disc", disc::volume(g)),
        ("inner_lining", lining),
        ("outer_lining", lining),
        ("inner_backplate", backplate),
        ("outer_backplate", backplate),
        ("piston", piston::volume(g)),
        ("caliper", caliper::volume(g)),
        ("anchor", anchor::volume(g)),
    ]
}

/// Largest angular cell of a component's grid.
fn max_dtheta(spec: &BrakeSpec, name: &str, h: f64) -> f64 {
    let g = &spec.geometry;
    let (grid, _) = match name {
        "disc" => disc::grid(g, h),
        "piston" => piston::grid(g, h),
        "caliper" => caliper::grid(g, h),
        "anchor" => anchor::grid(g, h),
        _ => pad::grid(g, Side::Inner, h),
    };
    let (theta, _) = grid.axes[1].points();
    theta.windows(2).map(|w| w[1] - w[0]).fold(0.0, nan_max)
}

#[test]
fn component_volumes_match_the_analytic_geometry() {
    for (kind, dofs) in [(ElementKind::Hex8I, 30_000), (ElementKind::Hex20, 60_000)] {
        let spec = BrakeSpec {
            element: kind,
            target_dofs: dofs,
            ..Default::default()
        };
        let model = generate(&spec).unwrap();
        assert_eq!(model.mesh.blocks.len(), 8);
        for (name, exact) in exact_volumes(&spec) {
            let v = block_volume(&model.mesh, name);
            let rel = (v - exact) / exact;
            let dtheta = max_dtheta(&spec, name, model.element_size);
            println!(
                "{kind:?} {name:<16} V = {v:.6e} m^3, exact {exact:.6e}, rel {rel:+.2e}, dtheta {dtheta:.3}"
            );
            if kind == ElementKind::Hex20 {
                // Parabolic arcs: measured rel ~ dtheta^4 / 480 (disc 1.4e-7 at 0.091 rad,
                // piston 4.9e-5 at 0.393 rad); asserted with a factor 2.
                assert!(
                    rel.abs() < dtheta.powi(4) / 240.0,
                    "{name}: relative error {rel:.2e}, dtheta {dtheta}"
                );
            } else {
                // Inscribed: between the chordal bound and the exact volume.
                assert!(
                    rel <= 1e-12 && rel >= -dtheta * dtheta / 6.0,
                    "{name}: relative error {rel:.2e}, dtheta {dtheta}"
                );
            }
        }
        // rho V: a solid (not ventilated) 300 x 28 mm cast-iron disc with its hat: 12.2 kg.
        let disc_mass = spec.materials.disc.density * disc::volume(&spec.geometry);
        assert!(
            (11.0..13.0).contains(&disc_mass),
            "disc mass {disc_mass} kg"
        );
    }
}

#[test]
fn target_dofs_is_met_within_ten_percent_and_quality_holds_at_every_size() {
    for (kind, target) in [
        (ElementKind::Hex8I, 5_000),
        (ElementKind::Hex8I, 20_000),
        (ElementKind::Hex8I, 100_000),
        (ElementKind::Hex20, 20_000),
        (ElementKind::Hex8I, 600_000),
    ] {
        let spec = BrakeSpec {
            element: kind,
            target_dofs: target,
            ..Default::default()
        };
        let h = element_size_for(&spec).unwrap();
        let model = generate_with_size(&spec, h);
        let dofs = 3 * model.mesh.node_count();
        let off = (dofs as f64 - target as f64) / target as f64;
        println!("{kind:?} target {target}: {dofs} DOF ({off:+.3}), h = {h:.4} m");
        assert!(off.abs() <= 0.1, "{dofs} DOF for {target}");
        if target <= 100_000 {
            let stats = quality::check(&model.mesh).unwrap();
            print!("{}", quality::table(&stats));
            for q in &stats {
                assert!(q.min_scaled_jacobian > 0.2, "{q:?}");
                assert!(q.max_aspect_ratio < 20.0, "{q:?}");
                assert!(q.max_warping_deg < 1.0, "{q:?}");
            }
        }
    }
}

#[test]
fn a_disc_and_pads_scene_builds_only_those_with_substitute_constraints() {
    let spec = BrakeSpec {
        components: vec![Component::Disc, Component::InnerPad, Component::OuterPad],
        target_dofs: 10_000,
        ..Default::default()
    };
    let model = generate(&spec).unwrap();
    let names: Vec<&str> = model.mesh.blocks.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "disc",
            "inner_lining",
            "inner_backplate",
            "outer_lining",
            "outer_backplate"
        ]
    );
    let interfaces: Vec<&str> = model.interfaces.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(interfaces, ["inner_lining_disc", "outer_lining_disc"]);
    let clamped: Vec<&str> = model.clamps.iter().map(|c| c.node_set.as_str()).collect();
    assert_eq!(
        clamped,
        [
            "disc_bolts",
            "inner_backplate_ears",
            "outer_backplate_ears",
            "outer_backplate_back"
        ]
    );
    assert_eq!(model.loads[0].surface, "inner_backplate_back");
    for surface in ["caliper_fingers", "anchor_abutments", "piston_rim"] {
        assert!(!model.mesh.surfaces.contains_key(surface));
    }
}

#[test]
fn the_full_brake_has_every_interface_and_its_surfaces_touch() {
    let spec = BrakeSpec {
        target_dofs: 20_000,
        ..Default::default()
    };
    let model = generate(&spec).unwrap();
    assert_eq!(model.interfaces.len(), 6);
    // Master and slave surfaces of every interface are coplanar (or co-cylindrical): the
    // master nodes lie on the slave's plane z = const, or angle = const for the abutments.
    for i in &model.interfaces {
        let master = model.mesh.surface_nodes(&i.master).unwrap();
        let slave = model.mesh.surface_nodes(&i.slave).unwrap();
        assert!(!master.is_empty() && !slave.is_empty(), "{}", i.name);
        let key = |n: usize| {
            let x = model.mesh.coords[n];
            if i.name.contains("abutments") {
                x[1].atan2(x[0]).abs()
            } else {
                x[2]
            }
        };
        let m0 = key(master[0]);
        let touches = slave.iter().any(|&n| (key(n) - m0).abs() < 1e-12);
        assert!(touches, "{}: master at {m0}, slave elsewhere", i.name);
    }
    // The constraint sets exist and are non-empty.
    for c in &model.clamps {
        assert!(
            !model.mesh.node_sets[&c.node_set].is_empty(),
            "{}",
            c.node_set
        );
    }
}

/// Sparse (row, column) -> value accumulation of assembled matrices.
#[derive(Default)]
struct MapSink(std::collections::HashMap<(i32, i32), f64>);

impl squeal::fem::assembly::MatrixSink for MapSink {
    type Error = std::convert::Infallible;
    fn add(&mut self, dofs: &[i32], values: &[f64]) -> Result<(), Self::Error> {
        let m = dofs.len();
        for (i, &r) in dofs.iter().enumerate() {
            for (j, &c) in dofs.iter().enumerate() {
                if r >= 0 && c >= 0 {
                    *self.0.entry((r, c)).or_default() += values[i * m + j];
                }
            }
        }
        Ok(())
    }
}

fn assembled(mesh: &Mesh, clamps: &[squeal::mesh::Clamp]) -> (MapSink, MapSink) {
    let dofs = squeal::fem::dofmap::dof_map(mesh, clamps, 1, 0).unwrap();
    let (mut k, mut m) = (MapSink::default(), MapSink::default());
    squeal::fem::assembly::assemble(mesh, &dofs, &mut k, &mut m).unwrap();
    (k, m)
}

fn max_relative_difference(a: &MapSink, b: &MapSink) -> f64 {
    let scale = a.0.values().fold(0.0_f64, |s, v| nan_max(s, v.abs()));
    assert_eq!(a.0.len(), b.0.len(), "different sparsity");
    a.0.iter()
        .map(|(key, v)| (v - b.0.get(key).copied().unwrap_or(f64::NAN)).abs() / scale)
        .fold(0.0, nan_max)
}

#[test]
fn generated_brake_written_as_inp_and_read_back_gives_the_same_k_and_m() {
    for (kind, target_dofs) in [(ElementKind::Hex8I, 8_000), (ElementKind::Hex20, 15_000)] {
        let spec = BrakeSpec {
            element: kind,
            target_dofs,
            ..Default::default()
        };
        let model = generate(&spec).unwrap();
        let path = std::env::temp_dir().join(format!("squeal-brake-{kind:?}.inp"));
        let clamps: Vec<(String, [bool; 3])> = model
            .clamps
            .iter()
            .map(|c| (c.node_set.clone(), c.components))
            .collect();
        squeal::mesh::abaqus_inp::write(&path, &model.mesh, &clamps).unwrap();
        let read = squeal::mesh::abaqus_inp::read(&path).unwrap();
        assert_eq!(read.mesh.surfaces, model.mesh.surfaces);
        assert_eq!(read.mesh.node_count(), model.mesh.node_count());
        let read_clamps: Vec<squeal::mesh::Clamp> = read
            .clamps
            .iter()
            .map(|(s, c)| squeal::mesh::Clamp {
                node_set: s.clone(),
                components: *c,
            })
            .collect();
        let (k0, m0) = assembled(&model.mesh, &model.clamps);
        let (k1, m1) = assembled(&read.mesh, &read_clamps);
        let (dk, dm) = (
            max_relative_difference(&k0, &k1),
            max_relative_difference(&m0, &m1),
        );
        println!("{kind:?}: max |K - K'| / max |K| = {dk:.1e}, M: {dm:.1e}");
        assert!(dk < 1e-14 && dm < 1e-14, "{dk} {dm}");
    }
}
