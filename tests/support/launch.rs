//! Running the `squeal` binary under mpirun from a test, with a deadline: a run that hangs
//! is killed and reported, never waited on forever.

use std::io::Read;
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// What a run did.
pub struct Outcome {
    /// None when the deadline passed and the run was killed.
    pub status: Option<ExitStatus>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `squeal args...` on `ranks` ranks in `cwd` with the extra environment `env`; kills
/// it after `deadline`. Without mpirun a 1-rank run starts squeal directly, and a run of more
/// ranks fails the test saying so.
pub fn squeal_run(
    ranks: usize,
    args: &[&str],
    cwd: &Path,
    env: &[(&str, &str)],
    deadline: Duration,
) -> Outcome {
    let squeal = env!("CARGO_BIN_EXE_squeal");
    let have_mpirun = Command::new("mpirun").arg("--version").output().is_ok();
    let mut cmd = if have_mpirun {
        let mut c = Command::new("mpirun");
        c.args(["-n", &ranks.to_string()]).arg(squeal);
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .env("OMPI_MCA_rmaps_base_oversubscribe", "1")
            // Tests run two of these at once on two cores: a rank waiting in a collective
            // call yields its core instead of spinning, so the rank it waits for is not starved
            // (a suspect for the rare "alone" verdict of a collective failure, see faults.rs).
            .env("OMPI_MCA_mpi_yield_when_idle", "1");
        c
    } else {
        // A test of several ranks must not pass as a run on one.
        assert!(
            ranks == 1,
            "mpirun not found: this test runs squeal on {ranks} ranks (scripts/setup installs openmpi-bin)"
        );
        Command::new(squeal)
    };
    cmd.args(args)
        .current_dir(cwd)
        .envs(env.iter().copied())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let start = Instant::now();
    let mut child = cmd.spawn().expect("squeal starts");
    // Pipes are drained by threads so a chatty run cannot block on a full pipe.
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            let _ = pipe.read_to_string(&mut text);
            text
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for squeal") {
            break Some(status);
        }
        if start.elapsed() > deadline {
            // SIGTERM first: mpirun then ends its ranks (SIGKILL would orphan them).
            let pid = child.id().to_string();
            let _ = Command::new("kill").args(["-TERM", &pid]).status();
            std::thread::sleep(Duration::from_secs(5));
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    Outcome {
        status,
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    }
}
