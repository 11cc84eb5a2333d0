//! `meshpyr extract F.pyr -o OUT [--level N]`: a level of the hierarchy as a mesh file. The
//! finest level of a complete file is the user's original mesh, exactly (vertex order, faces,
//! attributes, f32 bits); coarser levels and truncated files read only the progressive prefix,
//! except a textured file's coarser levels, which keep the faces' materials and groups and the
//! corners' texture coordinates (`docs/seams.md`) and so read the whole file.

use super::Global;
use anyhow::Context;
use meshpyr::format;
use meshpyr::io;
use meshpyr::wording::Count;
use std::path::PathBuf;

/// Arguments of `meshpyr extract`.
#[derive(clap::Args, Debug)]
pub(crate) struct ExtractArgs {
    /// Input `.pyr` file.
    pub(crate) input: PathBuf,
    /// Output mesh (.obj, .ply, .off, .stl).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Level (vertex count) to extract; default the finest (the original mesh).
    #[arg(long, value_name = "N")]
    pub(crate) level: Option<usize>,
}

/// Runs `meshpyr extract`.
pub(crate) fn run(args: ExtractArgs, global: &Global) -> anyhow::Result<()> {
    super::check_mesh_output(&args.output)?;
    let name = args.input.display().to_string();
    let bytes = std::fs::read(&args.input).with_context(|| format!("cannot read {name}"))?;
    if args.level.is_none() {
        // The finest level: the user's mesh exactly, if the file is complete (one replay of
        // the splits; only a damaged file falls back to the progressive reader below).
        if write_original(&args, global, &bytes, &name)?.is_none() {
            return Ok(());
        }
    }
    if let Some(n) = args.level
        && format::is_textured(&bytes)
        && let Some(()) = write_textured_level(&args, global, &bytes, &name, n)?
    {
        return Ok(());
    }
    let level =
        format::read_level(&bytes, args.level).with_context(|| format!("cannot read {name}"))?;
    if let Some(n) = args.level
        && (n < level.base || n > level.finest)
    {
        anyhow::bail!(
            "--level {n} is outside this file's levels {}..={}",
            level.base,
            level.finest
        );
    }
    let wanted = args.level.unwrap_or(level.finest);
    if level.level == level.finest && wanted == level.finest {
        // The finest level: the user's mesh exactly, if the trailing sections are intact.
        match write_original(&args, global, &bytes, &name)? {
            None => return Ok(()),
            Some(e) => eprintln!(
                "warning: {name}: {e}; writing the finest level in hierarchy order, without the original vertex order and attributes"
            ),
        }
    } else if level.level < wanted {
        eprintln!(
            "warning: {name} is truncated; writing its last complete level {} (asked for {wanted})",
            level.level
        );
    }
    io::write_mesh(&args.output, &level.to_polygon_mesh())?;
    global.say(format_args!(
        "wrote {}: level {} ({})",
        args.output.display(),
        level.level,
        Count(level.triangles.len(), "triangle", "triangles")
    ));
    Ok(())
}

/// Writes the user's mesh exactly as it was built into the file. `Some(error)` when the file
/// is truncated (the caller falls back to the progressive prefix); other damage is an error.
fn write_original(
    args: &ExtractArgs,
    global: &Global,
    bytes: &[u8],
    name: &str,
) -> anyhow::Result<Option<format::FormatError>> {
    match format::decode(bytes) {
        Ok(data) => {
            super::output::write_mesh_output(&args.output, &data.input, &Default::default())?;
            global.say(format_args!(
                "wrote {}: the original mesh, {}, {}",
                args.output.display(),
                Count(data.input.n_vertices(), "vertex", "vertices"),
                Count(data.input.n_faces(), "face", "faces")
            ));
            Ok(None)
        }
        Err(e @ format::FormatError::Truncated { .. }) => Ok(Some(e)),
        Err(e) => Err(e).with_context(|| format!("cannot read {name}")),
    }
}

/// Writes level `n` of a complete textured file with its per-vertex attributes, materials,
/// groups and per-corner data (`PyrData::level_mesh`). `None` when the file is truncated (the
/// caller falls back to the progressive prefix, which has none of them) or for the finest
/// level (the user's mesh, written as for any file).
fn write_textured_level(
    args: &ExtractArgs,
    global: &Global,
    bytes: &[u8],
    name: &str,
    n: usize,
) -> anyhow::Result<Option<()>> {
    let data = match format::decode(bytes) {
        Ok(data) => data,
        Err(format::FormatError::Truncated { .. }) => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("cannot read {name}")),
    };
    let (base, finest) = (data.pm.n_base_vertices(), data.pm.n_vertices());
    if !(base..=finest).contains(&n) {
        anyhow::bail!("--level {n} is outside this file's levels {base}..={finest}");
    }
    if n == finest {
        return Ok(None); // the user's mesh exactly, as for any file
    }
    if !data.pm.keeps_seams() && !data.input.corner_attributes.is_empty() {
        eprintln!(
            "warning: {name}: its hierarchy was built without keeping the texture seams (a .pyr file before format 2.3, or a partitioned build); level {n} is written without its corners' texture coordinates"
        );
    }
    let mesh = data
        .level_mesh(n)
        .with_context(|| format!("cannot read {name}"))?;
    super::output::write_mesh_output(&args.output, &mesh, &Default::default())?;
    global.say(format_args!(
        "wrote {}: level {n} ({})",
        args.output.display(),
        Count(mesh.n_faces(), "triangle", "triangles")
    ));
    Ok(Some(()))
}
