//! Whether a job fits in the memory this process may use, known before the work starts.
//!
//! A scan of tens of millions of vertices can need more memory than the machine (or the
//! process's limits) allow; without a check, the work runs for minutes and then aborts on a
//! failed allocation or is killed. [`check_file`] reads only the head of the input — a PLY or
//! OFF header's counts, a `.pyr` file's `META`, a binary STL's triangle count, or the size of
//! an OBJ or ASCII STL file — estimates the job's peak from per-vertex figures measured on
//! scans ([`FIGURES`]), and compares it with the limits:
//!
//! | limit | compared with | why |
//! |---|---|---|
//! | the address-space limit (`RLIMIT_AS`, `ulimit -v`) | the peak address space | an allocation beyond it fails |
//! | the cgroup's memory limit (`memory.max`, v1 `memory.limit_in_bytes`) | the peak resident memory | the kernel kills the process beyond it |
//! | the machine's RAM and swap (`MemTotal + SwapTotal`) | the peak resident memory | no process can hold more |
//!
//! These are hard limits: a job estimated above one is refused ([`TooLarge`]). The memory
//! available now (`MemAvailable + SwapFree`) is not: other programs may end or be swapped out,
//! so a job above it only comes with a warning ([`Fit::short_of_available`]).
//!
//! The estimate is an estimate: the figures are measured peaks on scans (about two triangles
//! per vertex, no extra attributes), scaled by the input's vertex count or half its face
//! count, whichever is larger. Setting the environment variable `MESHPYR_MEMORY_CHECK=off`
//! skips the check (for a job that is known to fit, or a limit that is known to be soft).
//!
//! ```
//! use meshpyr::memory::{self, Allowance, InputSize, Job};
//! let size = InputSize::mesh(100_000_000, 200_000_000);
//! let need = memory::estimate(Job::Pyramid, &size);
//! let small = Allowance { address_space: Some(1 << 30), ..Allowance::default() };
//! let refused = memory::check(Job::Pyramid, &size, &small).unwrap_err();
//! assert!(refused.to_string().contains("allowed (ulimit -v)"));
//! assert!(need.resident > 30_000_000_000);
//! ```

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::format;
use crate::io::{self, MeshFormat};
use crate::machine::cgroup_limit;
pub use crate::machine::{parse_cgroup_limit, parse_meminfo};
use crate::subdiv::Refinement;

mod build_path;
pub use build_path::{BuildPath, choose_build_path, parse_memory_size};

/// The environment variable that turns the check off (`off`, `0` or `no`).
pub const CHECK_ENV: &str = "MESHPYR_MEMORY_CHECK";

/// What a command does with its input: each job has its own measured peak.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Job {
    /// The progressive mesh and detail pyramid of a mesh (`filter`, `edit`, `spectrum`,
    /// `view`); from a `.pyr` file, the decoded hierarchy and its stored pyramid.
    Pyramid,
    /// The pyramid with its details encoded as a `.pyr` file (`build`).
    SavePyramid,
    /// Quadric-error decimation (`simplify`).
    Simplify,
    /// Denoising (`smooth`).
    Smooth,
    /// Subdivision (`subdivide`): the figure is per output vertex.
    Subdivide {
        /// Levels of refinement.
        levels: usize,
        /// How each level splits the triangles (4× or 2× the vertices per level).
        refinement: Refinement,
        /// The per-level systems are solved by sparse Cholesky factorisation (which holds
        /// the factor), not by an iterative solver.
        exact_solver: bool,
    },
}

impl fmt::Display for Job {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Job::Pyramid => f.write_str("the detail pyramid"),
            Job::SavePyramid => f.write_str("the detail pyramid and its .pyr file"),
            Job::Simplify => f.write_str("simplification"),
            Job::Smooth => f.write_str("denoising"),
            Job::Subdivide {
                levels,
                exact_solver,
                ..
            } => write!(
                f,
                "subdivision, {}{}",
                crate::wording::Count(*levels, "level", "levels"),
                if *exact_solver { ", exact solver" } else { "" }
            ),
        }
    }
}

