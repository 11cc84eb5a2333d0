//! `meshpyr render IN... -o OUT.png`: a picture of meshes side by side under one camera,
//! optionally coloured by a per-vertex attribute (see [`meshpyr::render`]).

use super::Global;
use anyhow::Context;
use meshpyr::format;
use meshpyr::mesh::PolygonMesh;
use meshpyr::render::{RenderOptions, Shading, Textures, View, render_textured_meshes};
use std::path::{Path, PathBuf};

/// Arguments of `meshpyr render`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Views: front (+z towards the viewer), back, left (-x), right (+x), top (+y), \
                  bottom, iso. --azimuth turns the model about the vertical axis, --elevation \
                  then tilts its top towards the viewer (degrees). Several inputs are drawn side \
                  by side with one camera, so equal sizes look equal, each captioned with its \
                  file name. --color-by colours the surface by a per-vertex PLY property (e.g. \
                  `distance` from `compare --per-vertex`) through viridis, with a colour bar \
                  showing the range (default: the values' minimum and maximum over all inputs). A \
                  textured mesh (OBJ map_Kd, PLY TextureFile; PNG or JPEG images) shows its texture, \
                  shaded like the surface; a missing or unreadable image is a warning and its \
                  faces are drawn plain."
)]
pub(crate) struct RenderArgs {
    /// Meshes to draw (.obj, .ply, .off, .stl, or a .pyr file: its stored input, or a level
    /// with --level).
    #[arg(required = true, value_name = "IN")]
    pub(crate) inputs: Vec<PathBuf>,
    /// The PNG to write.
    #[arg(short, long, value_name = "OUT.png")]
    pub(crate) output: PathBuf,
    /// Size of each panel in pixels (captions and the colour bar add strips).
    #[arg(long, value_name = "WxH", default_value = "480x480", value_parser = parse_size)]
    pub(crate) size: (usize, usize),
    /// Which side faces the viewer: front, back, left, right, top, bottom or iso.
    #[arg(long, default_value = "front", conflicts_with_all = ["azimuth", "elevation"])]
    pub(crate) view: View,
    /// Rotation about the vertical axis in degrees, instead of --view.
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub(crate) azimuth: Option<f64>,
    /// Tilt in degrees after the azimuth (positive shows the top), instead of --view.
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    pub(crate) elevation: Option<f64>,
    /// Draw the triangle edges over the surface.
    #[arg(long)]
    pub(crate) wireframe: bool,
    /// Smooth shading (interpolated vertex normals) instead of flat facets.
    #[arg(long)]
    pub(crate) smooth: bool,
    /// Colour by this per-vertex attribute (a PLY vertex property such as `distance`).
    #[arg(long, value_name = "ATTRIBUTE")]
    pub(crate) color_by: Option<String>,
    /// The values at the ends of the colour map (default: the values' own range).
    #[arg(long, value_name = "MIN:MAX", value_parser = parse_range, requires = "color_by", allow_hyphen_values = true)]
    pub(crate) range: Option<(f64, f64)>,
    /// Draw textured meshes in the plain surface colour instead of their images.
    #[arg(long)]
    pub(crate) no_texture: bool,
    /// Draw this level (vertex count) of each .pyr input instead of its stored mesh.
    #[arg(long, value_name = "N")]
    pub(crate) level: Option<usize>,
}

/// Largest panel side: big enough for print, small enough that a typo cannot ask for
/// gigabytes.
const MAX_SIDE: usize = 8192;

fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("expected WxH with W and H in 16..={MAX_SIDE}, e.g. 480x480");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h) = (w.parse::<usize>(), h.parse::<usize>());
    match (w, h) {
        (Ok(w), Ok(h)) if (16..=MAX_SIDE).contains(&w) && (16..=MAX_SIDE).contains(&h) => {
            Ok((w, h))
        }
        _ => Err(bad()),
    }
}

fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let bad = || "expected MIN:MAX with finite numbers and MIN < MAX, e.g. 0:0.01".to_string();
    let (lo, hi) = s.split_once(':').ok_or_else(bad)?;
    match (lo.trim().parse::<f64>(), hi.trim().parse::<f64>()) {
        (Ok(lo), Ok(hi)) if lo.is_finite() && hi.is_finite() && lo < hi => Ok((lo, hi)),
        _ => Err(bad()),
    }
}

