//! `meshpyr info MESH [--json]`: counts, topology, size and what the builder repaired.

use super::Global;
use super::input::{is_pyr_file, load_pyr};
use crate::mesh::{BuildReport, Mesh, PolygonMesh};
use crate::wording::Count;
use anyhow::Context;
use serde::Serialize;
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

/// Everything `info` reports. Counts describe the file as given; topology (loops, components,
/// χ, genus) is measured on the mesh the builder makes of it, which for a manifold file is the
/// file itself.
#[derive(Serialize, Debug)]
pub(crate) struct MeshInfo {
    /// Vertices in the file, unreferenced ones included.
    pub(crate) vertices: usize,
    /// Triangles after fan-triangulating the file's polygons.
    pub(crate) faces: usize,
    /// Polygons as stored in the file.
    pub(crate) polygons: usize,
    /// Distinct undirected edges of those triangles.
    pub(crate) edges: usize,
    /// Holes.
    pub(crate) boundary_loops: usize,
    /// Edge-connected components.
    pub(crate) components: usize,
    /// V − E + F of the surface (referenced vertices only).
    pub(crate) euler_characteristic: i64,
    /// Σ over components of (2 − b − χ)/2; null when the file is not manifold.
    pub(crate) genus: Option<u64>,
    /// The fewest vertices a surface of this topology can be simplified to
    /// ([`crate::mesh::topology::vertex_floor`], on the repaired mesh).
    pub(crate) floor_vertices: usize,
    /// For a `.pyr` file: the hierarchy's base level against that floor (null otherwise).
    pub(crate) pm_base: Option<String>,
    /// True when no edge has more than two triangles and no vertex is pinched.
    pub(crate) manifold: bool,
    /// Bounding-box diagonal.
    pub(crate) bbox_diagonal: f64,
    /// Mean edge length.
    pub(crate) mean_edge_length: f64,
    /// What the builder changed to make a valid half-edge mesh.
    pub(crate) repairs: BuildReport,
    /// Per-vertex attribute names, in file order.
    pub(crate) vertex_attributes: Vec<String>,
    /// Per-face attribute names, in file order.
    pub(crate) face_attributes: Vec<String>,
}

/// Computes [`MeshInfo`] for a file-level mesh.
pub(crate) fn mesh_info(poly: &PolygonMesh) -> anyhow::Result<MeshInfo> {
    let built = Mesh::from_polygons(poly)?;
    let topo = built.mesh.topology();
    let manifold = built.report.input_was_manifold();
    Ok(MeshInfo {
        vertices: poly.n_vertices(),
        faces: poly.n_triangles(),
        polygons: poly.n_faces(),
        edges: count_file_edges(poly),
        boundary_loops: topo.boundary_loops,
        components: topo.components,
        euler_characteristic: topo.euler_characteristic,
        genus: if manifold { topo.genus } else { None },
        floor_vertices: topo.floor_vertices,
        pm_base: None,
        manifold,
        bbox_diagonal: built.mesh.bbox_diagonal(),
        mean_edge_length: built.mesh.mean_edge_length(),
        repairs: built.report,
        vertex_attributes: poly
            .vertex_attributes
            .iter()
            .map(|a| a.name.clone())
            .collect(),
        face_attributes: poly
            .face_attributes
            .iter()
            .map(|a| a.name.clone())
            .collect(),
    })
}

/// Distinct undirected index pairs over the fan triangles (repeated-index pairs skipped).
fn count_file_edges(poly: &PolygonMesh) -> usize {
    let mut pairs: Vec<u64> = Vec::with_capacity(poly.n_triangles() * 3);
    for f in poly.faces() {
        for k in 1..f.len().saturating_sub(1) {
            let t = [f[0], f[k], f[k + 1]];
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if a != b {
                    pairs.push(((a.min(b) as u64) << 32) | a.max(b) as u64);
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs.len()
}

/// Runs `meshpyr info`.
pub(crate) fn run(args: InfoArgs, _global: &Global) -> anyhow::Result<()> {
    // A .pyr file is decoded once, for its stored input and its hierarchy.
    let (poly, pm_base) = if is_pyr_file(&args.mesh) {
        let data = load_pyr(&args.mesh)?;
        let base = data.pm.describe_base();
        (data.input, Some(base))
    } else {
        (crate::io::read_mesh(&args.mesh)?, None)
    };
    super::input::require(&args.mesh, poly.check_not_empty())?;
    let mut info = mesh_info(&poly).with_context(|| args.mesh.display().to_string())?;
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
    print_repairs(&info)
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