/// A job's measured peak per input vertex, for resident memory and for address space (which
/// also counts mapped files, such as a large pyramid's layout, and reserved but untouched
/// memory); a fixed part comes on top ([`FIXED_RESIDENT`], [`fixed_address_space`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Figure {
    /// Resident bytes per vertex at the peak.
    pub resident_per_vertex: u64,
    /// Address-space bytes per vertex at the peak.
    pub address_space_per_vertex: u64,
}

/// The fixed part of every job, resident: the program and a tiny mesh (`info` on the bundled
/// bunny peaks at 24 MB).
pub const FIXED_RESIDENT: u64 = 24 << 20;

/// The fixed part of every job, address space: 128 MB for the program, and 64 MB for each
/// thread's allocator arena (glibc reserves that much address space per arena, one per
/// thread up to eight per core), counted for as many threads as the machine runs at once.
/// On 2 cores: 256 MB, what `info` and `filter` on the bunny reach (227 and 261 MB).
pub fn fixed_address_space() -> u64 {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    (128u64 << 20).saturating_add(threads.saturating_mul(64 << 20))
}

/// The per-vertex figures of the jobs on a mesh file.
///
/// Resident: GNU `time -f %M` of the whole command on scans made by
/// `benches/compare/make_big.py`, at the largest size measured (6.66M vertices): per vertex it
/// grows a little with the size for most jobs (on a 603k scan the same commands take 8–15 %
/// less). Address space: the process's `VmPeak` on the 603k scan less the fixed part, plus the
/// growth of the resident figure to the larger scan. How to measure them again:
/// `docs/performance.md`, "Memory: the estimate before the work".
pub const FIGURES: [(Job, Figure); 4] = [
    // Reading, repair, the progressive mesh from the builder's corner table, and the pyramid
    // whose layout (about 600 B per vertex) goes into mapped temporary files: resident is the
    // working window, the address space holds the whole mapping.
    (Job::Pyramid, figure(391, 1_050)),
    // The same; then the details coded and the detail pyramid dropped before the hierarchy's
    // sections are encoded and written.
    (Job::SavePyramid, figure(396, 1_170)),
    // The decimator's quadrics, candidates and working mesh beside the input.
    (Job::Simplify, figure(391, 430)),
    // The builder's corner table as the denoiser's flat surface, the filter's per-face arrays
    // (normals, areas, dual-edge lengths, local scales, filtered normals) and each thread's
    // Dijkstra distances (8 B per face) beside the input, whose positions take the result.
    // Its `VmPeak` above the fixed part (270 B/v on the 603k scan) is below its resident
    // peak there (362 B/v), so the address space takes the larger.
    (Job::Smooth, figure(351, 360)),
];

/// A `.pyr` input's decoding, per vertex of the mesh it holds: the replay of its hierarchy
/// beside what is decoded, the file mapped (its pages handed back as it is decoded) and its
/// details still coded; the pyramid from the file peaks about as high. Every job on a `.pyr`
/// input needs at least this.
pub const PYR_DECODE: Figure = figure(361, 1_220);

/// Subdivision's figure per output vertex (the input's vertices times `4^levels`, or `2^levels`
/// by bisection): the half-edge mesh of the finest level, the solver's arrays and the output.
/// Measured with `subdivide --levels 2` on the bundled bunny (603k output vertices; `--solver
/// auto` takes conjugate gradients at that size).
pub const SUBDIVIDE_PER_OUTPUT_VERTEX: Figure = figure(340, 400);

/// [`SUBDIVIDE_PER_OUTPUT_VERTEX`] with the exact solver (`--solver exact`, and `auto` up to
/// 250k output vertices), whose Cholesky factor is most of it: `subdivide --levels 2 --solver
/// exact` on the bundled bunny.
pub const SUBDIVIDE_EXACT_PER_OUTPUT_VERTEX: Figure = figure(1_160, 1_130);

const fn figure(resident: u64, address_space: u64) -> Figure {
    Figure {
        resident_per_vertex: resident,
        address_space_per_vertex: address_space,
    }
}

