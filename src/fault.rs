//! Failing well on many ranks: a failure on one rank must end every rank within seconds
//! (never leave the others waiting in a collective call), and a developer must be able to
//! provoke one anywhere to check that.
//!
//! Fault injection (for developers and the CLI tests):
//! `SQUEAL_FAULT=<stage>@<rank>[:panic|:nan]` makes the stage named `<stage>` (as in the
//! timings table: `mesh`, `assembly`, `static preload`, `real modes`, `complex modes (full)`,
//! `reduction`, `transient`, ...) fail on rank `<rank>` before it starts, with an error
//! (default) or a panic (`write results.h5`, `write transient.h5`: a write to that file fails,
//! as on a full disk); `:nan` puts a NaN into the stage's input instead (`transient`: its
//! start state). `<rank>` may be `*` for every rank (a collective failure).

use std::cell::RefCell;
use std::fmt::Display;
use std::time::{Duration, Instant};

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

/// The environment variable read by [`inject`].
pub const FAULT_VARIABLE: &str = "SQUEAL_FAULT";

/// A failure provoked through [`FAULT_VARIABLE`].
#[derive(Debug, thiserror::Error)]
#[error("injected fault in stage '{stage}' on rank {rank} ({FAULT_VARIABLE})")]
pub struct InjectedFault {
    pub stage: String,
    pub rank: i32,
}

/// How an injected fault shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Error,
    Panic,
    /// A NaN in the stage's input (stages that support it: `transient`, its start state).
    Nan,
}

/// The fault [`FAULT_VARIABLE`] asks for in `stage` on this rank, if any.
fn requested(stage: &str) -> Option<Kind> {
    let spec = std::env::var(FAULT_VARIABLE).ok()?;
    let (target, kind) = match spec.rsplit_once(':') {
        Some((t, "panic")) => (t, Kind::Panic),
        Some((t, "nan")) => (t, Kind::Nan),
        _ => (spec.as_str(), Kind::Error),
    };
    let (name, on) = target.rsplit_once('@')?;
    let rank = SimpleCommunicator::world().rank();
    let on_this_rank = on == "*" || on.parse::<i32>() == Ok(rank);
    (name == stage && on_this_rank).then_some(kind)
}

/// Fails (error or panic) when [`FAULT_VARIABLE`] names this stage and this rank.
pub fn inject(stage: &str) -> Result<(), InjectedFault> {
    match requested(stage) {
        Some(Kind::Panic) => panic!("injected panic in stage '{stage}' ({FAULT_VARIABLE})"),
        Some(Kind::Error) => Err(InjectedFault {
            stage: stage.to_string(),
            rank: SimpleCommunicator::world().rank(),
        }),
        Some(Kind::Nan) | None => Ok(()),
    }
}

/// Whether [`FAULT_VARIABLE`] asks for a NaN in this stage's input on this rank.
pub fn poisoned(stage: &str) -> bool {
    requested(stage) == Some(Kind::Nan)
}

/// How long a failing rank waits for the others to fail too before it ends them all (long
/// enough for a rank descheduled on a loaded machine to arrive).
pub const GRACE: Duration = Duration::from_secs(10);

