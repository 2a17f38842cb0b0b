//! Transient benchmark, speed against error (run under mpirun by scripts/bench):
//!
//! 1. Memory bandwidth, measured in the same run as every figure compared with it: a read
//!    (sum of one array) and a triad (a = b + s c), by rank 0 alone and by every rank at once.
//! 2. The reduced brake: the superelement reduction of a brake of `--dofs` with `--modes` real
//!    modes, then `--steps` steps of the nonlinear transient from the kicked static state, once
//!    per `--factors` value (`jacobian_factor`: distributed, single, per-rank): reduction time,
//!    reduced size, factor size, seconds per step and per iteration, and the cost model of a
//!    step: for the solve, the linear force (K x), the contact evaluations and the contact
//!    tangent's products, the calls per step, the bytes each call streams (stored entries x
//!    (value + index) bytes; the factor's values x its passes), the bound (bytes over the
//!    bandwidth of all ranks at once: a part perfectly split and streaming from memory; a
//!    part that fits in cache can beat it) and the measured time, with their ratio; then
//!    150,000 steps extrapolated from the measured rate.
//! 3. Step size against error: the reduced brake of `--study-dofs` over `--study-time` with
//!    steps `--study-steps` (µs) against a reference at a quarter of the smallest step: error
//!    of a sensor's velocity (max over common sample times, relative to its largest value)
//!    and of the braking torque fluctuation, with the cost of each run.
//!
//!   mpirun -n 2 target/release/deps/transient-* --dofs 600000 --modes 200 --steps 500
//!
//! `--gemm-forwarding on,gemm,off` runs each factor with MUMPS' one-column GEMMs and TRSMs
//! sent to GEMV and TRSV, only its GEMMs, and none (la::one_column_gemm), the bandwidth
//! measured once for all.

use squeal::measure::nan_max;
use std::time::Instant;

use clap::Parser;
use squeal::la::Petsc;
use squeal::pipeline::{run_with, RunOptions, RunSummary};
use squeal::report::summary::TransientSummary;
use squeal::scene::Scene;

#[derive(Parser)]
struct Args {
    /// Target size of the reduced brake (DOF); 0 skips part 2.
    #[arg(long, default_value_t = 600_000)]
    dofs: usize,
    #[arg(long, default_value_t = 200)]
    modes: usize,
    #[arg(long, default_value_t = 500)]
    steps: usize,
    /// The transient's `jacobian_factor` values to run (one pipeline run each).
    #[arg(long, value_delimiter = ',', default_value = "distributed,single")]
    factors: Vec<String>,
    /// MUMPS' one-column GEMMs and TRSMs sent to GEMV and TRSV (`on`, the default), only the
    /// GEMMs (`gemm`), or none (`off`): one pipeline run per value and factor
    /// (la::one_column_gemm).
    #[arg(long, value_delimiter = ',', default_value = "on")]
    gemm_forwarding: Vec<String>,
    /// The transient's `first_jacobian` in part 2: `consistent` (the default) or `mock`.
    #[arg(long, default_value = "consistent")]
    first_jacobian: String,
    /// Target size of the step-size study (DOF); 0 skips part 3.
    #[arg(long, default_value_t = 12_000)]
    study_dofs: usize,
    /// Simulated time of the study (s) and its step sizes (µs).
    #[arg(long, default_value_t = 1e-3)]
    study_time: f64,
    #[arg(long, value_delimiter = ',', default_value = "4,2,1,0.5")]
    study_steps: Vec<f64>,
    /// Doubles per triad array and rank.
    #[arg(long, default_value_t = 1 << 24)]
    stream_len: usize,
    /// cargo bench passes --bench; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn scene(
    dofs: usize,
    modes: usize,
    step: f64,
    steps: usize,
    amplitude: f64,
    factor: &str,
    first_jacobian: &str,
) -> String {
    format!(
        "[model]\nsource = \"brake\"\ntarget_dofs = {dofs}\npressure_bar = 20.0\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = {modes}\n\
         [reduction]\n\
         [transient]\nstep = {step:e}\nsteps = {steps}\nmode = 2\namplitude = {amplitude:e}\n\
         state_interval = 0.0\ncheckpoint_every = 0\njacobian_factor = \"{factor}\"\n\
         first_jacobian = \"{first_jacobian}\"\n\
         [transient.sensors]\npad = [0.12, 0.0, 0.0295]\n"
    )
}