/// The size of an input as its file says it, before it is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputSize {
    /// Vertices (a `.pyr` file: of the mesh it was built from).
    pub vertices: u64,
    /// Faces as stored (polygons).
    pub faces: u64,
    /// The input is a `.pyr` file, whose hierarchy is decoded rather than built.
    pub pyr: bool,
    /// The counts are estimated from the file's size (OBJ, ASCII STL), not read from it.
    pub from_file_size: bool,
}

impl InputSize {
    /// A mesh of `vertices` and `faces`, counted.
    pub fn mesh(vertices: u64, faces: u64) -> InputSize {
        InputSize {
            vertices,
            faces,
            pyr: false,
            from_file_size: false,
        }
    }

    /// The vertex count the per-vertex figures apply to: the vertices, or half the faces when
    /// there are more (the figures are measured on scans with two triangles per vertex).
    pub fn scale(&self) -> u64 {
        self.vertices.max(self.faces / 2)
    }
}

/// A job's estimated peak, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Need {
    /// Resident memory.
    pub resident: u64,
    /// Address space.
    pub address_space: u64,
    /// The vertex count it was scaled by ([`InputSize::scale`]; subdivision: its output's).
    pub vertices: u64,
}

/// The estimated peak of `job` on an input of `size`.
pub fn estimate(job: Job, size: &InputSize) -> Need {
    let input = size.scale();
    let (per_vertex, vertices) = match job {
        Job::Subdivide {
            levels,
            refinement,
            exact_solver,
        } => {
            let base: u64 = match refinement {
                Refinement::Quadrisection => 4,
                Refinement::Bisection => 2,
            };
            let growth = base.saturating_pow(levels.min(64) as u32);
            let per = if exact_solver {
                SUBDIVIDE_EXACT_PER_OUTPUT_VERTEX
            } else {
                SUBDIVIDE_PER_OUTPUT_VERTEX
            };
            (per, input.saturating_mul(growth))
        }
        _ => (
            FIGURES
                .iter()
                .find(|(j, _)| *j == job)
                .map_or(figure(0, 0), |&(_, f)| f),
            input,
        ),
    };
    let times = |n: u64, per: u64, fixed: u64| fixed.saturating_add(n.saturating_mul(per));
    let mut need = Need {
        resident: times(vertices, per_vertex.resident_per_vertex, FIXED_RESIDENT),
        address_space: times(
            vertices,
            per_vertex.address_space_per_vertex,
            fixed_address_space(),
        ),
        vertices,
    };
    if size.pyr {
        let d = PYR_DECODE;
        need.resident = need
            .resident
            .max(times(input, d.resident_per_vertex, FIXED_RESIDENT));
        need.address_space = need.address_space.max(times(
            input,
            d.address_space_per_vertex,
            fixed_address_space(),
        ));
    }
    need
}

/// Where a limit comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitSource {
    /// The address-space limit, `RLIMIT_AS`.
    AddressSpace,
    /// The memory limit of the process's cgroup.
    Cgroup,
    /// The machine's RAM and swap.
    Machine,
}

impl fmt::Display for LimitSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LimitSource::AddressSpace => "ulimit -v",
            LimitSource::Cgroup => "the cgroup's memory limit",
            LimitSource::Machine => "the machine's RAM and swap",
        })
    }
}

/// The memory this process may use, in bytes (`None`: no such limit, or unknown).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Allowance {
    /// `RLIMIT_AS` (soft), compared with the address space a job needs.
    pub address_space: Option<u64>,
    /// The cgroup's limit, compared with the resident memory a job needs.
    pub cgroup: Option<u64>,
    /// RAM and swap, compared with the resident memory a job needs.
    pub machine: Option<u64>,
    /// RAM and swap available now: a job above it is warned about, not refused.
    pub available: Option<u64>,
}

impl Allowance {
    /// The limits of this process (Linux: from `/proc` and `/sys/fs/cgroup`; elsewhere none
    /// are known and every job fits).
    pub fn of_this_process() -> Allowance {
        let read = |p: &str| std::fs::read_to_string(p).ok();
        let meminfo = read("/proc/meminfo").map(|t| parse_meminfo(&t));
        Allowance {
            address_space: read("/proc/self/limits").and_then(|t| parse_address_space_limit(&t)),
            cgroup: read("/proc/self/cgroup")
                .and_then(|t| cgroup_limit(&t, Path::new("/sys/fs/cgroup"))),
            machine: meminfo.and_then(|m| m.0),
            available: meminfo.and_then(|m| m.1),
        }
    }
}

