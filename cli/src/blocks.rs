//! `--block-vertices N` and `--memory SIZE` of `build`, `filter` and `edit`: which way the
//! hierarchy of a mesh input is built (`meshpyr::memory::choose_build_path`), said on
//! standard error unless `--quiet`.

use super::Global;
use meshpyr::memory::{self, Allowance, BuildPath, InputSize, Job};
use meshpyr::mesh::PolygonMesh;
use meshpyr::pm::blocks::SharedRunner;
use meshpyr::pm::{MIN_BLOCK_VERTICES, PmOptions};
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
    /// cgroup allow); a scan whose estimate exceeds it is built in blocks, through task files
    /// in a folder next to the output (removed afterwards), and a pyramid's layout goes to a
    /// temporary file once it would take an eighth of it.
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
    /// Caps the memory this process's own choices take as available at `--memory` (the
    /// pyramid's layout goes to a temporary file rather than the heap once it would take more
    /// than an eighth of it: `meshpyr::machine::set_memory_allowance`).
    pub(crate) fn apply_allowance(&self) {
        if self.memory.is_some() {
            meshpyr::machine::set_memory_allowance(self.memory);
        }
    }

    /// The options of the build path chosen for `job` on the mesh `input` read from `path`,
    /// said unless `--quiet`: the block size, and where the passes' task files go. A path
    /// chosen because the scan would not fit runs through task files in a folder next to
    /// `output` (when known and the scan has no texture seams): the passes then hold only
    /// the tasks' blocks, where in memory they hold every block's result beside the whole
    /// mesh. A textured input is not built in blocks through task files ([`keeping_seams`]).
    pub(crate) fn pm_options(
        &self,
        path: &Path,
        output: Option<&Path>,
        job: Job,
        input: &PolygonMesh,
        global: &Global,
    ) -> anyhow::Result<PmOptions> {
        self.apply_allowance();
        let size = InputSize::mesh(input.n_vertices() as u64, input.n_faces() as u64);
        let allowance = Allowance::of_this_process();
        let chosen =
            memory::choose_build_path(job, &size, self.block_vertices, self.memory, &allowance);
        keeping_seams(path, &chosen, input, self.block_files.is_some())?;
        // Chosen by memory, without a folder given: the task files go next to the output.
        let by_memory = match chosen {
            BuildPath::Partitioned {
                by_memory: Some((need, _)),
                ..
            } if self.block_files.is_none() && !meshpyr::pm::keeps_texture_seams(input) => {
                output.map(|o| (folder_of(o), need))
            }
            _ => None,
        };
        let files = by_memory.as_ref().map_or(String::new(), |(dir, need)| {
            format!(
                ", through task files in {}; this process still holds the whole mesh \
                 (about {}: docs/partitioned.md)",
                dir.display(),
                memory::Bytes(*need)
            )
        });
        global.say(format_args!(
            "{}: building the hierarchy {chosen}{files}",
            path.display()
        ));
        Ok(PmOptions {
            block_vertices: chosen.block_vertices(),
            block_scratch: self.block_files.clone().or(by_memory.map(|(dir, _)| dir)),
            block_runner: self.runner.clone(),
            block_input: Some(path.to_path_buf()),
            ..PmOptions::default()
        })
    }
}

/// The folder `output` is written to (`.` for a bare file name).
fn folder_of(output: &Path) -> std::path::PathBuf {
    match output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    }
}

/// Refuses a partitioned build of `input`, read from `path`, through task files (`files`) when
/// its hierarchy keeps texture seams: the blocks keep the seams in memory, but the task files
/// (formats/blocks.md) do not carry the corners' wedges, so its coarser levels would lose the
/// texture (`docs/seams.md`).
fn keeping_seams(
    path: &Path,
    chosen: &BuildPath,
    input: &PolygonMesh,
    files: bool,
) -> anyhow::Result<()> {
    let BuildPath::Partitioned { .. } = chosen else {
        return Ok(());
    };
    if files && meshpyr::pm::keeps_texture_seams(input) {
        anyhow::bail!(
            "{}: --block-files: the scan is textured and the task files of a partitioned build \
             do not carry its texture seams (its coarser levels would lose the texture); leave \
             --block-files out to build it in blocks in memory, which keeps them",
            path.display()
        );
    }
    Ok(())
}
