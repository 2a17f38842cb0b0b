//! Failures on one rank end every rank, quickly, with the error and a non-zero exit; what was
//! written before stays readable (DESIGN.md §4). Faults are provoked with SQUEAL_FAULT
//! (src/fault.rs) in every stage of a scene that runs them all on the small brake, and a NaN
//! in the transient's start; a restart extends a run and refuses another scene (before
//! anything is computed or written).

use std::path::{Path, PathBuf};
use std::time::Duration;

#[path = "support/launch.rs"]
mod launch;

/// Every stage of a squeal run, short: 4,000-DOF brake, contact preload, 10 real modes,
/// projected complex modes, reduction, 20 transient steps.
const SCENE: &str = r#"
[model]
source = "brake"
target_dofs = 4000
pressure_bar = 20.0
[contact]
disc_speed = 6.2832
[contact.sliding]
normal = { law = "exponential", p0 = 1.0e6, lambda = 2.0e5 }
friction = { law = "coulomb", mu = 0.4, slip_speed = 1.0e-3 }
[statics]
[real_modes]
count = 10
[complex_modes]
method = "projected"
[reduction]
[transient]
step = 2.0e-6
steps = 20
start = "mode"
mode = 2
amplitude = 1.0e-9
[output]
directory = "results"
"#;

/// A hang is reported after this long (a run of the scene takes ~5 s on 2 ranks).
const DEADLINE: Duration = Duration::from_secs(120);

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-faults-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    dir
}

fn run_with_fault(dir: &Path, fault: &str) -> launch::Outcome {
    let env = [("SQUEAL_FAULT", fault), ("SQUEAL_PROGRESS", "0")];
    launch::squeal_run(2, &["run", "scene.toml"], dir, &env, DEADLINE)
}

/// The run ended with the message and squeal's own exit status: 1 for an error (said by all
/// ranks, or by one rank that ended the others), 70 for a panic (the hook's MPI_Abort). A
/// crash after the message (a signal, another code) fails.
fn assert_ends_with(out: &launch::Outcome, what: &str, needle: &str) {
    let log = format!("stdout:\n{}\nstderr:\n{}", out.stdout, out.stderr);
    let status = out
        .status
        .unwrap_or_else(|| panic!("{what}: hung ({DEADLINE:?})\n{log}"));
    let expected = if what == "panic" { 70 } else { 1 };
    assert_eq!(
        status.code(),
        Some(expected),
        "{what}: exit status {status}, not squeal's {expected}\n{log}"
    );
    assert!(
        out.stderr.contains(needle),
        "{what}: '{needle}' not said\n{log}"
    );
}

#[test]
fn an_error_on_one_rank_in_any_stage_ends_every_rank() {
    let dir = scratch("stages");
    let stages = [
        "mesh",
        "assembly",
        "contact pairing",
        "static preload",
        "real modes",
        "complex modes (projected)",
        "reduction",
        "transient",
    ];
    for stage in stages {
        let out = run_with_fault(&dir, &format!("{stage}@1"));
        let needle = format!("injected fault in stage '{stage}' on rank 1");
        assert_ends_with(&out, stage, &needle);
    }
}

#[test]
fn a_panic_on_one_rank_ends_every_rank() {
    let dir = scratch("panic");
    let out = run_with_fault(&dir, "static preload@1:panic");
    assert_ends_with(&out, "panic", "injected panic in stage 'static preload'");
}

#[test]
fn a_failure_on_every_rank_is_said_once() {
    let dir = scratch("collective");
    let out = run_with_fault(&dir, "real modes@*");
    assert_ends_with(&out, "collective", "squeal: error: injected fault");
    assert!(
        !out.stderr.contains("alone"),
        "a collective failure is not a lone one:\n{}",
        out.stderr
    );
}

/// A write that fails on one rank (a full disk or a quota; measured: the run then hung in the
/// collective close of the HDF5 file) ends every rank with the file named.
#[test]
fn a_failed_write_on_one_rank_ends_every_rank() {
    let dir = scratch("write");
    for (file, rank) in [("transient.h5", 1), ("results.h5", 0)] {
        let out = run_with_fault(&dir, &format!("write {file}@{rank}"));
        assert_ends_with(&out, file, &format!("writing {file} failed"));
    }
}