/// The soft address-space limit in `/proc/self/limits` text (`None`: unlimited or absent).
pub fn parse_address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    soft.parse().ok()
}

/// A job that fits, with its estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fit {
    /// The input's size the estimate was made from.
    pub size: InputSize,
    /// The estimate.
    pub need: Need,
    /// The memory available now, when the job needs more than that (a warning, not an
    /// error: other programs may free memory or be swapped out).
    pub short_of_available: Option<u64>,
}

/// A job whose estimated peak exceeds a hard limit. `Display` is one line:
/// `scan.ply: needs about 39.1 GB of memory for 100000000 vertices (the detail pyramid),
/// 1.1 GB allowed (ulimit -v); MESHPYR_MEMORY_CHECK=off runs it anyway`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "{}needs about {} of memory for {} vertices ({job}), {} allowed ({from}); \
     {CHECK_ENV}=off runs it anyway",
    path.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default(),
    Bytes(*need), vertices, Bytes(*limit)
)]
pub struct TooLarge {
    /// The input, when known.
    pub path: Option<PathBuf>,
    /// The job.
    pub job: Job,
    /// The vertex count the estimate was scaled by.
    pub vertices: u64,
    /// The estimated peak that exceeds the limit, in bytes (address space against `ulimit -v`,
    /// resident memory against the others).
    pub need: u64,
    /// The limit, in bytes.
    pub limit: u64,
    /// Where the limit comes from.
    pub from: LimitSource,
}

/// Checks `job` on an input of `size` against `allowance`.
pub fn check(job: Job, size: &InputSize, allowance: &Allowance) -> Result<Fit, TooLarge> {
    let need = estimate(job, size);
    let hard = [
        (
            allowance.address_space,
            need.address_space,
            LimitSource::AddressSpace,
        ),
        (allowance.cgroup, need.resident, LimitSource::Cgroup),
        (allowance.machine, need.resident, LimitSource::Machine),
    ];
    for (limit, needed, source) in hard {
        if let Some(limit) = limit
            && needed > limit
        {
            return Err(TooLarge {
                path: None,
                job,
                vertices: need.vertices,
                need: needed,
                limit,
                from: source,
            });
        }
    }
    Ok(Fit {
        size: *size,
        need,
        short_of_available: allowance.available.filter(|&a| need.resident > a),
    })
}

/// True unless [`CHECK_ENV`] turns the check off.
pub fn check_enabled() -> bool {
    !std::env::var(CHECK_ENV)
        .is_ok_and(|v| matches!(v.trim().to_ascii_lowercase().as_str(), "off" | "0" | "no"))
}

/// Checks `job` on the file at `path` against this process's limits, reading only the
/// file's head ([`input_size`]). `Ok(None)` when the check is off ([`CHECK_ENV`]) or the
/// file's size cannot be told from its head (unreadable, malformed, or a header whose counts
/// the file cannot hold: the reader reports those in its own words).
pub fn check_file(path: &Path, job: Job) -> Result<Option<Fit>, TooLarge> {
    if !check_enabled() {
        return Ok(None);
    }
    let Some(size) = input_size(path) else {
        return Ok(None);
    };
    check_size(path, job, &size).map(Some)
}

/// [`check_file`] with counts already known (a mesh that was read, say): errors name `path`.
/// Unlike [`check_file`] it does not look at [`CHECK_ENV`]: the caller decides whether to check
/// ([`check_enabled`]).
pub fn check_size(path: &Path, job: Job, size: &InputSize) -> Result<Fit, TooLarge> {
    check(job, size, &Allowance::of_this_process()).map_err(|e| TooLarge {
        path: Some(path.to_path_buf()),
        ..e
    })
}

/// Bytes read from the head of a file: enough for any PLY header but absurd ones, a `.pyr`
/// file's section table and `META`.
const HEAD: u64 = 1 << 16;