fn run(petsc: &Petsc, text: &str, dir: &str) -> RunSummary {
    let scene = Scene::parse(text, dir).expect("bench scene parses");
    let out = std::path::Path::new("target/bench").join(dir);
    run_with(
        petsc,
        &scene,
        text,
        std::path::Path::new("."),
        &out,
        &[],
        &RunOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{dir}: {e}"))
}

fn read(dir: &str, name: &str) -> Vec<f64> {
    let path = std::path::Path::new("target/bench")
        .join(dir)
        .join("results.h5");
    hdf5::File::open(&path)
        .and_then(|f| f.dataset(name))
        .and_then(|d| d.read_raw::<f64>())
        .unwrap_or_else(|e| panic!("{}: {name}: {e}", path.display()))
}

/// Memory bandwidth (bytes/s), best of 5: a read (sum of one array) and a triad
/// (a = b + s c: two reads, one write), by rank 0 alone and by every rank at once (the total).
#[derive(Clone, Copy)]
struct Bandwidth {
    read_one: f64,
    read_all: f64,
    triad_one: f64,
    triad_all: f64,
}

fn stream_bandwidth(petsc: &Petsc, n: usize) -> Bandwidth {
    let b = vec![1.0f64; n];
    let c = vec![2.0f64; n];
    let mut a = vec![0.0f64; n];
    let time = |alone: bool, kernel: &mut dyn FnMut()| -> f64 {
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            squeal::parallel::barrier(petsc.world());
            let t = Instant::now();
            if !alone || petsc.rank() == 0 {
                kernel();
            }
            let slowest = squeal::parallel::max(petsc.world(), t.elapsed().as_secs_f64());
            best = squeal::measure::nan_min(best, slowest);
        }
        best
    };
    let mut read = || {
        // Four partial sums: the loop is not bound by one addition's latency.
        let mut s = [0.0f64; 4];
        for chunk in b.chunks_exact(4) {
            for k in 0..4 {
                s[k] += chunk[k];
            }
        }
        std::hint::black_box(s);
    };
    let read_bytes = 8.0 * n as f64;
    let read_one = read_bytes / time(true, &mut read);
    let read_all = read_bytes * petsc.size() as f64 / time(false, &mut read);
    let mut triad = || {
        for ((x, y), z) in a.iter_mut().zip(&b).zip(&c) {
            *x = y + 3.0 * z;
        }
        std::hint::black_box(&mut a);
    };
    let triad_bytes = 3.0 * 8.0 * n as f64;
    let triad_one = triad_bytes / time(true, &mut triad);
    let triad_all = triad_bytes * petsc.size() as f64 / time(false, &mut triad);
    Bandwidth {
        read_one,
        read_all,
        triad_one,
        triad_all,
    }
}

