//! Abaqus `.inp` writer and reader: a generated model written and read back assembles to the
//! same K and M (to round-off: coordinates are written with 17 significant digits); the
//! keywords of the subset parse as documented; malformed files name the file and line.

use squeal::measure::nan_max;
use std::path::PathBuf;

use squeal::fem::assembly::{assemble, DenseSink};
use squeal::fem::dofmap::DofMap;
use squeal::mesh::abaqus_inp::{read, write};
use squeal::mesh::material::{Elasticity, Material};
use squeal::mesh::point::PointKind;
use squeal::mesh::structured::{annulus, block};
use squeal::mesh::ElementKind;
use squeal::mesh::Mesh;

#[path = "support/materials.rs"]
mod materials;
use materials::pad_lining;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-inp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn dense_k_m(mesh: &Mesh) -> (Vec<f64>, Vec<f64>) {
    let n = mesh.node_count();
    let dofs = DofMap::new(&vec![[false; 3]; n], 1, 0);
    let (mut k, mut m) = (DenseSink::new(3 * n), DenseSink::new(3 * n));
    assemble(mesh, &dofs, &mut k, &mut m).unwrap();
    (k.values, m.values)
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |s, v| nan_max(s, v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |s, (x, y)| nan_max(s, (x - y).abs()))
        / scale
}

#[test]
fn generated_model_written_and_read_gives_the_same_k_and_m() {
    let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
    for (name, mesh) in [
        (
            "hex8i",
            block(
                [0.2, 0.05, 0.03],
                [4, 2, 2],
                ElementKind::Hex8I,
                steel.clone(),
            ),
        ),
        (
            "hex20",
            annulus(
                0.1,
                0.15,
                0.02,
                [2, 12, 1],
                ElementKind::Hex20,
                pad_lining(),
            ),
        ),
        (
            "tet10",
            block(
                [0.1, 0.1, 0.05],
                [2, 2, 1],
                ElementKind::Tet10,
                pad_lining(),
            ),
        ),
    ] {
        let path = scratch(&format!("{name}.inp"));
        let clamps = vec![(
            mesh.node_sets.keys().next().unwrap().clone(),
            [true, false, true],
        )];
        write(&path, &mesh, &clamps).unwrap();
        let back = read(&path).unwrap();
        assert_eq!(back.mesh.node_count(), mesh.node_count(), "{name}");
        assert_eq!(back.mesh.element_count(), mesh.element_count(), "{name}");
        assert_eq!(back.clamps, clamps, "{name}");
        assert_eq!(back.mesh.materials[0], mesh.materials[0], "{name}");
        let (k0, m0) = dense_k_m(&mesh);
        let (k1, m1) = dense_k_m(&back.mesh);
        let (dk, dm) = (max_rel_diff(&k0, &k1), max_rel_diff(&m0, &m1));
        assert!(
            dk < 1e-14 && dm < 1e-14,
            "{name}: K differs by {dk:e}, M by {dm:e}"
        );
    }
}

const TWO_HEXES: &str = include_str!("data/seeds/two_hexes.inp");

#[test]
fn keywords_of_the_subset_are_read() {
    let path = scratch("two.inp");
    std::fs::write(&path, TWO_HEXES).unwrap();
    let m = read(&path).unwrap();
    assert_eq!(m.mesh.node_count(), 12);
    assert_eq!(m.mesh.blocks.len(), 2);
    assert_eq!(m.mesh.blocks[1].name, "PAD");
    assert_eq!(m.mesh.materials.len(), 2);
    assert!(
        matches!(m.mesh.materials[1].elasticity, Elasticity::Orthotropic { g23, .. } if g23 == 1e9)
    );
    assert_eq!(m.mesh.node_sets["LEFT"], vec![0, 3, 4, 7]);
    assert_eq!(m.clamps, vec![("LEFT".to_string(), [true, true, true])]);
    assert_eq!(m.mesh.surfaces["DISC_FACE"], vec![(0, 4)]);
    assert_eq!(m.mesh.surfaces["PAD_FACE"], vec![(1, 6)]);
    assert_eq!(m.contact_pairs.len(), 1);
    assert_eq!(m.contact_pairs[0].friction, Some(0.4));
    let skipped: Vec<&str> = m.skipped.iter().map(|(_, k)| k.as_str()).collect();
    assert_eq!(skipped, ["HEADING", "STEP", "FREQUENCY", "END STEP"]);
}