thread_local! {
    /// A communicator duplicated for failures only, so the barrier of [`agree`] can never
    /// match a collective call of the computation.
    static FAILURES: RefCell<Option<SimpleCommunicator>> = const { RefCell::new(None) };
    /// Set once every rank agreed that the run failed (later agreements are not needed).
    static AGREED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Makes failures agreed on over `world` ([`agree`]); call [`finish`] before MPI finalizes.
///
/// # Collective
pub fn init(world: &SimpleCommunicator) {
    let failures = world.duplicate();
    FAILURES.with(|f| *f.borrow_mut() = Some(failures));
}

/// Frees the communicator of [`init`] (before MPI finalizes).
pub fn finish() {
    FAILURES.with(|f| drop(f.borrow_mut().take()));
}

/// Called by a rank that failed with `message`, where the failure is detected and before
/// anything collective is dropped (a MUMPS factor, an HDF5 file): returns when every rank
/// failed within [`GRACE`] (a collective failure: inputs are read on every rank, solver
/// failures are agreed on), so they can unwind together. Otherwise this rank failed alone
/// while the others compute or wait in a collective call: it prints the message with its
/// rank and calls MPI_Abort, which ends every rank with a non-zero exit code. Does nothing
/// before [`init`] (library use).
pub fn agree(message: &dyn Display) {
    FAILURES.with(|f| {
        let guard = f.borrow();
        let Some(failures) = guard.as_ref() else {
            return;
        };
        if AGREED.get() {
            return;
        }
        let mut pending = failures.immediate_barrier();
        let start = Instant::now();
        loop {
            match pending.test() {
                Ok(_) => {
                    AGREED.set(true);
                    return;
                }
                Err(still) => pending = still,
            }
            if start.elapsed() > GRACE {
                let rank = failures.rank();
                say(&format!(
                    "squeal: error on rank {rank} (alone; ending all ranks): {message}"
                ));
                std::mem::forget(pending);
                failures.abort(1);
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    });
}

/// [`agree`] on the error of `result`, if any, and pass it on.
pub fn checked<T, E: Display>(result: Result<T, E>) -> Result<T, E> {
    if let Err(e) = &result {
        agree(e);
    }
    result
}

/// Ends this rank's part of a failed run: [`agree`], then rank 0 prints the message and a
/// rank whose message differs prints its own; the caller exits with an error code.
///
/// # Collective (on failure)
pub fn report_failed_run(message: &str) {
    agree(&message);
    let rank = SimpleCommunicator::world().rank();
    FAILURES.with(|f| {
        let hash = fnv1a(message.as_bytes());
        let mut root_hash = hash;
        if let Some(failures) = f.borrow().as_ref() {
            failures.process_at_rank(0).broadcast_into(&mut root_hash);
        }
        if rank == 0 {
            say(&format!("squeal: error: {message}"));
        } else if hash != root_hash {
            say(&format!("squeal: error on rank {rank}: {message}"));
        }
    });
}

/// The value of a write to a file every rank shares (results.h5, transient.h5), or, when it
/// failed (a full disk, a quota), the end of the run: the message (by [`report_failed_run`],
/// so a rank that failed alone ends the others) and MPI_Abort with exit code 1 on every rank.
/// Parallel HDF5 cannot be unwound after such a failure: the ranks' caches differ, and the
/// collective close that dropping the file makes waits forever (measured: a run whose disk
/// filled hung in H5Fclose). Files closed before (checkpoint.h5) stay as they were.
///
/// # Collective (on failure)
pub fn end_on_write_failure<T, E: Display>(result: Result<T, E>, file: &str) -> T {
    // (`SQUEAL_FAULT=write <file>@<rank>` fails it, as a full disk would.)
    let injected = inject(&format!("write {file}"));
    match result {
        Ok(value) if injected.is_ok() => value,
        failed => {
            let e = match failed {
                Err(e) => e.to_string(),
                Ok(_) => injected.expect_err("the other case").to_string(),
            };
            report_failed_run(&format!(
                "writing {file} failed: {e}. The run ends here (a file shared by the ranks cannot be closed after a failed write); free space or choose another --output, then resume with --restart from the last checkpoint"
            ));
            FAILURES.with(|f| match f.borrow().as_ref() {
                Some(failures) => failures.abort(1),
                None => std::process::exit(1),
            })
        }
    }
}

/// Writes `line` and its newline to stderr in one write, so that the lines of ranks failing
/// together never interleave (`eprintln!` may write its pieces separately; mpirun forwards
/// each rank's writes as they come).
pub fn say(line: &str) {
    use std::io::Write;
    let mut whole = String::with_capacity(line.len() + 1);
    whole.push_str(line);
    whole.push('\n');
    let _ = std::io::stderr().lock().write_all(whole.as_bytes());
}

/// FNV-1a: a stable hash (the same on every rank and platform), e.g. to tell whether two
/// ranks failed with the same message.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
