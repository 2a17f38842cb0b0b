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
        /// Compute only the K-th of N equal parts of the noise matrix' points (e.g. a SLURM
        /// array task: --slice $((SLURM_ARRAY_TASK_ID + 1))/$SLURM_ARRAY_TASK_COUNT); then
        /// `squeal merge` the slices' output directories.
        #[arg(long, value_name = "K/N")]
        slice: Option<squeal::matrix::sample::Slice>,
        /// PETSc/SLEPc options.
        #[arg(last = true)]
        petsc_options: Vec<String>,
    },
    /// Combine the output directories of the slices of one noise matrix (`run --slice`) into
    /// one journal, results.h5, CSVs, figures and report.
    Merge {
        /// The slices' output directories (or their matrix-points.jsonl).
        #[arg(required = true)]
        slices: Vec<PathBuf>,
        /// Where the merged results go.
        #[arg(long, short)]
        output: PathBuf,
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
            slice,
            petsc_options,
        } => {
            let options = squeal::pipeline::RunOptions {
                restart,
                slice: slice.unwrap_or_default(),
            };
            run_command(scene, output, options, petsc_options)
        }
        Command::Merge { slices, output } => merge_command(&slices, &output),
    }
}

fn merge_command(slices: &[PathBuf], output: &Path) -> ExitCode {
    let Some(universe) = mpi::initialize() else {
        eprintln!("squeal: MPI was already initialized");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    use mpi::traits::Communicator;
    if world.size() != 1 {
        if world.rank() == 0 {
            eprintln!("squeal merge: run it on one rank (it reads journals and writes one report)");
        }
        return ExitCode::FAILURE;
    }
    match squeal::pipeline::merge::merge(&world, slices, output) {
        Ok(report) => {
            println!("answer:\n    {}", report.answer_line());
            print!("{}", report.text());
            println!("merged into {}", output.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run_command(
    scene_path: Option<PathBuf>,
    output: Option<PathBuf>,
    options: squeal::pipeline::RunOptions,
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
