//! The MPI suite: every test that needs PETSc/SLEPc, in one binary (MPI can be initialized once
//! per process), run under `mpirun -n 1` and `mpirun -n 2` by scripts/test.
//!
//! Each test returns Ok or a message; the verdict is reduced over ranks so every rank agrees.
//! Usage: `mpirun -n N target/release/deps/mpi_suite-* [filter]`.

mod suite;

use std::time::Instant;

use mpi::traits::*;
use squeal::la::Petsc;

fn main() {
    // `cargo test` runs this binary once without mpirun; scripts/test runs it under
    // `mpirun -n 1` and `-n 2`, so a plain run would only repeat the 1-rank pass.
    let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    if !launched && std::env::var_os("SQUEAL_SUITE_ANYWAY").is_none() {
        println!(
            "mpi suite: not started by mpirun; scripts/test runs it on 1 and 2 ranks (SQUEAL_SUITE_ANYWAY=1 runs it here)"
        );
        return;
    }
    let universe = mpi::initialize().expect("MPI initializes once");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc initializes");
    let filter = std::env::args().nth(1).filter(|a| !a.starts_with('-'));
    let tests = suite::all();
    let rank = petsc.rank();
    let (mut passed, mut failed) = (0, 0);
    for (name, test) in tests {
        if let Some(f) = &filter {
            if !name.contains(f.as_str()) {
                continue;
            }
        }
        let start = Instant::now();
        let result = test(&petsc);
        let ok_here = result.is_ok() as i32;
        let mut ok_all = 0;
        petsc.world().all_reduce_into(
            &ok_here,
            &mut ok_all,
            mpi::collective::SystemOperation::min(),
        );
        if let Err(msg) = &result {
            eprintln!("[rank {rank}] {name}: {msg}");
        }
        if ok_all == 1 {
            passed += 1;
        } else {
            failed += 1;
        }
        if rank == 0 {
            println!(
                "test {name} ... {} ({:.2} s)",
                if ok_all == 1 { "ok" } else { "FAILED" },
                start.elapsed().as_secs_f64()
            );
        }
    }
    if rank == 0 {
        println!(
            "mpi suite on {} rank(s): {passed} passed, {failed} failed",
            petsc.size()
        );
    }
    drop(petsc);
    drop(universe);
    std::process::exit(if failed == 0 { 0 } else { 1 });
}