#[test]
fn results_written_before_a_failure_stay_readable() {
    let dir = scratch("kept");
    let out = run_with_fault(&dir, "transient@1");
    assert_ends_with(&out, "transient", "injected fault in stage 'transient'");
    let file = hdf5::File::open(dir.join("results/results.h5")).expect("results.h5 opens");
    for group in ["model", "static", "modes", "reduced"] {
        assert!(
            file.group(group).is_ok(),
            "/{group} missing from results.h5"
        );
    }
}

#[test]
fn an_output_folder_that_cannot_be_made_ends_every_rank() {
    let dir = scratch("folder");
    let out = launch::squeal_run(
        2,
        &[
            "run",
            "scene.toml",
            "--output",
            "/proc/squeal-cannot-write-here",
        ],
        &dir,
        &[("SQUEAL_PROGRESS", "0")],
        DEADLINE,
    );
    assert_ends_with(&out, "output folder", "/proc/squeal-cannot-write-here");
}

#[test]
fn a_nan_in_the_transient_stops_it_naming_the_step() {
    let dir = scratch("nan");
    let out = run_with_fault(&dir, "transient@1:nan");
    assert_ends_with(&out, "nan", "time step 0 (t = 0.000000e0 s)");
    assert!(out.stderr.contains("not finite"), "{}", out.stderr);
    let file = hdf5::File::open(dir.join("results/results.h5")).expect("results.h5 opens");
    assert!(
        file.group("modes").is_ok(),
        "/modes missing from results.h5"
    );
    // The report of what was computed, its answer saying why the run stopped.
    let report = std::fs::read_to_string(dir.join("results/report.html")).expect("report.html");
    let answer = report
        .split("id=\"answer\"")
        .nth(1)
        .expect("an answer section");
    assert!(
        answer.contains("the run stopped early") && answer.contains("not finite"),
        "{answer}"
    );
    assert!(
        report.contains("id=\"complex-modes\""),
        "no complex modes in the report"
    );
}

#[test]
fn a_factorization_that_cannot_fit_says_how_much_it_needs() {
    // MUMPS may use 1 MB per rank (ICNTL(23); squeal otherwise sets it to the node's
    // available memory over its ranks): the static preload's factorization is refused before
    // it allocates, and the error says what it needs and what to do.
    let dir = scratch("memory");
    let args = ["run", "scene.toml", "--", "-static_mat_mumps_icntl_23", "1"];
    let out = launch::squeal_run(2, &args, &dir, &[("SQUEAL_PROGRESS", "0")], DEADLINE);
    assert_ends_with(&out, "memory", "MB per rank in core");
    assert!(
        out.stderr.contains("-static_mat_mumps_icntl_22 1"),
        "{}",
        out.stderr
    );
}

#[test]
fn a_restart_extends_the_run_and_refuses_another_scene() {
    let dir = scratch("restart");
    let env = [("SQUEAL_PROGRESS", "0")];
    let run = |args: &[&str]| launch::squeal_run(2, args, &dir, &env, DEADLINE);
    let first = run(&["run", "scene.toml"]);
    assert!(
        first.status.is_some_and(|s| s.success()),
        "{}",
        first.stderr
    );
    // Another reduction basis size: the state means something else; refused, naming it.
    std::fs::write(
        dir.join("scene.toml"),
        SCENE.replace("count = 10", "count = 12"),
    )
    .unwrap();
    let results = dir.join("results").join("results.h5");
    let written = std::fs::metadata(&results)
        .and_then(|m| m.modified())
        .unwrap();
    let other = run(&["run", "scene.toml", "--restart"]);
    assert_ends_with(&other, "another scene", "the scene's [real_modes] differs");
    // Refused before the stages ahead of the transient: the first run's results stay.
    let kept = std::fs::metadata(&results)
        .and_then(|m| m.modified())
        .unwrap();
    assert_eq!(written, kept, "a refused restart rewrote results.h5");
    // More steps and another Newton variant: the same run, extended.
    let longer = SCENE.replace("steps = 20", "steps = 30\nnewton = \"full\"");
    std::fs::write(dir.join("scene.toml"), longer).unwrap();
    let extended = run(&["run", "scene.toml", "--restart"]);
    assert!(
        extended.status.is_some_and(|s| s.success()),
        "{}",
        extended.stderr
    );
    assert!(extended.stdout.contains("30 steps"), "{}", extended.stdout);
}