/// The cost model of one run: per part of a step, calls per step, bytes per call, the bound
/// (bytes over the bandwidth of every rank at once: the part perfectly split and streaming;
/// the per-rank factor streams its whole copy on every rank, so over one rank's share), the
/// measured time per call and their ratio.
fn cost_table(say: &dyn Fn(&str), t: &TransientSummary, bw: Bandwidth, ranks: usize) {
    let c = &t.cost;
    let per_rank = t.jacobian_solver.contains("every rank");
    let solve_bandwidth = if per_rank {
        bw.read_all / ranks as f64
    } else {
        bw.read_all
    };
    say(&format!(
        "cost model ({} unknowns, {}; bound = bytes / bandwidth of all {ranks} ranks at once: read {:.1} GB/s for the solve{}, triad {:.1} GB/s for the products):",
        c.unknowns,
        t.jacobian_solver,
        bw.read_all / 1e9,
        if per_rank { " over one rank's share" } else { "" },
        bw.triad_all / 1e9
    ));
    say("    part                   calls/step   MB/call   bound (ms)   measured (ms)   ratio   ms/step");
    let row = |name: &str, calls: f64, bytes: f64, bandwidth: f64, seconds: f64| {
        let bound = bytes / bandwidth;
        say(&format!(
            "    {name:<22} {calls:>10.2} {:>9.2} {:>12.3} {:>15.3} {:>7.1} {:>9.2}",
            bytes / 1e6,
            1e3 * bound,
            1e3 * seconds,
            seconds / bound,
            1e3 * seconds * calls
        ));
    };
    row(
        "solve",
        c.solves_per_step,
        c.bytes_per_solve,
        solve_bandwidth,
        c.seconds_per_solve,
    );
    if !per_rank && c.bytes_per_solve_largest_rank > 0.0 {
        // MUMPS splits the factor by its own mapping: the rank holding most streams its share
        // at that rank's part of the common bandwidth.
        row(
            "solve, as MUMPS split",
            c.solves_per_step,
            c.bytes_per_solve_largest_rank,
            bw.read_all / ranks as f64,
            c.seconds_per_solve,
        );
        say(&format!(
            "    (the largest rank holds {:.0} % of the factor)",
            100.0 * c.bytes_per_solve_largest_rank / c.bytes_per_solve
        ));
    }
    row(
        "linear force (K x)",
        c.linear_forces_per_step,
        c.bytes_linear_force,
        bw.triad_all,
        c.seconds_linear_force,
    );
    row(
        "contact evaluation",
        c.force_evaluations_per_step,
        c.bytes_per_force_evaluation,
        bw.triad_all,
        c.seconds_per_force_evaluation,
    );
    row(
        "contact tangent x",
        c.tangent_products_per_step,
        c.bytes_per_tangent_product,
        bw.triad_all,
        c.seconds_per_tangent_product,
    );
    let parts = c.solves_per_step * c.seconds_per_solve
        + c.linear_forces_per_step * c.seconds_linear_force
        + c.force_evaluations_per_step * c.seconds_per_force_evaluation
        + c.tangent_products_per_step * c.seconds_per_tangent_product;
    say(&format!(
        "    the rest (vector updates, norms, recording): {:.2} ms/step of {:.2}",
        1e3 * (t.seconds_per_step - parts),
        1e3 * t.seconds_per_step
    ));
}

