//! squeal: MPI init (rsmpi first), panic hook -> MPI_Abort, command line, dispatch.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use squeal::la::Petsc;
use squeal::pipeline::RunSummary;
use squeal::scene::{Scene, DEFAULT_SCENE};

#[derive(Parser)]
#[command(
    name = "squeal",
    version,
    about = "Finite-element analysis of brake squeal (MPI, PETSc/SLEPc)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (the embedded default scene when none is given).
    ///
    /// PETSc/SLEPc options go after `--`, e.g. `squeal run scene.toml -- -eps_ncv 300`.
    Run {
        /// Scene file (TOML).
        scene: Option<PathBuf>,
        /// Results folder (overrides output.directory of the scene).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Resume an interrupted (or extended: raise transient.steps) transient from
        /// <output>/checkpoint.h5; same scene otherwise, same number of ranks.
        #[arg(long)]
        restart: bool,
        /// PETSc/SLEPc options.
        #[arg(last = true)]
        petsc_options: Vec<String>,
    },
    /// Scene utilities.
    Scene {
        /// Print the embedded default scene (a starting point for your own).
        #[arg(long)]
        print_default: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Scene { print_default } => {
            if print_default {
                print!("{DEFAULT_SCENE}");
            } else {
                eprintln!("squeal scene: nothing to do (try --print-default)");
            }
            ExitCode::SUCCESS
        }
        Command::Run {
            scene,
            output,
            restart,
            petsc_options,
        } => run_command(scene, output, restart, petsc_options),
    }
}

fn run_command(
    scene_path: Option<PathBuf>,
    output: Option<PathBuf>,
    restart: bool,
    petsc_options: Vec<String>,
) -> ExitCode {
    let Some(universe) = mpi::initialize() else {
        eprintln!("squeal: MPI was already initialized");
        return ExitCode::FAILURE;
    };
    squeal::la::install_panic_hook();
    let rank = {
        use mpi::traits::Communicator;
        universe.world().rank()
    };
    let fail = |message: String| {
        // Every rank reaches the same error (inputs are read on all ranks, solver failures
        // are collective); rank 0 says it.
        if rank == 0 {
            eprintln!("squeal: error: {message}");
        }
        ExitCode::FAILURE
    };
    let (scene, text, name, dir) = match &scene_path {
        Some(p) => {
            let text = match std::fs::read_to_string(p) {
                Ok(t) => t,
                Err(e) => return fail(format!("{}: cannot read the scene: {e}", p.display())),
            };
            match Scene::parse(&text, &p.display().to_string()) {
                Ok(s) => {
                    let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
                    (s, text, p.display().to_string(), dir)
                }
                Err(e) => return fail(e.to_string()),
            }
        }
        None => match Scene::parse(DEFAULT_SCENE, "default scene") {
            Ok(s) => (
                s,
                DEFAULT_SCENE.to_string(),
                "default scene".into(),
                PathBuf::from("."),
            ),
            Err(e) => return fail(e.to_string()),
        },
    };
    let petsc = match Petsc::initialize(&universe, &petsc_options) {
        Ok(p) => p,
        Err(e) => return fail(e.to_string()),
    };
    let output = output.unwrap_or_else(|| scene.output.directory.clone());
    if rank == 0 {
        println!(
            "squeal {}: {name} on {} rank(s)",
            env!("CARGO_PKG_VERSION"),
            petsc.size()
        );
    }
    let options = squeal::pipeline::RunOptions { restart };
    let result = squeal::pipeline::run_with(
        &petsc,
        &scene,
        &text,
        &dir,
        &output,
        &petsc_options,
        &options,
    );
    let code = match result {
        Ok(summary) => {
            if rank == 0 {
                print_summary(&summary);
            }
            ExitCode::SUCCESS
        }
        Err(e) => fail(e.to_string()),
    };
    drop(petsc);
    code
}