#[test]
fn include_is_followed() {
    let nodes = scratch("nodes.inc");
    let main = scratch("main.inp");
    let (head, tail) = TWO_HEXES.split_at(TWO_HEXES.find("*ELEMENT").unwrap());
    std::fs::write(&nodes, head).unwrap();
    std::fs::write(&main, format!("*INCLUDE, INPUT=nodes.inc\n{tail}")).unwrap();
    assert_eq!(read(&main).unwrap().mesh.node_count(), 12);
}

fn error_of(text: &str) -> String {
    let path = scratch("bad.inp");
    std::fs::write(&path, text).unwrap();
    read(&path).unwrap_err().to_string()
}

#[test]
fn malformed_files_name_file_and_line() {
    let e = error_of(&TWO_HEXES.replace(
        "*NSET, NSET=LEFT, GENERATE",
        "*COUPLING, CONSTRAINT NAME=C, REF NODE=1, SURFACE=PAD_FACE\n*NSET, NSET=LEFT, GENERATE",
    ));
    assert!(e.contains("bad.inp:21") && e.contains("COUPLING"), "{e}");
    let e = error_of(&TWO_HEXES.replace("3, 1., 1., 0.", "3, 1., one, 0."));
    assert!(e.contains("bad.inp:7") && e.contains("'one'"), "{e}");
    let e = error_of(&TWO_HEXES.replace("TYPE=C3D8I, ELSET=PAD", "TYPE=S4R, ELSET=PAD"));
    assert!(
        e.contains("C3D4"),
        "the error lists the supported types: {e}"
    );
    assert!(e.contains("bad.inp:19") && e.contains("S4R"), "{e}");
    let e = error_of(&TWO_HEXES.replace(
        "2, 2, 9, 10, 3, 6, 11, 12, 7",
        "2, 2, 9, 10, 3, 6, 11, 12, 99",
    ));
    assert!(e.contains("node 99"), "{e}");
    let e = error_of(&TWO_HEXES.replace("*DENSITY\n7200.\n", ""));
    assert!(e.contains("'IRON'") && e.contains("DENSITY"), "{e}");
    let e = error_of(&TWO_HEXES.replace("0.4\n", "nan\n"));
    assert!(
        e.contains("not finite") || e.contains("not a number"),
        "{e}"
    );
    let e = error_of(&TWO_HEXES.replace("PAD_FACE, DISC_FACE", "PAD_FACE, ROTOR"));
    assert!(e.contains("'ROTOR'"), "{e}");
}