/// Runs `meshpyr render`.
pub(crate) fn run(args: RenderArgs, global: &Global) -> anyhow::Result<()> {
    check_png_output(&args.output)?;
    let meshes = args
        .inputs
        .iter()
        .map(|path| read_panel_mesh(path, args.level))
        .collect::<anyhow::Result<Vec<PolygonMesh>>>()?;
    let labels: Vec<String> = args.inputs.iter().map(|p| file_label(p)).collect();
    let textures: Vec<Option<Textures>> = meshes
        .iter()
        .zip(&args.inputs)
        .map(|(m, path)| (!args.no_texture).then(|| load_textures(m, path)))
        .collect();
    let panels: Vec<(&str, &PolygonMesh, Option<&Textures>)> = labels
        .iter()
        .zip(&meshes)
        .zip(&textures)
        .map(|((label, m), t)| (label.as_str(), m, t.as_ref()))
        .collect();
    let image = render_textured_meshes(&panels, &render_options(&args))?;
    meshpyr::io::write_atomic(&args.output, &image.encode_png()?)?;
    global.say(format_args!(
        "wrote {} ({}x{})",
        args.output.display(),
        image.width,
        image.height
    ));
    Ok(())
}

/// The library's options from the command line's.
fn render_options(args: &RenderArgs) -> RenderOptions {
    let (yaw, pitch) = if args.azimuth.is_some() || args.elevation.is_some() {
        (args.azimuth.unwrap_or(0.0), args.elevation.unwrap_or(0.0))
    } else {
        args.view.angles()
    };
    RenderOptions {
        width: args.size.0,
        height: args.size.1,
        yaw_degrees: yaw,
        pitch_degrees: pitch,
        shading: if args.smooth {
            Shading::Smooth
        } else {
            Shading::Flat
        },
        wireframe: args.wireframe,
        color_by: args.color_by.clone(),
        range: args.range,
        ..RenderOptions::default()
    }
}

/// The images of `mesh`'s materials, with a warning on standard error for each one that
/// cannot be drawn.
fn load_textures(mesh: &PolygonMesh, path: &Path) -> Textures {
    let (textures, warnings) = Textures::load(mesh);
    for w in warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    textures
}

/// Fails before any work when the output is not a `.png`.
fn check_png_output(path: &Path) -> anyhow::Result<()> {
    let is_png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    anyhow::ensure!(
        is_png,
        "{}: render writes PNG; name the output *.png",
        path.display()
    );
    Ok(())
}

/// The caption of an input: its file name.
fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The mesh of one input: the file's mesh, or level `level` of a `.pyr` file.
fn read_panel_mesh(path: &Path, level: Option<usize>) -> anyhow::Result<PolygonMesh> {
    let is_pyr = super::input::is_pyr_file(path);
    let Some(n) = level else {
        return super::input::read_input_mesh(path);
    };
    anyhow::ensure!(
        is_pyr,
        "{}: --level applies to .pyr files (made by `meshpyr build`), not to a mesh file",
        path.display()
    );
    let name = path.display();
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {name}"))?;
    let mesh =
        format::read_level(&bytes, Some(n)).with_context(|| format!("cannot read {name}"))?;
    anyhow::ensure!(
        (mesh.base..=mesh.finest).contains(&n),
        "{name}: --level {n} is outside this file's levels {}..={}",
        mesh.base,
        mesh.finest
    );
    anyhow::ensure!(
        mesh.level == n,
        "{name} is truncated: its last complete level is {}",
        mesh.level
    );
    Ok(mesh.to_polygon_mesh())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_within_bounds_only() {
        assert_eq!(parse_size("96x64"), Ok((96, 64)));
        assert_eq!(parse_size("96X64"), Ok((96, 64)));
        for bad in ["96", "0x96", "96x8", "x", "96x99999", "-5x5", "ax b"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn ranges_need_finite_increasing_ends() {
        assert_eq!(parse_range("0:0.01"), Ok((0.0, 0.01)));
        assert_eq!(parse_range("-1e-3:2"), Ok((-0.001, 2.0)));
        for bad in ["1:1", "2:1", "0", "a:1", "0:inf", "NaN:1", ":"] {
            assert!(parse_range(bad).is_err(), "{bad}");
        }
    }
}