/// OBJ bytes per vertex at most, for scans: a `v` line with 9-digit coordinates, a `vt` and a
/// `vn` line, and two `f` lines of `v/vt/vn` triples (about 40 + 25 + 40 + 2 × 50). An OBJ
/// file's vertex count is estimated as its size over this, so the estimate errs low.
const OBJ_BYTES_PER_VERTEX: u64 = 200;

/// ASCII STL bytes per triangle at most (a `facet normal` line, `outer loop`, three `vertex`
/// lines, `endloop`, `endfacet`, with 9-digit numbers and indentation).
const STL_ASCII_BYTES_PER_FACE: u64 = 300;

/// The size of the input at `path` from its head only: a `.pyr` file's counts (by its
/// signature), a PLY or OFF header's counts (gzipped too), a binary STL's triangle count, or
/// an estimate from the size of an OBJ or ASCII STL file. `None` when it cannot be told.
pub fn input_size(path: &Path) -> Option<InputSize> {
    let file = std::fs::File::open(path).ok()?;
    let len = file.metadata().ok()?.len();
    let mut head = Vec::new();
    file.take(HEAD).read_to_end(&mut head).ok()?;
    if format::is_pyr(&head) {
        let (vertices, faces) = format::pyr::head_counts(&head)?;
        return Some(InputSize {
            vertices,
            faces,
            pyr: true,
            from_file_size: false,
        });
    }
    let format = MeshFormat::from_path(path).ok()?;
    let gz = io::is_gzip(path);
    let (head, body_len) = if gz {
        (io::head_of_gz(&head, HEAD as usize)?, None)
    } else {
        (head, Some(len))
    };
    let counted = |(v, f)| Some(InputSize::mesh(v, f));
    let by_size = |vertices, faces| {
        Some(InputSize {
            vertices,
            faces,
            pyr: false,
            from_file_size: true,
        })
    };
    match format {
        MeshFormat::Ply => counted(io::ply::header_counts(&head, body_len)?),
        MeshFormat::Off => counted(io::off::header_counts(&head, body_len)?),
        // Compressed text's size says little: no estimate (the command line does not check
        // these after reading either).
        MeshFormat::Obj | MeshFormat::Stl if gz => None,
        MeshFormat::Obj => by_size(len / OBJ_BYTES_PER_VERTEX, 0),
        MeshFormat::Stl => match io::stl::binary_triangles(&head, len) {
            Some(n) => counted((n / 2, n)),
            None => by_size(0, len / STL_ASCII_BYTES_PER_FACE),
        },
    }
}

