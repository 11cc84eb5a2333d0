//! `meshpyr simplify IN -o OUT (--faces N | --ratio R | --error E)`: QEM decimation, i.e. the
//! progressive mesh cut at a level, written compacted with per-vertex attributes carried along
//! and a textured input's seams, corners and materials kept (docs/seams.md).

use super::{BarProgress, Global};
use anyhow::Context;
use meshpyr::io;
use meshpyr::pm::{PmOptions, SimplifyGoal, simplify_to_goal};
use meshpyr::wording::Count;
use std::path::PathBuf;

/// Arguments of `meshpyr simplify`.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["faces", "ratio", "error"])))]
pub(crate) struct SimplifyArgs {
    /// Input mesh (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) input: PathBuf,
    /// Output mesh; the format follows the extension.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Keep at most this many triangles.
    #[arg(long)]
    pub(crate) faces: Option<usize>,
    /// Keep at most this fraction of the triangles, in (0, 1].
    #[arg(long)]
    pub(crate) ratio: Option<f64>,
    /// Collapse while the quadric error (RMS distance) stays below this fraction of the
    /// bounding-box diagonal.
    #[arg(long)]
    pub(crate) error: Option<f64>,
    /// Largest rotation of a face normal one collapse may cause, in degrees, while at least 5 %
    /// of the input's faces are left; it widens to about 75° at 1 % (docs/pm-legality.md).
    #[arg(long, default_value_t = PmOptions::default().max_normal_angle_degrees)]
    pub(crate) max_angle: f64,
    /// Triangle quality (4√3·area / Σ edge², 1 = equilateral) below which a face left around
    /// the removed vertex is a sliver: a collapse that makes a worse one pays a penalty on top
    /// of its error, so fine levels stay well shaped (0 turns the penalty off).
    #[arg(long, default_value_t = PmOptions::default().min_quality)]
    pub(crate) min_quality: f64,
    /// Before simplifying, drop the connected pieces whose bounding-box diagonal is below this
    /// fraction of the whole mesh's (floating debris of reconstructions; the largest piece
    /// always stays). Reported; off unless given. `--ratio` still refers to the file's
    /// triangles.
    #[arg(long, value_name = "FRACTION")]
    pub(crate) prune: Option<f64>,
    /// Weight of the boundary-preserving planes (0 lets boundaries drift); it falls to 0.3 of
    /// this from 5 % to 1 % of the input's faces.
    #[arg(long, default_value_t = PmOptions::default().boundary_weight)]
    pub(crate) boundary_weight: f64,
    /// For a textured input: weight of the texture-coordinate error against the geometric
    /// error (a texture error of 1/W costs like a distance of the bounding box's longest side;
    /// 0 keeps the seams but ignores how the texture shifts; docs/seams.md).
    #[arg(long, value_name = "W", default_value_t = PmOptions::default().uv_weight)]
    pub(crate) uv_weight: f64,
}

/// Runs `meshpyr simplify`.
pub(crate) fn run(args: SimplifyArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let goal = SimplifyGoal::one_of(args.faces, args.ratio, args.error, args.prune)?;
    let input = super::input::read_input_mesh_for(&args.input, meshpyr::memory::Job::Simplify)?;
    let opts = PmOptions {
        max_normal_angle_degrees: args.max_angle,
        min_quality: args.min_quality,
        boundary_weight: args.boundary_weight,
        uv_weight: args.uv_weight,
        ..PmOptions::default()
    };
    let bar = global.progress("simplify");
    let (result, pruned) = simplify_to_goal(&input, &goal, &opts, &BarProgress(&bar))
        .with_context(|| format!("cannot simplify {}", args.input.display()))?;
    bar.finish_and_clear();
    if let (Some(pruned), Some(fraction)) = (pruned, goal.prune) {
        global.say(format_args!(
            "pruned {} of {} ({}) smaller than {fraction} of the diagonal",
            pruned.components,
            Count(pruned.of_components, "component", "components"),
            Count(pruned.faces, "polygon", "polygons")
        ));
    }
    io::write_mesh(&args.output, &result.mesh)?;
    super::input::warn_face_data_dropped(&args.input, &input, &result.mesh);
    if let Some(shortfall) = result.shortfall() {
        eprintln!("warning: {}: {shortfall}", args.input.display());
    }
    let relaxed = match result.relaxed_collapses {
        0 => String::new(),
        1 => " (1 collapse needed relaxed shape rules)".to_string(),
        n => format!(" ({n} collapses needed relaxed shape rules)"),
    };
    global.say(format_args!(
        "wrote {}: {} -> {}, {}{relaxed}",
        args.output.display(),
        result.input_triangles,
        Count(result.mesh.n_faces(), "triangle", "triangles"),
        Count(result.mesh.n_vertices(), "vertex", "vertices")
    ));
    Ok(())
}