fn print_summary(s: &RunSummary) {
    for note in &s.notes {
        println!("{note}");
    }
    println!("model: {} DOF", s.dofs);
    if !s.quality.is_empty() {
        println!("mesh quality (sJ: scaled Jacobian, AR: aspect ratio):");
        for line in squeal::mesh::quality::table(&s.quality).lines() {
            println!("    {line}");
        }
    }
    if let Some(b) = &s.balance {
        println!(
            "partition: rows per rank {:?} (imbalance {:.3}), elements per rank {:?} (imbalance {:.3})",
            b.rows, b.row_imbalance, b.elements, b.element_imbalance
        );
    }
    if let Some(st) = &s.statics {
        println!(
            "static preload: {} contact points, {} load steps, {} Newton iterations ({} solves), {} LU factorizations ({:.3e} entries), final residual {:.2e} N",
            st.points, st.load_steps, st.newton_iterations, st.solves, st.factorizations, st.factor_entries, st.final_residual
        );
        for (name, missed, of) in &st.misses {
            if *missed > 0 {
                println!("    {name}: {missed} of {of} master points have no partner within contact.search_distance (dropped)");
            }
        }
        println!("    interface                          normal force (N)  friction (N)  torque (N m)  max p (MPa)  open/stick/slip");
        for (name, i) in &st.interfaces {
            println!(
                "    {name:34} {:16.3} {:13.3} {:13.4} {:12.4}  {}/{}/{}",
                i.normal_force,
                i.friction_force,
                i.torque,
                i.max_pressure * 1e-6,
                i.open,
                i.stick,
                i.slip
            );
        }
        let torque: f64 = st.interfaces.iter().map(|(_, i)| i.torque).sum();
        println!(
            "    piston force {:.3} N, braking torque {:.4} N m",
            st.piston_force, torque
        );
    }
    if !s.unsupported.is_empty() && s.statics.is_none() {
        println!(
            "not held against rigid-body motion (no contact yet): {}; their modes at 0 Hz are flagged rigid",
            s.unsupported.join(", ")
        );
    }
    if !s.frequencies_hz.is_empty() {
        println!("real modes:    #   frequency (Hz)   ||K phi - w^2 M phi||   backward error");
        for (i, f) in s.frequencies_hz.iter().enumerate() {
            println!(
                "            {:4}   {:14.4}   {:21.3e}   {:14.3e}{}",
                i + 1,
                f,
                s.residual_norms[i],
                s.backward_errors[i],
                if s.rigid[i] { "   rigid-body mode" } else { "" }
            );
        }
        if let (Some(entries), Some(ordering)) = (s.factor_entries, s.ordering) {
            println!("MUMPS factor: {entries:.3e} entries ({ordering} ordering)");
        }
    }
    for c in &s.complex {
        let unstable = c.modes.iter().filter(|m| m.unstable).count();
        println!(
            "complex modes ({}{}): {} modes, {} unstable",
            c.route,
            if c.basis > 0 {
                format!(", {} real modes in the basis", c.basis)
            } else {
                String::new()
            },
            c.modes.len(),
            unstable
        );
        println!("       name   frequency (Hz)   damping ratio        Re(s) (1/s)   backward error   real mode");
        for m in &c.modes {
            println!(
                "    {:>7}   {:14.4}   {:13.4e}   {:16.6e}   {:14.3e}   {:>9}{}",
                m.name,
                m.frequency_hz,
                m.damping_ratio,
                m.eigenvalue.0,
                m.backward_error,
                m.dominant_real_mode
                    .map_or(String::new(), |k| format!("R{}", k + 1)),
                if m.unstable { "   UNSTABLE" } else { "" }
            );
        }
    }
    if let Some(r) = &s.reduction {
        println!(
            "reduction: {} -> {} DOF ({} kept in the contact zone + {} modal coordinates of {} offered, {} dropped), {:.2} s; reduced real modes vs full: max relative error {:.1e} over {}; static state represented to {:.1e}; basis M-orthonormal to {:.1e}; reduced unknowns per rank {:?}",
            r.full_dofs,
            r.kept + r.modal,
            r.kept,
            r.modal,
            r.offered,
            r.dropped,
            r.seconds,
            r.mode_error,
            r.mode_check.len(),
            r.static_error,
            r.orthonormality,
            r.rows_per_rank
        );
    }
    if let Some(t) = &s.transient {
        println!(
            "transient: {} steps to t = {:.4e} s, {:.2} fixed-Jacobian iterations per step (max {}), {:.2} ms per step; {} step cuts, {} Jacobian refreshes; {} Jacobian factorizations ({:.3e} entries, {:.2} s); one iteration {:.2} ms vs one solve with the factor {:.2} ms (ratio {:.2}); per step {:.2} ms in forces, {:.2} ms in operator products",
            t.steps,
            t.simulated,
            t.mean_iterations,
            t.max_iterations,
            1e3 * t.seconds_per_step,
            t.cuts,
            t.refreshes,
            t.factorizations,
            t.factor_entries,
            t.seconds_factorizing,
            1e3 * t.seconds_per_iteration,
            1e3 * t.seconds_per_solve,
            t.seconds_per_iteration / t.seconds_per_solve.max(1e-300),
            1e3 * t.seconds_forces_per_step,
            1e3 * t.seconds_products_per_step
        );
    }
    if let Some(sw) = &s.sweep {
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        println!(
            "sweep over {}: {} points, {} tracked modes; per point {:.3} s static re-solve, {:.4} s re-projection + complex modes",
            sw.parameter,
            sw.points,
            sw.tracks,
            mean(&sw.statics_seconds),
            mean(&sw.modal_seconds)
        );
        println!("    {:>14}   unstable modes", sw.parameter);
        for (v, u) in sw.values.iter().zip(&sw.unstable_per_point) {
            println!("    {v:14.6}   {u}");
        }
    }
    println!("timings (s):");
    for (name, secs) in &s.timings.stages {
        println!("    {name:26} {secs:9.3}");
    }
    println!(
        "peak memory per rank: {:.1} MiB",
        s.peak_memory_per_rank / (1024.0 * 1024.0)
    );
    println!(
        "results: {}/results.h5 (+ results.xdmf, model.png)",
        s.output.display()
    );
}
