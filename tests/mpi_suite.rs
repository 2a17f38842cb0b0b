//! The MPI suite: every test that needs PETSc/SLEPc, in one binary (MPI can be initialized once
//! per process), run under `mpirun -n 1`, `-n 2` and (a subset) `-n 4` by scripts/test.
//!
//! Each test returns Ok, Ok after `common::skip` (nothing to compare on this rank count), or a
//! message; the verdict is reduced over ranks so every rank agrees. Every test has a time limit
//! (`suite::time_limit`): a rank whose test overruns it prints which and aborts, so mpirun exits
//! non-zero instead of hanging. The first line says how many tests were selected, the last how
//! many ran, so a crash in between is visible to scripts/test.
//!
//! Usage: `mpirun -n N target/release/deps/mpi_suite-* [--shard=K/S] [name-substring...]`.
//! `--shard=K/S` runs the K-th (0-based) of S parts of the selected tests, balanced by their
//! expected times: scripts/test runs the 1-rank pass as two 1-rank shards side by side, one per
//! core.

mod suite;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mpi::traits::*;
use squeal::la::Petsc;

fn main() {
    // Neither `cargo test` nor `cargo nextest` runs this binary: scripts/test runs it under
    // mpirun. A plain run (or nextest's `--list`) therefore finds no tests.
    let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    if !launched && std::env::var_os("SQUEAL_SUITE_ANYWAY").is_none() {
        if !std::env::args().any(|a| a == "--list") {
            println!(
                "mpi suite: not started by mpirun; scripts/test runs it on 1, 2 and 4 ranks (SQUEAL_SUITE_ANYWAY=1 runs it here)"
            );
        }
        return;
    }
    let universe = mpi::initialize().expect("MPI initializes once");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc initializes");
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let selected: Vec<_> = suite::all()
        .into_iter()
        .filter(|(name, _)| filters.is_empty() || filters.iter().any(|f| name.contains(f.as_str())))
        .collect();
    let shard = std::env::args().find_map(|a| {
        let (k, s) = a.strip_prefix("--shard=")?.split_once('/')?;
        Some((k.parse::<usize>().ok()?, s.parse::<usize>().ok()?))
    });
    let (rank, size) = (petsc.rank(), petsc.size());
    let tests = match shard {
        Some((k, s)) if k < s => suite::shard(selected, k, s),
        Some(_) => panic!("--shard=K/S needs K < S"),
        None => selected,
    };
    if rank == 0 {
        let part = shard.map_or(String::new(), |(k, s)| format!(" (shard {k} of {s})"));
        println!("mpi suite: {} tests on {size} rank(s){part}", tests.len());
    }
    let watchdog = Watchdog::start(rank);
    let (mut passed, mut failed, mut skipped) = (0, 0, 0);
    for (name, test) in &tests {
        let limit = suite::time_limit(name, size);
        watchdog.arm(name, limit);
        let start = Instant::now();
        let result = test(&petsc);
        let skip_reason = suite::common::take_skip();
        watchdog.disarm();
        let verdict = Verdict::of(&result, skip_reason.is_some());
        let all = reduce_verdict(&petsc, verdict);
        if let Err(msg) = &result {
            eprintln!("[rank {rank}] {name}: {msg}");
        }
        match all {
            Verdict::Passed => passed += 1,
            Verdict::Skipped => skipped += 1,
            Verdict::Failed => failed += 1,
        }
        if rank == 0 {
            let word = match all {
                Verdict::Passed => "ok".to_string(),
                Verdict::Skipped => format!("skipped ({})", skip_reason.unwrap_or_default()),
                Verdict::Failed => "FAILED".to_string(),
            };
            println!(
                "test {name} ... {word} ({:.2} s of {} s)",
                start.elapsed().as_secs_f64(),
                limit.as_secs()
            );
        }
    }
    if rank == 0 {
        println!(
            "mpi suite on {size} rank(s): {passed} passed, {failed} failed, {skipped} skipped; ran {} of {}",
            passed + failed + skipped,
            tests.len()
        );
    }
    drop(petsc);
    drop(universe);
    std::process::exit(if failed == 0 { 0 } else { 1 });
}

/// One test's outcome; ordered so that the minimum over ranks is the verdict of the run.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Verdict {
    Failed = 0,
    Skipped = 1,
    Passed = 2,
}

impl Verdict {
    fn of(result: &suite::TestResult, skipped: bool) -> Verdict {
        match (result, skipped) {
            (Err(_), _) => Verdict::Failed,
            (Ok(()), true) => Verdict::Skipped,
            (Ok(()), false) => Verdict::Passed,
        }
    }
}

/// Failed if any rank failed; skipped if any rank skipped and none failed.
fn reduce_verdict(petsc: &Petsc, here: Verdict) -> Verdict {
    let mut all = 0i32;
    petsc.world().all_reduce_into(
        &(here as i32),
        &mut all,
        mpi::collective::SystemOperation::min(),
    );
    match all {
        0 => Verdict::Failed,
        1 => Verdict::Skipped,
        _ => Verdict::Passed,
    }
}

/// A thread that aborts this rank when the running test overruns its time limit: mpirun then
/// ends every rank with a non-zero status, where a deadlocked collective would wait forever.
struct Watchdog {
    running: Arc<Mutex<Option<(String, Instant, Duration)>>>,
}

impl Watchdog {
    fn start(rank: i32) -> Watchdog {
        let running: Arc<Mutex<Option<(String, Instant, Duration)>>> = Arc::new(Mutex::new(None));
        let watched = Arc::clone(&running);
        std::thread::spawn(move || loop {
            std::thread::sleep(Duration::from_millis(500));
            let overrun = watched
                .lock()
                .map(|r| {
                    r.clone()
                        .filter(|(_, start, limit)| start.elapsed() > *limit)
                })
                .unwrap_or(None);
            if let Some((name, _, limit)) = overrun {
                eprintln!(
                    "[rank {rank}] test {name} exceeded its time limit of {} s: aborting the suite",
                    limit.as_secs()
                );
                std::process::abort();
            }
        });
        Watchdog { running }
    }

    fn arm(&self, name: &str, limit: Duration) {
        *self.running.lock().unwrap() = Some((name.to_string(), Instant::now(), limit));
    }

    fn disarm(&self) {
        *self.running.lock().unwrap() = None;
    }
}