/// What pre-processors write, read as Abaqus reads it: parameter values by their start
/// (TYPE=ISO, TYPE=ENGINEERING), several *ELEMENT keywords of one ELSET into one block (a
/// deck of 256 such keywords imported and then failed writing results.h5 with a misleading
/// HDF5 message), padded element lines (the element's nodes first), and the keywords of other
/// analyses' steps skipped with a line each for the log.
#[test]
fn pre_processor_decks_are_read_as_abaqus_reads_them() {
    let text = TWO_HEXES
        .replace("*ELASTIC\n1.1e11", "*ELASTIC, TYPE=ISO\n1.1e11")
        .replace("TYPE=ENGINEERING CONSTANTS", "type=Engineering")
        .replace("ELSET=PAD\n", "ELSET=DISC\n")
        .replace("*SOLID SECTION, ELSET=PAD, MATERIAL=LINING\n", "")
        .replace("PAD_FACE, DISC_FACE", "DISC_FACE, DISC_FACE")
        .replace("2, S6", "DISC, S6")
        .replace("1, 1, 2, 3, 4, 5, 6, 7, 8", "1, 1, 2, 3, 4, 5, 6, 7, 8, 0, 0")
        .replace(
            "*END STEP",
            "*END STEP\n*STEP\n*STEADY STATE DYNAMICS\n100., 5000., 20\n*MODAL DAMPING\n1, 10, 0.02\n*END STEP\n*INITIAL CONDITIONS, TYPE=TEMP\nLEFT, 20.",
        );
    let path = scratch("preprocessor.inp");
    std::fs::write(&path, &text).unwrap();
    let m = read(&path).unwrap();
    assert_eq!(m.mesh.blocks.len(), 1, "one ELSET, one block");
    assert_eq!(m.mesh.blocks[0].name, "DISC");
    assert_eq!(m.mesh.element_count(), 2);
    assert_eq!(m.mesh.blocks[0].element(0), [0, 1, 2, 3, 4, 5, 6, 7]);
    assert!(matches!(
        m.mesh.materials[0].elasticity,
        Elasticity::Isotropic { e, .. } if e == 1.1e11
    ));
    assert!(
        m.notes
            .iter()
            .any(|n| n.contains("2 node ids more") && n.contains("first 8")),
        "{:?}",
        m.notes
    );
    let skipped = m.skipped_notes();
    for keyword in [
        "STEADY STATE DYNAMICS",
        "MODAL DAMPING",
        "INITIAL CONDITIONS",
    ] {
        assert!(
            skipped
                .iter()
                .any(|n| n.starts_with(&format!("*{keyword} skipped"))),
            "{keyword}: {skipped:?}"
        );
    }
    assert_eq!(
        m.element_types,
        vec![("DISC".to_string(), "C3D8I".to_string(), 2)]
    );
    // Initial stresses would change K: refused, naming the line.
    let stressed = text.replace("TYPE=TEMP", "TYPE=STRESS");
    let e = error_of(&stressed);
    assert!(
        e.contains("INITIAL CONDITIONS") && e.contains("could change the model"),
        "{e}"
    );
    // A form that is not read is refused, naming it.
    let e = error_of(&TWO_HEXES.replace("TYPE=ENGINEERING CONSTANTS", "TYPE=TRACTION"));
    assert!(
        e.contains("TYPE=TRACTION") && e.contains("bad.inp:35"),
        "{e}"
    );
}

/// *ELASTIC, TYPE=ORTHO (the nine D constants, Abaqus' Voigt order 11, 22, 33, 12, 13, 23)
/// gives the D of the same engineering constants, mapped onto squeal's (xx, yy, zz, xy, yz,
/// zx) order: D1313 is squeal's zx shear, D2323 its yz.
#[test]
fn orthotropic_d_constants_give_the_engineering_constants_d() {
    let engineering = scratch("eng.inp");
    std::fs::write(&engineering, TWO_HEXES).unwrap();
    let m = read(&engineering).unwrap();
    let d = m.mesh.materials[1].stiffness_matrix();
    // Abaqus order: D1111, D1122, D2222, D1133, D2233, D3333, D1212, D1313, D2323.
    let values = [
        d[0][0], d[0][1], d[1][1], d[0][2], d[1][2], d[2][2], d[3][3], d[5][5], d[4][4],
    ];
    let line: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
    let ortho = TWO_HEXES.replace(
        "*ELASTIC, TYPE=ENGINEERING CONSTANTS\n6e9, 6e9, 2e9, 0.25, 0.1, 0.1, 2.4e9, 1e9,\n1e9",
        &format!(
            "*ELASTIC, TYPE=ORTHO\n{},\n{}",
            line[..8].join(", "),
            line[8]
        ),
    );
    assert_ne!(ortho, TWO_HEXES);
    let p = scratch("ortho.inp");
    std::fs::write(&p, &ortho).unwrap();
    let back = read(&p).unwrap().mesh.materials[1].stiffness_matrix();
    for i in 0..6 {
        for j in 0..6 {
            assert!(
                (back[i][j] - d[i][j]).abs() <= 1e-12 * d[0][0],
                "D[{i}][{j}]: {} vs {}",
                back[i][j],
                d[i][j]
            );
        }
    }
}

