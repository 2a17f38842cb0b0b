//! Progress with an ETA for long stages: on rank 0, only when stdout is a terminal (quiet in
//! CI and in batch jobs, whose output is a file).

use std::io::{IsTerminal, Write};
use std::time::Instant;

/// A person is watching: SQUEAL_PROGRESS=1 says so, SQUEAL_PROGRESS=0 or CI says not; otherwise
/// the output must reach a terminal (and TERM name one). Under mpirun the rank's own stdout is
/// no evidence (Open MPI gives ranks a pseudo-terminal even when mpirun's output goes to a file
/// or a SLURM log), so there it is the launcher's stdout that must be a terminal.
pub fn interactive() -> bool {
    match std::env::var("SQUEAL_PROGRESS").as_deref() {
        Ok("1") => return true,
        Ok("0") => return false,
        _ => {}
    }
    let term_ok = std::env::var("TERM").is_ok_and(|t| !t.is_empty() && t != "dumb");
    let launched_by_mpirun = ["OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"]
        .iter()
        .any(|v| std::env::var_os(v).is_some());
    let to_terminal = if launched_by_mpirun {
        launcher_stdout_is_terminal()
    } else {
        std::io::stdout().is_terminal()
    };
    to_terminal && term_ok && std::env::var_os("CI").is_none()
}

/// Whether the parent process (mpirun, or the daemon that started this rank) writes its stdout
/// to a terminal; false when that cannot be told (no /proc, another user's process).
fn launcher_stdout_is_terminal() -> bool {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return false;
    };
    // The fields after the command name (which is in parentheses and may hold spaces):
    // state, then the parent's pid.
    let after_name = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let Some(parent) = after_name.split_whitespace().nth(1) else {
        return false;
    };
    std::fs::read_link(format!("/proc/{parent}/fd/1")).is_ok_and(|target| {
        let target = target.to_string_lossy();
        target.starts_with("/dev/pts/") || target.starts_with("/dev/tty")
    })
}

pub struct Progress {
    label: String,
    total: usize,
    start: Instant,
    enabled: bool,
    last_print: Option<Instant>,
    /// Work done before this run started (a restart): not counted in the rate.
    first: usize,
}

impl Progress {
    pub fn new(label: &str, total: usize, rank: i32) -> Self {
        Progress {
            label: label.to_string(),
            total: total.max(1),
            start: Instant::now(),
            enabled: rank == 0 && interactive(),
            last_print: None,
            first: 0,
        }
    }

    /// The run resumes with `done` of `total` already done (before this process started).
    pub fn resume_from(&mut self, done: usize) {
        self.first = done.min(self.total);
    }

    /// Reports `done` of `total`, with extra text; at most a few times per second.
    pub fn update(&mut self, done: usize, detail: &str) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        if self
            .last_print
            .is_some_and(|t| now.duration_since(t).as_secs_f64() < 0.25)
        {
            return;
        }
        self.last_print = Some(now);
        let elapsed = self.start.elapsed().as_secs_f64();
        let done = done.min(self.total);
        let eta = if done > self.first {
            format!(
                "ETA {:.0} s",
                elapsed * (self.total - done) as f64 / (done - self.first) as f64
            )
        } else {
            "ETA --".into()
        };
        print!(
            "\r{}: {done}/{} {detail}  {elapsed:.0} s elapsed, {eta}   ",
            self.label, self.total
        );
        let _ = std::io::stdout().flush();
    }

    /// Clears the progress line.
    pub fn finish(&mut self) {
        if self.enabled && self.last_print.is_some() {
            print!("\r{:80}\r", "");
            let _ = std::io::stdout().flush();
        }
    }
}
