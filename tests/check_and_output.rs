//! `squeal check` on every scene of jobs/ and on broken ones, and the output folder as a user
//! meets it: one that cannot be made, one whose parent is missing, and a run that fails before
//! writing (it leaves no empty folder). Every failure is a clean non-zero exit of all ranks
//! that names the file or key, not MPI's abort.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[path = "support/launch.rs"]
mod launch;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(ranks: usize, args: &[&str], cwd: &Path) -> (i32, String, String) {
    let out = launch::squeal_run(ranks, args, cwd, &[], Duration::from_secs(300));
    let status = out
        .status
        .unwrap_or_else(|| panic!("squeal {args:?} still ran after 300 s: killed"));
    (status.code().unwrap_or(-1), out.stdout, out.stderr)
}

#[test]
fn every_scene_of_jobs_passes_squeal_check() {
    let jobs = Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&jobs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 10, "{scenes:?}");
    for scene in &scenes {
        let (code, stdout, stderr) = run(1, &["check", &scene.display().to_string()], &jobs);
        assert_eq!(code, 0, "{}:\n{stdout}\n{stderr}", scene.display());
        assert!(stdout.contains("ok: a run can start"), "{stdout}");
        let mesh = !std::fs::read_to_string(scene)
            .unwrap()
            .contains("source = \"matrices\"");
        if mesh {
            assert!(stdout.contains("memory: about"), "{stdout}");
            assert!(stdout.contains("mesh quality"), "{stdout}");
        }
    }
    // On 2 ranks it prints once.
    let (code, stdout, _) = run(2, &["check"], &jobs);
    assert_eq!(code, 0);
    assert_eq!(stdout.matches("ok: a run can start").count(), 1, "{stdout}");
}

#[test]
fn squeal_check_names_what_is_wrong() {
    let dir = scratch("broken");
    let cases = [
        (
            "[model]\nsource = \"abaqus\"\nfile = \"missing.inp\"\n[real_modes]\n",
            "missing.inp",
        ),
        (
            "[model]\nsource = \"brake\"\ntarget_dofs = 3000\n[statics]\n[contact.interfaces.no_such_pair]\nfriction = { law = \"coulomb\", mu = 0.4, slip_speed = 1e-3 }\n",
            "no_such_pair",
        ),
        (
            "[model]\nsource = \"brake\"\ntarget_dofs = 3000\n[real_modes]\ncuont = 3\n",
            "line 5",
        ),
    ];
    for (k, (scene, needle)) in cases.iter().enumerate() {
        let file = format!("broken{k}.toml");
        std::fs::write(dir.join(&file), scene).unwrap();
        let (code, stdout, stderr) = run(2, &["check", &file], &dir);
        assert_eq!(code, 1, "{file}:\n{stdout}\n{stderr}");
        assert!(
            stderr.contains(needle) && stderr.contains(&file) && !stderr.contains("MPI_ABORT"),
            "{file}: {stderr}"
        );
    }
}

#[test]
fn an_output_folder_that_cannot_be_made_ends_the_run_at_once_and_cleanly() {
    let dir = scratch("output");
    let start = Instant::now();
    let (code, _, stderr) = run(2, &["run", "-o", "/proc/no/such/folder"], &dir);
    let seconds = start.elapsed().as_secs_f64();
    println!("unwritable output folder refused after {seconds:.1} s");
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("/proc/no/such/folder") && stderr.contains("--output"),
        "{stderr}"
    );
    // Every rank got the same answer: no rank alone, no MPI_Abort (which waits for the
    // others before it kills them).
    assert!(
        !stderr.contains("MPI_ABORT") && !stderr.contains("alone"),
        "{stderr}"
    );

    let (code, _, stderr) = run(2, &["run", "-o", "typo/results"], &dir);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("parent folder typo does not exist"),
        "{stderr}"
    );
    assert!(!dir.join("typo").exists(), "a parent was made silently");
}

#[test]
fn a_run_that_fails_before_writing_leaves_no_empty_folder() {
    let dir = scratch("early");
    let scene = "[model]\nsource = \"abaqus\"\nfile = \"missing.inp\"\n[real_modes]\ncount = 4\n";
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let (code, _, stderr) = run(2, &["run", "scene.toml", "-o", "out"], &dir);
    assert_eq!(code, 1);
    assert!(stderr.contains("missing.inp"), "{stderr}");
    assert!(!dir.join("out").exists(), "an empty output folder was left");
    // A folder that existed before stays.
    std::fs::create_dir(dir.join("kept")).unwrap();
    let (code, _, _) = run(2, &["run", "scene.toml", "-o", "kept"], &dir);
    assert_eq!(code, 1);
    assert!(dir.join("kept").is_dir());
}

/// The README's commands as written: its first block is `scripts/run` and `scripts/test`
/// (executable; `.ci/run` calls the second, the default-scene test runs the first's job),
/// and every `squeal ...` line of its shell blocks runs: `scene` and `check` as they are, and
/// each `run` as `check` of the same scene (a run's cost belongs to the tests of its scene).
#[test]
fn the_readme_commands_run_as_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let blocks: Vec<&str> = readme
        .split("```sh\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap())
        .collect();
    let first: Vec<&str> = blocks[0]
        .lines()
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .collect();
    assert_eq!(first, ["scripts/run", "scripts/test"], "{}", blocks[0]);
    use std::os::unix::fs::PermissionsExt;
    for script in ["scripts/run", "scripts/test", ".ci/run"] {
        let mode = std::fs::metadata(root.join(script))
            .unwrap()
            .permissions()
            .mode();
        assert!(mode & 0o111 != 0, "{script} is not executable");
    }
    let ci = std::fs::read_to_string(root.join(".ci/run")).unwrap();
    assert!(ci.contains("scripts/test"), "{ci}");

    let dir = scratch("readme");
    std::os::unix::fs::symlink(root.join("jobs"), dir.join("jobs")).unwrap();
    // The README's own way to a scene of your own.
    assert!(readme.contains("`squeal scene --print-default > my-brake.toml`"));
    let (code, default, _) = run(1, &["scene", "--print-default"], &dir);
    assert_eq!(code, 0);
    std::fs::write(dir.join("my-brake.toml"), default).unwrap();
    let mut ran = 0;
    for line in blocks.iter().flat_map(|b| b.lines()) {
        let command = line.split('#').next().unwrap();
        let words: Vec<&str> = command.split_whitespace().collect();
        let Some(at) = words
            .iter()
            .position(|w| w.ends_with("target/release/squeal"))
        else {
            continue;
        };
        let args = &words[at + 1..];
        let args: Vec<&str> = match args.first() {
            Some(&"run") => {
                let scene = args.get(1).filter(|a| !a.starts_with('-'));
                ["check"].into_iter().chain(scene.copied()).collect()
            }
            _ => args.iter().copied().take_while(|a| *a != ">").collect(),
        };
        let (code, stdout, stderr) = run(1, &args, &dir);
        assert_eq!(code, 0, "README: {line}\n{stdout}\n{stderr}");
        ran += 1;
    }
    assert!(ran >= 4, "{ran} squeal lines in the README");
}