/// Bytes as a message shows them: `1.4 GB`, `350 MB` (decimal units).
#[derive(Clone, Copy, Debug)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0 as f64;
        if b >= 1e9 {
            write!(f, "{:.1} GB", b / 1e9)
        } else {
            write!(f, "{:.0} MB", (b / 1e6).max(1.0))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: &str = "Limit                     Soft Limit           Hard Limit           Units     \n\
Max cpu time              unlimited            unlimited            seconds   \n\
Max address space         1073741824           unlimited            bytes     \n\
Max file locks            unlimited            unlimited            locks     \n";

    #[test]
    fn the_soft_address_space_limit_is_read_and_unlimited_is_none() {
        assert_eq!(parse_address_space_limit(LIMITS), Some(1 << 30));
        let unlimited = LIMITS.replace("1073741824", "unlimited");
        assert_eq!(parse_address_space_limit(&unlimited), None);
        assert_eq!(parse_address_space_limit(""), None);
    }

    #[test]
    fn meminfo_gives_ram_and_swap_in_bytes() {
        let text = "MemTotal:       24683772 kB\nMemFree:  100 kB\nMemAvailable:   23997504 kB\n\
                    SwapTotal:      1000 kB\nSwapFree:        500 kB\n";
        assert_eq!(
            parse_meminfo(text),
            (
                Some((24683772 + 1000) * 1024),
                Some((23997504 + 500) * 1024)
            )
        );
        assert_eq!(parse_meminfo("MemTotal: 10 kB\n"), (Some(10240), None));
    }

    #[test]
    fn cgroup_max_and_v1_unlimited_are_no_limit() {
        assert_eq!(parse_cgroup_limit("max\n"), None);
        assert_eq!(parse_cgroup_limit("9223372036854771712\n"), None);
        assert_eq!(parse_cgroup_limit("2147483648\n"), Some(2 << 30));
    }

    #[test]
    fn the_cgroup_limit_is_the_smallest_on_the_path() {
        let root = tempfile::tempdir().unwrap();
        let leaf = root.path().join("a/b");
        std::fs::create_dir_all(&leaf).unwrap();
        std::fs::write(root.path().join("a/memory.max"), "1000000\n").unwrap();
        std::fs::write(leaf.join("memory.max"), "max\n").unwrap();
        assert_eq!(cgroup_limit("0::/a/b\n", root.path()), Some(1_000_000));
        let v1 = root.path().join("memory/x");
        std::fs::create_dir_all(&v1).unwrap();
        std::fs::write(v1.join("memory.limit_in_bytes"), "5000\n").unwrap();
        assert_eq!(
            cgroup_limit("4:memory:/x\n2:cpu:/\n", root.path()),
            Some(5000)
        );
        assert_eq!(cgroup_limit("1:cpu:/\n", root.path()), None);
    }

    #[test]
    fn the_estimate_scales_with_vertices_or_half_the_faces() {
        let small = estimate(Job::Pyramid, &InputSize::mesh(1000, 2000));
        let big = estimate(Job::Pyramid, &InputSize::mesh(1_000_000, 2_000_000));
        let soup = estimate(Job::Pyramid, &InputSize::mesh(1000, 2_000_000));
        assert_eq!(big.vertices, 1_000_000);
        assert_eq!(soup, big);
        assert_eq!(big.resident - small.resident, 999_000 * 391);
        assert!(big.address_space > big.resident);
        let pyr = InputSize {
            pyr: true,
            ..InputSize::mesh(1_000_000, 2_000_000)
        };
        assert!(estimate(Job::Pyramid, &pyr).resident >= big.resident);
        let subdivide = |levels, refinement, exact_solver| Job::Subdivide {
            levels,
            refinement,
            exact_solver,
        };
        let small = InputSize::mesh(1000, 2000);
        let sub = estimate(subdivide(2, Refinement::Quadrisection, false), &small);
        assert_eq!(sub.vertices, 16_000);
        let exact = estimate(subdivide(2, Refinement::Quadrisection, true), &small);
        assert!(exact.resident > sub.resident);
        let halves = estimate(subdivide(2, Refinement::Bisection, false), &small);
        assert_eq!(halves.vertices, 4_000);
        let absurd = subdivide(40, Refinement::Quadrisection, false);
        assert_eq!(
            estimate(absurd, &InputSize::mesh(u64::MAX, 0)).resident,
            u64::MAX
        );
    }

    #[test]
    fn a_job_above_a_hard_limit_is_refused_in_one_line_and_one_above_available_warned() {
        let size = InputSize::mesh(10_000_000, 20_000_000);
        let unlimited = Allowance::default();
        assert_eq!(
            check(Job::Smooth, &size, &unlimited)
                .unwrap()
                .short_of_available,
            None
        );
        let tight = Allowance {
            address_space: Some(2_000_000_000),
            ..Allowance::default()
        };
        let e = check(Job::Smooth, &size, &tight).unwrap_err();
        assert_eq!(e.from, LimitSource::AddressSpace);
        let line = e.to_string();
        assert!(!line.contains('\n'), "{line}");
        assert!(
            line.starts_with("needs about ")
                && line.contains("for 10000000 vertices (denoising), 2.0 GB allowed (ulimit -v)"),
            "{line}"
        );
        let machine = Allowance {
            machine: Some(1 << 30),
            ..Allowance::default()
        };
        let e = check(Job::Smooth, &size, &machine).unwrap_err();
        assert_eq!(e.need, estimate(Job::Smooth, &size).resident);
        assert!(
            e.to_string().contains("(the machine's RAM and swap)"),
            "{e}"
        );
        let busy = Allowance {
            available: Some(1 << 30),
            ..Allowance::default()
        };
        assert_eq!(
            check(Job::Smooth, &size, &busy).unwrap().short_of_available,
            Some(1 << 30)
        );
    }

    /// A file of `head` followed by zeros up to `len` bytes (sparse: no disk used).
    fn file(dir: &Path, name: &str, head: &[u8], len: u64) -> PathBuf {
        let path = dir.join(name);
        let mut f = std::fs::File::create(&path).unwrap();
        std::io::Write::write_all(&mut f, head).unwrap();
        f.set_len(len.max(head.len() as u64)).unwrap();
        path
    }

    const PLY: &[u8] = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000\n\
        property float x\nproperty float y\nproperty float z\nelement face 2000000\n\
        property list uchar int vertex_indices\nend_header\n";

    #[test]
    fn a_ply_header_gives_the_counts_when_the_file_can_hold_them() {
        let dir = tempfile::tempdir().unwrap();
        let body = 1_000_000 * 12 + 2_000_000 * 13;
        let full = file(dir.path(), "a.ply", PLY, PLY.len() as u64 + body);
        assert_eq!(
            input_size(&full),
            Some(InputSize::mesh(1_000_000, 2_000_000))
        );
        // Too short for its counts (at least a count byte per face): no estimate, the reader
        // says what is wrong.
        let least = 1_000_000 * 12 + 2_000_000;
        let short = file(dir.path(), "b.ply", PLY, PLY.len() as u64 + least - 1);
        assert_eq!(input_size(&short), None);
        let gz = dir.path().join("c.ply.gz");
        std::fs::write(&gz, io::gzip(PLY)).unwrap();
        assert_eq!(input_size(&gz), Some(InputSize::mesh(1_000_000, 2_000_000)));
        let broken = file(dir.path(), "d.ply", b"ply\nformat nonsense\n", 1000);
        assert_eq!(input_size(&broken), None);
    }

    #[test]
    fn off_stl_and_obj_sizes_come_from_their_heads_or_lengths() {
        let dir = tempfile::tempdir().unwrap();
        let off = file(dir.path(), "a.off", b"OFF\n# scan\n5000 10000 0\n", 100_000);
        assert_eq!(input_size(&off), Some(InputSize::mesh(5000, 10000)));
        let too_short = file(dir.path(), "b.off", b"OFF\n5000 10000 0\n", 1000);
        assert_eq!(input_size(&too_short), None);
        let mut stl = vec![0u8; 84];
        stl[80..84].copy_from_slice(&1000u32.to_le_bytes());
        let binary = file(dir.path(), "a.stl", &stl, 84 + 50 * 1000);
        assert_eq!(input_size(&binary), Some(InputSize::mesh(500, 1000)));
        let ascii = file(dir.path(), "b.stl", b"solid x\n", 3_000_000);
        let size = input_size(&ascii).unwrap();
        assert!(size.from_file_size && size.scale() == 5000, "{size:?}");
        let obj = file(dir.path(), "a.obj", b"v 0 0 0\n", 2_000_000);
        let size = input_size(&obj).unwrap();
        assert!(size.from_file_size && size.vertices == 10_000, "{size:?}");
        assert_eq!(input_size(&dir.path().join("missing.ply")), None);
    }

    #[test]
    fn a_pyr_file_gives_the_counts_of_its_input_from_its_head() {
        let scan = crate::read_mesh("tests/data/mc/mc_bunny_vox40.ply").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.pyr");
        crate::Pyramid::build(&scan).unwrap().save(&path).unwrap();
        let size = input_size(&path).unwrap();
        assert!(size.pyr && !size.from_file_size);
        assert_eq!(
            (size.vertices, size.faces),
            (scan.n_vertices() as u64, scan.n_faces() as u64)
        );
    }

    #[test]
    fn bytes_show_in_decimal_units() {
        assert_eq!(Bytes(39_123_000_000).to_string(), "39.1 GB");
        assert_eq!(Bytes(350_000_000).to_string(), "350 MB");
        assert_eq!(Bytes(0).to_string(), "1 MB");
    }
}
