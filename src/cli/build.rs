//! `meshpyr build IN -o OUT.pyr [--relax …]`: build the progressive mesh and save it with the
//! exact input as a `.pyr` file (details are recomputed on load; see `formats/pyr.md`).
//!
//! Also holds loading a `.pyr` file into a [`ScanPyramid`] for `filter`, `spectrum`, `edit`.

use super::{BarProgress, Global};
use crate::format::{self, BuildInfo, FormatError, SizeReport};
use crate::io;
use crate::mesh::PolygonMesh;
use crate::pm::{PmOptions, ProgressiveMesh};
use crate::pyramid::ScanPyramid;
use crate::relax::{RelaxKind, RelaxationSpec};
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `meshpyr build`.
#[derive(clap::Args, Debug)]
pub struct BuildArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub input: PathBuf,
    /// Output `.pyr` file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Relaxation operator the pyramid is analysed with (recorded in the file; `filter`,
    /// `spectrum` and `edit` use it).
    #[arg(long, value_enum, default_value_t = RelaxKind::SecondDifference)]
    pub relax: RelaxKind,
}

/// Runs `meshpyr build`.
pub fn run(args: BuildArgs, global: &Global) -> anyhow::Result<()> {
    let relaxation = args.relax.spec();
    let input = super::read_input_mesh(&args.input)?;
    let start = Instant::now();
    let built = crate::mesh::Mesh::from_polygons(&input)
        .with_context(|| format!("cannot build the mesh of {}", args.input.display()))?;
    let bar = global.progress("build");
    let pm = ProgressiveMesh::build(&built.mesh, &PmOptions::default(), &BarProgress(&bar))
        .with_context(|| {
            format!(
                "cannot build the progressive mesh of {}",
                args.input.display()
            )
        })?;
    bar.finish_and_clear();
    let built_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (bytes, sizes) = encode_pyr(&input, &pm, relaxation)
        .with_context(|| format!("cannot encode {}", args.input.display()))?;
    let encode_s = start.elapsed().as_secs_f64();
    io::write_atomic(&args.output, &bytes)?;
    let n = input.n_vertices().max(1) as f64;
    global.say(format_args!(
        "wrote {}: {} bytes for {} vertices, levels {}..={} (PM {:.1} s, encode {:.3} s)",
        args.output.display(),
        sizes.total,
        input.n_vertices(),
        pm.n_base_vertices(),
        pm.n_vertices(),
        built_s,
        encode_s
    ));
    global.say(format_args!(
        "  bytes/vertex: whole file {:.2}, PM connectivity {:.2}, split errors {:.2}, positions {:.2}, input order+polygons+attributes {:.2}",
        sizes.total as f64 / n,
        sizes.pm_connectivity as f64 / n,
        sizes.split_errors as f64 / n,
        sizes.positions as f64 / n,
        sizes.trailing as f64 / n
    ));
    global.say(format_args!("  {}", pm.describe_base()));
    Ok(())
}

/// True when `path` is a `.pyr` file (by its signature; an unreadable file is "not").
pub fn is_pyr_file(path: &Path) -> bool {
    let mut head = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head))
        .is_ok_and(|_| format::is_pyr(&head))
}

/// Reads and decodes a whole `.pyr` file (validated), errors naming the file.
pub fn load_pyr(path: &Path) -> anyhow::Result<format::PyrData> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    format::decode(&bytes).with_context(|| format!("cannot load {}", path.display()))
}

/// Loads a `.pyr` file and recomputes its pyramid (the relaxation recorded in the file).
pub fn load_pyr_scan(
    path: &Path,
    global: &Global,
) -> anyhow::Result<(ScanPyramid, RelaxationSpec)> {
    let start = Instant::now();
    let data = load_pyr(path)?;
    let spec = data.info.relaxation;
    let loaded = start.elapsed().as_secs_f64();
    let bar = global.progress("analysis");
    let scan = data
        .into_scan(&BarProgress(&bar))
        .with_context(|| format!("cannot analyse {}", path.display()))?;
    bar.finish_and_clear();
    let p = &scan.pyramid;
    global.say(format_args!(
        "{}: {} vertices, levels {}..={} (loaded in {:.2} s, details recomputed in {:.2} s)",
        path.display(),
        scan.input.n_vertices(),
        p.n_base_vertices(),
        p.n_vertices(),
        loaded,
        start.elapsed().as_secs_f64() - loaded
    ));
    Ok((scan, spec))
}

/// Saves `scan` with new input positions as a `.pyr` file (same hierarchy, new originals).
pub fn save_edited(
    scan: &ScanPyramid,
    input_positions: Vec<glam::DVec3>,
    relaxation: RelaxationSpec,
    path: &Path,
) -> anyhow::Result<()> {
    let (input, pm) = format::with_positions(&scan.input, &scan.source, &scan.pm, input_positions)
        .context("cannot save the edit")?;
    let (bytes, _) = encode_pyr(&input, &pm, relaxation).context("cannot save the edit")?;
    io::write_atomic(path, &bytes)?;
    Ok(())
}

/// The `.pyr` file of `input` with its hierarchy `pm` (built with the default options, as
/// every command builds it) and the relaxation the pyramid is analysed with.
pub fn encode_pyr(
    input: &PolygonMesh,
    pm: &ProgressiveMesh,
    relaxation: RelaxationSpec,
) -> Result<(Vec<u8>, SizeReport), FormatError> {
    let info = BuildInfo {
        pm_options: PmOptions::default(),
        relaxation,
    };
    format::encode(input, pm, &info)
}
