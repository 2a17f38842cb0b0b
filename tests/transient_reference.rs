//! The transient driver keeps its trajectories: the braking torque of a stored run
//! (`tests/data/transient-reference`: 2,000 steps of the small reduced brake with retries of
//! stalled steps, from commit 7eefc9c) is met again to round-off.
//!
//! Round-off here is what a different summation order leaves, amplified by the run's own
//! dynamics: the same scene on 2 ranks against 1 measures it in this test (about 3e-10 of the
//! torque's range on the machine that stored the reference). Another CPU's BLAS kernels
//! round differently, as another rank count does; the stored run must be met within 10 times
//! that noise (a change of the algorithm, such as another step size or correction, moves the
//! torque by the Newton tolerance, 1e-6 of it and more).

use std::path::{Path, PathBuf};
use std::time::Duration;

use squeal::measure::{exceeds, largest_abs, max_abs_difference, nan_max, smallest};

#[path = "support/launch.rs"]
mod launch;

fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/transient-reference")
}

/// The stored time and torque columns.
fn stored() -> (Vec<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(reference_dir().join("torque.txt")).unwrap();
    let mut time = Vec::new();
    let mut torque = Vec::new();
    for (k, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#'))
    {
        let mut fields = line.split_whitespace().map(|f| {
            f.parse::<f64>()
                .unwrap_or_else(|e| panic!("torque.txt line {}: {e}", k + 1))
        });
        time.push(fields.next().unwrap());
        torque.push(fields.next().unwrap());
    }
    (time, torque)
}

fn run(ranks: usize) -> (Vec<f64>, Vec<f64>) {
    let dir = std::env::temp_dir().join(format!("squeal-reference-{}-{ranks}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(reference_dir().join("scene.toml"), dir.join("scene.toml")).unwrap();
    let out = launch::squeal_run(
        ranks,
        &["run", "scene.toml", "-o", "out"],
        &dir,
        &[],
        Duration::from_secs(600),
    );
    assert!(
        out.status.is_some_and(|s| s.success()),
        "{ranks} ranks:\n{}\n{}",
        out.stdout,
        out.stderr
    );
    let file = hdf5::File::open(dir.join("out/transient.h5")).unwrap();
    let read = |name: &str| file.dataset(name).unwrap().read_raw::<f64>().unwrap();
    let series = (read("time"), read("braking_torque"));
    let _ = std::fs::remove_dir_all(&dir);
    series
}

#[test]
fn the_stored_torque_of_2000_steps_is_met_to_round_off() {
    let (time, torque) = stored();
    assert_eq!(torque.len(), 2001, "the stored run's rows");
    let (time_1, torque_1) = run(1);
    let (_, torque_2) = run(2);
    assert_eq!(time_1.len(), time.len(), "steps of the run");
    let time_shift = max_abs_difference(&time, &time_1);
    assert!(
        !exceeds(time_shift, 1e-15),
        "times moved by {time_shift:e} s"
    );

    let minimum = smallest(torque.iter().copied());
    let range = largest_abs(&torque.iter().map(|t| t - minimum).collect::<Vec<_>>());
    assert!(range > 100.0, "the stored torque swings by {range} N m");
    let noise = max_abs_difference(&torque_1, &torque_2) / range;
    let bound = nan_max(10.0 * noise, 1e-14);
    let difference = max_abs_difference(&torque, &torque_1) / range;
    println!(
        "torque over {} steps: the stored run is met to {difference:.1e} of its range \
         {range:.1} N m; 2 ranks against 1: {noise:.1e}",
        torque.len() - 1
    );
    assert!(
        !exceeds(difference, bound),
        "the torque moved by {difference:e} of its range (bound {bound:e}, 10 x the 1-vs-2-rank noise)"
    );
}