/// *ORIENTATION on a *SOLID SECTION: read into the block (the axes, the extra rotation), and
/// what does not define axes refused with the line.
#[test]
fn orientations_are_read_and_bad_ones_refused() {
    let oriented = TWO_HEXES.replace(
        "*SOLID SECTION, ELSET=PAD, MATERIAL=LINING",
        "*ORIENTATION, NAME=PADAXES, SYSTEM=CYL\n0., 0., 0., 0., 1., 0.\n3, 10.\n*SOLID SECTION, ELSET=PAD, MATERIAL=LINING, ORIENTATION=padaxes",
    );
    let path = scratch("oriented.inp");
    std::fs::write(&path, &oriented).unwrap();
    let m = read(&path).unwrap();
    let o = m.mesh.blocks[1].orientation.expect("the pad's orientation");
    assert_eq!(m.mesh.orientations[o].name, "PADAXES");
    assert_eq!(m.mesh.orientations[o].extra_rotation, Some((2, 10.0)));
    assert_eq!(m.mesh.blocks[0].orientation, None);
    // The pad's centroid (1.5, 0.5, 0.5) is off the y axis; one on it is refused.
    let on_axis = oriented.replace("0., 0., 0., 0., 1., 0.", "1.5, 0., 0.5, 1.5, 1., 0.5");
    let e = error_of(&on_axis);
    assert!(
        e.contains("centroid on the axis") && e.contains("PADAXES"),
        "{e}"
    );
    let e = error_of(&oriented.replace("SYSTEM=CYL", "SYSTEM=SPHERICAL"));
    assert!(e.contains("SPHERICAL") && e.contains("bad.inp:"), "{e}");
    let e = error_of(&oriented.replace("SYSTEM=CYL", "SYSTEM=CYL, DEFINITION=NODES"));
    assert!(e.contains("DEFINITION=NODES"), "{e}");
    let e = error_of(&oriented.replace("ORIENTATION=padaxes", "ORIENTATION=other"));
    assert!(e.contains("'other'") && e.contains("*ORIENTATION"), "{e}");
    let e = error_of(&oriented.replace("0., 0., 0., 0., 1., 0.", "0., 0., 0., 0., 0., 0."));
    assert!(e.contains("do not define axes"), "{e}");
}

/// Point elements as pre-processors write them (one ELSET per kind, the value in *MASS /
/// *SPRING; SPRINGA's stiffness after a blank line), and their faults refused by line or set.
#[test]
fn masses_and_springs_are_read_and_bad_ones_refused() {
    let points = "*ELEMENT, TYPE=MASS, ELSET=WEIGHTS\n10, 7\n11, 8\n\
                  *ELEMENT, TYPE=SPRINGA, ELSET=STRUT\n12, 1, 12\n\
                  *ELEMENT, TYPE=SPRING1, ELSET=HOLD\n13, 9\n\
                  *MASS, ELSET=WEIGHTS\n0.25\n*SPRING, ELSET=STRUT\n\n2.5e5\n\
                  *SPRING, ELSET=HOLD\n3\n1.e6\n";
    let text = TWO_HEXES.replace(
        "*NSET, NSET=LEFT, GENERATE",
        &format!("{points}*NSET, NSET=LEFT, GENERATE"),
    );
    let path = scratch("points.inp");
    std::fs::write(&path, &text).unwrap();
    let m = read(&path).unwrap();
    let blocks: Vec<(&str, PointKind, f64, &[usize])> = m
        .mesh
        .point_blocks
        .iter()
        .map(|b| (b.name.as_str(), b.kind, b.value, b.connectivity.as_slice()))
        .collect();
    assert_eq!(
        blocks,
        [
            ("WEIGHTS", PointKind::Mass, 0.25, &[6usize, 7][..]),
            ("STRUT", PointKind::Axial, 2.5e5, &[0, 11][..]),
            ("HOLD", PointKind::Grounded { dof: 2 }, 1e6, &[8][..]),
        ]
    );
    // Written and read back: the same point blocks.
    let again = scratch("points-again.inp");
    write(&again, &m.mesh, &m.clamps).unwrap();
    assert_eq!(read(&again).unwrap().mesh.point_blocks, m.mesh.point_blocks);

    let with = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        error_of(&text.replace(from, to))
    };
    let e = with("*MASS, ELSET=WEIGHTS\n0.25\n", "");
    assert!(
        e.contains("MASS element 10") && e.contains("no *MASS"),
        "{e}"
    );
    let e = with("*SPRING, ELSET=HOLD\n3\n", "*SPRING, ELSET=HOLD\n4\n");
    assert!(e.contains("DOF '4'") && e.contains("no rotations"), "{e}");
    let e = with("*SPRING, ELSET=STRUT", "*SPRING, ELSET=STRUT, NONLINEAR");
    assert!(
        e.contains("NONLINEAR") && e.contains("linear springs"),
        "{e}"
    );
    let e = with("TYPE=MASS, ELSET=WEIGHTS", "TYPE=ROTARYI, ELSET=WEIGHTS");
    assert!(
        e.contains("ROTARYI") && e.contains("rotational DOFs"),
        "{e}"
    );
    let e = with("12, 1, 12\n", "12, 1, 1\n");
    assert!(e.contains("'STRUT'") && e.contains("same place"), "{e}");
    let e = with("0.25\n", "-0.25\n");
    assert!(e.contains("-0.25") && e.contains(">= 0"), "{e}");
    let e = with("*MASS, ELSET=WEIGHTS", "*MASS, ELSET=WEIGHT");
    assert!(e.contains("'WEIGHT'") && e.contains("not defined"), "{e}");
}

