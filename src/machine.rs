//! What the machine offers this process in memory, read from `/proc` and `/sys/fs/cgroup`
//! (Linux; elsewhere nothing is known): the figures both the memory check before a job
//! (module `memory`) and the pyramid's choice between memory and a temporary file for its
//! layout (module `pyramid`'s `spill`) start from.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// The allowance [`set_memory_allowance`] gave, in bytes; 0 when none was given.
static MEMORY_ALLOWANCE: AtomicU64 = AtomicU64::new(0);

/// Caps what [`available_memory`] reports, for the rest of this process, at `bytes`: the
/// memory a job has been allowed (the command line's `--memory`), so that the choices made
/// from the available memory (a large pyramid's layout kept in a temporary file rather than
/// on the heap) keep the job inside its allowance rather than inside the machine's free
/// memory. `None` lifts the cap.
pub fn set_memory_allowance(bytes: Option<u64>) {
    MEMORY_ALLOWANCE.store(bytes.map_or(0, |b| b.max(1)), Ordering::Relaxed);
}

/// The memory this process can take now without pushing anything out, in bytes: the
/// machine's `MemAvailable` (swap not counted: paging a layout out to swap is slower than
/// reading it from a file), capped by the cgroup's memory limit and by the allowance of
/// [`set_memory_allowance`]. `None` when none of them is known.
pub fn available_memory() -> Option<u64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let available = read("/proc/meminfo").and_then(|t| meminfo_field(&t, "MemAvailable"));
    let cgroup =
        read("/proc/self/cgroup").and_then(|t| cgroup_limit(&t, Path::new("/sys/fs/cgroup")));
    let allowance = match MEMORY_ALLOWANCE.load(Ordering::Relaxed) {
        0 => None,
        bytes => Some(bytes),
    };
    [available, cgroup, allowance].into_iter().flatten().min()
}

/// One `/proc/meminfo` field (given in kB) in bytes.
fn meminfo_field(meminfo: &str, name: &str) -> Option<u64> {
    meminfo.lines().find_map(|l| {
        let rest = l.strip_prefix(name)?.strip_prefix(':')?;
        let kb: u64 = rest.split_whitespace().next()?.parse().ok()?;
        Some(kb.saturating_mul(1024))
    })
}

/// `(MemTotal + SwapTotal, MemAvailable + SwapFree)` in bytes from `/proc/meminfo` text.
pub fn parse_meminfo(meminfo: &str) -> (Option<u64>, Option<u64>) {
    let field = |name| meminfo_field(meminfo, name);
    let swap = |name| field(name).unwrap_or(0);
    (
        field("MemTotal").map(|t| t.saturating_add(swap("SwapTotal"))),
        field("MemAvailable").map(|a| a.saturating_add(swap("SwapFree"))),
    )
}

/// A cgroup limit file's value: `max` (v2) or a value near 2^63 (v1's "unlimited") is none.
pub fn parse_cgroup_limit(text: &str) -> Option<u64> {
    let v: u64 = text.trim().parse().ok()?;
    (v < 1 << 60).then_some(v)
}

/// The smallest memory limit on the cgroup path `/proc/self/cgroup` names and its ancestors,
/// v2 (`memory.max`) or v1 (`memory.limit_in_bytes`), under `root` (`/sys/fs/cgroup`).
pub fn cgroup_limit(self_cgroup: &str, root: &Path) -> Option<u64> {
    let mut limit: Option<u64> = None;
    for line in self_cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (dir, file) = if id == "0" && controllers.is_empty() {
            (root.to_path_buf(), "memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            (root.join("memory"), "memory.limit_in_bytes")
        } else {
            continue;
        };
        let mut at = dir.join(path.trim_start_matches('/'));
        loop {
            if let Some(v) = std::fs::read_to_string(at.join(file))
                .ok()
                .and_then(|t| parse_cgroup_limit(&t))
            {
                limit = Some(limit.map_or(v, |l| l.min(v)));
            }
            if at == dir || !at.pop() {
                break;
            }
        }
    }
    limit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_meminfo_field_is_read_in_bytes_and_a_missing_one_is_none() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\nSwapFree: 0 kB\n";
        assert_eq!(meminfo_field(text, "MemAvailable"), Some(20_000_000 * 1024));
        assert_eq!(meminfo_field(text, "MemFree"), None);
        // A prefix of another field's name is not that field.
        assert_eq!(meminfo_field(text, "Mem"), None);
    }

    #[test]
    fn this_machine_reports_some_memory_available_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(available_memory().is_some_and(|b| b > 0));
        }
    }
}
