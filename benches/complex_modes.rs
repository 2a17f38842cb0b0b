//! Complex-mode benchmark, speed against error (run under mpirun by scripts/bench): on the
//! preloaded brake, the time of the real modes, of the projected and of the full complex
//! modes, and a table of projected-vs-full frequency and damping error against the number of
//! real modes in the basis, with the time of each; then the cost of one sweep point
//! (re-projection of a new tangent state + dense complex modes, static re-solve apart).
//!
//!   mpirun -n 2 target/release/deps/complex_modes-* --dofs 30000 --bases 50,100,250,400

use std::path::Path;

use clap::Parser;
use squeal::eigen::complex_modes::ComplexMode;
use squeal::la::Petsc;
use squeal::pipeline::{run, RunSummary};
use squeal::scene::Scene;

#[derive(Parser)]
struct Args {
    /// Target size of the brake (DOF).
    #[arg(long, default_value_t = 600_000)]
    dofs: usize,
    /// Real modes in the projection basis, comma separated; the largest also serves the full
    /// comparison run.
    #[arg(long, value_delimiter = ',', default_value = "50,100,250,400")]
    bases: Vec<usize>,
    /// Modes compared: those of the full route below this frequency (Hz).
    #[arg(long, default_value_t = 2500.0)]
    f_max: f64,
    /// Points of the timed friction sweep (basis: 250 modes or the largest below it).
    #[arg(long, default_value_t = 20)]
    sweep_points: usize,
    /// Output folder of the runs.
    #[arg(long, default_value = "target/bench/complex")]
    out: String,
    /// cargo bench passes --bench; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn scene(dofs: usize, modes: usize, method: &str, f_max: f64, sweep: Option<usize>) -> String {
    let mut s = format!(
        "[model]\nsource = \"brake\"\ntarget_dofs = {dofs}\npressure_bar = 20.0\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = {modes}\n\
         [complex_modes]\nmethod = \"{method}\"\nf_max_hz = {f_max}\ncount = 40\n"
    );
    if let Some(n) = sweep {
        s += &format!("[sweep]\nparameter = \"mu\"\nfrom = 0.3\nto = 0.5\npoints = {n}\n");
    }
    s
}

fn stage(s: &RunSummary, name: &str) -> f64 {
    s.timings
        .stages
        .iter()
        .filter(|(n, _)| n == name)
        .map(|(_, t)| t)
        .sum()
}

fn route<'a>(s: &'a RunSummary, r: &str) -> &'a [ComplexMode] {
    s.complex
        .iter()
        .find(|c| c.route == r)
        .map(|c| c.modes.as_slice())
        .unwrap_or(&[])
}

/// Largest and median frequency error (relative) and largest damping-ratio error (absolute)
/// of the projected modes against every full mode, by nearest eigenvalue.
fn errors(full: &[ComplexMode], projected: &[ComplexMode]) -> (f64, f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    let mut all = Vec::new();
    for m in full {
        let Some(p) = projected.iter().min_by(|a, b| {
            let d = |x: &ComplexMode| {
                (x.eigenvalue.0 - m.eigenvalue.0).hypot(x.eigenvalue.1 - m.eigenvalue.1)
            };
            d(a).total_cmp(&d(b))
        }) else {
            return (f64::NAN, f64::NAN, f64::NAN);
        };
        all.push((p.frequency_hz - m.frequency_hz).abs() / m.frequency_hz);
        worst.0 = worst
            .0
            .max((p.frequency_hz - m.frequency_hz).abs() / m.frequency_hz);
        worst.1 = worst.1.max((p.damping_ratio - m.damping_ratio).abs());
    }
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(f64::NAN);
    (worst.0, median, worst.1)
}

fn route_summary<'a>(s: &'a RunSummary, r: &str) -> Option<&'a squeal::pipeline::ComplexSummary> {
    s.complex.iter().find(|c| c.route == r)
}

fn main() {
    let args = Args::parse();
    let universe = mpi::initialize().expect("MPI");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc");
    let rank0 = petsc.rank() == 0;
    let go = |text: String, name: &str| -> RunSummary {
        let scene = Scene::parse(&text, name).expect("bench scene");
        let out = Path::new(&args.out).join(name);
        run(&petsc, &scene, &text, Path::new("."), &out, &[]).expect("bench run")
    };
    let mut bases = args.bases.clone();
    bases.sort_unstable();
    let largest = *bases.last().expect("at least one basis size");
    let reference = go(
        scene(args.dofs, largest, "both", args.f_max, None),
        "reference",
    );
    let full = route(&reference, "full").to_vec();
    if rank0 {
        println!(
            "brake: {} DOF on {} ranks; static preload {:.1} s; {largest} real modes {:.1} s; \
             full complex modes (SLEPc PEP, {} modes below {} Hz, {} unstable) {:.1} s \
             (+ operators {:.1} s)",
            reference.dofs,
            petsc.size(),
            stage(&reference, "static preload"),
            stage(&reference, "real modes"),
            full.len(),
            args.f_max,
            full.iter().filter(|m| m.unstable).count(),
            stage(&reference, "complex modes (full)"),
            stage(&reference, "complex operators"),
        );
        println!(
            "{:>10} {:>13} {:>14} {:>14} {:>13} {:>15} {:>32}",
            "real modes",
            "top mode (Hz)",
            "real modes (s)",
            "projection (s)",
            "dense CEA (s)",
            "residuals (s)",
            "error f max / f median / zeta max"
        );
    }
    for &m in &bases {
        let summary = if m == largest {
            None
        } else {
            Some(go(
                scene(args.dofs, m, "projected", args.f_max, None),
                &format!("basis-{m}"),
            ))
        };
        let s = summary.as_ref().unwrap_or(&reference);
        let (df, median, dz) = errors(&full, route(s, "projected"));
        let solve = route_summary(s, "projected").map_or(f64::NAN, |c| c.solve_seconds);
        if rank0 {
            println!(
                "{m:>10} {:>13.1} {:>14.2} {:>14.4} {:>13.4} {:>15.3} {:>12.2e} / {:.2e} / {:.2e}",
                s.frequencies_hz.last().copied().unwrap_or(0.0),
                stage(s, "real modes"),
                stage(s, "complex modes projection"),
                solve,
                stage(s, "complex modes (projected)") - solve,
                df,
                median,
                dz
            );
        }
    }
    let sweep_basis = bases
        .iter()
        .copied()
        .filter(|&m| m <= 250)
        .max()
        .unwrap_or(largest);
    let sw = go(
        scene(
            args.dofs,
            sweep_basis,
            "projected",
            args.f_max,
            Some(args.sweep_points),
        ),
        "sweep",
    );
    if let (true, Some(sweep)) = (rank0, &sw.sweep) {
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let modal = mean(&sweep.modal_seconds);
        println!(
            "sweep over mu ({} points, basis {sweep_basis}): per point {:.4} s re-projection + \
             dense complex modes (target < 1 s: {}), {:.2} s static re-solve (warm start); \
             100 points: {:.1} s modal + {:.0} s statics",
            sweep.points,
            modal,
            if modal < 1.0 { "met" } else { "missed" },
            mean(&sweep.statics_seconds),
            100.0 * modal,
            100.0 * mean(&sweep.statics_seconds)
        );
    }
}
