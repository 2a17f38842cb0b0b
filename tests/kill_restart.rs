//! A 2-rank transient killed with SIGKILL after a checkpoint and before the next, then run
//! again with `--restart`, ends where the uninterrupted run ends. The resumed run restarts
//! its Newton iterations from a fresh Jacobian, so it differs from the uninterrupted one at
//! the solver's tolerance, amplified by the squeal's growth like any other perturbation. The
//! measure of that noise is run here: the same scene on 1 rank against 2 differs by the same
//! tolerance entering at every step (measured 1e-10 of the torque, 3e-5 of the sensor's
//! velocity). The resumed run must stay within 3 times it (measured 0.6-1.8 times).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

use squeal::measure::{exceeds, max_abs_difference, nan_max};

#[path = "support/launch.rs"]
mod launch;

const STEPS: usize = 4000;
const CHECKPOINT_EVERY: usize = 500;

fn scene() -> String {
    format!(
        "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = 40\n[reduction]\n\
         [transient]\nstep = 2.0e-6\nsteps = {STEPS}\nmode = 2\namplitude = 1.0e-8\n\
         checkpoint_every = {CHECKPOINT_EVERY}\n\
         [transient.sensors]\npad = [0.12, 0.0, 0.0295]\n"
    )
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-kill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("scene.toml"), scene()).unwrap();
    dir
}

fn series(dir: &Path, name: &str) -> Vec<f64> {
    hdf5::File::open(dir.join("results.h5"))
        .and_then(|f| f.dataset(name))
        .and_then(|d| d.read_raw::<f64>())
        .unwrap_or_else(|e| panic!("{}: {name}: {e}", dir.display()))
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// Starts the scene on 2 ranks, waits for its first checkpoint, then for a third of a
/// checkpoint interval, and kills every rank with SIGKILL (mpirun then ends).
fn run_and_kill(dir: &Path) -> usize {
    let mut mpirun = Command::new("mpirun")
        .args([
            "-n",
            "2",
            env!("CARGO_BIN_EXE_squeal"),
            "run",
            "scene.toml",
            "-o",
            "out",
        ])
        .current_dir(dir)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
        .env("SQUEAL_PROGRESS", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("mpirun starts (scripts/setup installs openmpi-bin)");
    let checkpoint = dir.join("out/checkpoint.h5");
    let start = Instant::now();
    let first = loop {
        if let Some(t) = modified(&checkpoint) {
            break t;
        }
        assert!(
            mpirun.try_wait().unwrap().is_none(),
            "the run ended before its first checkpoint"
        );
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no checkpoint in 300 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    // The steps between two checkpoints, timed from the first: kill a third of the way in.
    let written = Instant::now();
    let since = first.elapsed().unwrap_or_default();
    std::thread::sleep(Duration::from_millis(300).saturating_sub(since));
    let ranks = String::from_utf8(
        Command::new("pgrep")
            .args(["-P", &mpirun.id().to_string()])
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap();
    let pids: Vec<&str> = ranks.split_whitespace().collect();
    assert_eq!(pids.len(), 2, "ranks of mpirun {}: {ranks}", mpirun.id());
    for pid in &pids {
        Command::new("kill").args(["-KILL", pid]).status().unwrap();
    }
    let at_kill = written.elapsed().as_secs_f64();
    let status = mpirun.wait().unwrap();
    assert!(!status.success(), "a killed run ended well");
    println!("killed {at_kill:.2} s after the first checkpoint appeared");
    // How far it had come: rows of the stored time (written in chunks as the run goes; 0
    // when the killed file does not open).
    hdf5::File::open(dir.join("out/transient.h5"))
        .and_then(|f| f.dataset("time"))
        .map(|d| d.shape()[0])
        .unwrap_or(0)
}

#[test]
fn a_transient_killed_between_checkpoints_resumes_to_the_uninterrupted_run() {
    let whole = scratch("whole");
    let out = launch::squeal_run(
        2,
        &["run", "scene.toml", "-o", "out"],
        &whole,
        &[],
        Duration::from_secs(600),
    );
    assert!(out.status.is_some_and(|s| s.success()), "{}", out.stderr);

    let killed = scratch("killed");
    let rows_at_kill = run_and_kill(&killed);
    println!(
        "the killed run had stored {rows_at_kill} of {} steps",
        STEPS + 1
    );
    assert!(
        rows_at_kill < STEPS + 1,
        "the killed run had finished: {rows_at_kill} rows"
    );
    let again = launch::squeal_run(
        2,
        &["run", "scene.toml", "-o", "out", "--restart"],
        &killed,
        &[],
        Duration::from_secs(600),
    );
    assert!(
        again.status.is_some_and(|s| s.success()),
        "the restart failed:\n{}\n{}",
        again.stdout,
        again.stderr
    );
    let one = scratch("one-rank");
    let out = launch::squeal_run(
        1,
        &["run", "scene.toml", "-o", "out"],
        &one,
        &[],
        Duration::from_secs(600),
    );
    assert!(out.status.is_some_and(|s| s.success()), "{}", out.stderr);
    let (a, b, c) = (whole.join("out"), killed.join("out"), one.join("out"));
    for name in [
        "transient/time",
        "transient/braking_torque",
        "transient/sensors/pad/velocity",
    ] {
        let (x, y, z) = (series(&a, name), series(&b, name), series(&c, name));
        let scale = nan_max(squeal::measure::largest_abs(&x), f64::MIN_POSITIVE);
        let noise = max_abs_difference(&x, &z) / scale;
        let bound = nan_max(3.0 * noise, 1e-14);
        assert!(
            !x.is_empty() && x.len() % (STEPS + 1) == 0,
            "{name}: {} values in the uninterrupted run",
            x.len()
        );
        assert_eq!(y.len(), x.len(), "{name}: rows after the restart");
        let diff = max_abs_difference(&x, &y) / scale;
        println!(
            "{name}: the resumed run differs by {diff:.1e} of the largest value, 1 rank by {noise:.1e}"
        );
        assert!(
            !exceeds(diff, bound),
            "{name}: {diff:e} of the largest (bound {bound:e})"
        );
    }
}
