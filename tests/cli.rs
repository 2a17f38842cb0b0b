//! End-to-end runs of the `squeal` binary under mpirun (2 ranks when mpirun is available):
//! the default scene completes and writes its results; bad input gives a non-zero exit and a
//! message that names the file and the key, without hanging any rank.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn squeal() -> &'static str {
    env!("CARGO_BIN_EXE_squeal")
}

fn mpirun(ranks: usize, args: &[&str], cwd: &Path) -> Output {
    let have_mpirun = Command::new("mpirun").arg("--version").output().is_ok();
    let mut cmd = if have_mpirun {
        let mut c = Command::new("mpirun");
        c.args(["-n", &ranks.to_string()]).arg(squeal());
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .env("OMPI_MCA_rmaps_base_oversubscribe", "1");
        c
    } else {
        Command::new(squeal())
    };
    cmd.args(args)
        .current_dir(cwd)
        .output()
        .expect("squeal runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn scene_file(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("jobs")
            .join(name),
    )
    .unwrap()
}

fn default_scene() -> String {
    scene_file("default.toml")
}

fn disc_ring_scene() -> String {
    scene_file("disc-ring-modes.toml")
}

#[test]
fn default_scene_runs_end_to_end_on_two_ranks() {
    let dir = scratch("default");
    let out = mpirun(2, &["run"], &dir);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "stdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("real modes"), "{stdout}");
    assert!(stdout.contains("timings"), "{stdout}");
    // Only rank 0 prints: the header appears once.
    assert_eq!(stdout.matches("squeal 0.").count(), 1, "{stdout}");
    assert!(stdout.contains("mesh quality"), "{stdout}");
    assert!(stdout.contains("rigid-body mode"), "{stdout}");
    for f in [
        "results/results.h5",
        "results/results.xdmf",
        "results/model.png",
    ] {
        let p = dir.join(f);
        assert!(
            p.metadata().map(|m| m.len() > 0).unwrap_or(false),
            "{} missing",
            p.display()
        );
    }
    let xdmf = std::fs::read_to_string(dir.join("results/results.xdmf")).unwrap();
    assert!(
        xdmf.contains("Hexahedron")
            && xdmf.contains("mode 001")
            && xdmf.contains("disc_friction_outer"),
        "{xdmf}"
    );
}

#[test]
fn print_default_scene_roundtrips() {
    let out = Command::new(squeal())
        .args(["scene", "--print-default"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout), default_scene());
}

fn expect_failure(name: &str, scene: &str, needles: &[&str]) {
    let dir = scratch(name);
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let out = mpirun(2, &["run", "scene.toml"], &dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{name}: should fail");
    for n in needles {
        assert!(stderr.contains(n), "{name}: '{n}' not in:\n{stderr}");
    }
}

#[test]
fn negative_thickness_names_the_key() {
    expect_failure(
        "thickness",
        &default_scene().replace("disc_thickness = 0.028", "disc_thickness = -0.028"),
        &["scene.toml", "model.geometry.disc_thickness"],
    );
}

#[test]
fn unknown_key_names_the_key() {
    expect_failure(
        "unknown",
        &default_scene().replace("count = 50", "count = 50\nnumber = 3"),
        &["scene.toml", "number"],
    );
}

#[test]
fn missing_matrix_file_names_the_file() {
    let scene = "[model]\nsource = \"matrices\"\nstiffness = [{ file = \"K.mtx\" }]\nmass = [{ file = \"M.mtx\" }]\n[real_modes]\ncount = 4\n";
    expect_failure("missing", scene, &["K.mtx", "No such file"]);
}

#[test]
fn missing_node_set_names_the_sets() {
    expect_failure(
        "nodeset",
        &disc_ring_scene().replace("clamp = [\"inner\"]", "clamp = [\"hat\"]"),
        &["no node set 'hat'", "inner"],
    );
}

/// The frequencies of a summary printed by `squeal run`.
fn frequencies(stdout: &str) -> Vec<f64> {
    stdout
        .lines()
        .skip_while(|l| !l.starts_with("real modes:"))
        .skip(1)
        .map_while(|l| {
            let mut w = l.split_whitespace();
            w.next()?.parse::<usize>().ok()?;
            w.next()?.parse::<f64>().ok()
        })
        .collect()
}

#[test]
fn written_inp_reimported_gives_the_same_modes() {
    let dir = scratch("inp");
    let scene = disc_ring_scene()
        .replace(
            "directory = \"results\"",
            "directory = \"first\"\nwrite_inp = true",
        )
        .replace("cells = [8, 120, 4]", "cells = [3, 40, 2]")
        .replace("count = 30", "count = 8");
    std::fs::write(dir.join("generated.toml"), &scene).unwrap();
    let first = mpirun(2, &["run", "generated.toml"], &dir);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let imported = "[model]\nsource = \"abaqus\"\nfile = \"first/model.inp\"\n[real_modes]\ncount = 8\n[output]\ndirectory = \"second\"\n";
    std::fs::write(dir.join("imported.toml"), imported).unwrap();
    let second = mpirun(2, &["run", "imported.toml"], &dir);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    let (a, b) = (
        frequencies(&String::from_utf8_lossy(&first.stdout)),
        frequencies(&String::from_utf8_lossy(&second.stdout)),
    );
    assert_eq!(a.len(), 8, "{a:?}");
    assert_eq!(a, b, "generated and re-imported models differ");
}
