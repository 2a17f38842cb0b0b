//! Real-mode benchmark on a structured Hex8I block (run under mpirun by scripts/bench):
//! assembly, MUMPS Cholesky factorization (time, factor entries, memory), one solve, N real
//! modes; optionally the MUMPS ordering study, and export of K and M in PETSc binary format
//! for SLEPc's own ex7 (the baseline scripts/bench runs on the same matrices).
//!
//!   mpirun -n 2 target/release/deps/real_modes-* --dofs 30000,150000 --modes 250

use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use squeal::eigen::real_modes::{real_modes, RealModeRequest};
use squeal::fem::petsc::assemble_system;
use squeal::la::{DirectSolver, Factorization, Petsc};
use squeal::mesh::material::Material;
use squeal::mesh::structured::block;
use squeal::mesh::Clamp;
use squeal::mesh::ElementKind;
use squeal::parallel;

#[derive(Parser)]
struct Args {
    /// Target sizes (DOF), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "30000,150000,600000")]
    dofs: Vec<usize>,
    /// Number of real modes (0: skip the eigen-solve).
    #[arg(long, default_value_t = 250)]
    modes: usize,
    /// Write K and M of each size in PETSc binary format to this folder (for SLEPc's ex7).
    #[arg(long)]
    export: Option<PathBuf>,
    /// Also factorize with each MUMPS ordering (AMD, AMF, PORD, QAMD).
    #[arg(long)]
    orderings: bool,
    /// cargo bench passes --bench; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

/// Block [4m, 2m, m] cells of Hex8I, clamped on the x = 0 face: DOF = 3 (4m)(2m+1)(m+1).
fn dofs_of(m: usize) -> usize {
    3 * (4 * m) * (2 * m + 1) * (m + 1)
}

fn blas_in_use() -> String {
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    let mut libs: Vec<String> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.contains("blas") || p.contains("lapack"))
        .map(String::from)
        .collect();
    libs.sort();
    libs.dedup();
    libs.join(", ")
}

fn main() {
    let args = Args::parse();
    let universe = mpi::initialize().expect("MPI");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc");
    let root = petsc.rank() == 0;
    let ranks = petsc.size();
    if root {
        println!("BLAS/LAPACK mapped in this process: {}", blas_in_use());
        println!(
            "{:>8} {:>5} {:>9} {:>9} {:>11} {:>9} {:>9} {:>9} {:>9} {:>10} {:>9}",
            "DOF",
            "ranks",
            "assembly",
            "factor",
            "entries",
            "MUMPS MB",
            "solve",
            "modes",
            "time",
            "asm/modes",
            "peak MiB"
        );
    }
    let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
    for &target in &args.dofs {
        let m = (2..200)
            .min_by_key(|&m| dofs_of(m).abs_diff(target))
            .unwrap();
        let mesh = block(
            [
                0.4 * m as f64 / 10.0,
                0.2 * m as f64 / 10.0,
                0.1 * m as f64 / 10.0,
            ],
            [4 * m, 2 * m, m],
            ElementKind::Hex8I,
            steel.clone(),
        );
        let t = Instant::now();
        let system = assemble_system(&petsc, &mesh, &[Clamp::all("u0")]).expect("assembly");
        let t_asm = parallel::max(petsc.world(), t.elapsed().as_secs_f64());
        let n = system.stiffness.global_rows();
        if let Some(dir) = &args.export {
            if root {
                std::fs::create_dir_all(dir).expect("export folder");
            }
            parallel::barrier(petsc.world());
            system
                .stiffness
                .save_binary(&petsc, &dir.join(format!("K-{n}.petsc")))
                .unwrap();
            system
                .mass
                .save_binary(&petsc, &dir.join(format!("M-{n}.petsc")))
                .unwrap();
        }

        let t = Instant::now();
        let solver =
            DirectSolver::factorize(&petsc, &system.stiffness, Factorization::Cholesky, "bench_")
                .expect("factorization");
        let t_fac = parallel::max(petsc.world(), t.elapsed().as_secs_f64());
        let report = solver.report();
        let mut b = system.stiffness.new_vector().unwrap();
        b.set_all(1.0).unwrap();
        let mut x = b.duplicate().unwrap();
        let reps = 5;
        let t = Instant::now();
        for _ in 0..reps {
            solver.solve(&b, &mut x).unwrap();
        }
        let t_solve = parallel::max(petsc.world(), t.elapsed().as_secs_f64()) / reps as f64;
        drop(solver);

        if args.orderings {
            for (icntl, name) in [(0, "AMD"), (2, "AMF"), (4, "PORD"), (6, "QAMD")] {
                petsc
                    .set_option("-order_mat_mumps_icntl_7", Some(&icntl.to_string()))
                    .unwrap();
                let t = Instant::now();
                let s = DirectSolver::factorize(
                    &petsc,
                    &system.stiffness,
                    Factorization::Cholesky,
                    "order_",
                )
                .expect("factorization");
                let secs = parallel::max(petsc.world(), t.elapsed().as_secs_f64());
                let r = s.report();
                if root {
                    println!(
                        "ORDERING dofs={n} ranks={ranks} icntl7={icntl} requested={name} used={} entries={:.3e} factor_s={secs:.2} mumps_mb={}",
                        r.ordering_name(), r.factor_entries, r.memory_mb
                    );
                }
            }
        }

        let (mut t_modes, mut nconv, mut low_hz, mut top_hz) = (0.0, 0, 0.0, 0.0);
        if args.modes > 0 {
            let request = RealModeRequest {
                count: args.modes,
                tolerance: 1e-10,
                ..Default::default()
            };
            let t = Instant::now();
            let modes = real_modes(&petsc, &system.stiffness, &system.mass, false, &request, "")
                .expect("modes");
            t_modes = parallel::max(petsc.world(), t.elapsed().as_secs_f64());
            nconv = modes.frequencies_hz.len();
            top_hz = *modes.frequencies_hz.last().unwrap();
            low_hz = modes.frequencies_hz[0];
        }
        let peak = parallel::max(petsc.world(), petsc.peak_memory()) / (1024.0 * 1024.0);
        if root {
            println!(
                "{n:>8} {ranks:>5} {t_asm:>9.3} {t_fac:>9.3} {:>11.3e} {:>9} {t_solve:>9.4} {nconv:>9} {t_modes:>9.2} {:>9.1}% {peak:>9.0}",
                report.factor_entries,
                report.memory_mb,
                if t_modes > 0.0 { 100.0 * t_asm / t_modes } else { 0.0 }
            );
            println!(
                "RESULT dofs={n} ranks={ranks} assembly_s={t_asm:.4} factor_s={t_fac:.3} factor_entries={:.4e} ordering={} mumps_mb_total={} mumps_mb_max_rank={} solve_s={t_solve:.5} modes={nconv} modes_s={t_modes:.3} lowest_hz={low_hz:.6} highest_hz={top_hz:.1} peak_rss_mib_max_rank={peak:.0}",
                report.factor_entries, report.ordering_name(), report.memory_mb, report.memory_max_mb
            );
        }
    }
}
