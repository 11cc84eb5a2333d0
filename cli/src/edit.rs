//! `meshpyr edit IN -o OUT --level K --move X,Y,Z:DX,DY,DZ --radius R`: multiresolution edit —
//! move the vertices of level K near a point, with a smooth falloff, and resynthesise so that
//! the finer details follow.

use super::Global;
use super::blocks::PathOptions;
use super::filter::{FilterOptions, say_band_warnings};
use super::input::load_pyramid_by;
use anyhow::Context;
use glam::DVec3;
use meshpyr::io;
use meshpyr::pyramid::{HandleReach, MoveHandle, PyrContent, Pyramid};
use meshpyr::relax::RelaxKind;
use std::path::{Path, PathBuf};

/// One `--move X,Y,Z:DX,DY,DZ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Move {
    /// Where to grab.
    pub(crate) at: DVec3,
    /// How far to move the grabbed point.
    pub(crate) by: DVec3,
}

fn parse_vec3(s: &str) -> Option<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    (v.len() == 3 && v.iter().all(|x| x.is_finite())).then(|| DVec3::new(v[0], v[1], v[2]))
}

fn parse_move(s: &str) -> Result<Move, String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("{s:?}: expected X,Y,Z:DX,DY,DZ"))?;
    match (parse_vec3(a), parse_vec3(b)) {
        (Some(at), Some(by)) => Ok(Move { at, by }),
        _ => Err(format!(
            "{s:?}: expected X,Y,Z:DX,DY,DZ with six finite numbers"
        )),
    }
}

/// Arguments of `meshpyr edit`.
#[derive(clap::Args, Debug)]
pub(crate) struct EditArgs {
    /// Input mesh (.obj, .ply, .off, .stl) or .pyr file.
    pub(crate) input: PathBuf,
    /// Output mesh: the input's vertices and faces in the same order, new positions. A `.pyr`
    /// output keeps the hierarchy with the edited positions as its new original positions.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// The level (vertex count) whose vertices are moved; coarser levels give broader edits.
    #[arg(long, value_name = "K")]
    pub(crate) level: usize,
    /// Grab the level-K surface at X,Y,Z and move it by DX,DY,DZ (repeatable; model units).
    #[arg(
        long = "move",
        value_name = "X,Y,Z:DX,DY,DZ",
        value_parser = parse_move,
        required = true,
        allow_hyphen_values = true
    )]
    pub(crate) moves: Vec<Move>,
    /// Radius of influence of each move (model units).
    #[arg(long, value_name = "R")]
    pub(crate) radius: f64,
    /// Filters applied while resynthesising (optional).
    #[command(flatten)]
    pub(crate) filters: FilterOptions,
    /// Relaxation operator used for the prediction (default second-difference; a .pyr input
    /// uses the one it was built with).
    #[arg(long, value_parser = crate::choices::named::<RelaxKind>())]
    pub(crate) relax: Option<RelaxKind>,
    /// With a `.pyr` output: leave the details out (a smaller file whose readers recompute
    /// them; with them, saving analyses the edited positions).
    #[arg(long)]
    pub(crate) no_details: bool,
    #[command(flatten)]
    pub(crate) path: PathOptions,
}

/// Runs `meshpyr edit`.
pub(crate) fn run(args: EditArgs, global: &Global) -> anyhow::Result<()> {
    let writes_pyr = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pyr"));
    if writes_pyr {
        super::output::check_output_folder(&args.output)?;
    } else {
        super::check_mesh_output(&args.output)?;
    }
    if !(args.radius > 0.0 && args.radius.is_finite()) {
        anyhow::bail!("--radius must be a positive number, got {}", args.radius);
    }
    let scan = load_pyramid_by(
        &args.input,
        Some(&args.output),
        args.relax,
        &args.path,
        global,
    )?;
    let levels = scan.levels();
    if !levels.contains(&args.level) {
        anyhow::bail!(
            "--level {} is outside this mesh's levels {}..={}",
            args.level,
            levels.start(),
            levels.end()
        );
    }
    let handles: Vec<MoveHandle> = args
        .moves
        .iter()
        .map(|m| MoveHandle {
            center: m.at,
            displacement: m.by,
            radius: args.radius,
        })
        .collect();
    let edited = scan.edit_reporting(args.level, &handles, &args.filters.filter())?;
    say_band_warnings(&edited.warnings, &args.input.display().to_string());
    warn_unreached(&args, &edited.reach);
    if writes_pyr {
        let positions = edited.mesh.positions;
        let content = if args.no_details {
            PyrContent::HierarchyOnly
        } else {
            PyrContent::WithDetails
        };
        save_edited(&scan, positions, content, &args.output)?;
    } else {
        super::output::write_mesh_output(&args.output, &edited.mesh, &Default::default())?;
    }
    global.say(format_args!("wrote {}", args.output.display()));
    Ok(())
}

/// A warning on standard error for every move that reaches no vertex of the level (it would
/// otherwise change nothing without a word, like an empty band).
fn warn_unreached(args: &EditArgs, reach: &[HandleReach]) {
    for (m, r) in args.moves.iter().zip(reach) {
        if r.points == 0 {
            eprintln!(
                "warning: {}: the move at {},{},{} reaches no vertex of level {} (the nearest is \
                 {:.6} away, the radius is {}); it changes nothing",
                args.input.display(),
                m.at.x,
                m.at.y,
                m.at.z,
                args.level,
                r.nearest,
                args.radius
            );
        }
    }
}

/// Saves `scan` with new input positions as a `.pyr` file (same hierarchy and options, new
/// originals, and their details unless `content` leaves them out).
fn save_edited(
    scan: &Pyramid,
    input_positions: Vec<DVec3>,
    content: PyrContent,
    path: &Path,
) -> anyhow::Result<()> {
    let (bytes, _) = scan
        .to_pyr_bytes_with_positions_as(input_positions, content)
        .context("cannot save the edit")?;
    io::write_atomic(path, &bytes)?;
    Ok(())
}
