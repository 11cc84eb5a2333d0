//! `meshpyr demo [--out DIR]`: the main job on the bundled scan.

use super::Global;
use super::info::mesh_info;
use crate::io::{self, MeshFormat};
use anyhow::Context;
use std::path::PathBuf;

/// The bundled default scan (Stanford bunny, 37.7k vertices; see `tests/data/README.md`).
pub const BUNDLED_SCAN: &[u8] = include_bytes!("../../tests/data/bunny.ply");

/// Arguments of `meshpyr demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// Directory for the outputs (created if missing).
    #[arg(long, default_value = "meshpyr-demo")]
    pub out: PathBuf,
}

/// Runs `meshpyr demo`.
pub fn run(args: DemoArgs, global: &Global) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let poly = io::read_mesh_bytes(BUNDLED_SCAN, MeshFormat::Ply)?;
    let info = mesh_info(&poly)?;
    global.say(format_args!(
        "bundled scan: {} vertices, {} faces, genus {}, bbox diagonal {:.4}",
        info.vertices,
        info.faces,
        info.genus.map_or("n/a".into(), |g| g.to_string()),
        info.bbox_diagonal
    ));
    let info_path = args.out.join("bunny-info.json");
    io::write_atomic(&info_path, serde_json::to_string_pretty(&info)?.as_bytes())?;
    global.say(format_args!("wrote {}", info_path.display()));
    // The input next to the results, to open side by side in a viewer.
    let input_path = args.out.join("bunny.ply");
    io::write_mesh(&input_path, &poly)?;
    global.say(format_args!("wrote {}", input_path.display()));
    super::filter::demo_filters(poly, "bunny", &args.out, global)?;
    Ok(())
}
