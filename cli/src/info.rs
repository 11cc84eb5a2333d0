//! `meshpyr info MESH [--json]`: counts, topology, size and what the builder repaired.

use super::Global;
use super::input::{is_pyr_file, load_pyr};
use anyhow::Context;
use meshpyr::mesh::MeshInfo;
use meshpyr::wording::Count;
use std::path::PathBuf;

/// Arguments of `meshpyr info`.
#[derive(clap::Args, Debug)]
pub(crate) struct InfoArgs {
    /// Mesh file (.obj, .ply, .off, .stl, or a .pyr file: its stored input mesh).
    pub(crate) mesh: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub(crate) json: bool,
}

/// Runs `meshpyr info`.
pub(crate) fn run(args: InfoArgs, _global: &Global) -> anyhow::Result<()> {
    // A .pyr file is decoded once, for its stored input and its hierarchy.
    let (poly, pm_base) = if is_pyr_file(&args.mesh) {
        let data = load_pyr(&args.mesh)?;
        let base = data.pm.describe_base();
        (data.input, Some(base))
    } else {
        (super::input::read_mesh_warning(&args.mesh)?, None)
    };
    super::input::require(&args.mesh, poly.check_not_empty())?;
    let mut info = MeshInfo::of(&poly).with_context(|| args.mesh.display().to_string())?;
    info.pm_base = pm_base;
    if args.json {
        outln!("{}", serde_json::to_string(&info)?);
        return Ok(());
    }
    outln!("{}", args.mesh.display());
    outln!(
        "  vertices {}  faces {} (from {} polygons)  edges {}",
        info.vertices,
        info.faces,
        info.polygons,
        info.edges
    );
    outln!(
        "  components {}  boundary loops {}  euler characteristic {}  genus {}",
        info.components,
        info.boundary_loops,
        info.euler_characteristic,
        info.genus
            .map_or("n/a (not manifold)".to_string(), |g| g.to_string())
    );
    outln!(
        "  simplifies to at least {} vertices (the floor of its topology)",
        info.floor_vertices
    );
    if let Some(base) = &info.pm_base {
        outln!("  hierarchy: {base}");
    }
    outln!(
        "  manifold {}  bbox diagonal {:.6}  mean edge length {:.6}",
        if info.manifold { "yes" } else { "no" },
        info.bbox_diagonal,
        info.mean_edge_length
    );
    if !info.vertex_attributes.is_empty() {
        outln!("  vertex attributes: {}", info.vertex_attributes.join(" "));
    }
    if !info.face_attributes.is_empty() {
        outln!("  face attributes: {}", info.face_attributes.join(" "));
    }
    if let Some(t) = &info.texture {
        print_texture(t)?;
    }
    print_repairs(&info)
}

/// Texture coordinates and seams, materials, groups, and the files they name.
fn print_texture(t: &meshpyr::mesh::TextureInfo) -> anyhow::Result<()> {
    for (name, pool, valued) in &t.corner_attributes {
        outln!(
            "  per-corner {name}: {} on {}",
            Count(*pool, "value", "values"),
            Count(*valued, "corner", "corners")
        );
    }
    if t.vertex_texcoords {
        outln!("  texture coordinates: per vertex (u v), no seams");
    }
    if t.corner_attributes.iter().any(|a| a.0 == "texcoord") {
        outln!(
            "  texture seams: {}, {}",
            Count(t.seam_edges, "edge", "edges"),
            Count(t.seam_vertices, "vertex", "vertices")
        );
    }
    if !t.materials.is_empty() {
        outln!("  materials: {}", t.materials.join(" "));
    }
    if t.groups + t.objects > 0 {
        outln!(
            "  {}, {}",
            Count(t.groups, "group", "groups"),
            Count(t.objects, "object", "objects")
        );
    }
    for (file, found) in &t.files {
        let state = match found {
            Some(true) => "found",
            Some(false) => "missing",
            None => "not looked up",
        };
        outln!("  file {file}: {state}");
    }
    Ok(())
}

/// The repairs the builder makes, and what they mean for the levels of the hierarchy.
fn print_repairs(info: &MeshInfo) -> anyhow::Result<()> {
    let r = &info.repairs;
    let repairs = [
        (
            "polygon triangulated",
            "polygons triangulated",
            r.triangulated_polygons,
        ),
        (
            "triangle with a repeated index dropped",
            "triangles with a repeated index dropped",
            r.dropped_repeated_index,
        ),
        (
            "zero-area triangle (kept)",
            "zero-area triangles (kept)",
            r.zero_area_faces,
        ),
        (
            "non-manifold edge cut",
            "non-manifold edges cut",
            r.non_manifold_edges,
        ),
        (
            "pinched vertex",
            "pinched vertices",
            r.non_manifold_vertices,
        ),
        ("vertex copy added", "vertex copies added", r.split_vertices),
        (
            "triangle re-oriented",
            "triangles re-oriented",
            r.flipped_faces,
        ),
        (
            "edge cut to orient",
            "edges cut to orient",
            r.orientation_cuts,
        ),
        (
            "vertex detached (multi-edges)",
            "vertices detached (multi-edges)",
            r.detached_vertices,
        ),
        (
            "unreferenced vertex (kept)",
            "unreferenced vertices (kept)",
            r.unreferenced_vertices,
        ),
    ];
    let done: Vec<String> = repairs
        .iter()
        .filter(|(.., n)| *n > 0)
        .map(|&(one, many, n)| Count(n, one, many).to_string())
        .collect();
    if done.is_empty() {
        outln!("  repairs: none needed");
    } else {
        outln!("  repairs for processing: {}", done.join(", "));
    }
    if info.faces == 0 {
        outln!(
            "  no faces: a point cloud (info and convert take it; the other commands need a surface)"
        );
    }
    if r.split_vertices > 0 {
        outln!(
            "  levels (build, filter, edit) count the repaired mesh's vertices: these {} plus the \
             {} made where the surface is not manifold",
            info.vertices,
            Count(r.split_vertices, "vertex copy", "vertex copies")
        );
    }
    Ok(())
}