fn main() {
    let args = Args::parse();
    let universe = mpi::initialize().expect("MPI initializes");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc initializes");
    let say = |s: &str| {
        if petsc.rank() == 0 {
            println!("{s}");
        }
    };
    let bw = stream_bandwidth(&petsc, args.stream_len);
    say(&format!(
        "memory bandwidth: read {:.1} GB/s one rank alone, {:.1} GB/s all {} at once; triad {:.1} / {:.1} GB/s",
        bw.read_one / 1e9,
        bw.read_all / 1e9,
        petsc.size(),
        bw.triad_one / 1e9,
        bw.triad_all / 1e9
    ));

    let runs = args.factors.iter().flat_map(|factor| {
        args.gemm_forwarding
            .iter()
            .map(move |forwarding| (factor, forwarding))
    });
    for (factor, forwarding) in runs.filter(|_| args.dofs > 0) {
        let (gemm, trsm) = match forwarding.as_str() {
            "on" => (true, true),
            "gemm" => (true, false),
            "off" => (false, false),
            other => panic!("--gemm-forwarding takes on, gemm or off, not {other}"),
        };
        squeal::la::one_column_gemm::set_forwarding_of(gemm, trsm);
        let text = scene(
            args.dofs,
            args.modes,
            2e-6,
            args.steps,
            1e-9,
            factor,
            &args.first_jacobian,
        );
        let calls_before = squeal::la::one_column_gemm::calls();
        let s = run(
            &petsc,
            &text,
            &format!("transient-{}-{factor}-gemm-{forwarding}", args.dofs),
        );
        let calls_after = squeal::la::one_column_gemm::calls();
        let r = s.reduction.as_ref().expect("reduction ran");
        let t = s.transient.as_ref().expect("transient ran");
        let stage = |name: &str| {
            s.timings
                .stages
                .iter()
                .find(|(n, _)| n == name)
                .map_or(0.0, |(_, v)| *v)
        };
        say(&format!(
            "brake {} DOF (jacobian_factor = \"{factor}\"): static preload {:.1} s, {} real modes {:.1} s, reduction {:.1} s (basis work {:.1} s + reduced-mode check)",
            r.full_dofs,
            stage("static preload"),
            args.modes,
            stage("real modes"),
            stage("reduction"),
            r.seconds
        ));
        say(&format!(
            "reduced model: {} DOF = {} kept + {} modal, stiffness {:.3e} stored entries, unknowns per rank {:?}; reduced real modes vs full {:.1e}",
            r.kept + r.modal,
            r.kept,
            r.modal,
            r.stiffness_entries,
            r.rows_per_rank,
            r.mode_error
        ));
        say(&format!(
            "transient: {} steps of 2 us, {:.2} iterations/step, {:.2} ms/step; {}: factor {:.3e} entries ({:.0} MB read per solve), factorized in {:.2} s; one iteration {:.2} ms vs one solve {:.2} ms",
            t.steps,
            t.mean_iterations,
            1e3 * t.seconds_per_step,
            t.jacobian_solver,
            t.factor_entries,
            t.cost.bytes_per_solve / 1e6,
            t.seconds_factorizing,
            1e3 * t.seconds_per_iteration,
            1e3 * t.seconds_per_solve,
        ));
        say(&format!(
            "one-column GEMM/TRSM forwarding {forwarding}: rank 0 sent {} calls to GEMV/TRSV and {} to the library's GEMM/TRSM over the whole run",
            calls_after.0 - calls_before.0,
            calls_after.1 - calls_before.1
        ));
        cost_table(&say, t, bw, petsc.size() as usize);
        say(&format!(
            "150,000 steps at this rate (measured on {} steps, extrapolated; one factorization included): {:.1} min (target < 30 min; the paper: 12 h)",
            t.steps,
            (150_000.0 * t.seconds_per_step + t.seconds_factorizing) / 60.0
        ));
    }

    if args.study_dofs > 0 {
        let mut steps = args.study_steps.clone();
        steps.sort_by(|a, b| b.total_cmp(a));
        let reference = steps.last().copied().unwrap_or(1.0) / 4.0;
        let study = |h_us: f64| -> (String, f64, RunSummary) {
            let h = h_us * 1e-6;
            let n = (args.study_time / h).round() as usize;
            let dir = format!("study-{h_us}us");
            let t = Instant::now();
            let s = run(
                &petsc,
                &scene(args.study_dofs, 60, h, n, 1e-7, "auto", "consistent"),
                &dir,
            );
            (dir, t.elapsed().as_secs_f64(), s)
        };
        let (ref_dir, ref_seconds, _) = study(reference);
        let rt = read(&ref_dir, "transient/time");
        let rv = read(&ref_dir, "transient/sensors/pad/velocity");
        let rq = read(&ref_dir, "transient/braking_torque");
        let vmax = rv.iter().map(|v| v.abs()).fold(0.0, nan_max);
        let qmax = rq.iter().map(|q| (q - rq[0]).abs()).fold(0.0, nan_max);
        say(&format!(
            "step size vs error: reduced {}-DOF brake over {} s, kick 1e-7 m on mode 2; reference h = {reference} us ({ref_seconds:.1} s); pad velocity up to {vmax:.2e} m/s, torque fluctuation up to {qmax:.2e} N m",
            args.study_dofs, args.study_time
        ));
        say("    h (us)   steps   iterations/step   velocity error   torque error   run (s)   transient (s)");
        for h_us in steps {
            let (dir, seconds, s) = study(h_us);
            let t = read(&dir, "transient/time");
            let v = read(&dir, "transient/sensors/pad/velocity");
            let q = read(&dir, "transient/braking_torque");
            // Common times: every sample of this run (the reference's step divides it).
            let ratio = (h_us / reference).round() as usize;
            let (mut ev, mut eq) = (0.0f64, 0.0f64);
            for (k, _) in t.iter().enumerate() {
                let j = k * ratio;
                if j >= rt.len() {
                    break;
                }
                for c in 0..3 {
                    ev = nan_max(ev, (v[3 * k + c] - rv[3 * j + c]).abs());
                }
                eq = nan_max(eq, (q[k] - rq[j]).abs());
            }
            let tr = s.transient.as_ref().expect("transient ran");
            say(&format!(
                "{h_us:>10} {:>7} {:>17.2} {:>16.2e} {:>14.2e} {:>9.1} {:>15.1}",
                tr.steps,
                tr.mean_iterations,
                ev / vmax,
                eq / squeal::measure::nan_max(qmax, f64::MIN_POSITIVE),
                seconds,
                tr.seconds_per_step * tr.steps as f64
            ));
        }
    }
}
