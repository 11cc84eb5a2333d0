//! `meshpyr compare RESULT REFERENCE [--json]`: E_v, E_n and the sampled Hausdorff distance of
//! a processed mesh against a reference (see [`meshpyr::metrics::error`]).

use super::Global;
use anyhow::Context;
use meshpyr::mesh::Mesh;
use meshpyr::mesh::{Attribute, AttributeData};
use meshpyr::metrics::{Comparison, FieldPercentiles, Reference, compare, vertex_distances};
use std::path::{Path, PathBuf};

/// Arguments of `meshpyr compare`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "E_v: area-weighted RMS distance from RESULT's vertices to REFERENCE's surface. \
                  E_n: area-weighted RMS of |n(T) - n(T')| over RESULT's triangles T', with T the \
                  REFERENCE triangle closest to the centroid of T' (dimensionless, 0..2). \
                  Hausdorff: symmetric, sampled at the vertices, edge midpoints and face \
                  centroids of each mesh with exact distances to the other surface (a lower \
                  bound of the continuous Hausdorff distance). `_rel` values are divided by \
                  REFERENCE's bounding-box diagonal; e_n_rel equals e_n. Distances below 64ε \
                  times the diagonal (rounding noise) are reported as 0. Both meshes are \
                  repaired and consistently oriented by the builder first (see `meshpyr info`)."
)]
pub(crate) struct CompareArgs {
    /// The processed mesh M' (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) result: PathBuf,
    /// The reference mesh M (same formats).
    pub(crate) reference: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub(crate) json: bool,
    /// Also write RESULT to this .ply with a per-vertex float property `distance`: the exact
    /// unsigned distance from each vertex to REFERENCE's surface, in model units (vertices,
    /// faces and other attributes as in RESULT). Adds the field's percentiles to the output.
    #[arg(long, value_name = "OUT.ply")]
    pub(crate) per_vertex: Option<PathBuf>,
}

fn load(path: &Path) -> anyhow::Result<Mesh> {
    let poly = super::input::read_input_mesh(path)?;
    Ok(Mesh::from_polygons(&poly)
        .with_context(|| format!("building a mesh from {}", path.display()))?
        .mesh)
}

/// Runs `meshpyr compare`.
pub(crate) fn run(args: CompareArgs, global: &Global) -> anyhow::Result<()> {
    if let Some(out) = &args.per_vertex {
        check_ply_output(out)?;
    }
    let result = load(&args.result)?;
    let reference = load(&args.reference)?;
    let c: Comparison = compare(&result, &reference)
        .with_context(|| {
            format!(
                "comparing {} against {}",
                args.result.display(),
                args.reference.display()
            )
        })?
        .without_rounding_noise();
    let field = match &args.per_vertex {
        Some(out) => Some(write_per_vertex(&args, &reference, out, global)?),
        None => None,
    };
    if args.json {
        outln!("{}", comparison_json(&c, field)?);
        return Ok(());
    }
    outln!(
        "{} against {}",
        args.result.display(),
        args.reference.display()
    );
    outln!(
        "  E_v        {:.6e}  ({:.4e} of the bbox diagonal, {:.4} L)",
        c.e_v,
        c.e_v_rel,
        c.e_v_over_l
    );
    if c.e_v == 0.0 && c.hausdorff > 0.0 {
        outln!(
            "             (E_v is 0: every vertex of the result lies on the reference's surface, as \
             simplification keeps vertices where they were; E_n and Hausdorff measure the change)"
        );
    }
    outln!("  E_n        {:.6e}", c.e_n);
    outln!(
        "  Hausdorff  {:.6e}  ({:.4e} of the bbox diagonal; result->reference {:.6e}, \
         reference->result {:.6e}; sampled at vertices, edge midpoints and centroids)",
        c.hausdorff,
        c.hausdorff_rel,
        c.hausdorff_result_to_reference,
        c.hausdorff_reference_to_result
    );
    outln!(
        "  reference: bbox diagonal {:.6}, mean edge length L {:.6}",
        c.bbox_diagonal,
        c.mean_edge_length
    );
    if let Some(f) = field {
        outln!(
            "  per vertex p50 {:.6e}, p90 {:.6e}, p99 {:.6e}, max {:.6e}",
            f.p50,
            f.p90,
            f.p99,
            f.max
        );
    }
    Ok(())
}

/// The comparison as JSON; with a field, its percentiles follow under `per_vertex_distance`
/// (the other keys keep their order, so output without `--per-vertex` does not change).
fn comparison_json(c: &Comparison, field: Option<FieldPercentiles>) -> anyhow::Result<String> {
    #[derive(serde::Serialize)]
    struct WithField<'a> {
        #[serde(flatten)]
        comparison: &'a Comparison,
        per_vertex_distance: FieldPercentiles,
    }
    Ok(match field {
        None => serde_json::to_string(c)?,
        Some(per_vertex_distance) => serde_json::to_string(&WithField {
            comparison: c,
            per_vertex_distance,
        })?,
    })
}

/// Fails before any work when `--per-vertex` does not name a PLY file, the one format that
/// keeps a per-vertex property.
fn check_ply_output(path: &Path) -> anyhow::Result<()> {
    let format = meshpyr::io::MeshFormat::from_path(path)?;
    anyhow::ensure!(
        format == meshpyr::io::MeshFormat::Ply,
        "--per-vertex {}: the distance field needs a .ply output (the only format with per-vertex properties)",
        path.display()
    );
    Ok(())
}

/// Writes RESULT as read (its file's vertex order, faces and attributes) with the per-vertex
/// `distance` to `reference` (replacing an existing `distance` in place); returns the field's
/// percentiles.
fn write_per_vertex(
    args: &CompareArgs,
    reference: &Mesh,
    out: &Path,
    global: &Global,
) -> anyhow::Result<FieldPercentiles> {
    let result_path = &args.result;
    let mut poly = super::input::read_input_mesh(result_path)?;
    let surface = Reference::from_mesh(reference)
        .with_context(|| format!("preparing {} as the reference", args.reference.display()))?;
    let field = vertex_distances(&poly.positions, &surface);
    let percentiles = FieldPercentiles::of(&field)
        .with_context(|| format!("{} has no vertices", result_path.display()))?;
    poly.set_vertex_attribute(Attribute {
        name: "distance".into(),
        data: AttributeData::F32(field.iter().map(|&d| d as f32).collect()),
    })
    .map_err(anyhow::Error::msg)?;
    meshpyr::io::write_mesh(out, &poly)?;
    global.say(format_args!(
        "wrote {} with the per-vertex distance ({} vertices)",
        out.display(),
        poly.n_vertices()
    ));
    Ok(percentiles)
}