/// *EQUATION: node ids and node sets (one equation per node, paired in label order), several
/// equations under one keyword, and the faults named by line.
#[test]
fn equations_are_read_and_bad_ones_refused() {
    let equations = "*NSET, NSET=TOP\n6, 5\n*NSET, NSET=BOTTOM\n1, 2\n\
                     *EQUATION\n2\nTOP, 3, 1.0, BOTTOM, 3, -1.0\n3\n7, 1, 2., 8, 1, -1., 12, 2, -1.\n";
    let text = TWO_HEXES.replace(
        "*NSET, NSET=LEFT, GENERATE",
        &format!("{equations}*NSET, NSET=LEFT, GENERATE"),
    );
    let path = scratch("equations.inp");
    std::fs::write(&path, &text).unwrap();
    let m = read(&path).unwrap();
    let terms: Vec<Vec<(usize, usize, f64)>> = m
        .mesh
        .constraints
        .equations
        .iter()
        .map(|c| c.terms.clone())
        .collect();
    assert_eq!(
        terms,
        [
            vec![(4, 2, 1.0), (0, 2, -1.0)],
            vec![(5, 2, 1.0), (1, 2, -1.0)],
            vec![(6, 0, 2.0), (7, 0, -1.0), (11, 1, -1.0)],
        ]
    );
    let again = scratch("equations-again.inp");
    write(&again, &m.mesh, &m.clamps).unwrap();
    let back = read(&again).unwrap().mesh.constraints.equations;
    let back_terms: Vec<_> = back.iter().map(|c| c.terms.clone()).collect();
    assert_eq!(back_terms, terms);

    let with = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        error_of(&text.replace(from, to))
    };
    let e = with("7, 1, 2.,", "7, 4, 2.,");
    assert!(e.contains("DOF 4") && e.contains("no rotations"), "{e}");
    let e = with("\n3\n7, 1, 2.", "\n4\n7, 1, 2.");
    assert!(e.contains("4 terms announced, 3 given"), "{e}");
    let e = with(
        "*NSET, NSET=BOTTOM\n1, 2\n",
        "*NSET, NSET=BOTTOM\n1, 2, 3\n",
    );
    assert!(e.contains("differ in size"), "{e}");
    let e = with("7, 1, 2.,", "7, 1, 0.,");
    assert!(e.contains("first term's coefficient is 0"), "{e}");
    let e = with("BOTTOM, 3, -1.0", "BASE, 3, -1.0");
    assert!(e.contains("'BASE'") && e.contains("not defined"), "{e}");
}

