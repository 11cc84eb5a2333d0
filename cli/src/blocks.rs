//! `--block-vertices N` and `--memory SIZE` of `build`, `filter` and `edit`: which way the
//! hierarchy of a mesh input is built (`meshpyr::memory::choose_build_path`), said on
//! standard error unless `--quiet`.

use super::Global;
use meshpyr::memory::{self, Allowance, BuildPath, InputSize, Job};
use meshpyr::mesh::PolygonMesh;
use meshpyr::pm::MIN_BLOCK_VERTICES;
use meshpyr::pm::blocks::SharedRunner;
use std::path::Path;

fn parse_block_vertices(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a vertex count"))?;
    if n < MIN_BLOCK_VERTICES {
        return Err(format!(
            "blocks must hold at least {MIN_BLOCK_VERTICES} vertices"
        ));
    }
    Ok(n)
}

/// The options that choose the build path.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct PathOptions {
    /// Build the hierarchy in spatial blocks of at most N vertices, their borders pinned for
    /// one pass at a time (docs/partitioned.md), whatever the memory.
    #[arg(long, value_name = "N", value_parser = parse_block_vertices)]
    pub(crate) block_vertices: Option<usize>,
    /// The memory the build may use (8G, 3GB, 1.5GiB; default: what the machine and the
    /// cgroup allow); a scan whose estimate exceeds it is built in blocks.
    #[arg(long, value_name = "SIZE", value_parser = memory::parse_memory_size)]
    pub(crate) memory: Option<u64>,
    /// When the hierarchy is built in blocks: run every pass through task files in a new
    /// folder under DIR, removed afterwards (the same hierarchy; formats/blocks.md).
    #[arg(long, value_name = "DIR")]
    pub(crate) block_files: Option<std::path::PathBuf>,
    /// With `--block-files`: what runs each round's tasks, set by [`crate::run_with_block_runner`]
    /// (`None`: this process's threads).
    #[arg(skip)]
    pub(crate) runner: Option<SharedRunner>,
}

impl PathOptions {
    /// The path for `job` on the mesh `input` read from `path`, said unless `--quiet`. A
    /// textured input is never built in blocks ([`keeping_seams`]).
    pub(crate) fn choose(
        &self,
        path: &Path,
        job: Job,
        input: &PolygonMesh,
        global: &Global,
    ) -> anyhow::Result<BuildPath> {
        let size = InputSize::mesh(input.n_vertices() as u64, input.n_faces() as u64);
        let allowance = Allowance::of_this_process();
        let chosen =
            memory::choose_build_path(job, &size, self.block_vertices, self.memory, &allowance);
        let chosen = keeping_seams(path, chosen, input)?;
        global.say(format_args!(
            "{}: building the hierarchy {chosen}",
            path.display()
        ));
        Ok(chosen)
    }
}

/// `chosen` for `input`, read from `path`, when its hierarchy keeps texture seams: the blocks
/// of a partitioned build decide their collapses without the seams (`docs/seams.md`), so its
/// coarser levels would lose the texture. Forced blocks are refused; blocks chosen for memory
/// give way to one process, with a warning that it may not fit.
fn keeping_seams(path: &Path, chosen: BuildPath, input: &PolygonMesh) -> anyhow::Result<BuildPath> {
    let BuildPath::Partitioned { by_memory, .. } = chosen else {
        return Ok(chosen);
    };
    if !meshpyr::pm::keeps_texture_seams(input) {
        return Ok(chosen);
    }
    let Some((need, allowed)) = by_memory else {
        anyhow::bail!(
            "{}: --block-vertices: the scan is textured and a partitioned build does not keep \
             its texture seams (its coarser levels would lose the texture); leave \
             --block-vertices out to build it in one process",
            path.display()
        );
    };
    eprintln!(
        "warning: {}: the scan is textured and a partitioned build does not keep its texture \
         seams, so its hierarchy is built in one process, estimated at {} with {} allowed; it \
         may swap or be stopped by the system (a larger --memory says it may use more)",
        path.display(),
        memory::Bytes(need),
        memory::Bytes(allowed)
    );
    Ok(BuildPath::OneProcess {
        need,
        allowed: Some(allowed),
    })
}
