//! squeal: MPI init (rsmpi first), panic hook -> MPI_Abort, command line, dispatch; a
//! failure on any rank ends every rank (squeal::fault).
#![allow(clippy::disallowed_methods)] // clippy.toml's bar is for the tests' checks

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
        /// Split the ranks into G groups that compute the noise matrix' points side by side,
        /// each on its own copy of the model (for a model too small to gain from more ranks
        /// per solve); rank 0 merges their results into the output directory.
        #[arg(long, value_name = "G", default_value_t = 1)]
        groups: usize,
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
    /// Check a scene without solving: the scene's keys, the model files (deck, mesh or
    /// matrices), mesh quality, clamps, loads, contact pairing and the memory a run takes per
    /// rank. Exit 0 when a run can start; else the error names the file, key or line.
    Check {
        /// Scene file (TOML); the embedded default scene when none is given.
        scene: Option<PathBuf>,
        /// Ranks of the planned run, for the memory estimate.
        #[arg(long, default_value_t = 2)]
        ranks: usize,
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
            groups,
            petsc_options,
        } => {
            let options = squeal::pipeline::RunOptions {
                restart,
                slice: slice.unwrap_or_default(),
            };
            run_command(scene, output, options, groups.max(1), petsc_options)
        }
        Command::Merge { slices, output } => merge_command(&slices, &output),
        Command::Check { scene, ranks } => check_command(scene.as_deref(), ranks),
    }
}

/// `squeal check`: rank 0 checks (the others wait for its verdict, so `mpirun squeal check`
/// prints once and every rank exits alike).
fn check_command(scene_path: Option<&Path>, ranks: usize) -> ExitCode {
    let Some(universe) = mpi::initialize() else {
        eprintln!("squeal: MPI was already initialized");
        return ExitCode::FAILURE;
    };
    use mpi::traits::Communicator;
    let world = universe.world();
    let mut verdict = String::new();
    if world.rank() == 0 {
        verdict = match check_scene(scene_path, ranks) {
            Ok(report) => {
                print!("{report}");
                String::new()
            }
            Err(e) => e,
        };
    }
    squeal::parallel::broadcast_string(&world, 0, &mut verdict);
    if verdict.is_empty() {
        if world.rank() == 0 {
            println!("ok: a run can start");
        }
        ExitCode::SUCCESS
    } else {
        if world.rank() == 0 {
            eprintln!("squeal check: error: {verdict}");
        }
        ExitCode::FAILURE
    }
}

fn check_scene(scene_path: Option<&Path>, ranks: usize) -> Result<String, String> {
    let (text, name, dir) = match scene_path {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| format!("{}: cannot read the scene: {e}", p.display()))?;
            let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
            (text, p.display().to_string(), dir)
        }
        None => (
            DEFAULT_SCENE.to_string(),
            "default scene".into(),
            ".".into(),
        ),
    };
    let scene = Scene::parse(&text, &name).map_err(|e| e.to_string())?;
    let report =
        squeal::stages::check::check(&scene, &dir, ranks).map_err(|e| format!("{name}: {e}"))?;
    let output = scene.output.directory.display();
    Ok(format!(
        "squeal check: {name}\n{report}output: {output} (or --output)\n"
    ))
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
    let whole = squeal::matrix::sample::Slice::WHOLE;
    match squeal::pipeline::merge::merge(&world, slices, output, whole) {
        Ok(report) => {
            print_merged(&report);
            println!("merged into {}", output.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A merged noise matrix' answer (its verdict first) and its summary.
fn print_merged(report: &squeal::report::matrix::MatrixReport) {
    println!(
        "answer:\n    {}\n    {}",
        squeal::report::answer::matrix_verdict(report),
        report.answer_line()
    );
    print!("{}", report.text());
}

/// With `--groups G > 1`: the scene splits into groups, and the output folder that holds the
/// groups' folders is made (or refused) once, before they start.
///
/// # Collective
fn groups_can_start(
    world: &mpi::topology::SimpleCommunicator,
    scene: &Scene,
    groups: usize,
    output: &Path,
) -> Result<(), String> {
    use mpi::traits::Communicator;
    if groups <= 1 {
        return Ok(());
    }
    let size = world.size() as usize;
    if let Some(why) = squeal::pipeline::groups::refusal(scene, groups, size) {
        return Err(why);
    }
    squeal::pipeline::prepare_output(world, output)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn run_command(
    scene_path: Option<PathBuf>,
    output: Option<PathBuf>,
    mut options: squeal::pipeline::RunOptions,
    groups: usize,
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
    use mpi::traits::Communicator;
    use squeal::pipeline::groups;
    let world = universe.world();
    let size = world.size() as usize;
    let output = output.unwrap_or_else(|| scene.output.directory.clone());
    if let Err(why) = groups_can_start(&world, &scene, groups, &output) {
        return fail(why);
    }
    let group = groups::group_of(rank as usize, size, groups);
    let color = mpi::topology::Color::with_value(group as i32);
    let communicator = world.split_by_color(color).expect("every rank has a color");
    let petsc = match Petsc::initialize_in(&universe, communicator, &petsc_options) {
        Ok(p) => p,
        Err(e) => return fail(e.to_string()),
    };
    let run_output = if groups > 1 {
        options.slice = groups::group_slice(options.slice, group, groups);
        groups::group_dir(&output, group, groups)
    } else {
        output.clone()
    };
    if group > 0 && petsc.rank() == 0 {
        // Only rank 0 prints: the other groups' roots keep their console in their folder.
        let kept = std::fs::create_dir_all(&run_output)
            .and_then(|()| squeal::la::redirect_stdout(&run_output.join("console.log")));
        if let Err(e) = kept {
            return fail(format!("{}: {e}", run_output.display()));
        }
    }
    if petsc.rank() == 0 {
        println!(
            "squeal {}: {name} on {} rank(s){}",
            env!("CARGO_PKG_VERSION"),
            petsc.size(),
            if groups > 1 {
                format!(
                    " x {groups} groups (group {} of {groups}: {})",
                    group + 1,
                    run_output.display()
                )
            } else {
                String::new()
            }
        );
    }
    let result = squeal::pipeline::run_with(
        &petsc,
        &scene,
        &text,
        &dir,
        &run_output,
        &petsc_options,
        &options,
    );
    let result = match (result, groups > 1) {
        (Ok(summary), true) => {
            // Every group done (a failed one ended the run through fault::agree), rank 0 merges.
            squeal::parallel::barrier(&world);
            if rank == 0 {
                // The group's own summary is a part of the whole: in its folder, not here.
                println!(
                    "group 1 of {groups} done: its summary in {}",
                    summary.output.join("summary.txt").display()
                );
                let dirs: Vec<PathBuf> = (0..groups)
                    .map(|g| groups::group_dir(&output, g, groups))
                    .collect();
                let whole_slice = squeal::matrix::sample::Slice {
                    index: (options.slice.index - 1) / groups + 1,
                    count: options.slice.count / groups,
                };
                let own = mpi::topology::SimpleCommunicator::self_comm();
                match squeal::pipeline::merge::merge(&own, &dirs, &output, whole_slice) {
                    Ok(report) => {
                        println!("groups merged into {}", output.display());
                        print_merged(&report);
                    }
                    Err(e) => return fail(format!("merging the groups: {e}")),
                }
            }
            Ok(None)
        }
        (Ok(summary), false) => Ok(Some(summary)),
        (Err(e), _) => Err(e),
    };
    let code = match result {
        Ok(summary) => {
            if let (Some(summary), 0) = (summary, rank) {
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
