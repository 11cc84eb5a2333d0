//! Multiresolution editing with the library API: build the detail pyramid of a mesh, pull a
//! region of a coarse level outwards, and resynthesise — the fine details follow the bend.
//!
//! ```text
//! cargo run --release --example multires_edit -- [IN] [OUT] [LEVEL]
//! ```
//!
//! Defaults: the bundled bunny, `multires-edit.ply`, level 500. Also writes a side-by-side
//! preview `multires-edit.png` (before | after).

use meshpyr::io;
use meshpyr::progress::NoProgress;
use meshpyr::pyramid::{LevelGains, MoveHandle, Pyramid, PyramidOptions};
use meshpyr::render::{RenderOptions, Triangles, render_panels};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let input = args.next().map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.ply"),
        PathBuf::from,
    );
    let output = PathBuf::from(args.next().unwrap_or_else(|| "multires-edit.ply".into()));
    let level: usize = args.next().map_or(Ok(500), |s| s.parse())?;

    let scan = Pyramid::build_with(
        io::read_mesh(&input)?,
        &PyramidOptions::default(),
        &NoProgress,
    )?;
    let pyr = &scan.pyramid;
    let level = level.clamp(pyr.n_base_vertices(), pyr.n_vertices());

    // Grab the level's highest vertex and pull it up and forwards by 8% of the model size.
    let coarse = pyr.signal_at_level(level);
    let top = coarse[..level]
        .iter()
        .copied()
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap_or_default();
    let size = pyr.bbox_diagonal();
    let handle = MoveHandle {
        center: top,
        displacement: glam::DVec3::new(0.0, 0.05, 0.06) * size,
        radius: 0.25 * size,
    };
    let edited = pyr.edit(level, &[handle], &LevelGains::unit())?;
    io::write_mesh(&output, &scan.output_mesh(&edited))?;

    let before = pyr.synthesize(&LevelGains::unit());
    let faces = scan.pm.finest_faces();
    let preview = render_panels(
        &[
            Triangles {
                positions: &before,
                triangles: faces,
            },
            Triangles {
                positions: &edited,
                triangles: faces,
            },
        ],
        &RenderOptions::default(),
    );
    let png = output.with_extension("png");
    io::write_atomic(&png, &preview.encode_png()?)?;
    println!(
        "edited level {level} of {} at {top:.3?} (radius {:.3}); wrote {} and {}",
        pyr.n_vertices(),
        handle.radius,
        output.display(),
        png.display()
    );
    Ok(())
}
