//! Which way a command builds a scan's hierarchy: in one decimation of the whole scan, or in
//! spatial blocks (`PmOptions::block_vertices`, `docs/partitioned.md`).
//!
//! The one-process path is taken whenever the job's estimated peak ([`estimate`]) fits the
//! memory allowed: `--memory SIZE`, or by default what the machine and the cgroup allow. A
//! scan above it takes the partitioned path with blocks whose own working set is a small share
//! of the allowance (each of the threads works on one block at a time); `--block-vertices N`
//! forces blocks of at most `N` vertices.

use super::{Allowance, Bytes, InputSize, Job, estimate};
use std::fmt;

/// How a hierarchy is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildPath {
    /// One decimation of the whole scan.
    OneProcess {
        /// The estimated peak, in bytes.
        need: u64,
        /// The memory allowed, in bytes (`None`: no limit known).
        allowed: Option<u64>,
    },
    /// Spatial blocks of at most `block_vertices` vertices.
    Partitioned {
        /// The largest block.
        block_vertices: usize,
        /// The estimated peak of the one-process path and the memory allowed, when the
        /// choice was made by memory (`None`: forced by `--block-vertices`).
        by_memory: Option<(u64, u64)>,
    },
}

impl BuildPath {
    /// The block size to build with (`None`: one process).
    pub fn block_vertices(&self) -> Option<usize> {
        match *self {
            BuildPath::OneProcess { .. } => None,
            BuildPath::Partitioned { block_vertices, .. } => Some(block_vertices),
        }
    }
}

/// `in one process (estimated 1.2 GB of 24.0 GB allowed)`, `in blocks of at most 50000
/// vertices (--block-vertices)`.
impl fmt::Display for BuildPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BuildPath::OneProcess { need, allowed } => {
                write!(f, "in one process (estimated {}", Bytes(need))?;
                match allowed {
                    Some(a) => write!(f, " of {} allowed)", Bytes(a)),
                    None => write!(f, ", no memory limit known)"),
                }
            }
            BuildPath::Partitioned {
                block_vertices,
                by_memory,
            } => {
                write!(f, "in blocks of at most {block_vertices} vertices")?;
                match by_memory {
                    Some((need, allowed)) => write!(
                        f,
                        " (one process estimated at {}, {} allowed)",
                        Bytes(need),
                        Bytes(allowed)
                    ),
                    None => write!(f, " (--block-vertices)"),
                }
            }
        }
    }
}

/// Tasks of one block at a time per thread share the allowance: a block's working set is
/// held to this share of it, so that the blocks in flight stay well inside it.
const BLOCK_SHARE_OF_ALLOWANCE: u64 = 16;

/// The path for `job` on an input of `size`: forced blocks of `block_vertices`, else one
/// process when the job's estimate fits `memory` (default: the allowance's cgroup or machine
/// limit, whichever is smaller), else blocks sized to a share of that memory.
pub fn choose_build_path(
    job: Job,
    size: &InputSize,
    block_vertices: Option<usize>,
    memory: Option<u64>,
    allowance: &Allowance,
) -> BuildPath {
    let need = estimate(job, size).resident;
    if let Some(n) = block_vertices {
        return BuildPath::Partitioned {
            block_vertices: n,
            by_memory: None,
        };
    }
    let allowed = memory.or(match (allowance.cgroup, allowance.machine) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    });
    match allowed {
        Some(allowed) if need > allowed => {
            let per_vertex = (need / size.scale().max(1)).max(1);
            let fits = allowed / BLOCK_SHARE_OF_ALLOWANCE / per_vertex;
            let block = (fits as usize).clamp(crate::pm::MIN_BLOCK_VERTICES, 1 << 24);
            BuildPath::Partitioned {
                block_vertices: block,
                by_memory: Some((need, allowed)),
            }
        }
        _ => BuildPath::OneProcess { need, allowed },
    }
}

/// A memory size as a user writes it: bytes, or a number with a unit `K`, `M`, `G`, `T`
/// (powers of 1000, optionally followed by `B`; `KiB`, `MiB`, `GiB`, `TiB` for powers of
/// 1024): `8G`, `3GB`, `1.5GiB`, `500M`.
pub fn parse_memory_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => {
            return Err(format!(
                "unknown unit in memory size {text:?} (use K, M, G or T)"
            ));
        }
    };
    let value: f64 = number
        .parse()
        .map_err(|_| format!("memory size {text:?} is not a number with a unit such as 8G"))?;
    let bytes = value * scale;
    if !(1.0..1.8e19).contains(&bytes) {
        return Err(format!("memory size {text:?} is out of range"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size(v: u64) -> InputSize {
        InputSize::mesh(v, 2 * v)
    }

    #[test]
    fn memory_sizes_read_with_decimal_and_binary_units() {
        assert_eq!(parse_memory_size("8G"), Ok(8_000_000_000));
        assert_eq!(parse_memory_size("3GB"), Ok(3_000_000_000));
        assert_eq!(parse_memory_size("1.5GiB"), Ok(1_610_612_736));
        assert_eq!(parse_memory_size(" 500m "), Ok(500_000_000));
        assert_eq!(parse_memory_size("4096"), Ok(4096));
        for bad in ["", "G", "8X", "-1G", "0", "1e30"] {
            assert!(parse_memory_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_scan_that_fits_takes_one_process_and_one_that_does_not_takes_blocks() {
        let machine = Allowance {
            machine: Some(24_000_000_000),
            ..Allowance::default()
        };
        let small = choose_build_path(Job::Pyramid, &size(1_000_000), None, None, &machine);
        assert!(matches!(small, BuildPath::OneProcess { .. }), "{small}");
        let big = choose_build_path(
            Job::Pyramid,
            &size(1_000_000),
            None,
            Some(100_000_000),
            &machine,
        );
        let Some(block) = big.block_vertices() else {
            panic!("{big}")
        };
        assert!(
            (crate::pm::MIN_BLOCK_VERTICES..1_000_000).contains(&block),
            "{big}"
        );
        assert!(big.to_string().contains("100 MB allowed"), "{big}");
    }

    #[test]
    fn forced_blocks_win_over_memory() {
        let path = choose_build_path(
            Job::Pyramid,
            &size(10),
            Some(500),
            None,
            &Allowance::default(),
        );
        assert_eq!(path.block_vertices(), Some(500));
        assert!(path.to_string().contains("--block-vertices"));
    }

    #[test]
    fn the_smaller_of_the_cgroup_and_the_machine_is_the_default_allowance() {
        let tight = Allowance {
            cgroup: Some(50_000_000),
            machine: Some(24_000_000_000),
            ..Allowance::default()
        };
        let path = choose_build_path(Job::Pyramid, &size(1_000_000), None, None, &tight);
        assert!(path.block_vertices().is_some(), "{path}");
    }
}