/// *TIE: a node-based slave surface (node ids and sets) and an element-face master read into
/// a tie; its faults named by line.
#[test]
fn ties_are_read_and_bad_ones_refused() {
    let tie = "*SURFACE, TYPE=NODE, NAME=GLUED\nLEFT\n9\n\
               *TIE, NAME=T1, POSITION TOLERANCE=0.01, ADJUST=NO\nGLUED, DISC_FACE\n";
    let text = format!("{TWO_HEXES}{tie}");
    let path = scratch("tie.inp");
    std::fs::write(&path, &text).unwrap();
    let m = read(&path).unwrap();
    assert_eq!(m.ties.len(), 1);
    let t = &m.ties[0];
    assert_eq!(
        (t.name.as_str(), t.master.as_str(), t.tolerance, t.adjust),
        ("T1", "DISC_FACE", Some(0.01), false)
    );
    assert_eq!(t.slave_nodes, [0, 3, 4, 7, 8]);
    let with = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        error_of(&text.replace(from, to))
    };
    let e = with("GLUED, DISC_FACE", "GLUED, ROTOR");
    assert!(e.contains("master surface 'ROTOR' is not defined"), "{e}");
    let e = with("GLUED, DISC_FACE", "DISC_FACE, GLUED");
    assert!(
        e.contains("node-based") && e.contains("TYPE=ELEMENT"),
        "{e}"
    );
    let e = with("ADJUST=NO", "ADJUST=MAYBE");
    assert!(e.contains("ADJUST=MAYBE"), "{e}");
    let e = with("*TIE, NAME=T1", "*TIE, NAME=T1, TYPE=SURFACE TO SURFACE");
    assert!(e.contains("TYPE") && e.contains("translations"), "{e}");
    let e = with("LEFT\n9\n*TIE", "RIGHT\n9\n*TIE");
    assert!(e.contains("'RIGHT'") && e.contains("not defined"), "{e}");
    let e = with("GLUED, DISC_FACE\n", "");
    assert!(e.contains("no 'slave surface, master surface' line"), "{e}");
}

/// Parts and instances: ids offset per instance, names scoped (`Instance.Set`), coordinates
/// translated then rotated; the faults named by line.
#[test]
fn instances_of_parts_are_flattened_and_bad_ones_refused() {
    let (head, rest) = TWO_HEXES.split_at(TWO_HEXES.find("*NODE").unwrap());
    let (part, model) = rest.split_at(rest.find("*MATERIAL").unwrap());
    let sections =
        "*SOLID SECTION, ELSET=DISC, MATERIAL=IRON\n*SOLID SECTION, ELSET=PAD, MATERIAL=LINING\n";
    let model = model
        .lines()
        .filter(|l| {
            !l.starts_with("*SOLID SECTION")
                && !l.starts_with("*CONTACT PAIR")
                && !l.starts_with("PAD_FACE")
        })
        .collect::<Vec<_>>()
        .join("\n")
        .replace("\nLEFT, 1, 3", "\nBOTH_LEFT, 1, 3");
    let text = format!(
        "{head}*PART, NAME=P\n{part}{sections}*END PART\n*ASSEMBLY, NAME=A\n\
         *INSTANCE, NAME=I1, PART=P\n*END INSTANCE\n\
         *INSTANCE, NAME=I2, PART=P\n10., 0., 0.\n10., 0., 0., 10., 0., 1., 90.\n*END INSTANCE\n\
         *NSET, NSET=BOTH_LEFT, INSTANCE=I2\nLEFT\n*END ASSEMBLY\n{model}\n"
    );
    let path = scratch("instances.inp");
    std::fs::write(&path, &text).unwrap();
    let m = read(&path).unwrap();
    assert_eq!(m.mesh.node_count(), 24);
    let names: Vec<&str> = m.mesh.blocks.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["I1.DISC", "I1.PAD", "I2.DISC", "I2.PAD"]);
    assert!(m.mesh.surfaces.contains_key("I2.PAD_FACE"));
    // I2's node 2 (1, 0, 0): translated to (11, 0, 0), turned 90 degrees about the vertical
    // axis through (10, 0): (10, 1, 0).
    let x = m.mesh.coords[13];
    assert!(
        (x[0] - 10.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12 && x[2].abs() < 1e-12,
        "{x:?}"
    );
    // The assembly-level set takes I2's LEFT (its nodes 1, 4, 5, 8: 13, 16, 17, 20 overall).
    assert_eq!(m.mesh.node_sets["BOTH_LEFT"], [12, 15, 16, 19]);
    assert_eq!(m.mesh.node_sets["I1.LEFT"], [0, 3, 4, 7]);

    let with = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        error_of(&text.replace(from, to))
    };
    let e = with("*END PART\n", "");
    assert!(e.contains("*PART P has no *END PART"), "{e}");
    let e = with("NAME=I2, PART=P", "NAME=I2, PART=Q");
    assert!(e.contains("part 'Q' is not defined"), "{e}");
    let e = with("10., 0., 0.\n10.,", "10., 0.\n10.,");
    assert!(e.contains("translation line"), "{e}");
    let e = with("INSTANCE=I2\n", "INSTANCE=I3\n");
    assert!(e.contains("INSTANCE=I3"), "{e}");
}
