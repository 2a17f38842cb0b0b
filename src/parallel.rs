//! Small collective helpers on top of rsmpi.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

/// True on every rank when `flag` is true on any rank (so all ranks take the same branch).
///
/// # Collective
pub fn any_rank(comm: &SimpleCommunicator, flag: bool) -> bool {
    let local = flag as i32;
    let mut global = 0i32;
    comm.all_reduce_into(&local, &mut global, SystemOperation::max());
    global != 0
}

/// Sum over ranks.
///
/// # Collective
pub fn sum(comm: &SimpleCommunicator, value: f64) -> f64 {
    let mut global = 0.0;
    comm.all_reduce_into(&value, &mut global, SystemOperation::sum());
    global
}

/// Element-wise sum over ranks, in place.
///
/// # Collective
pub fn sum_in_place(comm: &SimpleCommunicator, values: &mut [f64]) {
    let local = values.to_vec();
    comm.all_reduce_into(&local[..], values, SystemOperation::sum());
}

/// Element-wise maximum over ranks, in place.
///
/// # Collective
pub fn max_in_place(comm: &SimpleCommunicator, values: &mut [f64]) {
    let local = values.to_vec();
    comm.all_reduce_into(&local[..], values, SystemOperation::max());
}

/// Maximum over ranks.
///
/// # Collective
pub fn max(comm: &SimpleCommunicator, value: f64) -> f64 {
    let mut global = 0.0;
    comm.all_reduce_into(&value, &mut global, SystemOperation::max());
    global
}

/// `data` of rank `root` on every rank (its length too).
///
/// # Collective
pub fn broadcast_f64s(comm: &SimpleCommunicator, root: i32, data: &mut Vec<f64>) {
    let mut len = data.len() as u64;
    comm.process_at_rank(root).broadcast_into(&mut len);
    data.resize(len as usize, 0.0);
    comm.process_at_rank(root).broadcast_into(&mut data[..]);
}

/// `text` of rank `root` on every rank.
///
/// # Collective
pub fn broadcast_string(comm: &SimpleCommunicator, root: i32, text: &mut String) {
    let mut bytes = std::mem::take(text).into_bytes();
    let mut len = bytes.len() as u64;
    comm.process_at_rank(root).broadcast_into(&mut len);
    bytes.resize(len as usize, 0);
    // An empty buffer is refused by MPI_Bcast (a null pointer): nothing to send then.
    if len > 0 {
        comm.process_at_rank(root).broadcast_into(&mut bytes[..]);
    }
    *text = String::from_utf8_lossy(&bytes).into_owned();
}

/// # Collective
pub fn barrier(comm: &SimpleCommunicator) {
    comm.barrier();
}

/// Peak resident set size of this process (VmHWM from /proc/self/status), in bytes.
pub fn peak_rss_bytes() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// Memory this node can still give (bytes): MemAvailable of /proc/meminfo, lowered to what
/// the job's cgroup still allows (SLURM confines jobs with cgroups; /proc/meminfo shows the
/// whole node). None where neither can be read.
pub fn available_memory_bytes() -> Option<f64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024.0)
        });
    let read =
        |path: &str| -> Option<f64> { std::fs::read_to_string(path).ok()?.trim().parse().ok() };
    // cgroup v2, then v1 ("max" or a huge number: no limit).
    let cgroup = read("/sys/fs/cgroup/memory.max")
        .zip(read("/sys/fs/cgroup/memory.current"))
        .or_else(|| {
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes")
                .zip(read("/sys/fs/cgroup/memory/memory.usage_in_bytes"))
        })
        .filter(|(limit, _)| *limit < 1e18)
        .map(|(limit, used)| (limit - used).max(0.0));
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
