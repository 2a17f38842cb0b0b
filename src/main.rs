//! squeal: MPI init (rsmpi first), panic hook -> MPI_Abort, command line, dispatch; a
//! failure on any rank ends every rank (squeal::fault).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use squeal::la::Petsc;
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
        let world = universe.world();
        squeal::fault::init(&world);
        world.rank()
    };
    let fail = |message: String| {
        // Collective failures: rank 0 says it; a failure on one rank alone ends all ranks.
        squeal::fault::report_failed_run(&message);
        squeal::fault::finish();
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
                print!("{summary}");
            }
            ExitCode::SUCCESS
        }
        Err(e) => fail(e.to_string()),
    };
    drop(petsc);
    squeal::fault::finish();
    code
}
