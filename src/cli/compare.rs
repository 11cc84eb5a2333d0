//! `meshpyr compare RESULT REFERENCE [--json]`: E_v, E_n and the sampled Hausdorff distance of
//! a processed mesh against a reference (see [`crate::metrics::error`]).

use super::Global;
use crate::mesh::Mesh;
use crate::metrics::{Comparison, compare};
use anyhow::Context;
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
}

fn load(path: &Path) -> anyhow::Result<Mesh> {
    let poly = super::input::read_input_mesh(path)?;
    Ok(Mesh::from_polygons(&poly)
        .with_context(|| format!("building a mesh from {}", path.display()))?
        .mesh)
}

/// Runs `meshpyr compare`.
pub(crate) fn run(args: CompareArgs, _global: &Global) -> anyhow::Result<()> {
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
    if args.json {
        outln!("{}", serde_json::to_string(&c)?);
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
    Ok(())
}
