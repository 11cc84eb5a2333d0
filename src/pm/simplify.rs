//! Simplification of a file-level mesh: the progressive mesh cut at a level, written with the
//! input's per-vertex attributes carried along (the behaviour of `meshpyr simplify`).
//!
//! A textured input keeps its seams (`super::seams`): the surviving triangles are input
//! triangles with vertices renamed, so each keeps its polygon's face attributes (material,
//! groups) and each of its corners takes the values of the survivor's corner in the same wedge.

use super::decimate::{FlatMesh, Stop, decimate_with_seams, live_triangles};
use super::progressive::{PmError, PmOptions, decimate_params};
use super::seams::Seams;
use crate::mesh::CornerAttribute;
use crate::mesh::{BoundingBox, BuildError, CornerTable, Mesh, PolygonMesh, Topology};
use crate::progress::Progress;
use glam::DVec3;

/// When to stop simplifying.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SimplifyTarget {
    /// At most this many triangles.
    Faces(usize),
    /// At most this fraction of the input's triangles, in `(0, 1]`.
    Ratio(f64),
    /// Every collapse's quadric error (an RMS distance) at most this fraction of the bounding-box
    /// diagonal; collapses continue until the next one would exceed it.
    Error(f64),
}

/// Why a mesh could not be simplified.
#[derive(Debug, thiserror::Error)]
pub enum SimplifyError {
    /// The input holds no surface (nothing at all, a point cloud, only degenerate faces).
    #[error(transparent)]
    NoSurface(#[from] crate::mesh::MissingSurface),
    /// The input cannot be turned into a half-edge mesh.
    #[error(transparent)]
    Build(#[from] BuildError),
    /// The progressive mesh could not be built.
    #[error(transparent)]
    Pm(#[from] PmError),
    /// The target is out of range.
    #[error("invalid target: {0}")]
    InvalidTarget(String),
}

/// The simplified mesh and what happened.
#[derive(Clone, Debug)]
pub struct Simplified {
    /// The result: triangles, the surviving vertices at their original positions (PM order),
    /// the input's per-vertex attributes gathered along. Each triangle keeps the face
    /// attributes and face lists of the polygon it came from (materials and groups among
    /// them), and its corners the per-corner data of the survivor's corner on the same side
    /// of every seam (`docs/seams.md`); extra elements are dropped.
    pub mesh: PolygonMesh,
    /// Triangles of the input after the builder's repairs.
    pub input_triangles: usize,
    /// For each output vertex, the input vertex it came from.
    pub source_rows: Vec<u32>,
    /// Why simplification stopped: the target, or, short of it, no legal collapse left.
    pub stop: Stop,
    /// Collapses that needed relaxed shape rules ([`Relaxation`](super::Relaxation)).
    pub relaxed_collapses: usize,
    /// The result's topology (components, holes, genus and the floor they set) when it
    /// stopped short of the target; `None` when the target was reached.
    pub short_of_target: Option<Topology>,
}

impl Simplified {
    /// One line saying where simplification stopped and why, when it stopped short of the
    /// target (`None` otherwise).
    pub fn shortfall(&self) -> Option<String> {
        let topology = self.short_of_target.as_ref()?;
        Some(format!(
            "stopped at {} triangles, {} vertices: {}; the floor of its topology is {}",
            self.mesh.n_faces(),
            self.mesh.n_vertices(),
            self.stop,
            topology.describe_floor(),
        ))
    }
}

/// Simplifies `input` by quadric-error half-edge collapses (the base level
/// [`ProgressiveMesh::build`](super::ProgressiveMesh::build) would reach);
/// the stopping rule in `opts` is replaced by `target`.
pub fn simplify(
    input: &PolygonMesh,
    target: SimplifyTarget,
    opts: &PmOptions,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    // The decimator works on the builder's corner table directly: the half-edge records a
    // `Mesh` would add are never needed for a single cut (see `decimate`'s module docs).
    input.check_surface()?;
    let repaired = CornerTable::from_polygons(input)?;
    let n_faces = repaired.corners.n_triangles();
    let positions: Vec<DVec3> = repaired
        .source
        .vertex_source
        .iter()
        .map(|&s| input.positions[s as usize])
        .collect();
    let bbox_diagonal = BoundingBox::of(positions.iter().copied()).map_or(0.0, |b| b.diagonal());
    let mut o = PmOptions {
        target_vertices: 0,
        target_faces: 0,
        max_error: None,
        ..opts.clone()
    };
    match target {
        SimplifyTarget::Faces(f) => o.target_faces = f,
        SimplifyTarget::Ratio(r) => {
            if !(r > 0.0 && r <= 1.0) {
                return Err(SimplifyError::InvalidTarget(format!(
                    "ratio must be in (0, 1], got {r}"
                )));
            }
            o.target_faces = (r * n_faces as f64).round() as usize;
        }
        SimplifyTarget::Error(e) => {
            if !(e >= 0.0 && e.is_finite()) {
                return Err(SimplifyError::InvalidTarget(format!(
                    "error must be a finite number >= 0, got {e}"
                )));
            }
            o.max_error = Some(e);
        }
    }
    let params = decimate_params(&o, bbox_diagonal)?;
    let extent = BoundingBox::of(positions.iter().copied()).map_or(0.0, |b| b.max_side());
    let flat = FlatMesh::from_corners(positions, &repaired.corners);
    let mut seams = Seams::of(
        input,
        &repaired.corners.corner_vertex,
        &repaired.source.face_source,
        &repaired.source.vertex_source,
        &flat,
        o.uv_weight,
        extent,
    );
    let (_, coarse, outcome) = decimate_with_seams(flat, &params, seams.as_mut(), progress);
    // The cut is the progressive mesh's base level: survivors in slot order, live triangles in
    // input order (exactly what `ProgressiveMesh::level_triangles` gives there).
    let survivors = coarse.survivors();
    let mut compact = vec![u32::MAX; repaired.source.vertex_source.len()];
    for (i, &v) in survivors.iter().enumerate() {
        compact[v as usize] = i as u32;
    }
    let tris: Vec<[u32; 3]> = coarse
        .triangles()
        .into_iter()
        .map(|t| t.map(|v| compact[v as usize]))
        .collect();
    let source_rows: Vec<u32> = survivors
        .iter()
        .map(|&v| repaired.source.vertex_source[v as usize])
        .collect();
    let live = live_triangles(&coarse);
    let faces: Vec<u32> = live
        .iter()
        .map(|&t| repaired.source.face_source[t as usize])
        .collect();
    let corners: Option<Vec<u32>> = seams.as_ref().map(|seams| {
        live.iter()
            .flat_map(|&t| (3 * t..3 * t + 3).map(|c| seams.source_corner(seams.wedge(c))))
            .collect()
    });
    let mesh = cut_mesh(input, &source_rows, &tris, &faces, corners.as_deref());
    let short_of_target = match outcome.stop {
        Stop::NoLegalCollapse(_) => Some(Mesh::from_polygons(&mesh)?.mesh.topology()),
        _ => None,
    };
    Ok(Simplified {
        mesh,
        input_triangles: n_faces,
        source_rows,
        stop: outcome.stop,
        relaxed_collapses: outcome.relaxed.iter().sum(),
        short_of_target,
    })
}

/// A mesh cut from `input`: the vertices at input rows `source_rows` with their per-vertex
/// attributes, the triangles `tris` (over those vertices), each from input polygon `faces[i]`
/// and keeping its face attributes, face lists, material and groups, and, with `corners` (the
/// input polygon corner of each of the triangles' corners), their per-corner data, each
/// attribute's pool reduced to the rows in use (in order of first use).
pub(crate) fn cut_mesh(
    input: &PolygonMesh,
    source_rows: &[u32],
    tris: &[[u32; 3]],
    faces: &[u32],
    corners: Option<&[u32]>,
) -> PolygonMesh {
    let mut out = PolygonMesh::from_triangles(
        source_rows
            .iter()
            .map(|&r| input.positions[r as usize])
            .collect(),
        tris,
    );
    out.position_type = input.position_type;
    out.comments = input.comments.clone();
    out.vertex_attributes = input
        .vertex_attributes
        .iter()
        .map(|a| a.gathered(source_rows))
        .collect();
    out.face_attributes = input
        .face_attributes
        .iter()
        .map(|a| a.gathered(faces))
        .collect();
    out.face_lists = input.face_lists.iter().map(|l| l.gathered(faces)).collect();
    out.materials = input.materials.clone();
    out.group_names = input.group_names.clone();
    out.object_names = input.object_names.clone();
    if let Some(corners) = corners {
        out.corner_attributes = input
            .corner_attributes
            .iter()
            .map(|a| compacted(a, corners))
            .collect();
    }
    out
}

/// `a` on the polygon corners `corners` (one per output corner), its pool reduced to the rows
/// they use.
fn compacted(a: &CornerAttribute, corners: &[u32]) -> CornerAttribute {
    let mut new_row = vec![u32::MAX; a.pool_len()];
    let mut rows = Vec::new();
    let indices = corners
        .iter()
        .map(|&c| match a.row(c as usize) {
            None => crate::mesh::NO_VALUE,
            Some(r) => {
                if new_row[r] == u32::MAX {
                    new_row[r] = rows.len() as u32;
                    rows.push(r as u32);
                }
                new_row[r]
            }
        })
        .collect();
    CornerAttribute {
        name: a.name.clone(),
        columns: a.columns.iter().map(|c| c.gathered(&rows)).collect(),
        indices,
    }
}
