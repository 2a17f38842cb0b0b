//! Progress with an ETA for long stages: on rank 0, only when stdout is a terminal (quiet in
//! CI and in batch jobs, whose output is a file).

use std::io::{IsTerminal, Write};
use std::time::Instant;

/// A person is watching: stdout is a terminal, TERM names one, and neither CI nor
/// SQUEAL_PROGRESS=0 says otherwise (mpirun gives ranks a pseudo-terminal even when its own
/// output goes to a file, so the terminal test alone is not enough).
pub fn interactive() -> bool {
    let term_ok = std::env::var("TERM").is_ok_and(|t| !t.is_empty() && t != "dumb");
    std::io::stdout().is_terminal()
        && term_ok
        && std::env::var_os("CI").is_none()
        && std::env::var("SQUEAL_PROGRESS").map_or(true, |v| v != "0")
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
